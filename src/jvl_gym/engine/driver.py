"""The batched stepping driver: blocks of motors, threads, and the hooks of a task.

N motors advance in blocks of ``lanes`` motors (the family's block size). An outer sample of a
block is the family's outer sample of every motor of the block, one motor at a time, then the
block's inner samples in one call. A block belongs to one thread, and the motors' arithmetic
is independent of each other, so an N-motor array is bit-for-bit equal to N one-motor arrays,
serial or threaded (docs/architecture.md).

The functions here are templates: they call names that :func:`jvl_gym.engine.specialize.specialise`
binds for a family —

- ``outer_sample(view, i, t)``: the family's outer sample of motor ``i`` (``t``: the row of the
  world-input plan), inlined;
- ``inner_block(view, i0, n, blk)``: the inner samples of motors ``i0 .. i0 + n - 1`` of block
  ``blk``;
- ``lanes``: the block size;

and, for a task, its state and hooks (each inlined, called per copy ``i``; ``view`` is the
engine's :class:`~jvl_gym.engine.view.EngineView`, ``episode`` the env's
:class:`~jvl_gym.engine.view.Episode` arrays, ``task`` the task's state):

- ``task_state(args)``: the task's state (its named tuple) from the plain tuple of arrays the
  driver is given (numba dispatches on a plain tuple fastest), once per block;

- ``task_begin(i, view, episode, task, actions)``: once per env step, before the motors;
- ``task_before(i, view, episode, task)``: before each outer sample of the motor;
- ``task_after(i, view, episode, task)``: after each outer sample (after the inner samples);
- ``task_end(i, view, episode, task, actions)``: once per env step: reward, termination,
  observation;
- ``task_observe(i, view, episode, task)``: the observation of a copy after its reset.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import njit, prange

from . import two_cores
from .jit import KERNEL, KERNEL_PARALLEL
from .packed import PackedArguments, unpack
from .specialize import specialise
from .view import EngineView, Episode

__all__ = ["PARALLEL_MIN", "MotorDriver", "TaskDriver", "noop_hook", "noop_step_hook",
           "same_state"]

#: from this many motors (or env copies) the blocks are spread over threads
PARALLEL_MIN = 32

# names bound by ``specialise``; defined here only for linters and readers
outer_sample: Any = None
inner_block: Any = None
lanes: int = 0
task_state: Any = None
task_begin: Any = None
task_before: Any = None
task_after: Any = None
task_end: Any = None
task_observe: Any = None


@njit(cache=True, inline="always")
def same_state(args: tuple) -> tuple:  # pragma: no cover - compiled
    """A ``task_state`` that passes the driver's tuple to the hooks as it is."""
    return args


@njit(cache=True, inline="always")
def noop_hook(i: int, view: EngineView, episode: Episode, task: tuple) -> None:  # pragma: no cover
    """A ``task_before`` / ``task_after`` hook that does nothing."""


@njit(cache=True, inline="always")
def noop_step_hook(i: int, view: EngineView, episode: Episode, task: tuple,
                   actions: np.ndarray) -> None:  # pragma: no cover
    """A ``task_begin`` / ``task_end`` hook that does nothing."""


@njit(cache=True, inline="always")
def block_index(blk: int) -> np.int64:  # pragma: no cover - compiled
    """A block's index as int64 for the call in a ``prange`` loop: numba types a ``prange``
    index as int64 when it types the loop and as uint64 in the parallel function it builds, so
    without the cast the block function is compiled twice, once for each type."""
    return np.int64(blk)


@njit(**KERNEL)
def all_finite(actions: np.ndarray) -> bool:  # pragma: no cover - compiled
    """True when every entry of the (N, A) action array is finite (checked before any step)."""
    for i in range(actions.shape[0]):
        for k in range(actions.shape[1]):
            if not math.isfinite(actions[i, k]):
                return False
    return True


# --- motors alone (MotorArray.step) ------------------------------------------------------------
# The entry points take the arrays one by one (numba dispatches on plain array arguments
# fastest) and each block builds its named views itself (so a threaded loop captures plain
# arrays, not tuples).
def _advance_block(regs, state, params, inputs, keys, buf, rec, fmt, plan, scratch,
                   i0, n, n_outer, blk):  # pragma: no cover - compiled
    """Advance motors ``i0 .. i0 + n - 1`` (block ``blk``) by ``n_outer`` outer samples."""
    view = EngineView(regs, state, params, inputs, keys, buf, rec, fmt, plan, scratch)
    for t in range(n_outer):
        for i in range(i0, i0 + n):
            outer_sample(view, i, t)
        inner_block(view, i0, n, blk)


def _run_serial(regs, state, params, inputs, keys, buf, rec, fmt, plan, scratch,
                n_outer):  # pragma: no cover - compiled
    """Advance every motor by ``n_outer`` outer samples in one thread (the fields of an
    :class:`EngineView`, then the count)."""
    n_motors = regs.shape[0]
    for blk in range(scratch.shape[0]):
        i0 = blk * lanes
        _advance_block(regs, state, params, inputs, keys, buf, rec, fmt, plan, scratch,
                       i0, min(lanes, n_motors - i0), n_outer, blk)


