"""Gear function blocks: gear follow (4.1.3), gear position (4.1.12), AVG (4.1.7), AG (4.1.9).

The pulse input V_EXT [counts/sample] is scaled to the profile unit (1/16 count/sample):
``16·V_EXT·GEARF1/GEARF2`` — nominally the motor follows 4096 pulses per revolution with
GEARF1/GEARF2 = 1 (4.4.4), so one pulse is one encoder count. G_FNC (1/16 count) keeps the
fractional part of the gearing exactly (float64), so a 1024/125 gear does not drift.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ....engine.jit import KERNEL
from ....physics.fixed import clamp
from ....physics.profile import max_landing_speed
from .. import constants as c
from .. import layout as L
from . import regs as R
from .blocks import _finish

_AVG_BIAS = c.rpm_to_v_soll(300.0)  #: AVG: ±10 V ↔ ±300 rpm (4.4.7)


@njit(cache=True, inline="always")
def gear_factor(r: np.ndarray) -> float:
    """``16·GEARF1/GEARF2`` (0 when GEARF2 = 0; writes making it 0 in a gear mode are refused)."""
    g2 = float(r[R.GEARF2])
    return 16.0 * r[R.GEARF1] / g2 if g2 != 0.0 else 0.0


@njit(cache=True, inline="always")
def analog_gear_factor(r: np.ndarray) -> float:
    """AG factor: ANINP −10..+10 V ↔ 0.87..1.15, linear (4.1.9; +10 V ↔ 1.15, decision)."""
    return 1.01 + 0.14 * r[R.ANINP] / 1023.0


@njit(**KERNEL)
def gear_position_block(r: np.ndarray, s: np.ndarray, factor: float) -> float:
    """Gear position block (4.1.12): stop at the right position without overshooting.

    ``G_FNC −= V_EXT·gear``; the speed towards ``−G_FNC`` is the largest that can still brake to
    rest on it (``FNC_OUT = −2·G_FNC/T``, ``T = |V_OLD|/A_SOLL``, made exact for the sampled
    profile), limited to ±V_SOLL and by ±A_SOLL per sample; ``G_FNC += FNC_OUT``.
    """
    s[L.S_G_FNC] -= r[R.V_EXT] * factor
    dp = -s[L.S_G_FNC]
    a = float(r[R.A_SOLL])
    sg = 1.0 if dp > 0.0 else (-1.0 if dp < 0.0 else 0.0)
    desired = sg * min(max_landing_speed(abs(dp), a), abs(float(r[R.V_SOLL])))
    v_old = s[L.S_V_OLD]
    f = _finish(r, s, v_old + clamp(desired - v_old, -a, a))
    s[L.S_G_FNC] += f
    return f


@njit(**KERNEL)
def gear_follow_block(r: np.ndarray, s: np.ndarray, factor: float) -> float:
    """Gear follow block (4.1.3): least follow error, overshoots when the pulses stop.

    ``G_FNC −= V_EXT·gear``; ``V_NEW = −G_FNC`` limited to ±V_SOLL; ``DV`` limited to ±A_SOLL;
    ``FNC_OUT = V_OLD + DV``; ``G_FNC += FNC_OUT``.
    """
    s[L.S_G_FNC] -= r[R.V_EXT] * factor
    vmax = abs(float(r[R.V_SOLL]))
    a = float(r[R.A_SOLL])
    v_new = clamp(-s[L.S_G_FNC], -vmax, vmax)
    v_old = s[L.S_V_OLD]
    f = _finish(r, s, v_old + clamp(float(int(v_new)) - v_old, -a, a))
    s[L.S_G_FNC] += f
    return f


@njit(cache=True, inline="always")
def avg_target(r: np.ndarray) -> float:
    """AVG velocity (4.1.7): gear velocity + analogue bias (±10 V ↔ ±300 rpm), within ±V_SOLL."""
    vmax = abs(float(r[R.V_SOLL]))
    v = r[R.V_EXT] * gear_factor(r) + r[R.ANINP] / 1023.0 * _AVG_BIAS
    return float(int(clamp(v, -vmax, vmax)))
