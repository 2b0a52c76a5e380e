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

import math
import os
import re
from pathlib import Path
from typing import Annotated, Any

import yaml
from pydantic import (
    BaseModel,
    BeforeValidator,
    ConfigDict,
    Field,
    ValidationError,
    ValidationInfo,
    field_validator,
)

__all__ = [
    "ConfigError",
    "canonical_motor_name",
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


#: a number literal: YAML 1.1 (PyYAML) reads ``1e-3`` (no dot) as a string
_NUMBER_TEXT = re.compile(r"[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?")


def _real(value: Any) -> float:
    """A finite real number: an int or float (not a bool), or a number literal that YAML 1.1
    left a string (``1e-3``)."""
    if isinstance(value, str) and _NUMBER_TEXT.fullmatch(value.strip()):
        value = float(value)
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"must be a number, got {type(value).__name__} {value!r}")
    if not math.isfinite(value):
        raise ValueError(f"must be finite, got {value!r}")
    return float(value)


def _whole(value: Any) -> int:
    """An integer (not a bool, not a float)."""
    if isinstance(value, bool) or not isinstance(value, int):
        raise ValueError(f"must be an integer, got {type(value).__name__} {value!r}")
    return value


def _text(value: Any) -> str:
    if not isinstance(value, str):
        raise ValueError(f"must be text, got {type(value).__name__} {value!r}")
    return value


#: a finite real number (ints are converted; bools, strings, NaN and infinities are refused)
Real = Annotated[float, BeforeValidator(_real)]
#: an integer (bools and floats are refused)
Whole = Annotated[int, BeforeValidator(_whole)]
Text = Annotated[str, BeforeValidator(_text)]


class MotorConfig(BaseModel):
    """Physical data of one motor type (SI units), representative values (docs/model.md §15).

    Every physical value must be a finite number of its type (a bool, a string or an infinity
    is refused) inside the interval given here: physically plausible for an integrated servo of
    this class and inside the region where the simulation's integration is stable. The DC bus
    takes the motor power explicitly over an inner sample (``mac050_141.plant.supply``): a bus
    capacitance of a few µF lets the bus voltage diverge, so at least 100 µF is required. The
    end stops' damping (0.05 N·m·s/rad by default, ``mac050_141.plant.mechanics``) is explicit
    over an inner sample of 128 µs and diverges for a total inertia below about 3.2e-6 kg·m²,
    so the rotor inertia is at least 5e-6 kg·m².
    """

    model_config = ConfigDict(extra="forbid", frozen=True)

    name: Text
    motor_type_code: Whole = Field(ge=0, le=65535, description="MOTOR_TYPE register (3.2.153)")
    rated_torque: Real = Field(gt=0, le=100.0, description="N·m")
    peak_torque: Real = Field(gt=0, le=300.0, description="N·m at T_SOLL = 1023, >= rated")
    rated_speed_rpm: Real = Field(gt=0, le=20000.0)
    rotor_inertia: Real = Field(ge=5e-6, lt=1.0, description="J_m, kg·m²")
    flux_linkage: Real = Field(ge=1e-4, le=0.2, description="λ, V·s")
    phase_resistance: Real = Field(ge=1e-3, lt=100.0, description="Ω per phase")
    phase_inductance: Real = Field(ge=1e-6, lt=1.0, description="H per phase")
    amps_per_count: Real = Field(ge=1e-5, lt=1.0, description="A per ADC count")
    pole_pairs: Whole = Field(2, ge=1, le=16)
    supply_voltage: Real = Field(48.0, ge=12.0, le=60.0, description="V, nominal")
    pwm_delay_samples: Whole = Field(1, ge=0, le=1)
    thermal_time_constant: Real = Field(10.0, ge=0.01, le=1e5, description="s")
    regen_time_constant: Real = Field(2.0, ge=0.01, le=1e5, description="s")
    bus_capacitance: Real = Field(2.0e-3, ge=1e-4, le=10.0, description="F")
    supply_resistance: Real = Field(0.05, ge=1e-3, le=100.0, description="Ω")
    dump_voltage: Real = Field(52.0, le=100.0, description="V, above supply_voltage")
    dump_resistance: Real = Field(3.0, ge=0.1, le=1e4, description="Ω")
    setup: Text
    provenance: Text = Field(min_length=10)

    @field_validator("peak_torque")
    @classmethod
    def _peak_at_least_rated(cls, value: float, info: ValidationInfo) -> float:
        rated = info.data.get("rated_torque")
        if rated is not None and value < rated:
            raise ValueError(f"must be >= rated_torque ({rated}), got {value}")
        return value

    @field_validator("dump_voltage")
    @classmethod
    def _dump_above_supply(cls, value: float, info: ValidationInfo) -> float:
        supply = info.data.get("supply_voltage")
        if supply is not None and value <= supply:
            raise ValueError(f"must be above supply_voltage ({supply} V), got {value} V: the "
                             "power dump would burn the supply's power")
        return value

    @property
    def torque_per_vf(self) -> float:
        """Motor torque per VF_OUT unit at AMPLITUDE 0.83 [N·m] (manual 4.3, docs/model.md §3)."""
        return 1.5 * self.pole_pairs * self.flux_linkage * self.amps_per_count * 1023 * 0.83 / 1023