def _run_parallel(regs, state, params, inputs, keys, buf, rec, fmt, plan, scratch,
                  n_outer):  # pragma: no cover - compiled
    """:func:`_run_serial` with the blocks spread over threads."""
    n_motors = regs.shape[0]
    for blk in prange(scratch.shape[0]):
        b = block_index(blk)
        i0 = b * lanes
        _advance_block(regs, state, params, inputs, keys, buf, rec, fmt, plan, scratch,
                       i0, min(lanes, n_motors - i0), n_outer, b)


# --- a task's env step -------------------------------------------------------------------------
def _task_block(blk, regs, state, params, inputs, keys, buf, rec, fmt, plan, scratch,
                prev_action, t, noise_key, obs, reward, terminated, truncated, task,
                actions, decimation):  # pragma: no cover - compiled
    """One env step of the copies of block ``blk``: the task's begin hook per copy,
    ``decimation`` outer samples (before hook, family outer sample per copy; the block's inner
    samples; after hook per copy), then the task's end hook per copy."""
    view = EngineView(regs, state, params, inputs, keys, buf, rec, fmt, plan, scratch)
    episode = Episode(prev_action, t, noise_key, obs, reward, terminated, truncated)
    hooks_task = task_state(task)
    i0 = blk * lanes
    n = min(lanes, regs.shape[0] - i0)
    for i in range(i0, i0 + n):
        task_begin(i, view, episode, hooks_task, actions)
    for t in range(decimation):
        for i in range(i0, i0 + n):
            task_before(i, view, episode, hooks_task)
            outer_sample(view, i, t)
        inner_block(view, i0, n, blk)
        for i in range(i0, i0 + n):
            task_after(i, view, episode, hooks_task)
    for i in range(i0, i0 + n):
        task_end(i, view, episode, hooks_task, actions)


def _task_serial(packed, actions, decimation):  # pragma: no cover - compiled
    """One env step of every copy in one thread (``packed``: the fields of an
    :class:`EngineView` and of an :class:`Episode` and the task's tuple, packed; the actions;
    the decimation); False (nothing changed) if an action is not finite."""
    if not all_finite(actions):
        return False
    (regs, state, params, inputs, keys, buf, rec, fmt, plan, scratch, prev_action, t,
     noise_key, obs, reward, terminated, truncated, task) = unpack(packed)
    for blk in range(scratch.shape[0]):
        _task_block(blk, regs, state, params, inputs, keys, buf, rec, fmt, plan, scratch,
                    prev_action, t, noise_key, obs, reward, terminated, truncated, task,
                    actions, decimation)
    return True


def _task_parallel(packed, actions, decimation):  # pragma: no cover - compiled
    """:func:`_task_serial` with the blocks spread over threads."""
    if not all_finite(actions):
        return False
    (regs, state, params, inputs, keys, buf, rec, fmt, plan, scratch, prev_action, t,
     noise_key, obs, reward, terminated, truncated, task) = unpack(packed)
    for blk in prange(scratch.shape[0]):
        _task_block(block_index(blk), regs, state, params, inputs, keys, buf, rec, fmt, plan,
                    scratch, prev_action, t, noise_key, obs, reward, terminated, truncated,
                    task, actions, decimation)
    return True


def _task_observe(idx, packed):  # pragma: no cover - compiled
    """The task's observation hook for copies ``idx`` (after their reset; ``packed`` as
    :func:`_task_serial` takes it)."""
    (regs, state, params, inputs, keys, buf, rec, fmt, plan, scratch, prev_action, t,
     noise_key, obs, reward, terminated, truncated, task) = unpack(packed)
    view = EngineView(regs, state, params, inputs, keys, buf, rec, fmt, plan, scratch)
    episode = Episode(prev_action, t, noise_key, obs, reward, terminated, truncated)
    hooks_task = task_state(task)
    for i in idx:
        task_observe(i, view, episode, hooks_task)


_MOTOR_TEMPLATES = {"_advance_block": _advance_block, "_run_serial": _run_serial,
                    "_run_parallel": _run_parallel}
#: a block's step is called, not copied, by the serial and threaded drivers (engine.apart)
_MOTOR_OPTIONS = {"_advance_block": {**KERNEL, "apart": True},
                  "_run_serial": KERNEL, "_run_parallel": KERNEL_PARALLEL}
_TASK_TEMPLATES = {"_task_block": _task_block, "_task_serial": _task_serial,
                   "_task_parallel": _task_parallel, "_task_observe": _task_observe}
_TASK_OPTIONS = {"_task_block": {**KERNEL, "apart": True}, "_task_serial": KERNEL,
                 "_task_parallel": KERNEL_PARALLEL, "_task_observe": KERNEL}


def _family_bindings(family: Any) -> dict[str, Any]:
    compiled = family.compiled
    return {"outer_sample": compiled.outer_sample, "inner_block": compiled.inner_block,
            "lanes": compiled.LANES}


