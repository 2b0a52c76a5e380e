"""Compile what numba compiles on first use, ahead of that use (``jvl-gym compile``).

A fresh install compiles a family's simulator kernel on the first step of a motor array of that
family and each environment's step on its first step; together several minutes on a 2-core
machine. Running this once after installing (``make setup`` does) fills numba's on-disk cache,
so that every later process starts in about a second.

The work is split into units, each compiled in its own spawned process, as many at once as
there are workers: the motor array of each family (serial and threaded drivers, register
writes), and each environment (single and vector with threads) on each family it runs on (its
default motor type, and the default motor type of each further family). An environment's unit
starts after its family's unit has finished, so that it loads what that unit cached. A line on
stderr says when a unit starts, with the seconds it is expected to take (what it took the last
time it compiled, kept beside numba's cache, else :data:`ESTIMATE`), and one when it ends.
"""

from __future__ import annotations

import json
import multiprocessing
import os
import sys
import time
from collections.abc import Callable, Iterable, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = ["Unit", "ESTIMATE", "motor_units", "env_units", "compile_motors", "compile_env",
           "compile_units", "compile_all", "expected_seconds"]

#: enough copies for the threaded drivers (``jvl_gym.engine.driver.PARALLEL_MIN``)
_THREADED = 32
#: expected compile time of a unit that has not compiled on this machine yet, by kind [s]
ESTIMATE = {"motors": 90.0, "env": 20.0}
#: a unit that took less than this loaded its code from the cache rather than compiling [s]
_CACHED_BELOW = 5.0
#: the file of measured unit times, in numba's cache folder
_TIMES_NAME = "jvl_gym.compile-times.json"


@dataclass(frozen=True)
class Unit:
    """One process's worth of compiling.

    Attributes
    ----------
    name : str
        What the progress lines call it (``"motors MAC140"``, ``"jvl_gym/GearSync-v0"``).
    kind : str
        ``"motors"`` (a family's motor array) or ``"env"`` (an environment).
    family : str
        Key of the motor family it compiles for.
    motor_type : str or None
        The motor type it runs; None: an environment's default.
    env_id : str or None
        The environment's id; None for a motor array.
    after : tuple of str
        Names of the units that must have finished first.
    """

    name: str
    kind: str
    family: str
    motor_type: str | None = None
    env_id: str | None = None
    after: tuple[str, ...] = field(default=())


def motor_units(motor_types: Iterable[str] | None = None) -> list[Unit]:
    """A motor-array unit per family: of the families of ``motor_types`` (any user spelling),
    each compiled with the first of those types; default: every registered family with its
    first motor type. ``ConfigError`` for a motor type no family lists."""
    from ..families import families, family, family_of_motor

    if motor_types is None:
        chosen = {key: family(key).motor_types()[0] for key in families()}
    else:
        chosen = {}
        for name in motor_types:
            fam = family_of_motor(name)
            chosen.setdefault(fam.key, fam.config.canonical_motor_name(name))
    return [Unit(f"motors {motor_type}", "motors", key, motor_type)
            for key, motor_type in chosen.items()]


def env_units(env_ids: Sequence[str], motors: Sequence[Unit]) -> list[Unit]:
    """A unit per environment in ``env_ids`` and family it runs on (``None``, the env's default
    type, for its first family; the default motor type of each further one), each after the
    unit in ``motors`` of its family, if any."""
    import importlib

    import gymnasium as gym

    import jvl_gym  # noqa: F401  (registers the ids)

    from ..families import family

    after = {u.family: (u.name,) for u in motors}
    units: list[Unit] = []
    for env_id in env_ids:
        module, _, name = str(gym.spec(env_id).vector_entry_point).partition(":")
        keys = getattr(importlib.import_module(module), name).supported_families()
        for k, key in enumerate(keys):
            motor_type = None if k == 0 else family(key).task.DEFAULT_MOTOR_TYPE
            label = env_id if motor_type is None else f"{env_id} ({motor_type})"
            units.append(Unit(label, "env", key, motor_type, env_id, after.get(key, ())))
    return units


def compile_motors(motor_type: str) -> float:
    """Compile the motor-array paths of the family of ``motor_type``: stepping (serial and
    threaded) and register writes. Returns the wall time [s]."""
    from ..motor.array import MotorArray

    start = time.perf_counter()
    for n in (1, _THREADED):
        m = MotorArray(motor_type, n=n, seed=0)
        m.write(m.MODE_REGISTER, m.read_raw(m.MODE_REGISTER))  # the write path
        m.step(2)
    return time.perf_counter() - start


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


