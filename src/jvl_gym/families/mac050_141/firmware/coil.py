"""COIL_MODE traverse profile (manual 4.4.20, figures 4.4.20.A and B).

The traverse follows the spindle like the gear mode (gear factor GEARF1/GEARF2, pulse input
V_EXT plus V8), but the sign of the gearing flips at the thread positions P1 and P4: a virtual
position bounces between 16·P1 and 16·P4 (figure A) and the commanded position is that virtual
position limited to [16·P2, 16·P3], which makes the traverse dwell at the stop positions while a
turn is laid on the previous one (figure B). With the analogue input high (> 5 V) the block
positions to the start position P5 and, when the input goes low, resumes winding from there in
the direction P6. The rules P1 ≤ P2 ≤ P3 ≤ P4, P1 ≤ P5 ≤ P4, P6 = ±1 are enforced when
COIL_MODE is entered and when P1..P6 are written in it. The commanded position is followed with
the gear position block's exact braking profile (V_SOLL, A_SOLL), so turns bunch at the
reversals at high spindle speed, as they do on the real machine.

State: S_AUX0 virtual position [1/16 count], S_AUX1 direction (±1), S_AUX2 start-position flag.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ....engine.jit import KERNEL
from ....physics.fixed import clamp
from ....physics.profile import max_landing_speed
from .. import layout as L
from . import regs as R
from .blocks import _finish
from .gear_blocks import gear_factor

ANALOG_HIGH = 512  #: ANINP above 5 V counts as "high" (start-position command)


@njit(**KERNEL)
def coil_entry(r: np.ndarray, s: np.ndarray) -> None:
    """Start winding from the present function position in the direction P6."""
    s[L.S_AUX0] = float(r[R.P_FNC])
    s[L.S_AUX1] = 1.0 if r[R.P6] >= 0 else -1.0
    s[L.S_AUX2] = 0.0


@njit(**KERNEL)
def coil_block(r: np.ndarray, s: np.ndarray) -> float:
    """One sample of the COIL profile; returns FNC_OUT [1/16 count/sample]."""
    a = float(r[R.A_SOLL])
    vmax = abs(float(r[R.V_SOLL]))
    if r[R.ANINP] > ANALOG_HIGH:
        s[L.S_AUX2] = 1.0
        target = 16.0 * r[R.P5]
        s[L.S_AUX0] = target
        s[L.S_AUX1] = 1.0 if r[R.P6] >= 0 else -1.0
    else:
        s[L.S_AUX2] = 0.0
        lo = 16.0 * r[R.P1]
        hi = 16.0 * r[R.P4]
        x = s[L.S_AUX0] + (r[R.V_EXT] + r[R.V8]) * gear_factor(r) * s[L.S_AUX1]
        for _ in range(8):
            if x > hi and hi > lo:
                x = 2.0 * hi - x
                s[L.S_AUX1] = -s[L.S_AUX1]
            elif x < lo and hi > lo:
                x = 2.0 * lo - x
                s[L.S_AUX1] = -s[L.S_AUX1]
            else:
                break
        s[L.S_AUX0] = clamp(x, lo, hi)
        target = clamp(x, 16.0 * r[R.P2], 16.0 * r[R.P3])
    dp = target - r[R.P_FNC]
    sg = 1.0 if dp > 0.0 else (-1.0 if dp < 0.0 else 0.0)
    desired = sg * min(max_landing_speed(abs(dp), a), vmax)
    v_old = s[L.S_V_OLD]
    f = _finish(r, s, v_old + clamp(desired - v_old, -a, a))
    s[L.S_G_FNC] = r[R.P_FNC] - target
    return f