class MotorDriver:
    """Steps an array of motors of one family (``MotorArray.step``), serial or threaded.

    Parameters
    ----------
    family : jvl_gym.families.Family
        The motor family: its compiled outer sample, inner block and block size.
    """

    def __init__(self, family: Any) -> None:
        self.family = family
        fns = specialise(_MOTOR_TEMPLATES, _family_bindings(family), f"{family.key}",
                         family.compiled.__file__, _MOTOR_OPTIONS)
        self._prepared = False
        #: the compiled drivers, ``(*arrays, n_outer)``: one thread, and blocks over threads
        self.serial = fns["_run_serial"]
        self.parallel = fns["_run_parallel"]

    def run(self, arrays: tuple, n_outer: int, serial: bool = False) -> None:
        """Advance every motor by ``n_outer`` outer samples (``arrays``: the fields of an
        :class:`EngineView` as a plain tuple, ``MotorArray.engine_view()``); ``serial``: in
        this thread whatever the number of motors (for a caller that steps one outer sample
        at a time, where starting the threads would cost more than the sample)."""
        self.runner(arrays, serial)(*arrays, n_outer)

    def runner(self, arrays: tuple, serial: bool = False) -> Any:
        """The compiled driver for the motors ``arrays`` (the fields of an
        :class:`EngineView`): threaded from :data:`PARALLEL_MIN` motors unless ``serial``,
        taken with the arguments of :meth:`run` spread, ``(*arrays, n_outer)``."""
        if not self._prepared:
            two_cores.prepare(self.family.compiled, arrays)
            self._prepared = True
        return self.parallel if not serial and arrays[0].shape[0] >= PARALLEL_MIN else self.serial


class TaskDriver:
    """The compiled env step of one task over one family: the family's motors and the task's
    hooks, advanced block by block, threaded from :data:`PARALLEL_MIN` copies.

    Parameters
    ----------
    family : jvl_gym.families.Family
        The motor family the task runs on.
    source : str
        The task module's file (its edits recompile the step).
    begin, before, after, end, observe : numba dispatchers
        The task's hooks (``task_begin`` … ``task_observe`` of the module docstring), compiled
        with ``inline="always"``; :func:`noop_hook` / :func:`noop_step_hook` where a task has
        none.
    state : numba dispatcher
        ``task_state`` of the module docstring (inlined); default :func:`same_state`.
    tag : str
        Identifier of the task in cache file names.
    """

    def __init__(self, family: Any, source: str, tag: str, *, begin: Any = noop_step_hook,
                 before: Any = noop_hook, after: Any = noop_hook, end: Any = noop_step_hook,
                 observe: Any = noop_hook, state: Any = same_state) -> None:
        self.family = family
        bindings = {**_family_bindings(family), "task_state": state, "task_begin": begin,
                    "task_before": before, "task_after": after, "task_end": end,
                    "task_observe": observe}
        fns = specialise(_TASK_TEMPLATES, bindings, f"{tag}__{family.key}", source,
                         _TASK_OPTIONS)
        self._prepared = False
        #: the compiled steps, ``(packed, actions, decimation)`` (:meth:`pack`): one thread,
        #: and blocks over threads
        self.serial = fns["_task_serial"]
        self.parallel = fns["_task_parallel"]
        self._observe = fns["_task_observe"]

    @staticmethod
    def pack(arrays: tuple, episode: tuple, task: tuple) -> PackedArguments:
        """The arguments of an env step before the actions, packed for the compiled step
        (:mod:`jvl_gym.engine.packed`: converted once, not at every call): ``arrays`` and
        ``episode`` are the fields of an :class:`EngineView` and an :class:`Episode` as plain
        tuples, ``task`` the plain tuple of the task's arrays (``task_state`` makes the hooks'
        state of it). An env packs its arrays once and passes the result to every step while
        the motors keep their arrays."""
        return PackedArguments((*arrays, *episode, task))

    def step(self, arrays: tuple, episode: tuple, task: tuple, actions: np.ndarray,
             decimation: int) -> bool:
        """One env step of every copy (one motor each) with ``actions`` (N, A) float64; the
        other arguments as :meth:`pack` takes them.

        Returns
        -------
        bool
            False, with nothing changed, when an action is not finite.
        """
        return self.runner(arrays)(self.pack(arrays, episode, task), actions, decimation)

    def runner(self, arrays: tuple) -> Any:
        """The compiled step for the motors ``arrays`` (the fields of an :class:`EngineView`):
        threaded from :data:`PARALLEL_MIN` copies, else serial; taken with the arguments
        ``(packed, actions, decimation)``, ``packed`` from :meth:`pack`. An env keeps it (its
        number of copies does not change) and calls it without :meth:`step`'s frame."""
        if not self._prepared:
            two_cores.prepare(self.family.compiled, arrays)
            self._prepared = True
        return self.parallel if arrays[0].shape[0] >= PARALLEL_MIN else self.serial

    def observe(self, packed: PackedArguments, idx: np.ndarray) -> None:
        """The task's observation of copies ``idx`` (M,) int64 after their reset (``packed``
        from :meth:`pack`)."""
        self._observe(idx, packed)
