"""A task's compiled hooks written once and specialised for the motor family an env runs on.

An env's hooks (``jvl_gym.engine.driver``: ``task_begin`` … ``task_observe``) are plain Python
functions that use a family's names without importing them: its task interface (``R``,
``reg``, ``set_reg``, ``set_analog_volts`` … ``ERROR_BITS``: the ``__all__`` of the family's
public ``task`` module), its constants as ``c`` (the public ``constants`` module), and the
figures the task derives from them (e.g. 3000 rpm in counts/sample from the family's counts per
revolution and sample rate). :class:`FamilyHooks` binds those names for a family with
:func:`jvl_gym.engine.specialize.specialise`, compiles the hooks with ``inline="always"`` and
builds the family's :class:`~jvl_gym.engine.TaskDriver` from them, on the first use of that
family; numba caches each family's specialisation under its own name
(``<hook>__<task>__<family>``).

The names below stand for the bound ones so that linters and readers see where the hooks' free
names come from; they are never called as they are.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from types import ModuleType
from typing import Any

from ..engine import TaskDriver
from ..engine.specialize import specialise
from ..families import Family, family

__all__ = ["TaskFamily", "task_family", "FamilyHooks", "c", "R", "reg", "set_reg",
           "shaft_angle", "set_analog_volts", "set_load_torque", "set_pulse_counts",
           "ERROR_BITS"]

# names bound per family by ``FamilyHooks``; defined here only for linters and readers
c: Any = None
R: Any = None
reg: Any = None
set_reg: Any = None
shaft_angle: Any = None
set_analog_volts: Any = None
set_load_torque: Any = None
set_pulse_counts: Any = None
ERROR_BITS: int = 0

_HOOK_OPTIONS = {"cache": True, "inline": "always"}
_HOOKS = ("begin", "before", "after", "end", "observe")


@dataclass(frozen=True)
class TaskFamily:
    """What a task sees of a motor family: its record and its public ``task`` and
    ``constants`` modules.

    Attributes
    ----------
    key : str
        The family's key (``"mac050_141"``, ``"mac800"``).
    family : jvl_gym.families.Family
        The family's record.
    task : module
        The family's task interface (``families/<family>/task.py``).
    constants : module
        The family's constants (``families/<family>/constants.py``).
    """

    key: str
    family: Family
    task: ModuleType
    constants: ModuleType

    def names(self) -> dict[str, Any]:
        """The names a hook may use: the task module's ``__all__`` and ``c``."""
        out = {name: getattr(self.task, name) for name in self.task.__all__}
        out["c"] = self.constants
        return out


@functools.cache
def task_family(key: str) -> TaskFamily:
    """The :class:`TaskFamily` of the registered family ``key``: the task interface and the
    constants its contract names (:class:`jvl_gym.families.Family`)."""
    fam = family(key)
    return TaskFamily(key, fam, fam.task, fam.constants)


class FamilyHooks:
    """The hooks of one task, specialised and driven per motor family on first use.

    Parameters
    ----------
    source : str
        The task module's file (its edits recompile the specialisations).
    tag : str
        The task's identifier in cache file names.
    figures : callable
        ``figures(task_family) -> dict``: the task's names derived from the family's figures
        (bound beside the family's own names).
    helpers : mapping of str to function, optional
        Further plain functions the hooks call that use family names (specialised alike).
    begin, before, after, end, observe : function, optional
        The hooks as plain Python functions (``None``: the engine's no-op hook).
    """

    def __init__(self, source: str, tag: str, figures: Callable[[TaskFamily], dict[str, Any]],
                 *, helpers: Mapping[str, Callable[..., Any]] | None = None,
                 **hooks: Callable[..., Any] | None) -> None:
        unknown = set(hooks) - set(_HOOKS)
        if unknown:
            raise TypeError(f"unknown hooks {sorted(unknown)}; known: {', '.join(_HOOKS)}")
        self.source = source
        self.tag = tag
        self.figures = figures
        self.helpers = dict(helpers or {})
        self.hooks = {name: fn for name, fn in hooks.items() if fn is not None}
        self._drivers: dict[str, TaskDriver] = {}

    def driver(self, key: str) -> TaskDriver:
        """The :class:`~jvl_gym.engine.TaskDriver` of the task over family ``key`` (built, not
        yet compiled, on the first call for that family)."""
        drv = self._drivers.get(key)
        if drv is None:
            tf = task_family(key)
            templates = {**self.helpers, **{fn.__name__: fn for fn in self.hooks.values()}}
            options = {name: _HOOK_OPTIONS for name in templates}
            fns = specialise(templates, {**tf.names(), **self.figures(tf)},
                             f"{self.tag}__{key}", self.source, options)
            bound = {name: fns[fn.__name__] for name, fn in self.hooks.items()}
            drv = self._drivers[key] = TaskDriver(tf.family, self.source, self.tag, **bound)
        return drv
