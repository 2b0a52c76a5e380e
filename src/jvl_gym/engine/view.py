"""The two named tuples a compiled driver builds of the arrays it is given, for the hooks.

:class:`EngineView` is what a motor array is to compiled code: the register banks and the
family's state, parameters and inputs of N motors, one row per motor, with the sample buffer,
the world-input plan and the blocks' working memory. The column meaning of ``state``,
``params`` and ``inputs`` belongs to the motor family; a task reads and writes them only
through the family's task interface (``jvl_gym.families.<family>.task``).

:class:`Episode` holds the per-copy bookkeeping every environment shares.

:func:`take_planned_inputs` and :func:`record_rows` are what every family's outer sample does
with the view before its firmware runs.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

__all__ = ["EngineView", "Episode", "take_planned_inputs", "record_rows"]


class EngineView(NamedTuple):
    """The compiled face of a :class:`~jvl_gym.MotorArray` (``MotorArray.engine_view()``)."""

    regs: np.ndarray  #: (N, number of registers) int64 register banks
    state: np.ndarray  #: (N, family state fields) float64
    params: np.ndarray  #: (N, family parameters) float64, SI units
    inputs: np.ndarray  #: (N, family world inputs) float64, held over an outer sample
    keys: np.ndarray  #: (N,) uint64 noise keys
    buf: np.ndarray  #: (N, depth, channels) int64 sample buffer, or (1, …) when unallocated
    rec: bool  #: whether ``buf`` is allocated
    fmt: np.ndarray  #: (number of registers,) int64 format codes (``registers.FORMAT_CODES``)
    plan: np.ndarray  #: (T, N, inputs) world inputs per outer sample, or (0, N, inputs): held
    scratch: np.ndarray  #: (blocks, width) float64 working memory of the blocks


class Episode(NamedTuple):
    """Per-copy episode arrays of an environment (``N`` copies, ``A`` actions, ``K``
    observations)."""

    prev_action: np.ndarray  #: (N, A) float64, the last clipped action
    t: np.ndarray  #: (N,) int64 steps since the episode started
    noise_key: np.ndarray  #: (N,) uint64 key of the observation noise
    obs: np.ndarray  #: (N, K) float32 observation
    reward: np.ndarray  #: (N,) float64
    terminated: np.ndarray  #: (N,) bool
    truncated: np.ndarray  #: (N,) bool


@njit(cache=True, inline="always")
def take_planned_inputs(view: EngineView, i: int, t: int) -> None:  # pragma: no cover
    """Set motor ``i``'s world inputs from row ``t`` of the world-input plan, when the plan is
    not empty (otherwise the inputs are held)."""
    plan = view.plan
    inputs = view.inputs
    if plan.shape[0] > 0:
        for k in range(inputs.shape[1]):
            inputs[i, k] = plan[t, i, k]


@njit(cache=True, inline="always")
def record_rows(view: EngineView, i: int) -> np.ndarray:  # pragma: no cover - compiled
    """Motor ``i``'s sample buffer (depth, channels), or the placeholder when none is
    allocated."""
    return view.buf[i] if view.rec else view.buf[0]
