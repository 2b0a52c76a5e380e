"""Speed regulator at 520.8 Hz: FF, VB, VF filters, KVOUT, torque limit and function correction.

Manual 4.2 and the filter registers 3.2.89–3.2.105::

    FF_OUT = FF(FNC_OUT)            FF(z) = KFF3 + KFF2 z⁻¹ + KFF1 z⁻² + KFF0 z⁻³      (Fixed8)
    VB_OUT = GEARB · VB(V_IST)      VB(z) = KVB3 + KVB2 z⁻¹ + KVB1 z⁻² + KVB0 z⁻³      (Fixed8)
    VF_OUT = KVOUT · VF(FF_OUT − VB_OUT)
             VF(z) = (KVFX4 + KVFX3 z⁻¹ + KVFX2 z⁻² + KVFX1 z⁻³)
                     / (1 − KVFY3 z⁻¹ − KVFY2 z⁻² − KVFY1 z⁻³ − KVFY0 z⁻⁴)             (Fixed4)

FF_OUT, VB_OUT, VF_OUT are Integer registers: each is rounded and saturated when stored and the
next block reads the stored value. |VF_OUT| > T_SOLL is limited; in the correcting modes the
function correction of docs/model.md §8 solves for the FNC_OUT that gives exactly ±T_SOLL
(∂VF_OUT/∂FNC_OUT = KVOUT·KVFX4·KFF3), recomputes FF and VF with it so no filter winds up, and
reports the correction. When limited, the VF output history holds VF_OUT/KVOUT (decision,
docs/model.md §7), so the integrator does not wind up in the non-correcting modes either.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ....engine.jit import KERNEL
from ....physics.correction import corrected_profile, held_output, vf_output
from ....physics.fixed import clamp, fx4, fx8, rnd, sat16
from .. import layout as L
from . import regs as R


@njit(cache=True, inline="always")
def _ff(r: np.ndarray, s: np.ndarray, f: float) -> float:
    return sat16(fx8(r[R.KFF3]) * f + fx8(r[R.KFF2]) * s[L.S_F1] + fx8(r[R.KFF1]) * s[L.S_F2]
                 + fx8(r[R.KFF0]) * s[L.S_F3])


@njit(**KERNEL)
def speed_regulator(r: np.ndarray, s: np.ndarray, f: float, correcting: bool,
                    t_limit: float) -> tuple[float, float]:
    """Run one sample of the speed regulator.

    Parameters
    ----------
    r, s : ndarray
        The motor's register row and state row.
    f : float
        FNC_OUT from the function block [1/16 count/sample].
    correcting : bool
        Function correction active (docs/model.md §8).
    t_limit : float
        Torque limit (T_SOLL, or the mode's own limit) [0..1023].

    Returns
    -------
    f_final : float
        FNC_OUT after correction (equal to ``f`` when none was needed).
    correction : float
        ``f_final − f`` [1/16 count/sample], accumulated into FNCERR by the caller.
    """
    v = float(r[R.V_IST])
    vb = sat16(fx8(r[R.GEARB]) * (fx8(r[R.KVB3]) * v + fx8(r[R.KVB2]) * s[L.S_V1]
                                  + fx8(r[R.KVB1]) * s[L.S_V2] + fx8(r[R.KVB0]) * s[L.S_V3]))
    x4 = fx4(r[R.KVFX4])
    rest = (fx4(r[R.KVFX3]) * s[L.S_E1] + fx4(r[R.KVFX2]) * s[L.S_E2]
            + fx4(r[R.KVFX1]) * s[L.S_E3] + fx4(r[R.KVFY3]) * s[L.S_Y1]
            + fx4(r[R.KVFY2]) * s[L.S_Y2] + fx4(r[R.KVFY1]) * s[L.S_Y3]
            + fx4(r[R.KVFY0]) * s[L.S_Y4])
    kvout = fx8(r[R.KVOUT])
    ff = _ff(r, s, f)
    e, y, vf = vf_output(ff, vb, x4, rest, kvout)
    correction = 0.0
    if abs(vf) > t_limit:
        gain = kvout * x4 * fx8(r[R.KFF3])
        if correcting and gain != 0.0:
            f_new = corrected_profile(f, vf, t_limit, gain)
            ff = _ff(r, s, f_new)
            e, y, vf = vf_output(ff, vb, x4, rest, kvout)
            correction = f_new - f
            f = f_new
        if abs(vf) > t_limit:
            vf, y = held_output(vf, t_limit, kvout)
    vf_out = clamp(rnd(vf), -1023.0, 1023.0)
    r[R.FNC_OUT] = int(clamp(f, -32767.0, 32767.0))
    r[R.FF_OUT] = int(ff)
    r[R.VB_OUT] = int(vb)
    r[R.VF_OUT] = int(vf_out)
    s[L.S_F3] = s[L.S_F2]
    s[L.S_F2] = s[L.S_F1]
    s[L.S_F1] = f
    s[L.S_V3] = s[L.S_V2]
    s[L.S_V2] = s[L.S_V1]
    s[L.S_V1] = v
    s[L.S_E3] = s[L.S_E2]
    s[L.S_E2] = s[L.S_E1]
    s[L.S_E1] = e
    s[L.S_Y4] = s[L.S_Y3]
    s[L.S_Y3] = s[L.S_Y2]
    s[L.S_Y2] = s[L.S_Y1]
    s[L.S_Y1] = y
    return f, correction
