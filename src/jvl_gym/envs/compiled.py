"""Compiled pieces of an environment step shared by the tasks' hooks.

A task with a compiled step runs its whole env step in one compiled call: the engine's task
driver (``jvl_gym.engine.TaskDriver``) advances the copies block by block and calls the task's
hooks (action, process model, reward, termination, truncation, the observation with its noise
and clipping). These helpers are the task-independent parts of the hooks; observation noise
comes from the one counter-based generator, :mod:`jvl_gym.motor.noise`, as in the numpy-stepped
tasks.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..engine.jit import KERNEL, plain_arguments
from ..motor.noise import normal

__all__ = ["OBS_BOUND", "action", "put_obs", "end_step", "reset_counters"]

#: observations are normalised so that typical values lie within ±1 and clipped to ±OBS_BOUND
OBS_BOUND = 5.0


@njit(cache=True, inline="always")
def action(actions: np.ndarray, i: int, k: int) -> float:  # pragma: no cover - compiled
    """Component ``k`` of copy ``i``'s action clipped to [-1, 1]."""
    return min(max(actions[i, k], -1.0), 1.0)


@plain_arguments
@njit(**KERNEL)
def obs_normal(key: np.uint64, counter: int, k: int, n: int) -> float:  # pragma: no cover
    """:func:`jvl_gym.motor.noise.normal` compiled once, as a function of its own: numba's IR
    inliner would copy it (and the generator it inlines) into each observation component's
    store, and a literal component index would compile it once per component."""
    return normal(key, counter, k, n)


@njit(cache=True, inline="always")
def put_obs(obs: np.ndarray, i: int, k: int, x: float, key: np.uint64, counter: int,
            noise: float) -> None:  # pragma: no cover - compiled
    """Store observation component ``k`` of copy ``i``: add noise, clip to ±OBS_BOUND."""
    if noise > 0.0:
        x += noise * obs_normal(key, counter, k, obs.shape[1])
    obs[i, k] = min(max(x, -OBS_BOUND), OBS_BOUND)


@njit(cache=True, inline="always")
def end_step(i: int, terminated: bool, t: np.ndarray, max_steps: int, term: np.ndarray,
             trunc: np.ndarray) -> None:  # pragma: no cover - compiled
    """Store termination and truncation of copy ``i`` (``t`` already counts this step)."""
    term[i] = terminated
    trunc[i] = (t[i] >= max_steps) and not terminated


@njit(**KERNEL)
def reset_counters(idx: np.ndarray, keys: np.ndarray, noise_key: np.ndarray, t: np.ndarray,
                   prev: np.ndarray, scope_count: np.ndarray) -> None:  # pragma: no cover
    """Start the episodes of copies ``idx`` (M,): the observation noise keys from column 1 of
    ``keys`` (M, 2) uint64 (column 0 seeds the motors), step counters ``t`` and
    ``scope_count`` 0, the previous action ``prev`` (N, A) 0."""
    for j in range(idx.shape[0]):
        i = idx[j]
        noise_key[i] = keys[j, 1]
        t[i] = 0
        scope_count[i] = 0
        for k in range(prev.shape[1]):
            prev[i, k] = 0.0
