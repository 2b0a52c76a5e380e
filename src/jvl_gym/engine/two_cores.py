"""A family's first compile on two cores: part of it in a second process (:func:`prepare`).

numba compiles in one thread. Before a driver's first compile, the engine compiles the large
functions the driver calls, which a family lists in two independent halves
(``compile_split(arrays) -> (beside, here)``, each a list of ``(dispatcher, argument types)``
of functions that numba caches on their own, such as those compiled apart,
:mod:`jvl_gym.engine.apart`). When the first of ``beside`` is not in numba's on-disk cache
yet, a second Python process compiles ``beside`` into the cache while this one compiles
``here``; then this one loads what the other process cached. The machine code is the same
either way (each function is compiled on its own, for the same types); only the wall time of a
cold start changes. A family without ``compile_split`` compiles them in its own
``prepare(arrays)``.

The second process is not started when the cache is warm, on a machine with one CPU, when
numba keeps no on-disk cache, inside such a second process, or with ``JVL_COMPILE_ALONE=1``.
If it fails or takes longer than :data:`TIMEOUT`, this process compiles what it had to;
nothing depends on it.
"""

from __future__ import annotations

import importlib
import os
import pickle
import subprocess
import sys
from collections.abc import Callable
from typing import Any

from .apart import _APART

__all__ = ["start", "prepare", "start_beside", "finish_beside", "TIMEOUT"]

#: the second process's time limit [s]: this process compiles the rest itself after it
TIMEOUT = 600.0
#: set in the second process (and by a user who wants one process): no further process
ALONE = "JVL_COMPILE_ALONE"
#: the families (compiled modules) whose second process was considered, and those running
_started: set[str] = set()
_children: dict[str, subprocess.Popen] = {}
#: the families (compiled modules) whose functions :func:`prepare` compiled or loaded
_prepared: set[str] = set()


def _cold(dispatcher: Any) -> bool:
    """True when numba's on-disk cache holds nothing of ``dispatcher`` yet (no index file);
    False when it does, or when numba keeps no cache for it."""
    cache_file = getattr(getattr(dispatcher, "_cache", None), "_cache_file", None)
    index = getattr(cache_file, "_index_path", None)
    return index is not None and not os.path.exists(index)


def _start(module: str, beside: list[tuple[Any, tuple]]) -> subprocess.Popen | None:
    """A second process compiling ``beside`` (after importing the family's compiled module
    ``module``), or None when it should not run (the module docstring)."""
    if (os.environ.get(ALONE) == "1" or (os.cpu_count() or 1) < 2 or not beside
            or not _cold(beside[0][0])):
        return None
    job = [(d.py_func.__module__, d.py_func.__qualname__, tuple(sig)) for d, sig in beside]
    # the same interpreter, environment (numba's cache folder) and import path as this process
    env = {**os.environ, ALONE: "1", "JVL_QUIET_COMPILE": "1",
           "PYTHONPATH": os.pathsep.join(path for path in sys.path if path)}
    try:
        child = subprocess.Popen([sys.executable, "-m", __name__], stdin=subprocess.PIPE,
                                 stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env)
        assert child.stdin is not None
        child.stdin.write(pickle.dumps((module, job)))
        child.stdin.close()
    except (OSError, pickle.PicklingError):
        return None
    return child


def start(compiled: Any, arrays: tuple) -> None:
    """Start the second process on the ``beside`` half of the family's ``compile_split``
    when its cache is cold (once per process and family; nothing without ``compile_split``).
    A motor array calls it as soon as its arrays exist, so that the other process works while
    this one compiles the power-on; :func:`prepare` starts it otherwise. The parameters are
    :func:`prepare`'s.
    """
    split = getattr(compiled, "compile_split", None)
    if split is None or compiled.__name__ in _started:
        return
    _started.add(compiled.__name__)
    child = _start(compiled.__name__, split(arrays)[0])
    if child is not None:
        _children[compiled.__name__] = child


def prepare(compiled: Any, arrays: tuple) -> None:
    """Compile (or load) the family's large compiled functions for ``arrays`` (the fields of
    an :class:`~jvl_gym.engine.view.EngineView`) before a driver's first compile, once per
    process: both halves of its ``compile_split``, the ``here`` half while the second process
    (:func:`start`) compiles the other when the cache was cold; a family without
    ``compile_split`` runs its own ``prepare(arrays)``.

    Parameters
    ----------
    compiled : module
        The family's compiled-step module (``Family.compiled``).
    arrays : tuple
        The fields of the motors' engine view.
    """
    split = getattr(compiled, "compile_split", None)
    if split is None:
        compiled.prepare(arrays)
        return
    if compiled.__name__ in _prepared:
        return
    start(compiled, arrays)
    beside, here = split(arrays)
    child = _children.pop(compiled.__name__, None)
    if child is not None:
        for dispatcher, sig in here:
            dispatcher.compile(sig)
        _wait(child)
    for dispatcher, sig in (*beside, *here):  # loads what the other process cached
        dispatcher.compile(sig)
    _prepared.add(compiled.__name__)


def _wait(child: subprocess.Popen) -> None:
    """Wait for a second process, at most :data:`TIMEOUT` (then it is stopped)."""
    try:
        child.wait(TIMEOUT)
    except subprocess.TimeoutExpired:
        child.kill()
        child.wait()


def start_beside(name: str, listing: Callable[[], list[tuple[Any, tuple]]]) -> None:
    """Start a second process on ``listing()`` (``(dispatcher, argument types)`` of functions
    numba caches on their own) when the first of them is not in the cache yet, once per
    process and ``name``: an environment's own functions its step calls, compiled there while
    this process compiles what the environment's first reset needs. :func:`finish_beside`
    waits for it. ``listing`` is called only the first time."""
    if name in _started:
        return
    _started.add(name)
    beside = listing()
    child = _start(beside[0][0].py_func.__module__, beside)
    if child is not None:
        _children[name] = child


def finish_beside(name: str, listing: Callable[[], list[tuple[Any, tuple]]]) -> None:
    """Wait for the second process :func:`start_beside` started for ``name``, if any, then
    compile or load ``listing()`` here (from the cache it filled); once per process and
    ``name``."""
    if name in _prepared:
        return
    child = _children.pop(name, None)
    if child is not None:
        _wait(child)
    for dispatcher, sig in listing():
        dispatcher.compile(sig)
    _prepared.add(name)


def _compile_job(module: str, job: list[tuple[str, str, tuple]]) -> None:
    """In the second process: import ``module`` (which defines the apart functions), then
    compile each ``(module, qualified name, argument types)`` of ``job`` into the cache."""
    importlib.import_module(module)
    for mod, qualname, sig in job:
        dispatcher = _APART.get((mod, qualname))
        if dispatcher is None:
            dispatcher = getattr(importlib.import_module(mod), qualname)
        dispatcher.compile(sig)


if __name__ == "__main__":  # the second process: the job on stdin
    _compile_job(*pickle.loads(sys.stdin.buffer.read()))
