"""The toolkit's speed-loop design as the baseline of the FilterTuning-v0 env: give
:func:`speed_loop_registers` to the env as its ``designer`` (``jvl_gym`` does not import the
toolkit)."""

from __future__ import annotations

import functools

from .family import setup_registers, tuned_family
from .models import MotorData
from .synthesis import design_speed_loop

__all__ = ["speed_loop_registers", "STRATEGY"]

STRATEGY = "testu_pi"  #: the strategy whose speed filter :func:`design_speed_loop` designs

_CURRENT_KEYS = ("KIFX2", "KIFX1", "KIFY1", "KIFY0", "KIB1", "KIB0")


@functools.lru_cache(maxsize=8)
def speed_loop_registers(motor_type: str) -> dict[str, float] | None:
    """Speed-loop registers of the toolkit's synthesis (:func:`tuning.synthesis.
    design_speed_loop`, on the current loop of the type's default setup) at KVOUT = 1 for a
    motor type (the design is load-invariant with KVOUT = J_total/J_m); None for a family
    whose tuning strategy is not :data:`STRATEGY` (another speed filter) or that has none."""
    try:
        fam = tuned_family(motor_type)
    except ValueError:
        return None
    if fam.tuning is None or fam.tuning.strategy != STRATEGY:
        return None
    cfg = fam.load_motor(motor_type)
    setup = setup_registers(fam, cfg)
    current = {k: float(setup[k]) for k in _CURRENT_KEYS}
    design = design_speed_loop(MotorData.from_config(cfg), current, cfg.rotor_inertia)
    return {k: float(v) for k, v in design.registers.items() if k != "KVOUT"}
