"""Motor data and register-set configs: loading and validation.

A *motor config* (``configs/motors/<TYPE>.yaml``) holds the physical data of one motor type
(docs/model.md §15: representative values, each file carries its ``provenance``). A *setup*
(``configs/setups/<TYPE>.yaml``) is a register set: register name → value in user units, written
to the motor after power-on exactly as a user would write it (manual 3, "Parameter and Data
Description": the default set-up is stored in ROM; a user set-up in flash).

Both are validated on load; a malformed file raises :class:`ConfigError` naming the file and the
offending field, and nothing is loaded.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator

__all__ = [
    "ConfigError",
    "MotorConfig",
    "SetupConfig",
    "configs_dir",
    "load_motor",
    "load_setup",
    "motor_types",
]


class ConfigError(ValueError):
    """A config file is missing, unreadable or fails validation."""


def configs_dir() -> Path:
    """Directory holding ``motors/`` and ``setups/``.

    ``$JVL_GYM_CONFIGS`` if set, else the repository's ``configs/`` next to ``src/``.
    """
    env = os.environ.get("JVL_GYM_CONFIGS")
    if env:
        return Path(env)
    return Path(__file__).resolve().parents[2] / "configs"


class MotorConfig(BaseModel):
    """Physical data of one motor type (SI units), representative values (docs/model.md §15)."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    name: str
    motor_type_code: int = Field(ge=0, le=65535, description="MOTOR_TYPE register (3.2.153)")
    rated_torque: float = Field(gt=0, description="N·m")
    peak_torque: float = Field(gt=0, description="N·m at T_SOLL = 1023")
    rated_speed_rpm: float = Field(gt=0)
    rotor_inertia: float = Field(gt=0, lt=1.0, description="J_m, kg·m²")
    flux_linkage: float = Field(gt=0, lt=1.0, description="λ, V·s")
    phase_resistance: float = Field(gt=0, lt=100.0, description="Ω per phase")
    phase_inductance: float = Field(gt=0, lt=1.0, description="H per phase")
    amps_per_count: float = Field(gt=0, lt=1.0, description="A per ADC count")
    pole_pairs: int = Field(2, ge=1, le=16)
    supply_voltage: float = Field(48.0, ge=12.0, le=60.0, description="V, nominal")
    pwm_delay_samples: int = Field(1, ge=0, le=1)
    thermal_time_constant: float = Field(10.0, gt=0)
    regen_time_constant: float = Field(2.0, gt=0)
    bus_capacitance: float = Field(2.0e-3, gt=0)
    supply_resistance: float = Field(0.05, gt=0)
    dump_voltage: float = Field(52.0, gt=0)
    dump_resistance: float = Field(3.0, gt=0)
    setup: str
    provenance: str = Field(min_length=10)

    @property
    def torque_per_vf(self) -> float:
        """Motor torque per VF_OUT unit at AMPLITUDE 0.83 [N·m] (manual 4.3, docs/model.md §3)."""
        return 1.5 * self.pole_pairs * self.flux_linkage * self.amps_per_count * 1023 * 0.83 / 1023


class SetupConfig(BaseModel):
    """A register set: register name → value in user units (Fixed formats as real numbers)."""

    model_config = ConfigDict(extra="forbid")

    motor: str | None = None
    provenance: str = ""
    registers: dict[str, float]

    @field_validator("registers")
    @classmethod
    def _finite(cls, regs: dict[str, float]) -> dict[str, float]:
        for key, val in regs.items():
            bad = not isinstance(val, (int, float)) or val != val
            if bad or val in (float("inf"), -float("inf")):
                raise ValueError(f"register {key!r}: value {val!r} is not a finite number")
        return regs


def _resolve(kind: str, name_or_path: str | os.PathLike[str]) -> Path:
    path = Path(name_or_path)
    if path.suffix in (".yaml", ".yml") or path.exists():
        return path
    return configs_dir() / kind / f"{name_or_path}.yaml"


def _read_yaml(path: Path) -> dict[str, Any]:
    if not path.is_file():
        raise ConfigError(f"config file not found: {path}")
    try:
        data = yaml.safe_load(path.read_text())
    except yaml.YAMLError as exc:
        raise ConfigError(f"{path}: not valid YAML: {exc}") from exc
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: expected a mapping at top level, got {type(data).__name__}")
    return data


def _validate(model: type[BaseModel], data: dict[str, Any], origin: str) -> Any:
    try:
        return model.model_validate(data)
    except ValidationError as exc:
        lines = [f"{'.'.join(str(p) for p in e['loc'])}: {e['msg']}" for e in exc.errors()]
        raise ConfigError(f"{origin}: invalid {model.__name__}:\n  " + "\n  ".join(lines)) from exc


def load_motor(name_or_path: str | os.PathLike[str] | MotorConfig) -> MotorConfig:
    """Load and validate a motor config by type name (``"MAC140"``) or path."""
    if isinstance(name_or_path, MotorConfig):
        return name_or_path
    path = _resolve("motors", name_or_path)
    return _validate(MotorConfig, _read_yaml(path), str(path))


def load_setup(name_or_path: str | os.PathLike[str] | dict[str, Any]) -> SetupConfig:
    """Load and validate a register set by name, path, or an in-memory mapping.

    A mapping may be a full setup (with a ``registers`` key) or a bare name → value mapping.
    Register names are checked against the register table when the set is written.
    """
    if isinstance(name_or_path, dict):
        data = name_or_path if "registers" in name_or_path else {"registers": name_or_path}
        return _validate(SetupConfig, data, "setup mapping")
    path = _resolve("setups", name_or_path)
    return _validate(SetupConfig, _read_yaml(path), str(path))


def motor_types() -> list[str]:
    """Names of the motor types that have a config in :func:`configs_dir`."""
    return sorted(p.stem for p in (configs_dir() / "motors").glob("*.yaml"))
