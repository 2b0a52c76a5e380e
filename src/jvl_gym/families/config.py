"""Config files: the validators and loaders every motor family and the project's configs share.

A motor family keeps its *motor configs* (the physical data of each motor type, with their
provenance) and its *setups* in its own folder (``families/<key>/config.py`` and
``families/<key>/configs``): its config model in the field types :data:`Real`, :data:`Whole`
and :data:`Text` (a field bounded by another with :func:`bounded_by`), and the loaders of
:class:`MotorConfigs` over its folder (built on :func:`resolve_config`,
:func:`read_config_file` and :func:`validate_config`).

A *setup* (:class:`SetupConfig`) is a register set: register name → value in user units,
written to the motor after power-on exactly as a user would write it
(MAC050–141 manual 3, "Parameter and Data Description": the default set-up is stored in ROM; a
user set-up in flash).

Every file is validated on load; a malformed file raises :class:`ConfigError` naming the file
and the offending field, and nothing is loaded.
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Callable
from pathlib import Path
from typing import Annotated, Any, Generic, TypeVar

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
    "Real",
    "Whole",
    "Text",
    "SetupConfig",
    "configs_dir",
    "resolve_config",
    "read_config_file",
    "validate_config",
    "load_setup",
    "MotorData",
    "bounded_by",
    "MotorConfigs",
]


class ConfigError(ValueError):
    """A config file is missing, unreadable or fails validation."""


def configs_dir() -> Path:
    """Directory of the project's configs: ``rl/`` (training), ``sweeps/``, ``fleets/``.

    ``$JVL_GYM_CONFIGS`` if set, else the repository's ``configs/`` next to ``src/``. Motor data
    and default setups belong to their motor family (``families/<key>/configs``).
    """
    env = os.environ.get("JVL_GYM_CONFIGS")
    if env:
        return Path(env)
    return Path(__file__).resolve().parents[3] / "configs"


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


def resolve_config(directory: Path | None, name_or_path: str | os.PathLike[str],
                   what: str) -> Path:
    """The file a config name or path stands for.

    Parameters
    ----------
    directory : Path or None
        Folder of the named configs (``<name>.yaml``); None: only paths are accepted.
    name_or_path : str or path-like
        A name (no ``.yaml``/``.yml`` suffix, no folder) or the path of a YAML file.
    what : str
        What a config of this kind is called in messages (``"motor type"``, ``"setup"``).

    Raises
    ------
    ConfigError
        An unknown name (the message lists the known ones and the folder looked in).
    """
    path = Path(name_or_path)
    if path.suffix in (".yaml", ".yml") or path.exists():
        return path
    name = str(name_or_path)
    if directory is None:
        raise ConfigError(f"unknown {what} {name!r}: give the path of a .yaml file")
    found = directory / f"{name}.yaml"
    if not found.is_file() and os.sep not in name and "/" not in name:
        known = ", ".join(sorted(p.stem for p in directory.glob("*.yaml")))
        raise ConfigError(f"unknown {what} {name!r}; known: {known} (or give the path of a "
                          f".yaml file; looked in {directory})")
    return found


def read_config_file(path: Path) -> dict[str, Any]:
    """The top-level mapping of a YAML config file; :class:`ConfigError` naming the file if it
    is missing, unreadable, not YAML or not a mapping."""
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


def validate_config(model: type[BaseModel], data: dict[str, Any], origin: str) -> Any:
    """``model`` validated from ``data``; :class:`ConfigError` naming ``origin`` (the file) and
    every failing field."""
    try:
        return model.model_validate(data)
    except ValidationError as exc:
        lines = [f"{'.'.join(str(p) for p in e['loc'])}: {e['msg']}" for e in exc.errors()]
        raise ConfigError(f"{origin}: invalid {model.__name__}:\n  " + "\n  ".join(lines)) from exc


def load_setup(name_or_path: str | os.PathLike[str] | dict[str, Any],
               directory: Path | None = None) -> SetupConfig:
    """Load and validate a register set by name (a file in ``directory``, a motor family's
    setups folder), path, or an in-memory mapping.

    A mapping may be a full setup (with a ``registers`` key) or a bare name → value mapping.
    Register names are checked against the register table when the set is written.
    """
    if isinstance(name_or_path, dict):
        data = name_or_path if "registers" in name_or_path else {"registers": name_or_path}
        return validate_config(SetupConfig, data, "setup mapping")
    if not isinstance(name_or_path, (str, os.PathLike)):
        raise ConfigError(f"a setup is a name, a path or a mapping, got {name_or_path!r}")
    path = resolve_config(directory, name_or_path, "setup")
    return validate_config(SetupConfig, read_config_file(path), str(path))


class MotorData(BaseModel):
    """Base of a family's motor config model: frozen, no field beyond the declared ones, and
    the provenance of the file's values (where each figure comes from)."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    provenance: Text = Field(min_length=10)


