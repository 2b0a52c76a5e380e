"""The MAC800's sixth-order main servo filter at 770 Hz (register overview §1.2 "Filters",
registers 121–143, 154–157; the structure is the MAC050–141's speed regulator, manual 4.2, with
every filter two orders longer)::

    FF_OUT = FF(FNC_OUT)       FF(z) = KFF5 + KFF4 z⁻¹ + … + KFF0 z⁻⁵                (Fixed24)
    VB_OUT = VB(16·V_IST)      VB(z) = KVB4 + KVB3 z⁻¹ + … + KVB0 z⁻⁴                (Fixed24)
    VF_OUT = KVOUT · VF(FF_OUT − VB_OUT) / 2^MODEL_POT
             VF(z) = (KVFX6 + KVFX5 z⁻¹ + … + KVFX1 z⁻⁵)
                     / (1 − KVFY5 z⁻¹ − KVFY4 z⁻² − … − KVFY0 z⁻⁶)                   (Fixed16)

Decisions (the overview lists only the names and formats):

- VB's input is ``16·V_IST``, the unit of FNC_OUT (1/16 count/sample): the MAC800 has no GEARB
  register, which scales VB on the MAC050–141, so KVB4 = 1 is a unity feedback.
- S_ORDER = n (0 … 6) is the order in use: VF's denominator taps of delay 1 … n, its numerator
  taps of delay 0 … n − 1 (at least delay 0), FF's and VB's taps of delay up to n.
- MODEL_POT is a power-of-two exponent ("POT") dividing VF's output, so that small gains keep
  their Fixed16 resolution.
- FNC_OUT (register 166, Fixed16) holds the profile in counts/sample, 16 fractional bits: the
  function blocks' 1/16 count/sample is 1/16 in it.
- FF_OUT and VB_OUT are rounded when stored (Int32 registers) and the next block reads the
  stored value; VF_OUT is rounded and limited to ±T_SOLL (±1023).
- Function correction (MAC050–141 manual 4.2, docs/model.md §8): in the correcting modes a VF_OUT
  beyond the torque limit is met by solving for the FNC_OUT that gives exactly the limit
  (∂VF_OUT/∂FNC_OUT = KVOUT·KVFX6·KFF5/2^MODEL_POT) and recomputing FF and VF with it; the
  correction goes to FNCERR. When still limited, VF's output history holds the limited value
  (no integrator wind-up).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ....engine.jit import KERNEL
from ....physics.correction import corrected_profile, held_output, vf_output
from ....physics.fixed import clamp, rnd
from .. import layout as L
from . import regs as R

_FX16 = 1.0 / 65536.0
_FX24 = 1.0 / 16777216.0
#: 2^−MODEL_POT for MODEL_POT = 0 … 16 (exact)
_POW2_NEG = np.array([2.0**-k for k in range(17)])
_INT32 = 2147483647.0
#: FNC_OUT is Fixed16 (register 166) in counts/sample: raw = (1/16 count/sample)·65536/16
_FNC_RAW = 4096.0


@njit(cache=True, inline="always")
def _ff(r: np.ndarray, s: np.ndarray, f: float, order: int) -> float:
    """FF_OUT of FNC_OUT ``f`` with the stored history (taps of delay up to ``order``)."""
    acc = r[R.KFF5] * _FX24 * f
    for d in range(1, 6):
        if d <= order:
            acc += r[R.KFF5 + d] * _FX24 * s[L.S_F1 + d - 1]
    return clamp(rnd(acc), -_INT32, _INT32)


@njit(**KERNEL)
def main_filter(r: np.ndarray, s: np.ndarray, f: float, correcting: bool,
                t_limit: float) -> tuple[float, float]:
    """One sample of the main filter for the profile ``f`` (FNC_OUT of the function block,
    1/16 count/sample) on the motor's register row ``r`` and state row ``s``: FF_OUT, VB_OUT
    and VF_OUT stored in ``r``, VF_OUT limited to ``±t_limit`` (0 … 1023 of peak torque), with
    the function correction when ``correcting``.

    Returns
    -------
    f_final : float
        FNC_OUT after the correction (``f`` when none was needed).
    correction : float
        ``f_final − f`` [1/16 count/sample].
    """
    order = int(r[R.S_ORDER])
    v16 = 16.0 * float(r[R.V_IST])
    vb = r[R.KVB4] * _FX24 * v16
    for d in range(1, 5):
        if d <= order:
            vb += r[R.KVB4 + d] * _FX24 * s[L.S_B1 + d - 1]
    vb = clamp(rnd(vb), -_INT32, _INT32)
    x0 = r[R.KVFX6] * _FX16
    rest = 0.0
    for d in range(1, 6):
        if d <= order - 1:
            rest += r[R.KVFX6 + d] * _FX16 * s[L.S_E1 + d - 1]
    for d in range(1, 7):
        if d <= order:
            rest += r[R.KVFY5 + d - 1] * _FX16 * s[L.S_Y1 + d - 1]
    scale = r[R.KVOUT] * _FX16 * _POW2_NEG[int(r[R.MODEL_POT])]
    ff = _ff(r, s, f, order)
    e, y, vf = vf_output(ff, vb, x0, rest, scale)
    correction = 0.0
    if abs(vf) > t_limit:
        gain = scale * x0 * r[R.KFF5] * _FX24
        if correcting and gain != 0.0:
            f_new = corrected_profile(f, vf, t_limit, gain)
            ff = _ff(r, s, f_new, order)
            e, y, vf = vf_output(ff, vb, x0, rest, scale)
            correction = f_new - f
            f = f_new
        if abs(vf) > t_limit:
            vf, y = held_output(vf, t_limit, scale)
    r[R.FNC_OUT] = int(clamp(f * _FNC_RAW, -_INT32, _INT32))
    r[R.FF_OUT] = int(ff)
    r[R.VB_OUT] = int(vb)
    r[R.VF_OUT] = int(clamp(rnd(vf), -1023.0, 1023.0))
    for d in range(4, 0, -1):
        s[L.S_F1 + d] = s[L.S_F1 + d - 1]
        s[L.S_E1 + d] = s[L.S_E1 + d - 1]
    for d in range(3, 0, -1):
        s[L.S_B1 + d] = s[L.S_B1 + d - 1]
    for d in range(5, 0, -1):
        s[L.S_Y1 + d] = s[L.S_Y1 + d - 1]
    s[L.S_F1] = f
    s[L.S_B1] = v16
    s[L.S_E1] = e
    s[L.S_Y1] = y
    return f, correction


@njit(**KERNEL)
def clear_filter(s: np.ndarray) -> None:
    """Empty the filter histories (a regulated mode entered from passive)."""
    for k in range(L.S_F1, L.S_Y6 + 1):
        s[k] = 0.0


def filter_valid(raw_kvfy: np.ndarray, order: int) -> bool:
    """Whether a main-filter setting is valid (ERR_STAT bit 16 OLD_FILT_ERR clear): VF's
    denominator ``1 − Σ KVFY·z⁻ᵈ`` (taps in use for ``order``) has no pole outside the unit
    circle (an integrator's pole at 1 is allowed; decision: the overview gives the bit's name
    only, "Filter setting not valid").

    Parameters
    ----------
    raw_kvfy : (6,) int array
        Stored KVFY5 … KVFY0 (Fixed16 raw values).
    order : int
        S_ORDER.
    """
    taps = raw_kvfy[:max(0, min(order, 6))] / 65536.0
    if taps.size == 0 or not np.any(taps):
        return True
    poles = np.roots(np.concatenate([[1.0], -taps]))
    return bool(np.all(np.abs(poles) <= 1.0 + 1e-6))
