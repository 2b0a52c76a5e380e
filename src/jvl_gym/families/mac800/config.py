"""MAC800 motor configs: the physical data of a motor type, validated when loaded.

A motor config is ``configs/motors/<TYPE>.yaml`` in this package (``family: mac800``); its
default register set is ``configs/setups/<setup>.yaml``. Every value must be a finite number of
its type inside the interval given here: physically plausible for a MAC800-class servo (about
750 W, 3000 RPM, a rectified-mains DC bus of about 325 V) and inside the region where the
simulation's integration is stable (the end stops' damping is explicit over an 87 µs
current-loop sample and diverges for a total inertia below about 2e-5 kg·m², so the rotor
inertia is at least 5e-5 kg·m²; the bus takes the motor power explicitly over a sample, so its
capacitance is at least 100 µF). A malformed file raises :class:`jvl_gym.config.ConfigError`
naming the file and the field.
"""

from __future__ import annotations

from pathlib import Path
from typing import ClassVar

from pydantic import Field

from ...config import MotorConfigs, MotorData, Real, Text, Whole, bounded_by

__all__ = ["Mac800Config", "CONFIGS", "MOTORS_DIR", "SETUPS_DIR", "canonical_motor_name",
           "load_motor", "motor_types", "setup_path"]

#: the family's configs: ``motors/`` and ``setups/``
CONFIGS = Path(__file__).resolve().parent / "configs"


class Mac800Config(MotorData):
    """Physical data of one MAC800 motor type (SI units)."""

    FAMILY_KEY: ClassVar[str] = "mac800"

    family: Text = Field(pattern="^mac800$")
    name: Text
    motor_type_code: Whole = Field(ge=0, le=2**31 - 1, description="MOTOR_TYPE (register 203)")
    rated_torque: Real = Field(gt=0, le=20.0, description="N·m, continuous (I2T's 100 %)")
    peak_torque: Real = Field(gt=0, le=60.0, description="N·m at T_SOLL = 1023 (300 %)")
    rated_speed_rpm: Real = Field(gt=0, le=6000.0)
    rotor_inertia: Real = Field(ge=5e-5, lt=0.1, description="J_m, kg·m²")
    flux_linkage: Real = Field(ge=1e-3, le=1.0, description="λ, V·s (peak, per phase)")
    phase_resistance: Real = Field(ge=1e-2, lt=100.0, description="Ω per phase")
    phase_inductance: Real = Field(ge=1e-4, lt=1.0, description="H per phase")
    amps_per_count: Real = Field(ge=1e-4, lt=1.0, description="A per ADC count")
    pole_pairs: Whole = Field(ge=1, le=16)
    supply_voltage: Real = Field(ge=100.0, le=400.0, description="V, rectified mains DC")
    pwm_delay_samples: Whole = Field(1, ge=0, le=1)
    thermal_time_constant: Real = Field(ge=0.1, le=1e5, description="s, I2T filter")
    winding_time_constant: Real = Field(ge=1.0, le=1e5, description="s, winding temperature")
    thermal_resistance: Real = Field(gt=0.0, le=100.0, description="K/W, winding → ambient")
    regen_power: Real = Field(gt=0.0, le=1e4, description="W, UIT's 100 %")
    regen_time_constant: Real = Field(ge=0.01, le=1e5, description="s, UIT filter")
    bus_capacitance: Real = Field(ge=1e-4, le=1.0, description="F")
    supply_resistance: Real = Field(ge=1e-2, le=100.0, description="Ω")
    dump_voltage: Real = Field(le=445.0, description="V, above supply_voltage, below 450 V")
    dump_resistance: Real = Field(ge=10.0, le=1e5, description="Ω")
    setup: Text

    _peak_at_least_rated = bounded_by("peak_torque", "rated_torque")
    _dump_above_supply = bounded_by("dump_voltage", "supply_voltage", strict=True, unit="V",
                                    why="the power dump would burn the supply's power")

    @property
    def rated_current(self) -> float:
        """Phase current amplitude at rated torque [A]: ``T = 1.5·p·λ·î``."""
        return self.rated_torque / (1.5 * self.pole_pairs * self.flux_linkage)


_CONFIGS = MotorConfigs(Mac800Config, CONFIGS, "MAC800 motor type")
#: the motor configs of the family's types
MOTORS_DIR = _CONFIGS.motors_dir
#: the default setups (register sets) of the family's types
SETUPS_DIR = _CONFIGS.setups_dir
#: the config of a motor type name (``"MAC800"``; one spelling each), a ``.yaml`` path or a
#: config
load_motor = _CONFIGS.load_motor
motor_types = _CONFIGS.motor_types  #: names of the MAC800 motor types (one config each)
canonical_motor_name = _CONFIGS.canonical_motor_name  #: the name as written
setup_path = _CONFIGS.setup_path  #: the file of a default setup named in a motor config
