"""Function blocks: profile generation at 520.8 Hz (manual 4.1).

Each block writes its velocity profile FNC_OUT [1/16 count/sample], keeps V_OLD, sets ACC_FLAG /
DEC_FLAG, and advances P_FNC [1/16 count]. All profile arithmetic is integer-valued (float64 holding
integers), as in the firmware's 16/32-bit registers.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ....engine.jit import KERNEL
from ....physics.fixed import clamp, wrap32
from ....physics.profile import max_landing_speed
from .. import constants as c
from .. import layout as L
from . import regs as R


@njit(cache=True, inline="always")
def _finish(r: np.ndarray, s: np.ndarray, f: float) -> float:
    """ACC/DEC flags, V_OLD and P_FNC bookkeeping shared by the profile blocks (4.1.1, 4.1.2)."""
    v_old = s[L.S_V_OLD]
    st = r[R.ERR_STAT] & ~(c.ACC_FLAG | c.DEC_FLAG)
    if f > v_old:
        st |= c.ACC_FLAG
    elif f < v_old:
        st |= c.DEC_FLAG
    r[R.ERR_STAT] = st
    s[L.S_V_OLD] = f
    r[R.P_FNC] = wrap32(r[R.P_FNC] + int(f))
    return f


@njit(**KERNEL)
def velocity_block(r: np.ndarray, s: np.ndarray, target: float, accel: float) -> float:
    """Velocity function block (4.1.1): ramp V_OLD towards ``target`` by at most ``accel``.

    ``DV = target − V_OLD``, limited to ±A; ``FNC_OUT = V_OLD + DV``.
    """
    v_old = s[L.S_V_OLD]
    f = v_old + clamp(target - v_old, -accel, accel)
    return _finish(r, s, f)


@njit(**KERNEL)
def position_block(r: np.ndarray, s: np.ndarray, dp: float, vmax: float, accel: float) -> float:
    """Position function block (4.1.2) towards the remaining distance ``dp`` [1/16 count].

    ``dp = 16·P_SOLL − P_FNC``. The speed towards the target is the largest one that can still
    brake to rest exactly at the target with ``accel``, limited to ``vmax``; the change per sample
    is limited to ``accel``; P_FNC accumulates FNC_OUT.
    """
    sg = 1.0 if dp > 0.0 else (-1.0 if dp < 0.0 else 0.0)
    desired = sg * min(max_landing_speed(abs(dp), accel), abs(vmax))
    v_old = s[L.S_V_OLD]
    f = v_old + clamp(desired - v_old, -accel, accel)
    return _finish(r, s, f)


@njit(**KERNEL)
def stop_block(r: np.ndarray, s: np.ndarray) -> float:
    """Stop function block (4.1.8): decelerate to 0 with A_SOLL, or ACC_EMERG after an error."""
    a = float(r[R.A_SOLL])
    if s[L.S_EMERG] > 0.5 and r[R.ACC_EMERG] > 0:
        a = float(r[R.ACC_EMERG])
    if a <= 0.0:
        a = abs(s[L.S_V_OLD])
    return velocity_block(r, s, 0.0, a)
