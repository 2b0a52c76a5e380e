"""Register arithmetic of the firmware (manual 3.1): rounding, saturation, fixed-point reads.

A value the firmware stores in a register is rounded (half away from zero) and saturated to the
register's format at the moment it is stored (MODEL.md §3); blocks then read the stored value.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True, inline="always")
def rnd(x: float) -> float:
    """Round half away from zero, returned as float64 holding an integer.

    Written without a branch on the sign: the current loops round signals whose sign changes
    at random when the torque command does, and a mispredicted branch costs more than the
    whole rounding.
    """
    return math.copysign(np.floor(abs(x) + 0.5), x)


@njit(cache=True, inline="always")
def clamp(x: float, lo: float, hi: float) -> float:
    """Limit ``x`` to ``[lo, hi]``."""
    return lo if x < lo else (hi if x > hi else x)


@njit(cache=True, inline="always")
def sat16(x: float) -> float:
    """Round and saturate to the Integer format (−32767..32767)."""
    return clamp(rnd(x), -32767.0, 32767.0)


@njit(cache=True, inline="always")
def wrap32(x: int) -> int:
    """Wrap an integer to signed 32 bits, as a LongInt register does."""
    return ((x + 2147483648) % 4294967296) - 2147483648


@njit(cache=True, inline="always")
def fx4(raw: int) -> float:
    """Fixed4 register value (raw / 4096)."""
    return raw / 4096.0


@njit(cache=True, inline="always")
def fx8(raw: int) -> float:
    """Fixed8 register value (raw / 256)."""
    return raw / 256.0


@njit(cache=True, inline="always")
def sign(x: float) -> float:
    """−1, 0 or 1."""
    return 1.0 if x > 0.0 else (-1.0 if x < 0.0 else 0.0)
