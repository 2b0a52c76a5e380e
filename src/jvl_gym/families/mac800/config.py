"""MAC800 motor configs: the physical data of a motor type, validated when loaded.

A motor config is ``configs/motors/<TYPE>.yaml`` in this package (``family: mac800``); its
default register set is ``configs/setups/<setup>.yaml``. Every value must be a finite number of
its type inside the interval of ``configs/limits.yaml`` (:mod:`..servo_config`; the file says
why each bound is where it is) or given here. A malformed file raises
:class:`jvl_gym.families.config.ConfigError` naming the file and the field.
"""

from __future__ import annotations

from pathlib import Path
from typing import ClassVar

from pydantic import Field

from ..config import MotorConfigs, Real, Text
from ..servo_config import bounded_servo_data

__all__ = ["Mac800Config", "CONFIGS", "MOTORS_DIR", "SETUPS_DIR", "canonical_motor_name",
           "load_motor", "motor_types", "setup_path"]

#: the family's configs: ``motors/`` and ``setups/``
CONFIGS = Path(__file__).resolve().parent / "configs"


class Mac800Config(bounded_servo_data(CONFIGS / "limits.yaml", "Mac800Config")):
    """Physical data of one MAC800 motor type (SI units): the servo motor data in the bounds of
    ``configs/limits.yaml``, the family key, and the winding temperature and regeneration
    models' data."""

    FAMILY_KEY: ClassVar[str] = "mac800"

    family: Text = Field(pattern="^mac800$")
    winding_time_constant: Real = Field(ge=1.0, le=1e5, description="s, winding temperature")
    thermal_resistance: Real = Field(gt=0.0, le=100.0, description="K/W, winding → ambient")
    regen_power: Real = Field(gt=0.0, le=1e4, description="W, UIT's 100 %")

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
