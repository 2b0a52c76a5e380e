"""Motor configs of the MIS/SMC types (``configs/motors/<TYPE>.yaml`` beside this module).

Each file holds one type's representative motor data with its ``provenance`` (the MIS manual
§5.1 gives holding torques and currents; the electrical and inertia figures are representative
values of the frame size, see each file). A file is validated on load: every value a finite
number of its type inside the range given here (physically plausible and where the plant's
integration is stable), no unknown field; an error names the file and the field.

Stability (``plant`` docstring): the rotor's magnetic stiffness ``50·Kt·I`` (= 50 × the holding
torque) with the rotor inertia gives the natural frequency ``ω_n``; the semi-implicit Euler step
of 100 µs is stable for ``ω_n·h < 2`` and accurate well below; the configs must keep
``ω_n·h ≤ 0.5`` (a load inertia only lowers it).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import ClassVar

from pydantic import Field, model_validator

from ..config import MotorConfigs, MotorData, Real, Text, Whole
from . import constants as c
from .units import CURRENT_AMPS_PER_UNIT, ENCODER_TYPES, MOTOR_TYPE_CODES

__all__ = ["MisMotorConfig", "CONFIGS_DIR", "MOTORS_DIR", "SETUPS_DIR", "canonical_motor_name",
           "motor_types", "load_motor", "setup_path"]

#: largest ``ω_n·h`` a config may give (module docstring)
MAX_STIFFNESS_STEP = 0.5


class MisMotorConfig(MotorData):
    """Motor data of one MIS/SMC type (SI units unless stated)."""

    FAMILY_KEY: ClassVar[str] = "mis"

    family: Text = "mis"
    name: Text
    run_current_max: Whole = Field(ge=1, le=1533, description="RUN_CURRENT units (§8.2.7)")
    standby_current_max: Whole | None = Field(
        None, ge=1, le=1533, description="RUN_CURRENT units; None: run_current_max (§5.1)")
    holding_torque: Real = Field(gt=0.01, le=50.0, description="N·m at run_current_max")
    rotor_inertia: Real = Field(ge=1e-6, le=0.05, description="kg·m²")
    phase_resistance: Real = Field(ge=0.01, le=50.0, description="Ω")
    phase_inductance: Real = Field(ge=1e-5, le=0.5, description="H")
    detent_torque: Real = Field(ge=0.0, le=5.0, description="N·m")
    viscous_friction: Real = Field(ge=0.0, le=1.0, description="N·m·s/rad")
    coulomb_friction: Real = Field(ge=0.0, le=10.0, description="N·m")
    damping_ratio: Real = Field(ge=0.0, le=1.0, description="rotor against the field (plant)")
    supply_voltage: Real = Field(ge=12.0, le=80.0, description="V")
    encoder_type: Whole = Field(ge=0, le=4, description="ENCODER_TYPE code (§8.2.49)")

    @model_validator(mode="after")
    def _consistent(self) -> MisMotorConfig:
        if self.family != "mis":
            raise ValueError(f"family must be 'mis', got {self.family!r}")
        if self.encoder_type not in ENCODER_TYPES:
            raise ValueError(f"encoder_type must be one of {sorted(ENCODER_TYPES)}")
        if self.standby_current_max is not None and \
                self.standby_current_max > self.run_current_max:
            raise ValueError("standby_current_max must be at most run_current_max")
        if self.detent_torque > 0.2 * self.holding_torque:
            raise ValueError("detent_torque must be at most 20 % of holding_torque")
        if self.coulomb_friction > 0.5 * self.holding_torque:
            raise ValueError("coulomb_friction must be at most half the holding_torque")
        step = math.sqrt(c.POLE_PAIRS * self.holding_torque / self.rotor_inertia) * c.INNER_DT
        if step > MAX_STIFFNESS_STEP:
            raise ValueError(f"rotor_inertia too small for holding_torque: ω_n·h = {step:.2f} "
                             f"> {MAX_STIFFNESS_STEP} (unstable plant step)")
        return self

    @property
    def rated_current(self) -> float:
        """Largest phase current [A RMS]."""
        return self.run_current_max * CURRENT_AMPS_PER_UNIT

    @property
    def standby_current_limit(self) -> int:
        """Largest effective STANDBY_CURRENT [RUN_CURRENT units]: ``standby_current_max``, or
        the largest running current where the type's table gives both the same range."""
        return self.run_current_max if self.standby_current_max is None else \
            self.standby_current_max

    @property
    def torque_constant(self) -> float:
        """Torque per ampere of current amplitude [N·m/A] (= back-EMF constant [V·s/rad]):
        the holding torque at the rated RMS current, whose amplitude is √2 times it."""
        return self.holding_torque / (math.sqrt(2.0) * self.rated_current)

    @property
    def motor_type_code(self) -> int:
        """MOTORTYPE register value (§8.2.89); unknown names read as MIS232's."""
        return MOTOR_TYPE_CODES.get(self.name, MOTOR_TYPE_CODES["MIS232"])


CONFIGS_DIR = Path(__file__).resolve().with_name("configs")
_CONFIGS = MotorConfigs(MisMotorConfig, CONFIGS_DIR, "MIS/SMC motor type", setups=False,
                        cached=True)
#: the motor configs of the family's types
MOTORS_DIR = _CONFIGS.motors_dir
#: the family's default setups: none (a motor powers on with the table's defaults, §8.2)
SETUPS_DIR: Path | None = _CONFIGS.setups_dir
#: the config of a type name, a YAML path or a config object
load_motor = _CONFIGS.load_motor
motor_types = _CONFIGS.motor_types  #: names of the MIS/SMC types with a config
canonical_motor_name = _CONFIGS.canonical_motor_name  #: the name as written
#: the file of a default setup: the MIS/SMC types have none (ValueError)
setup_path = _CONFIGS.setup_path
