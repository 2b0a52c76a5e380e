"""The MAC800's incremental encoder: 8000 counts per revolution and one index pulse per turn
(resolution derived from the unit figures, :mod:`jvl_gym.families.mac800.units`; the index
from the INDEX_OFFSET, INDEX_HOME and INDEX_ERR descriptions of the register overview §1.2).

The count is ``floor(θ·8000/2π)``; the electrical angle ELDEG_IST is 4096 units per electrical
turn (decision), aligned with the rotor from power-on.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..constants import ELDEG_PER_TURN
from ..units import COUNTS_PER_REV

_COUNTS_PER_RAD = COUNTS_PER_REV / (2.0 * math.pi)
_ELDEG_PER_RAD = ELDEG_PER_TURN / (2.0 * math.pi)
_PER_ELDEG_TURN = 1.0 / ELDEG_PER_TURN  #: exact (a power of two)
_PER_TURN_RAD = 1.0 / (2.0 * math.pi)


@njit(cache=True, inline="always")
def encoder_count(theta: float) -> float:
    """Absolute encoder count of the mechanical angle ``theta`` [rad] (an integer as float)."""
    return np.floor(theta * _COUNTS_PER_RAD)


@njit(cache=True, inline="always")
def eldeg(theta_e: float) -> float:
    """ELDEG_IST of the electrical angle ``theta_e`` [rad]: 0 … 4095 (an integer as float,
    the ``mod 4096`` by ``floor``, exact, so that it runs in SIMD lanes)."""
    e = np.floor(theta_e * _ELDEG_PER_RAD)
    return e - ELDEG_PER_TURN * np.floor(e * _PER_ELDEG_TURN)


@njit(cache=True, inline="always")
def turn(theta: float, index_pos: float) -> float:
    """Number of index pulses passed: ``floor((θ − index angle)/2π)``."""
    return np.floor((theta - index_pos) * _PER_TURN_RAD)


@njit(cache=True, inline="always")
def counts_from_index(theta: float, index_pos: float) -> float:
    """Signed counts from the nearest index pulse to the angle ``theta`` (−4000 … 3999)."""
    c = np.floor((theta - index_pos) * _COUNTS_PER_RAD)
    c -= COUNTS_PER_REV * np.floor(c / COUNTS_PER_REV)
    return c - COUNTS_PER_REV if c >= COUNTS_PER_REV / 2 else c