def _run(unit: Unit) -> float:
    """Compile ``unit`` (in a worker process). Returns the wall time [s]."""
    if unit.kind == "motors":
        assert unit.motor_type is not None
        return compile_motors(unit.motor_type)
    assert unit.env_id is not None
    return compile_env(unit.env_id, unit.motor_type)


def _times_path() -> Path:
    """The file of measured unit times: in ``NUMBA_CACHE_DIR`` if set, else in the jvl_gym
    package's ``__pycache__`` (beside the compile stamp, :mod:`jvl_gym.engine.cache`)."""
    folder = os.environ.get("NUMBA_CACHE_DIR")
    return (Path(folder) if folder else Path(__file__).resolve().parents[1] / "__pycache__") \
        / _TIMES_NAME


def _load_times() -> dict[str, float]:
    try:
        data = json.loads(_times_path().read_text())
    except (OSError, ValueError):
        return {}
    return {k: float(v) for k, v in data.items() if isinstance(v, (int, float))} \
        if isinstance(data, dict) else {}


def _save_times(times: dict[str, float]) -> None:
    path = _times_path()
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(times, indent=1, sort_keys=True))
    except OSError:  # a read-only install keeps its estimates
        pass


def expected_seconds(unit: Unit, measured: dict[str, float]) -> float:
    """Expected compile time of ``unit`` [s]: what it took the last time it compiled
    (``measured``, by unit name), else :data:`ESTIMATE` of its kind."""
    return measured.get(unit.name, ESTIMATE[unit.kind])


def _say(text: str) -> None:
    print(f"jvl_gym compile: {text}", file=sys.stderr, flush=True)


def compile_units(units: Sequence[Unit], workers: int | None = None,
                  say: Callable[[str], None] = _say,
                  run: Callable[[Unit], float] = _run) -> dict[str, float]:
    """Compile ``units`` in ``workers`` spawned processes (default: the CPU count), each unit
    once all units it comes ``after`` have finished, with a line to ``say`` as each starts
    (and its expected time) and ends. ``run`` (a picklable function) does a unit's work in
    the worker and returns its wall time. Returns the wall time of each unit's work [s], by
    name; the times of units that compiled (rather than loaded from the cache) are kept for
    the next run's expectations."""
    measured = _load_times()
    pending = list(units)
    total = len(pending)
    done: dict[str, float] = {}
    running: dict[Future[float], tuple[Unit, float]] = {}
    workers = max(1, min(workers or os.cpu_count() or 1, total or 1))
    # spawned, not forked: the parent may have started numba's worker threads
    with ProcessPoolExecutor(max_workers=workers,
                             mp_context=multiprocessing.get_context("spawn")) as pool:
        while pending or running:
            ready = [u for u in pending if all(a in done for a in u.after)]
            for unit in ready[:workers - len(running)]:
                pending.remove(unit)
                say(f"[{total - len(pending)}/{total}] {unit.name}: compiling, expected "
                    f"{expected_seconds(unit, measured):.0f} s")
                running[pool.submit(run, unit)] = (unit, time.perf_counter())
            finished, _ = wait(running, return_when=FIRST_COMPLETED)
            for future in finished:
                unit, start = running.pop(future)
                seconds = future.result()  # a failure ends the run with the worker's exception
                done[unit.name] = seconds
                if seconds >= _CACHED_BELOW:
                    measured[unit.name] = round(seconds, 1)
                say(f"{unit.name}: done in {seconds:.1f} s, {time.perf_counter() - start:.1f} s "
                    f"with its process ({len(done)}/{total})")
    _save_times(measured)
    return done


def compile_all(workers: int | None = None, envs: bool = True,
                motor_types: Iterable[str] | None = None) -> dict[str, float]:
    """Compile the motor arrays of the families of ``motor_types`` (default: every family)
    and, with ``envs``, every registered environment on each family it runs on, in
    ``workers`` processes (:func:`compile_units`). Returns the wall time of each unit [s]."""
    from ..envs.registration import ENV_IDS

    motors = motor_units(motor_types)
    units = motors + (env_units(ENV_IDS, motors) if envs else [])
    return compile_units(units, workers)


def main() -> None:  # pragma: no cover - command line
    """``python -m jvl_gym.cli.precompile [--motors-only]``."""
    compile_all(envs="--motors-only" not in sys.argv[1:])


if __name__ == "__main__":  # pragma: no cover
    main()
