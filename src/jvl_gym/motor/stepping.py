"""Stepping of a motor array: the family's compiled step driven by the engine.

The world inputs' schedule (``jvl_gym.world``) is sampled per outer sample; a compiled task gets
the arrays as :meth:`Stepping.engine_view` and advances the motors itself.
"""

from __future__ import annotations

import functools
import math
from typing import Any, ClassVar

import numpy as np

from ..engine import MotorDriver
from ..engine.entry import entry_point
from ..families import family
from .arguments import MotorIndex, as_index, outer_count

__all__ = ["Stepping", "driver"]

#: the attributes that make up :meth:`Stepping.engine_view`: binding any of them anew (the
#: sample buffer at the first recording) makes the view and the compiled entry be taken again
_VIEW_FIELDS = frozenset({"regs", "state", "params", "inputs", "keys", "_buf", "_buf_allocated",
                          "_fmt", "_no_schedule", "_scratch"})


@functools.cache
def driver(family_key: str) -> MotorDriver:
    """The stepping driver of a family (specialised and compiled once per process)."""
    return MotorDriver(family(family_key))


class Stepping:
    """Stepping of :class:`~jvl_gym.MotorArray` (a mixin over its arrays)."""

    FAMILY_KEY: ClassVar[str]
    OUTER_HZ: ClassVar[float]
    PHYSICAL: ClassVar[frozenset[str]]
    n: int
    regs: np.ndarray
    state: np.ndarray
    params: np.ndarray
    inputs: np.ndarray
    keys: np.ndarray
    world: Any
    _buf: np.ndarray
    _buf_allocated: bool
    _fmt: np.ndarray
    _no_schedule: np.ndarray
    _scratch: np.ndarray
    #: :meth:`engine_view` without a plan, taken on first use (None: to be taken)
    _view: tuple | None = None
    #: the compiled driver's entry for :attr:`_view` with inputs held (None: to be taken)
    _run_held: Any = None

    def __setattr__(self, name: str, value: Any) -> None:
        object.__setattr__(self, name, value)
        if name in _VIEW_FIELDS:  # an array of the view bound anew: take view and entry again
            object.__setattr__(self, "_view", None)
            object.__setattr__(self, "_run_held", None)

    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        state.pop("_view", None)
        state.pop("_run_held", None)  # machine code: taken again after unpickling
        return state

    def step(self, n_outer: int = 1) -> None:
        """Advance all motors by ``n_outer`` outer samples (:attr:`OUTER_HZ`)."""
        if type(n_outer) is not int or n_outer < 0:
            n_outer = outer_count(n_outer, "step")
        if n_outer == 0:
            return
        if self.world is not None:
            plan = self.world.schedule(self, n_outer)
            driver(self.FAMILY_KEY).run(self.engine_view(plan), n_outer)
            return
        run = self._run_held
        if run is None:
            run = self._held_runner()
        run(*self._view, n_outer)  # type: ignore[misc]

    def _held_runner(self) -> Any:
        """The compiled driver of the motors with their inputs held (no world schedule),
        threaded from ``PARALLEL_MIN`` motors: its machine code's own entry for the types of
        :meth:`engine_view`, which do not change while the arrays are the motors' (taken again
        when one is bound anew), so that a call skips the dispatcher's look-up by type."""
        view = self.engine_view()
        compiled = driver(self.FAMILY_KEY).runner(view)
        compiled(*view, 0)  # compile or load from the cache, advancing nothing
        run = entry_point(compiled, (*view, 0))
        object.__setattr__(self, "_run_held", run)
        return run

    def engine_view(self, plan: np.ndarray | None = None) -> tuple:
        """The arrays of the motors as the engine's compiled drivers take them (the arrays
        themselves, not copies): the fields of a :class:`~jvl_gym.engine.EngineView`, in its
        order, as a plain tuple. A driver passes them as separate arguments (the compiled
        dispatcher is fastest on plain arrays) and builds the named view of them per block.
        Without ``plan`` the tuple is the same object from call to call while the motors keep
        their arrays.

        A task that advances the motors itself (``jvl_gym.engine.TaskDriver``) holds the
        inputs over each outer sample and sets them between samples; the :attr:`world`
        schedule applies to :meth:`step` only. ``plan`` (T, N, inputs): world inputs per outer
        sample, default none (inputs held).
        """
        view = self._view
        if view is None:
            view = (self.regs, self.state, self.params, self.inputs, self.keys, self._buf,
                    self._buf_allocated, self._fmt, self._no_schedule, self._scratch)
            object.__setattr__(self, "_view", view)
        if plan is None:
            return view
        return (*view[:8], plan, view[9])

    def reseed(self, keys: np.ndarray, index: MotorIndex = None) -> None:
        """Give the motors ``index`` new noise keys (one uint64 per motor, as the ``seed``
        sequence of the constructor): their noise streams restart from these keys.

        Parameters
        ----------
        keys : (M,) array of uint64
            One key per selected motor.
        index : int, slice, bool mask or int array, optional
            The motors (default all).
        """
        idx = as_index(index, self.n)
        arr = np.asarray(keys)
        if arr.dtype != np.uint64 or arr.shape != (idx.size,):
            raise ValueError(f"keys must be a uint64 array of shape ({idx.size},), got "
                             f"{arr.dtype} {arr.shape}")
        self.keys[idx] = arr

    def run(self, seconds: float) -> None:
        """Advance by ``seconds`` (rounded to whole outer samples of the family's outer
        rate)."""
        real = (int, float, np.integer, np.floating)
        if (isinstance(seconds, (bool, np.bool_)) or not isinstance(seconds, real)
                or not math.isfinite(seconds) or seconds < 0):
            raise ValueError(f"seconds must be a finite number >= 0, got {seconds!r}")
        self.step(int(round(seconds * self.OUTER_HZ)))

    def trace(self, keys: list[str | int], n_outer: int) -> dict[str, np.ndarray]:
        """Step ``n_outer`` outer samples and record registers and physical quantities.

        ``keys`` are register names/numbers or the family's physical properties
        (:attr:`PHYSICAL`, e.g. ``speed_rpm``, ``position_rad``). Returns
        ``{"t": (T,), key: (T, N)}`` (user units; ``t`` from :attr:`time`), like a scope
        attached to every motor at the outer rate.
        """
        n_outer = outer_count(n_outer, "trace")
        physical = self.PHYSICAL
        regs = [k for k in keys if k not in physical]
        for k in regs:
            self._lookup(k)  # unknown names fail before anything runs
        out: dict[str, list] = {"t": []}
        out.update({str(k): [] for k in keys})
        for _ in range(int(n_outer)):
            self.step()
            out["t"].append(float(self.time[0]))
            for k in keys:
                out[str(k)].append(getattr(self, k) if k in physical else self.read(k))
        return {k: np.asarray(v) for k, v in out.items()}
