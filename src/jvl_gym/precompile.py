"""Compile everything numba compiles on first use, ahead of that use (``jvl-gym compile``).

A fresh install compiles the simulator's kernel on the first step of a motor array and each
environment's step on its first step; together several minutes on a 2-core machine. Running
this once after installing (``make setup`` does) fills numba's on-disk cache, so that every
later process starts in about a second. Jobs: the motor arrays of every family (serial and
threaded drivers, register writes) first, since every environment inlines its family's kernel,
then each environment (single and vector with threads) on each motor family it runs on (its
default motor type, and the default motor type of each further family) in a pool of worker
processes.
"""

from __future__ import annotations

import multiprocessing
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np

__all__ = ["compile_motors", "compile_env", "env_jobs", "compile_all"]

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


def env_jobs(env_ids: tuple[str, ...]) -> list[tuple[str, str | None]]:
    """``(env_id, motor_type)`` of each env on each family it runs on: ``None`` (the env's
    default) for its first family, the default motor type of each further one."""
    import importlib

    import gymnasium as gym

    import jvl_gym  # noqa: F401  (registers the ids)

    from .families import family

    jobs: list[tuple[str, str | None]] = []
    for env_id in env_ids:
        module, _, name = str(gym.spec(env_id).vector_entry_point).partition(":")
        keys = getattr(importlib.import_module(module), name).supported_families()
        jobs.append((env_id, None))
        jobs.extend((env_id, family(key).task.DEFAULT_MOTOR_TYPE) for key in keys[1:])
    return jobs


def compile_env(env_id: str, motor_type: str | None = None) -> float:
    """Compile the single and the threaded vector step of ``env_id`` (on the family of
    ``motor_type``; default: the env's default type). Returns the wall time [s]."""
    import gymnasium as gym

    import jvl_gym  # noqa: F401  (registers the ids)

    kwargs = {} if motor_type is None else {"motor_type": motor_type}
    start = time.perf_counter()
    env = gym.make(env_id, **kwargs)
    env.reset(seed=0)
    env.step(env.action_space.sample())
    env.close()
    vec = gym.make_vec(env_id, num_envs=_THREADED, vectorization_mode="vector_entry_point",
                       **kwargs)
    vec.reset(seed=0)
    vec.step(np.zeros(vec.action_space.shape, dtype=np.float32))
    vec.close()
    return time.perf_counter() - start


def compile_all(workers: int | None = None, envs: bool = True) -> dict[str, float]:
    """Compile the motor array, then (``envs``) every registered environment on each family it
    runs on (:func:`env_jobs`) in ``workers`` processes (default: the CPU count). Returns the
    wall time of each job [s], by env id (and motor type for a further family)."""
    from .envs.registration import ENV_IDS

    times = {"MotorArray": compile_motors()}
    if envs:
        jobs = env_jobs(ENV_IDS)
        workers = workers or os.cpu_count() or 1
        # spawned, not forked: this process has started numba's worker threads
        with ProcessPoolExecutor(max_workers=min(workers, len(jobs)),
                                 mp_context=multiprocessing.get_context("spawn")) as pool:
            ids, types = zip(*jobs)
            for env_id, motor_type, seconds in zip(ids, types,
                                                   pool.map(compile_env, ids, types)):
                times[env_id if motor_type is None else f"{env_id} ({motor_type})"] = seconds
    return times


def main() -> None:  # pragma: no cover - command line
    """``python -m jvl_gym.precompile [--motors-only]``."""
    times = compile_all(envs="--motors-only" not in sys.argv[1:])
    for job, seconds in times.items():
        print(f"{job}: {seconds:.1f} s", file=sys.stderr)


if __name__ == "__main__":  # pragma: no cover
    main()