def bounded_by(field: str, other: str, *, strict: bool = False, unit: str = "",
               why: str = "") -> Any:
    """A pydantic field validator of a config model: ``field`` is at least (``strict``: above)
    the value of the field ``other`` declared before it.

    Parameters
    ----------
    field, other : str
        The checked field and its bound (validated first, so declared first).
    strict : bool
        Whether ``field`` must exceed ``other`` (else it may equal it).
    unit : str
        Unit named after both numbers in the message (``"V"``).
    why : str
        What goes wrong otherwise, appended to the message.

    Returns
    -------
    object
        The validator, to assign to a name in the model's class body.
    """
    suffix = f" {unit}" if unit else ""
    relation = "above" if strict else ">="

    def check(cls: type[BaseModel], value: float, info: ValidationInfo) -> float:
        bound = info.data.get(other)
        if bound is not None and (value <= bound if strict else value < bound):
            reason = f": {why}" if why else ""
            raise ValueError(f"must be {relation} {other} ({bound}{suffix}), got "
                             f"{value}{suffix}{reason}")
        return value

    check.__name__ = f"_{field}_{'above' if strict else 'at_least'}_{other}"
    return field_validator(field)(check)


ModelT = TypeVar("ModelT", bound=BaseModel)


class MotorConfigs(Generic[ModelT]):
    """The motor configs and default setups in a motor family's ``configs`` folder.

    A family's ``config`` module binds the names of the family contract's ``FamilyConfig``
    to one instance: ``MOTORS_DIR``, ``SETUPS_DIR``, ``load_motor``, ``motor_types``,
    ``canonical_motor_name``, ``setup_path`` (and ``load_setup``).

    Parameters
    ----------
    model : pydantic model class
        The family's motor config model.
    configs : Path
        The family's ``configs`` folder: ``motors/<TYPE>.yaml`` and, with ``setups``,
        ``setups/<name>.yaml``.
    what : str
        What a motor type of the family is called in messages (``"MAC800 motor type"``).
    setups : bool
        Whether the family has default setups (else :meth:`setup_path` refuses every name).
    canonical : callable, optional
        The type name a user's spelling stands for (default: the name as written).
    cached : bool
        Whether a file is read once and its config kept (a frozen model; for a family whose
        arrays load their types often).
    """

    def __init__(self, model: type[ModelT], configs: Path, what: str, *, setups: bool = True,
                 canonical: Callable[[str], str] | None = None, cached: bool = False) -> None:
        self.model = model
        self.what = what
        self.motors_dir = configs / "motors"
        self.setups_dir = configs / "setups" if setups else None
        self._canonical = canonical
        self.cached = cached
        self._loaded: dict[Path, ModelT] = {}

    def motor_types(self) -> list[str]:
        """Names of the motor types that have a config in the motors folder."""
        return sorted(p.stem for p in self.motors_dir.glob("*.yaml"))

    def canonical_motor_name(self, name: str) -> str:
        """The motor-type name a user's spelling ``name`` stands for."""
        return name if self._canonical is None else self._canonical(name)

    def load_motor(self, motor: str | os.PathLike[str] | ModelT) -> ModelT:
        """The validated config of a motor type name (in its user spelling:
        :meth:`canonical_motor_name`), a ``.yaml`` path, or a config (returned as it is).

        Raises
        ------
        ConfigError
            Not a name, path or config; an unknown type (the message lists the known ones); a
            missing or unreadable file; a field that fails validation (named with the file).
        """
        if isinstance(motor, self.model):
            return motor
        if not isinstance(motor, (str, os.PathLike)):
            raise ConfigError(f"a motor is a type name, a config path or a "
                              f"{self.model.__name__}, got {motor!r}")
        if isinstance(motor, str) and not motor.endswith((".yaml", ".yml")):
            motor = self.canonical_motor_name(motor)
        path = resolve_config(self.motors_dir, motor, self.what)
        if not self.cached:
            return validate_config(self.model, read_config_file(path), str(path))
        path = path.resolve()
        loaded = self._loaded.get(path)
        if loaded is None:
            loaded = self._loaded[path] = validate_config(self.model, read_config_file(path),
                                                          str(path))
        return loaded

    def setup_path(self, name: str) -> Path:
        """The file of the default setup ``name`` (a motor config's ``setup``).

        Raises
        ------
        ValueError
            The family has no default setups.
        """
        if self.setups_dir is None:
            raise ValueError(f"the {self.what}s have no default setups (asked for {name!r}); "
                             "give a setup file or mapping")
        return self.setups_dir / f"{name}.yaml"

    def load_setup(self, name_or_path: str | os.PathLike[str] | dict[str, Any]
                   ) -> SetupConfig:
        """A register set by name (a default setup), path or mapping (:func:`load_setup`)."""
        return load_setup(name_or_path, self.setups_dir)
