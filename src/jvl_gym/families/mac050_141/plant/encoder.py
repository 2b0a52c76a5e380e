"""Incremental encoder, 4096 counts/rev, and the electrical angle (manual 3.2.10, 3.2.143).

The encoder count is ``floor(θ·4096/2π)``; P_IST counts from the power-on position. The
electrical angle ELDEG_IST (2048 per electrical turn) is synchronised to the rotor at power-on:
the hall-sensor synchronisation of 3.2.124/125 is modelled as already done with offsets that
match the rotor (docs/model.md §5.3).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ....engine.jit import LANE_KERNEL
from ..constants import COUNTS_PER_REV, ELDEG_PER_TURN

_COUNTS_PER_RAD = COUNTS_PER_REV / (2.0 * math.pi)
_ELDEG_PER_RAD = ELDEG_PER_TURN / (2.0 * math.pi)
_PER_TURN = 1.0 / ELDEG_PER_TURN  #: exact (a power of two)


@njit(**LANE_KERNEL, forceinline=True)
def encoder_count(theta: float) -> float:
    """Absolute encoder count of a mechanical angle [rad] (an integer, as float64)."""
    return np.floor(theta * _COUNTS_PER_RAD)


@njit(**LANE_KERNEL, forceinline=True)
def eldeg(theta_e: float) -> float:
    """ELDEG_IST of an electrical angle [rad], in 0..2047 (a float holding the integer; the
    ``mod 2048`` by ``floor``, exact, so that it runs in SIMD lanes, ``mac050_141.lanes``)."""
    e = np.floor(theta_e * _ELDEG_PER_RAD)
    return e - ELDEG_PER_TURN * np.floor(e * _PER_TURN)
