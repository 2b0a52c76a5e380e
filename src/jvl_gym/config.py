"""Config files: the validators and loaders every motor family and the project's configs share.

A motor family keeps its *motor configs* (the physical data of each motor type, with their
provenance) and its *setups* in its own folder (``families/<key>/config.py`` and
``families/<key>/configs``) and loads them with :func:`resolve_config`,
:func:`read_config_file` and :func:`validate_config`, in the field types :data:`Real`,
:data:`Whole` and :data:`Text`. A *setup* (:class:`SetupConfig`) is a register set: register
name → value in user units, written to the motor after power-on exactly as a user would write it
(MAC050–141 manual 3, "Parameter and Data Description": the default set-up is stored in ROM; a
user set-up in flash).

Every file is validated on load; a malformed file raises :class:`ConfigError` naming the file
and the offending field, and nothing is loaded.
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
    ValidationError,
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
