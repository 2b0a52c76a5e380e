"""The output stage of the speed loop: the VF filter's output, the torque limit and the
function correction, common to the servo families' main filters (MAC050–141 manual 4.2 and
docs/model.md §7–8; the MAC800's main filter, register overview §1.2 "Filters", has the same
structure with longer filters).

VF's output is ``y = x0·e + rest`` for the input ``e = FF_OUT − VB_OUT``, its leading tap
``x0`` and the sum ``rest`` of the other taps over the history; VF_OUT = ``scale·y``
(:func:`vf_output`). A VF_OUT beyond the torque limit is met, in the correcting modes, by the
FNC_OUT that gives exactly the limit: with ``gain = ∂VF_OUT/∂FNC_OUT`` (the output scale times
the leading taps of VF and FF) it is ``FNC_OUT + (±limit − VF_OUT)/gain``, rounded
(:func:`corrected_profile`). An output that is still beyond the limit is limited, and the
filter's output history holds the limited value divided by the output scale, so that no
integrator winds up (:func:`held_output`).
"""

from __future__ import annotations

from numba import njit

from ..engine.jit import KERNEL
from .fixed import clamp, rnd


@njit(**KERNEL)
def vf_output(ff: float, vb: float, x0: float, rest: float, scale: float
              ) -> tuple[float, float, float]:
    """``(e, y, VF_OUT)`` for FF_OUT ``ff`` and VB_OUT ``vb`` (module docstring)."""
    e = ff - vb
    y = x0 * e + rest
    return e, y, scale * y


@njit(**KERNEL)
def corrected_profile(f: float, vf: float, t_limit: float, gain: float) -> float:
    """FNC_OUT that brings the output ``vf`` (beyond ``±t_limit``) to the limit, given the
    output's ``gain`` per FNC_OUT unit (non-zero); in FNC_OUT's unit, rounded."""
    target = t_limit if vf > 0.0 else -t_limit
    return rnd(f + (target - vf) / gain)


@njit(**KERNEL)
def held_output(vf: float, t_limit: float, scale: float) -> tuple[float, float]:
    """The output limited to ``±t_limit`` and the value the filter's output history holds
    (the limited output over the output ``scale``; 0 when the scale is 0)."""
    vf = clamp(vf, -t_limit, t_limit)
    return vf, (vf / scale if scale != 0.0 else 0.0)
