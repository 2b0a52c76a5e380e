"""Compiled pieces of an environment step shared by the tasks (numba, one block of copies at a
time).

A task with a compiled step (``MotorVectorEnv.compiled``) runs a whole step of a block of
:data:`jvl_gym.lanes.LANES` copies in one compiled function (``_step_block`` of the task
module): action (clipped here, never written back to the caller's array), motor kernel, process
model, reward, termination, truncation and the observation with its noise and clipping. The
copies of a block advance in lockstep: each outer sample runs the process model's work before
the motor and the firmware's outer step copy by copy, then the block's inner samples in one
call (:func:`jvl_gym.lanes.inner_samples`), then the process model's work after the motor copy
by copy. The copies' arithmetic stays independent of each other, so a copy's trajectory does
not depend on its block or the number of copies. The Python side makes one call per step, for
one copy (the single env: one block of one copy) or all copies (the vector env, blocks spread
over threads from :data:`PARALLEL_MIN` copies), so a single env step costs little more than the
motor kernel itself. These helpers are the task-independent parts; they reproduce
:func:`jvl_gym.envs.noise.normals` (same counter-based streams) so noise does not depend on the
path.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..firmware.noise import uniform
from ..jit import KERNEL

__all__ = ["PARALLEL_MIN", "OBS_BOUND", "all_finite", "action", "block_index", "put_obs",
           "normal", "end_step", "reset_counters"]

#: from this many copies a vector env step runs its blocks of copies in parallel threads
PARALLEL_MIN = 32
#: observations are normalised so that typical values lie within ±1 and clipped to ±OBS_BOUND
OBS_BOUND = 5.0


@njit(**KERNEL)
def all_finite(actions: np.ndarray) -> bool:  # pragma: no cover - compiled
    """True when every entry of the (N, A) action array is finite (checked before any step)."""
    for i in range(actions.shape[0]):
        for k in range(actions.shape[1]):
            if not math.isfinite(actions[i, k]):
                return False
    return True


@njit(cache=True, inline="always")
def block_index(blk: int) -> np.int64:  # pragma: no cover - compiled
    """A block's index as int64, for the ``_step_block`` call in a ``prange`` loop.

    numba types a ``prange`` index as int64 when it types the loop and as uint64 in the
    parallel function it builds from it, so without the cast ``_step_block`` (with everything
    inlined into it: the task, the firmware's outer step) was compiled twice, once for each
    type, the int64 one being ``_steps_serial``'s. CoilWinding's second compile took 26 s.
    """
    return np.int64(blk)


@njit(cache=True, inline="always")
def action(actions: np.ndarray, i: int, k: int) -> float:  # pragma: no cover - compiled
    """Component ``k`` of copy ``i``'s action clipped to [-1, 1]."""
    return min(max(actions[i, k], -1.0), 1.0)


@njit(cache=True, inline="always")
def normal(key: np.uint64, counter: int, k: int, n: int) -> float:  # pragma: no cover
    """Channel ``k`` of ``n`` of :func:`jvl_gym.envs.noise.normals` for one copy."""
    u1 = uniform(key, counter, k)
    u2 = uniform(key, counter, n + k)
    return math.sqrt(-2.0 * math.log(u1)) * math.cos(2.0 * math.pi * u2)


@njit(cache=True, inline="always")
def put_obs(obs: np.ndarray, i: int, k: int, x: float, key: np.uint64, counter: int,
            noise: float) -> None:  # pragma: no cover - compiled
    """Store observation component ``k`` of copy ``i``: add noise, clip to ±OBS_BOUND."""
    if noise > 0.0:
        x += noise * normal(key, counter, k, obs.shape[1])
    obs[i, k] = min(max(x, -OBS_BOUND), OBS_BOUND)


@njit(cache=True, inline="always")
def end_step(i: int, terminated: bool, t: np.ndarray, max_steps: int, term: np.ndarray,
             trunc: np.ndarray) -> None:  # pragma: no cover - compiled
    """Store termination and truncation of copy ``i`` (``t`` already counts this step)."""
    term[i] = terminated
    trunc[i] = (t[i] >= max_steps) and not terminated


@njit(**KERNEL)
def reset_counters(idx: np.ndarray, keys: np.ndarray, motor_keys: np.ndarray,
                   noise_key: np.ndarray, t: np.ndarray, prev: np.ndarray,
                   scope_count: np.ndarray) -> None:  # pragma: no cover - compiled
    """Start the episodes of copies ``idx`` (M,): the motors' noise keys and the observation
    noise keys from ``keys`` (M, 2) uint64, step counters ``t`` and ``scope_count`` 0, the
    previous action ``prev`` (N, A) 0."""
    for j in range(idx.shape[0]):
        i = idx[j]
        motor_keys[i] = keys[j, 0]
        noise_key[i] = keys[j, 1]
        t[i] = 0
        scope_count[i] = 0
        for k in range(prev.shape[1]):
            prev[i, k] = 0.0
