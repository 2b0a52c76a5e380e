"""Motor families: each one folder of its own, registered here by key.

A family is its register table, constants and units, firmware, plant, configs and default
setups, and the compiled step the engine drives (docs/architecture.md, "Adding a motor
family"). The generic layers reach a family only through its :class:`Family` record.
"""

from __future__ import annotations

import functools
import importlib
from dataclasses import dataclass
from types import ModuleType
from typing import Any

__all__ = ["Family", "register_family", "family", "families"]


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
    """

    key: str
    title: str
    compiled: ModuleType


_MODULES: dict[str, str] = {"mac050_141": "jvl_gym.families.mac050_141"}


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
