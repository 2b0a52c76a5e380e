"""Function blocks of the MAC800 at 770 Hz: the velocity profile FNC_OUT of each mode.

The MAC050–141's function blocks (its manual 4.1) with the MAC800's registers: each block
writes FNC_OUT [1/16 count/sample], keeps V_OLD, sets ERR_STAT ACC_FLAG / DEC_FLAG (bits 5, 6)
and advances the function position (``S_PF16`` in 1/16 count; P_FUNC, register 8, holds it in
counts). Profile arithmetic is integer-valued (float64 holding integers). With V_SOLL = 277 the
velocity block settles at FNC_OUT = 277 (100 RPM ± 0.01 %); with A_SOLL = 360 it changes by
360 per sample (100 052 RPM/s), the overview's examples (registers 5 and 6). The position
block's landing-speed search is the MAC050–141's (``mac050_141.firmware.blocks``, register-free
arithmetic on the sampled profile).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ....engine.jit import KERNEL
from ....physics.fixed import clamp
from ....physics.profile import max_landing_speed
from .. import constants as c
from .. import layout as L
from . import regs as R


@njit(cache=True, inline="always")
def _finish(r: np.ndarray, s: np.ndarray, f: float) -> float:
    """ACC/DEC flags, V_OLD and the function position after a block computed ``f``."""
    v_old = s[L.S_V_OLD]
    st = r[R.ERR_STAT] & ~(c.ACC_FLAG | c.DEC_FLAG)
    if abs(f) > abs(v_old):
        st |= c.ACC_FLAG
    elif abs(f) < abs(v_old):
        st |= c.DEC_FLAG
    r[R.ERR_STAT] = st
    s[L.S_V_OLD] = f
    s[L.S_PF16] += f
    return f


@njit(**KERNEL)
def velocity_block(r: np.ndarray, s: np.ndarray, target: float, accel: float) -> float:
    """Velocity block: V_OLD ramps towards ``target`` by at most ``accel`` per sample."""
    v_old = s[L.S_V_OLD]
    return _finish(r, s, v_old + clamp(target - v_old, -accel, accel))


@njit(**KERNEL)
def position_block(r: np.ndarray, s: np.ndarray, vmax: float, accel: float) -> float:
    """Position block towards P_SOLL: the fastest profile that can still brake to rest at the
    target with ``accel``, limited to ``vmax``, changing by at most ``accel`` per sample."""
    dp = 16.0 * float(r[R.P_SOLL]) - s[L.S_PF16]
    sg = 1.0 if dp > 0.0 else (-1.0 if dp < 0.0 else 0.0)
    desired = sg * min(max_landing_speed(abs(dp), accel), abs(vmax))
    v_old = s[L.S_V_OLD]
    return _finish(r, s, v_old + clamp(desired - v_old, -accel, accel))


@njit(**KERNEL)
def stop_block(r: np.ndarray, s: np.ndarray) -> float:
    """Error stop: decelerate to 0 with ACC_EMERG (register 32; A_SOLL if ACC_EMERG = 0)."""
    a = float(r[R.ACC_EMERG])
    if a <= 0.0:
        a = float(r[R.A_SOLL])
    if a <= 0.0:
        a = abs(s[L.S_V_OLD])
    return velocity_block(r, s, 0.0, a)


@njit(**KERNEL)
def geared_velocity(r: np.ndarray, s: np.ndarray, factor: float) -> float:
    """GV_EXT: the pulse input's speed V_EXT times GEARF_1/GEARF_2 (registers 14, 15, 163,
    164) and ``factor``, in 1/16 count/sample, the division's remainder carried to the next
    sample so that no count is lost. Computed in the modes that use it (3, 6, 18); GV_EXT is 0
    in the others (decision)."""
    num = 16.0 * float(r[R.V_EXT]) * float(r[R.GEARF_1]) * factor + s[L.S_GEAR_REM]
    den = float(r[R.GEARF_2])
    q = math.floor(num / den)
    s[L.S_GEAR_REM] = num - q * den
    r[R.GV_EXT] = int(clamp(q, -2147483647.0, 2147483647.0))
    return q


@njit(**KERNEL)
def gear_block(r: np.ndarray, s: np.ndarray, gv: float) -> float:
    """Gear block: FNC_OUT follows the geared input speed ``gv``; G_FNC (register 165) is the
    geared input position not yet followed (what a torque-limited correction held back)."""
    s[L.S_G_FNC] += gv
    f = _finish(r, s, gv)
    s[L.S_G_FNC] -= f
    return f
