"""Compile everything numba compiles on first use, ahead of that use (``jvl-gym compile``).

A fresh install compiles the simulator's kernel on the first step of a motor array and each
environment's step on its first step; together several minutes on a 2-core machine. Running
this once after installing (``make setup`` does) fills numba's on-disk cache, so that every
later process starts in about a second. Jobs: the motor arrays of every family (serial and
threaded drivers, register writes) first, since every environment inlines its family's kernel,
then each environment (single and vector with threads) in a pool of worker processes.
"""

from __future__ import annotations

import multiprocessing
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np

__all__ = ["compile_motors", "compile_env", "compile_all"]

#: enough copies for the threaded drivers (``jvl_gym.engine.driver.PARALLEL_MIN``)
_THREADED = 32


def compile_motors() -> float:
    """Compile the motor arrays' paths of every registered family: stepping (serial and
    threaded) and register writes. Returns the wall time [s]."""
    from .families import families, family
    from .sim import MotorArray

    start = time.perf_counter()
    for key in families():
        motor_type = family(key).motor_types()[0]
        for n in (1, _THREADED):
            m = MotorArray(motor_type, n=n, seed=0)
            m.write(m.MODE_REGISTER, m.read_raw(m.MODE_REGISTER))  # the write path
            m.step(2)
    return time.perf_counter() - start


def compile_env(env_id: str) -> float:
    """Compile the single and the threaded vector step of ``env_id``. Returns the wall time
    [s]."""
    import gymnasium as gym

    import jvl_gym  # noqa: F401  (registers the ids)

    start = time.perf_counter()
    env = gym.make(env_id)
    env.reset(seed=0)
    env.step(env.action_space.sample())
    env.close()
    vec = gym.make_vec(env_id, num_envs=_THREADED, vectorization_mode="vector_entry_point")
    vec.reset(seed=0)
    vec.step(np.zeros(vec.action_space.shape, dtype=np.float32))
    vec.close()
    return time.perf_counter() - start


def compile_all(workers: int | None = None, envs: bool = True) -> dict[str, float]:
    """Compile the motor array, then (``envs``) every registered environment in ``workers``
    processes (default: the CPU count). Returns the wall time of each job [s]."""
    from .envs.registration import ENV_IDS

    times = {"MotorArray": compile_motors()}
    if envs:
        workers = workers or os.cpu_count() or 1
        # spawned, not forked: this process has started numba's worker threads
        with ProcessPoolExecutor(max_workers=min(workers, len(ENV_IDS)),
                                 mp_context=multiprocessing.get_context("spawn")) as pool:
            for env_id, seconds in zip(ENV_IDS, pool.map(compile_env, ENV_IDS)):
                times[env_id] = seconds
    return times


def main() -> None:  # pragma: no cover - command line
    """``python -m jvl_gym.precompile [--motors-only]``."""
    times = compile_all(envs="--motors-only" not in sys.argv[1:])
    for job, seconds in times.items():
        print(f"{job}: {seconds:.1f} s", file=sys.stderr)


if __name__ == "__main__":  # pragma: no cover
    main()
