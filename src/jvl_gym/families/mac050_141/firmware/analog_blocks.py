"""Analogue function blocks: AV (4.1.5), AVZ (4.1.6), VAT (4.4.18), A2POS (4.1.10), APOS (4.1.11).

ANINP is ±1023 for ±10 V (3.2.122). The position blocks set P_SOLL (or P_FNC) from the analogue
input and then run the position function block.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ....engine.jit import KERNEL, plain_arguments
from ....physics.fixed import wrap32
from ....physics.levels import hysteresis_level
from .. import constants as c
from .. import layout as L
from . import regs as R

_A2POS_HIGH = 5.4 * c.ANINP_FULL / c.ANINP_VOLTS  #: low → high above 5.4 V
_A2POS_LOW = 4.4 * c.ANINP_FULL / c.ANINP_VOLTS  #: high → low below 4.4 V


@njit(cache=True, inline="always")
def av_target(r: np.ndarray) -> float:
    """AV: ±10 V ↔ ±V_SOLL (4.1.5)."""
    return float(int(r[R.ANINP] * float(r[R.V_SOLL]) / 1023.0))


@njit(cache=True, inline="always")
def avz_target(r: np.ndarray) -> float:
    """AVZ: dead band ±64 counts (0.625 V), scale 0.0010416·V_SOLL per count (4.1.6)."""
    a = float(r[R.ANINP])
    if a > 64.0:
        w = (a - 64.0) * 0.0010416 * r[R.V_SOLL]
    elif a > -64.0:
        w = 0.0
    else:
        w = (a + 64.0) * 0.0010416 * r[R.V_SOLL]
    return float(int(w))


@njit(cache=True, inline="always")
def vat_torque_limit(r: np.ndarray) -> float:
    """VAT: torque limit ``|ANINP·T_SOLL/1024|`` (4.4.18)."""
    return abs(r[R.ANINP] * float(r[R.T_SOLL]) / 1024.0)


@plain_arguments
@njit(**KERNEL)
def a2pos_update(r: np.ndarray, s: np.ndarray, entering: bool) -> None:
    """A2POS: analogue input as a logic input with hysteresis 5.4 V / 4.4 V (4.1.10).

    Edges set the target: absolute ``P_SOLL = P2`` (low→high) / ``P1`` (high→low); with
    ERR_STAT RELPOSPSOLL ``P_SOLL += P2 / P1``; with RELPOSPFNC ``P_FNC −= 16·P2 / 16·P1``
    (the bits of 3.2.35; 4.1.10 calls them RELPSOLL/RELPFNC). On entry the level is taken
    without an edge; in absolute positioning the target is set from it.
    """
    a = float(r[R.ANINP])
    level = s[L.S_AUX3]
    if entering:
        level = 1.0 if a > _A2POS_HIGH else 0.0
        s[L.S_AUX3] = level
        if (r[R.ERR_STAT] & (c.RELPOSPSOLL | c.RELPOSPFNC)) == 0:
            r[R.P_SOLL] = r[R.P2] if level > 0.5 else r[R.P1]
        return
    new = hysteresis_level(level, a, _A2POS_HIGH, _A2POS_LOW)
    if new == level:
        return
    s[L.S_AUX3] = new
    px = r[R.P2] if new > 0.5 else r[R.P1]
    st = r[R.ERR_STAT]
    if st & c.RELPOSPFNC:
        r[R.P_FNC] = wrap32(r[R.P_FNC] - 16 * px)
    elif st & c.RELPOSPSOLL:
        r[R.P_SOLL] = wrap32(r[R.P_SOLL] + px)
    else:
        r[R.P_SOLL] = px


@njit(**KERNEL)
def apos_update(r: np.ndarray) -> None:
    """APOS: ``P_NEW = ANINP·P2/16 + P1`` with a dead band P3 (4.1.11).

    If P_NEW + P3 < P_SOLL then P_SOLL = P_NEW + P3;
    if P_NEW − P3 > P_SOLL then P_SOLL = P_NEW − P3.
    """
    p_new = int(r[R.ANINP] * r[R.P2] / 16.0) + r[R.P1]
    if p_new < r[R.P_SOLL]:
        p_new = p_new + r[R.P3]
        if p_new < r[R.P_SOLL]:
            r[R.P_SOLL] = p_new
    else:
        p_new = p_new - r[R.P3]
        if p_new > r[R.P_SOLL]:
            r[R.P_SOLL] = p_new
