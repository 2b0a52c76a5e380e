"""What the servo strategies share: the position-mode acceptance move, the model's current and
speed loops for the report's plots, and the velocity-mode speed step on the simulator."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from jvl_gym.families import Family

from ..models import (
    MotorData,
    current_open_loop,
    speed_closed_loop,
    speed_open_loop,
    speed_plant,
)
from ..pipeline import Candidate, Move, position_trial
from ..verify import velocity_step

__all__ = ["ServoLoops", "SPEED_STEP", "motor_data"]

SPEED_STEP: int = 800  #: V_SOLL of the simulated speed step [1/16 count/sample]


def motor_data(motor: str, settings: Mapping[str, Any]) -> MotorData:
    """The motor type's data, R and L from ``resistance``, ``inductance`` of ``settings``
    where given [Ω, H]."""
    md = MotorData.from_config(motor)
    if settings.get("resistance"):
        md = md.with_(R_phase=settings["resistance"])
    if settings.get("inductance"):
        md = md.with_(L_phase=settings["inductance"])
    return md


class ServoLoops:
    """Mixin of a strategy for a servo family with the current loop (IF, IB) and the speed
    filter (FF, VB, VF, KVOUT) of :mod:`tuning.models`."""

    family: Family

    def trial(self, m: Any, move: Move) -> tuple[np.ndarray, np.ndarray]:
        """The move as a position-mode move (:func:`tuning.pipeline.position_trial`)."""
        return position_trial(m, move)

    def open_loops(self, candidate: Candidate, motor: MotorData, J: float
                   ) -> list[tuple[str, Any]]:
        """The current loop and the speed loop (with the closed current loop) broken at their
        outputs (:func:`tuning.models.current_open_loop`,
        :func:`tuning.models.speed_open_loop`)."""
        regs = candidate.registers
        return [("current loop", current_open_loop(motor, regs)),
                ("speed loop", speed_open_loop(speed_plant(motor, regs, J), regs,
                                               motor.family))]

    def step_loop(self, candidate: Candidate, motor: MotorData, J: float) -> Any:
        """FNC_OUT → the speed in FNC_OUT's unit (:func:`tuning.models.speed_closed_loop`)."""
        regs = candidate.registers
        return speed_closed_loop(speed_plant(motor, regs, J), regs, motor.family)

    def speed_step(self, m: Any) -> tuple[np.ndarray, float]:
        """A velocity-mode step to V_SOLL = :data:`SPEED_STEP` (:func:`tuning.verify.
        velocity_step`): V_IST in V_SOLL's unit, shape (n, N), and the step."""
        spec = self.family.tuning
        assert spec is not None
        return velocity_step(m, SPEED_STEP) * spec.speed_units, float(SPEED_STEP)

    def truth(self, m: Any, load_inertia: float, viscous: float, coulomb: float
              ) -> dict[str, float]:
        """The simulated motor's true values by the keys of the report's rows: J, KVOUT, the
        friction, the coil (line-to-line and per phase)."""
        cfg = m.motor_configs[0]
        return {"J": cfg.rotor_inertia + load_inertia,
                "kvout": 1 + load_inertia / cfg.rotor_inertia,
                "viscous": viscous, "coulomb": coulomb,
                "R_line": 2 * cfg.phase_resistance, "L_line_mH": 2e3 * cfg.phase_inductance,
                "R_phase": cfg.phase_resistance, "L_phase_mH": 1e3 * cfg.phase_inductance}
