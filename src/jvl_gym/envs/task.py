"""The one way to write a task: a :class:`Task` declared on the family contract.

A task is an env class (a :class:`~jvl_gym.envs.base.MotorVectorEnv` subclass: its labels,
ranges, reset and termination reasons) and its :class:`Task`, which declares

- ``needs``: the :class:`~jvl_gym.families.Capability` members a family must support for the
  task to run on it; the env runs on every registered family that declares them all and refuses
  the others with the contract's :class:`~jvl_gym.families.UnsupportedOperation` message;
- ``state``: the class of the task's state, a ``typing.NamedTuple`` whose fields are numpy
  arrays: per-env constants and per-copy scalars as structured arrays of named fields
  (:func:`record`), per-copy profiles or vectors as plain (N, …) arrays. The env allocates one
  instance; the compiled step and the Python side read and write the same arrays by name;
- the compiled hooks (``begin``, ``before``, ``after``, ``end``, ``observe``, see
  :mod:`jvl_gym.engine.driver`) as plain Python functions over ``(i, view, episode, state, …)``
  that use a family's names without importing them: its task interface (the ``__all__`` of its
  ``task`` module: ``R``, ``reg``, ``set_reg``, ``set_analog_volts`` … ``ERROR_BITS``), its
  constants as ``c``, and the task's ``figures`` of that family (e.g. 3000 rpm in counts per
  sample). On the first env of a family the hooks are bound to that family's names with
  :func:`jvl_gym.engine.specialize.specialise`, compiled with ``inline="always"`` and inlined
  into the family's :class:`~jvl_gym.engine.TaskDriver`; numba caches each specialisation under
  its own name (``<hook>__<task>__<family>``).

A task whose step is not dominated by the motor kernel (FilterTuning: a whole commissioning
trial per step) declares no hooks and writes its step in numpy
(:class:`~jvl_gym.envs.numpy_step.NumpyTaskEnv`).

The names below stand for the bound ones so that linters and readers see where the hooks' free
names come from; they are never called as they are.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping
from typing import Any

import numpy as np

from ..engine import TaskDriver
from ..engine.jit import KERNEL
from ..engine.specialize import specialise
from ..families import Capability, Family, UnsupportedOperation, families, family

__all__ = ["Task", "record", "clear_records", "c", "R", "reg", "set_reg", "shaft_angle",
           "set_analog_volts", "set_load_torque", "set_pulse_counts", "coil_direction",
           "rotor_speed", "copper_energy", "lost_steps", "ERROR_BITS"]

# names bound per family by ``Task``; defined here only for linters and readers
c: Any = None
R: Any = None
reg: Any = None
set_reg: Any = None
shaft_angle: Any = None
set_analog_volts: Any = None
set_load_torque: Any = None
set_pulse_counts: Any = None
coil_direction: Any = None
rotor_speed: Any = None
copper_energy: Any = None
lost_steps: Any = None
ERROR_BITS: int = 0

_HOOK_OPTIONS = {"cache": True, "inline": "always"}
#: the observation hook is compiled once, as a function of its own that the step's end hook
#: and the observation after a reset both call, and that LLVM inlines into each (forceinline):
#: inlined at numba's IR level it was compiled twice, once into each caller; a plain call
#: would pass every array of the view, the episode and the state per copy
_OBSERVE_OPTIONS = {**KERNEL, "forceinline": True}
_HOOKS = ("begin", "before", "after", "end", "observe")


def record(**fields: Any) -> np.dtype:
    """The structured dtype of named scalar fields ``name=type`` (float, int or a numpy
    scalar type), in the order given: a row of a task's state that the compiled hooks read and
    write by name (``state.copies[i].target``) and the Python side by column
    (``state.copies["target"]``)."""
    return np.dtype([(name, np.dtype(kind)) for name, kind in fields.items()])


def clear_records(rows: np.ndarray, idx: np.ndarray) -> None:
    """Set every field of the records ``idx`` ((M,) int64) of ``rows``, a C-contiguous (N,)
    array of a :func:`record` dtype, to 0: through a byte view of the rows, as numpy assigns
    a record field by field (about half the time)."""
    rows.view(np.uint8).reshape(rows.size, rows.dtype.itemsize)[idx] = 0


def _as_state(args):  # pragma: no cover - compiled
    """The task's state (``STATE``, bound per task) of the driver's plain tuple."""
    return STATE(*args)


STATE: Any = None  # bound per task by ``Task``


class Task:
    """A task's declaration: the families it needs, its state and its compiled hooks.

    Parameters
    ----------
    tag : str
        The task's identifier in cache file names.
    source : str
        The task module's file (its edits recompile the specialisations).
    needs : iterable of Capability
        What a family must support for the task to run on it.
    state : type, optional
        The task's state, a ``typing.NamedTuple`` of arrays (see the module docstring); None:
        the task keeps no state the hooks see.
    figures : callable, optional
        ``figures(family) -> dict``: the hooks' names derived from the family's figures
        (bound beside the family's own names).
    helpers : mapping of str to function, optional
        Further plain functions the hooks call that use family names (specialised alike).
    begin, before, after, end, observe : function, optional
        The compiled hooks as plain Python functions (``None``: the engine's no-op hook); a
        task with none steps in numpy.
    beside : callable, optional
        ``beside(env) -> list of (dispatcher, argument types)``: compiled functions of the
        task's own (no family names; numba caches each on its own, e.g. compiled apart) that
        its step calls and its first reset does not, with their argument types for ``env``.
        On a cold cache a second process compiles them while this one compiles the env's first
        reset (:func:`jvl_gym.engine.two_cores.start_beside`).
    """

    def __init__(self, tag: str, source: str, *, needs: Iterable[Capability] = (),
                 state: type | None = None,
                 figures: Callable[[Family], dict[str, Any]] | None = None,
                 helpers: Mapping[str, Callable[..., Any]] | None = None,
                 beside: Callable[[Any], list[tuple[Any, tuple]]] | None = None,
                 **hooks: Callable[..., Any] | None) -> None:
        unknown = set(hooks) - set(_HOOKS)
        if unknown:
            raise TypeError(f"unknown hooks {sorted(unknown)}; known: {', '.join(_HOOKS)}")
        self.tag = tag
        self.source = source
        self.needs = frozenset(needs)
        self.state = state
        self.figures = figures
        self.helpers = dict(helpers or {})
        self.beside = beside
        self.hooks = {name: fn for name, fn in hooks.items() if fn is not None}
        self._drivers: dict[str, TaskDriver] = {}

    @property
    def compiled(self) -> bool:
        """Whether the task's step is compiled (it has hooks)."""
        return bool(self.hooks)

    def missing(self, key: str) -> Capability | None:
        """The first of :attr:`needs` (in the enum's order) family ``key`` does not support, or
        None."""
        fam = family(key)
        return next((cap for cap in Capability if cap in self.needs and not fam.supports(cap)),
                    None)

    def refusal(self, key: str) -> UnsupportedOperation | None:
        """Why the task does not run on family ``key`` (the contract's message), or None."""
        cap = self.missing(key)
        return None if cap is None else UnsupportedOperation(family(key).title, cap)

    def families(self) -> tuple[str, ...]:
        """Keys of the registered families the task runs on, in registration order."""
        return tuple(key for key in families() if self.missing(key) is None)

    @staticmethod
    def names(key: str) -> dict[str, Any]:
        """The family names a hook may use: the task module's ``__all__`` and ``c`` (the
        family's constants)."""
        fam = family(key)
        out = {name: getattr(fam.task, name) for name in fam.task.__all__}
        out["c"] = fam.constants
        return out

    def driver(self, key: str) -> TaskDriver:
        """The :class:`~jvl_gym.engine.TaskDriver` of the task over family ``key`` (built, not
        yet compiled, on the first call for that family)."""
        drv = self._drivers.get(key)
        if drv is None:
            fam = family(key)
            figures = self.figures(fam) if self.figures is not None else {}
            templates = {**self.helpers, **{fn.__name__: fn for fn in self.hooks.values()}}
            options: dict[str, Mapping[str, Any]] = {name: _HOOK_OPTIONS for name in templates}
            if "observe" in self.hooks:
                options[self.hooks["observe"].__name__] = _OBSERVE_OPTIONS
            bound_names = {**self.names(key), **figures}
            if self.state is not None:
                templates["_as_state"] = _as_state  # after the hooks: their module's globals
                options["_as_state"] = _HOOK_OPTIONS
                bound_names["STATE"] = self.state
            fns = specialise(templates, bound_names, f"{self.tag}__{key}", self.source, options)
            bound = {name: fns[fn.__name__] for name, fn in self.hooks.items()}
            if self.state is not None:
                bound["state"] = fns["_as_state"]
            drv = self._drivers[key] = TaskDriver(fam, self.source, self.tag, **bound)
        return drv
