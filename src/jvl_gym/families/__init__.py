"""Motor families: each one folder of its own, registered here by key.

A family is its register table, constants and units, firmware, plant, configs and default
setups, the compiled step the engine drives and its motor-array class (docs/architecture.md,
"Adding a motor family"). The generic layers reach a family only through its :class:`Family`
record, the contract of :mod:`.contract`. ``mis`` (the MIS/SMC step motors) and ``mac800``
(MAC800 and MAC400) are registered beside ``mac050_141``.
"""

from __future__ import annotations

import functools
import importlib
import os
from pathlib import Path
from typing import Any

import yaml

from .contract import (
    CanopenSpec,
    Capability,
    Family,
    FamilyConfig,
    TuningSpec,
    TwinSpec,
    UnsupportedOperation,
)

__all__ = ["Family", "Capability", "FamilyConfig", "TwinSpec", "TuningSpec", "CanopenSpec",
           "UnsupportedOperation", "register_family", "family", "families", "family_of_motor",
           "families_with", "unknown_motor_type"]

# --- registration data ---------------------------------------------------------------------
#: family key → the package that defines its ``FAMILY``
_MODULES: dict[str, str] = {"mac050_141": "jvl_gym.families.mac050_141",
                            "mis": "jvl_gym.families.mis",
                            "mac800": "jvl_gym.families.mac800"}
#: the family that reads a motor config file naming no ``family`` (its config files predate
#: the key), and whose loader reports a file no family can read
_UNTAGGED_CONFIGS = "mac050_141"


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


def families_with(capability: Capability) -> tuple[Family, ...]:
    """The registered families that declare ``capability``, in registration order."""
    return tuple(family(k) for k in _MODULES if family(k).supports(capability))


def family_of_motor(motor: Any) -> Family:
    """The family of ``motor``: a motor config object (its class's ``FAMILY_KEY``), a config
    file (its top-level ``family`` key; a file naming none, or that cannot be read, goes to the
    loader of the family whose files carry no key, which says what is wrong) or a motor type
    name (in a user's spelling) that one registered family lists.

    Raises
    ------
    ConfigError
        A motor type name no registered family lists (the message lists every family's types),
        or something that is no name, path or config.
    """

    key = getattr(type(motor), "FAMILY_KEY", None)
    if isinstance(key, str) and key in _MODULES:
        return family(key)
    if not isinstance(motor, (str, os.PathLike)):
        raise unknown_motor_type(motor)
    path = Path(motor)
    if path.suffix in (".yaml", ".yml") or path.exists():
        key = _family_in_file(path)
        return family(key if isinstance(key, str) and key in _MODULES else _UNTAGGED_CONFIGS)
    name = str(motor)
    for k in _MODULES:
        fam = family(k)
        if fam.canonical_name(name) in fam.motor_types():
            return fam
    raise unknown_motor_type(name)


def unknown_motor_type(name: Any) -> ValueError:
    """The error for ``name``, a motor type no registered family lists or no motor at all: a
    ConfigError that lists every family's types."""
    from .config import ConfigError

    known = "; ".join(f"{', '.join(family(k).motor_types())} ({family(k).title})"
                      for k in _MODULES)
    what = (f"unknown motor type {name!r}" if isinstance(name, str) else
            f"a motor is a type name, a config path or a motor config, got {name!r}")
    return ConfigError(f"{what}; known: {known} (or give the path of a .yaml motor config)")


def _family_in_file(path: Path) -> str | None:
    """The ``family`` key of a motor config file, if it is readable and has one."""
    try:
        data = yaml.safe_load(path.read_text())
    except (OSError, yaml.YAMLError):
        return None
    return data.get("family") if isinstance(data, dict) else None
