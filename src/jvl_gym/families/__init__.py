"""Motor families: each one folder of its own, registered here by key.

A family is its register table, constants and units, firmware, plant, configs and default
setups, the compiled step the engine drives and its motor-array class (docs/architecture.md,
"Adding a motor family"). The generic layers reach a family only through its :class:`Family`
record. ``mis`` (the MIS/SMC step motors) and ``mac800`` (MAC800 and MAC400) are registered
beside ``mac050_141``.
"""

from __future__ import annotations

import functools
import importlib
import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import Any

import yaml

__all__ = ["Family", "DEFAULT_FAMILY", "register_family", "family", "families",
           "family_of_motor"]

#: the family of a motor type no registered family names
DEFAULT_FAMILY = "mac050_141"


@dataclass(frozen=True)
class Family:
    """What the engine knows of a motor family.

    Attributes
    ----------
    key : str
        Identifier (``"mac050_141"``), also used in compiled-cache file names.
    title : str
        Human name (``"MAC050–141 integrated servo motors"``).
    compiled : module
        The compiled step: ``outer_sample``, ``inner_block``, ``LANES``, ``prepare``,
        ``scratch`` (see :mod:`jvl_gym.engine.driver`).
    array_class : type
        The family's :class:`~jvl_gym.MotorArray` subclass.
    motor_types : callable
        Names of the family's motor types (each with a motor config).
    canonical_name : callable
        The motor-type name a user's spelling stands for (default: unchanged).
    """

    key: str
    title: str
    compiled: ModuleType
    array_class: type
    motor_types: Callable[[], list[str]]
    canonical_name: Callable[[str], str] = str


_MODULES: dict[str, str] = {"mac050_141": "jvl_gym.families.mac050_141",
                            "mis": "jvl_gym.families.mis",
                            "mac800": "jvl_gym.families.mac800"}


def register_family(key: str, module: str) -> None:
    """Register the family ``key`` whose package ``module`` defines ``FAMILY``."""
    if not key.isidentifier():
        raise ValueError(f"family key must be an identifier, got {key!r}")
    _MODULES[key] = module
    family.cache_clear()


@functools.cache
def family(key: str) -> Family:
    """The registered family ``key`` (imported on first use)."""
    if key not in _MODULES:
        raise KeyError(f"unknown motor family {key!r}; known: {', '.join(sorted(_MODULES))}")
    fam: Any = importlib.import_module(_MODULES[key]).FAMILY
    return fam


def families() -> tuple[str, ...]:
    """Keys of the registered families."""
    return tuple(_MODULES)


def family_of_motor(motor: Any) -> Family:
    """The family of ``motor``: a motor config object (its class's ``FAMILY_KEY``), a config
    file (its top-level ``family`` key) or a motor type name one registered family lists;
    anything else belongs to :data:`DEFAULT_FAMILY`, whose loader says what is wrong."""
    key = getattr(type(motor), "FAMILY_KEY", None)
    if key is None and isinstance(motor, (str, os.PathLike)):
        path = Path(motor)
        if path.suffix in (".yaml", ".yml"):
            key = _family_in_file(path)
        else:
            key = next((k for k in _MODULES if family(k).canonical_name(str(motor))
                        in family(k).motor_types()), None)
            if key is None and not path.exists():
                raise _unknown_motor(motor)
    elif key is None and not hasattr(motor, "name"):  # not a config object either
        raise _unknown_motor(motor)
    return family(key if isinstance(key, str) and key in _MODULES else DEFAULT_FAMILY)


def _unknown_motor(motor: Any) -> Exception:
    """The error for ``motor`` that names no motor: it lists every family's motor types."""
    from ..config import ConfigError

    known = "; ".join(f"{family(k).title}: {', '.join(family(k).motor_types())}"
                      for k in _MODULES)
    what = (f"unknown motor type {str(motor)!r}" if isinstance(motor, (str, os.PathLike))
            else f"a motor is a type name, a config path or a config object, got {motor!r}")
    return ConfigError(f"{what}; known types: {known} (or give the path of a .yaml file)")


def _family_in_file(path: Path) -> str | None:
    """The ``family`` key of a motor config file, if it is readable and has one."""
    try:
        data = yaml.safe_load(path.read_text())
    except (OSError, yaml.YAMLError):
        return None
    return data.get("family") if isinstance(data, dict) else None