class SetupConfig(BaseModel):
    """A register set: register name → value in user units (Fixed formats as real numbers)."""

    model_config = ConfigDict(extra="forbid")

    motor: Text | None = None
    provenance: Text = ""
    registers: dict[str, Any]

    @field_validator("registers")
    @classmethod
    def _finite(cls, regs: dict[str, Any]) -> dict[str, float | int]:
        out: dict[str, float | int] = {}
        for key, val in regs.items():
            try:
                num = _real(val)
            except ValueError as exc:
                raise ValueError(f"register {key!r}: value {val!r} is not a finite number"
                                 ) from exc
            out[key] = val if isinstance(val, int) else num
        return out


def canonical_motor_name(name: str) -> str:
    """The config name of a motor type as users write it: ``"MAC50"`` and ``"mac050"`` are
    ``"MAC050"``, ``"MAC95"`` is ``"MAC095"``; other names are returned unchanged."""
    match = re.fullmatch(r"(?i)mac0*(\d{2,3})", name.strip())
    return f"MAC{int(match.group(1)):03d}" if match else name


def _resolve(kind: str, name_or_path: str | os.PathLike[str]) -> Path:
    path = Path(name_or_path)
    if path.suffix in (".yaml", ".yml") or path.exists():
        return path
    name = canonical_motor_name(str(name_or_path)) if kind == "motors" else str(name_or_path)
    found = configs_dir() / kind / f"{name}.yaml"
    if not found.is_file() and os.sep not in name and "/" not in name:
        known = ", ".join(sorted(p.stem for p in (configs_dir() / kind).glob("*.yaml")))
        what = "motor type" if kind == "motors" else "setup"
        raise ConfigError(f"unknown {what} {str(name_or_path)!r}; known: {known} (or give the "
                          f"path of a .yaml file; looked in {configs_dir() / kind})")
    return found


def _read_yaml(path: Path) -> dict[str, Any]:
    if not path.is_file():
        raise ConfigError(f"config file not found: {path}")
    try:
        data = yaml.safe_load(path.read_text(encoding="utf-8"))
    except (yaml.YAMLError, UnicodeDecodeError, OSError) as exc:
        reason = str(exc).replace("\n", " ")
        raise ConfigError(f"{path}: not a readable YAML file: {reason}") from exc
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
    """Load and validate a motor config by type name (``"MAC140"``, also ``"MAC50"`` for
    ``"MAC050"``: :func:`canonical_motor_name`) or path.

    Raises
    ------
    ConfigError
        Unknown type (the message lists the known ones), missing or unreadable file, or a
        field that fails validation (named with the file).
    """
    if isinstance(name_or_path, MotorConfig):
        return name_or_path
    if not isinstance(name_or_path, (str, os.PathLike)):
        raise ConfigError(f"a motor is a type name, a config path or a MotorConfig, got "
                          f"{name_or_path!r}")
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
    if not isinstance(name_or_path, (str, os.PathLike)):
        raise ConfigError(f"a setup is a name, a path or a mapping, got {name_or_path!r}")
    path = _resolve("setups", name_or_path)
    return _validate(SetupConfig, _read_yaml(path), str(path))


def motor_types() -> list[str]:
    """Names of the motor types that have a config in :func:`configs_dir`."""
    return sorted(p.stem for p in (configs_dir() / "motors").glob("*.yaml"))
