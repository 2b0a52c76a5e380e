"""Hall sensors and the synchronisation of ELDEG_IST (manual 3.2.124, 3.2.125, 3.2.36).

Three hall sensors divide the electrical turn into six 60° sectors; the transition between the
last and the first sector (at the electrical angle ``hall_angle``) is the zero point. When the
rotor crosses it in the positive direction the firmware writes ELDEGP_OFFSET to ELDEG_IST, in the
negative direction ELDEGN_OFFSET; between corrections ELDEG_IST follows the encoder (2048 counts
per electrical turn). The first correction happens automatically after power-on, later ones only
with CNTRL_BITS HALL_INT. Before it, the firmware knows only the sector: the simulator starts
ELDEG_IST at the sector centre (up to ±30° error) when the motor parameter ``hall_start`` is 1;
with ``hall_start = 0`` (default) the commutation is taken as aligned from power-on.
The hall status of CNTRL_BITS bits 15..13 is the sector's 3-bit hall code.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ....engine.jit import LANE_KERNEL

SECTOR = math.pi / 3.0
_PER_SECTOR = 1.0 / SECTOR  #: a multiplication, not a division, in every inner sample
#: hall code (bits 15..13 of CNTRL_BITS) of sectors 0..5: one sensor changes per sector
HALL_CODES = np.array([5, 1, 3, 2, 6, 4], dtype=np.int64)


@njit(**LANE_KERNEL, forceinline=True)
def sector_index(theta_e: float, hall_angle: float) -> float:
    """Unwrapped sector index ``floor((θe − hall angle)/60°)`` (its change gives the direction)."""
    return np.floor((theta_e - hall_angle) * _PER_SECTOR)


@njit(**LANE_KERNEL, forceinline=True)
def hall_code(sector: float) -> int:
    """3-bit hall code of an (unwrapped) sector index."""
    return HALL_CODES[int(sector) % 6]


@njit(**LANE_KERNEL, forceinline=True)
def zero_crossing(prev: float, now: float) -> int:
    """+1 / −1 when the zero transition (sector 5 ↔ 0) was crossed upwards / downwards, else 0."""
    if now > prev and int(now) % 6 == 0:
        return 1
    if now < prev and int(prev) % 6 == 0:
        return -1
    return 0
