"""Whether identified values are credible: bounds, formats, intervals and fit quality.

An identification can return numbers no engineer would accept: inconsistent records (two TESTA
records of different loads) give an inertia of 0.17 kg·m² with KVOUT 10 000 (beyond the Fixed8
format, manual 3.2.13), a negative Coulomb friction, 95 % intervals that include zero and a fit
of 16 %. :func:`problems` lists what is not credible; ``jvl-tune identify`` prints the list and
exits non-zero unless told to accept it. Friction that comes out negative is "not detected"
(:func:`friction_text`): friction cannot drive the rotor.
"""

from __future__ import annotations

import math
from typing import Any

from .models import MotorData

__all__ = ["MIN_FIT", "problems", "friction_text"]

#: NRMSE fit [%] below which a model does not describe the record
MIN_FIT: float = 70.0
#: the total inertia is at least this fraction of the rotor's (allowing for model error)
_J_MIN_OF_ROTOR: float = 0.5


def _positive_interval(name: str, value: float, ci: tuple[float, float] | None) -> list[str]:
    out = []
    if not math.isfinite(value) or value <= 0:
        out.append(f"{name} = {value:.4g} is not positive")
    elif ci is not None and ci[0] <= 0:
        out.append(f"the 95 % interval of {name} ({ci[0]:.3g} … {ci[1]:.3g}) includes zero")
    return out


def problems(motor: MotorData, mech: Any = None, coil: Any = None) -> list[str]:
    """What is not credible in the estimates ``mech`` (:class:`~tuning.identify_mechanics.
    MechanicsEstimate`) and ``coil`` (:class:`~tuning.identify_coil.CoilEstimate`) of
    ``motor``: a quantity that must be positive and is not or whose 95 % interval includes
    zero, an inertia below half the rotor's or a KVOUT outside its Fixed8 range (manual
    3.2.13), a fit below :data:`MIN_FIT`. Empty when every estimate is credible.
    """
    from .family import tuned_family

    out: list[str] = []
    if coil is not None:
        for name in ("R_line", "L_line"):
            out += _positive_interval(name, getattr(coil, name), coil.ci.get(name))
        if not coil.nrmse_fit >= MIN_FIT:
            out.append(f"coil fit {coil.nrmse_fit:.1f} % < {MIN_FIT:g} %")
    if mech is not None:
        out += _positive_interval("J", mech.J, mech.ci.get("J"))
        kv = tuned_family(motor.name).table.lookup("KVOUT")
        if math.isfinite(mech.J) and mech.J < _J_MIN_OF_ROTOR * motor.J_m:
            out.append(f"J = {mech.J:.4g} kg m^2 is below half the rotor inertia "
                       f"{motor.J_m:.4g} kg m^2")
        if not kv.minimum <= mech.kvout <= kv.maximum:
            out.append(f"KVOUT = {mech.kvout:.4g} is outside its {kv.format.value} range "
                       f"{kv.minimum:g} … {kv.maximum:g} (manual {kv.section})")
        if not mech.nrmse_fit >= MIN_FIT:
            out.append(f"mechanics fit {mech.nrmse_fit:.1f} % < {MIN_FIT:g} %")
    return out


def friction_text(name: str, value: float, unit: str, detected: bool | None = None,
                  raw: float | None = None) -> str:
    """``"b 1.2e-05 N m s/rad"``, or ``"b not detected (estimate -3e-06, 95 % interval reaches
    0)"`` for an estimate that is not positive or not detected (``detected`` False: the
    detection rule of :func:`tuning.intervals.positive`; ``raw``: the estimate before it)."""
    if math.isfinite(value) and value > 0 and detected is not False:
        return f"{name} {value:.3g} {unit}"
    est = value if raw is None else raw
    return f"{name} not detected (estimate {est:.3g}, 95 % interval reaches 0)"
