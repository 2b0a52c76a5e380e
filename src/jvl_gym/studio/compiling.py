"""What numba is compiling now, for the pages' compile notice.

On a first start numba compiles the kernels of each family the studio runs (minutes, once per
machine and source version; :mod:`jvl_gym.engine.notice` says so on stderr). Meanwhile the
simulated motors do not step and the pages show no values; a listener on numba's
``numba:compile`` event (raised only on a cache miss) keeps the jvl_gym function being compiled
and since when, so the pages can say why they wait.
"""

from __future__ import annotations

import threading
import time
from typing import Any

__all__ = ["CompileWatch", "install", "current"]


class CompileWatch:
    """The top-level jvl_gym compiles in progress (of any thread)."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._local = threading.local()
        self._running: dict[int, tuple[str, float]] = {}

    def on_start(self, ev: Any) -> None:
        """A compile starts (numba's event)."""
        depth = getattr(self._local, "depth", 0)
        self._local.depth = depth + 1
        fn = getattr(ev.data.get("dispatcher"), "py_func", None)
        module = getattr(fn, "__module__", "") or ""
        if depth == 0 and module.split(".")[0] in ("jvl_gym", "tuning"):
            with self._lock:
                self._running[threading.get_ident()] = (
                    f"{module}.{fn.__qualname__}", time.monotonic())

    def on_end(self, ev: Any) -> None:
        """A compile ends (numba's event)."""
        self._local.depth = max(0, getattr(self._local, "depth", 1) - 1)
        if self._local.depth == 0:
            with self._lock:
                self._running.pop(threading.get_ident(), None)

    def current(self) -> str | None:
        """``"compiling <function> (<s> s)"`` of the longest-running compile, None if none."""
        with self._lock:
            if not self._running:
                return None
            name, start = min(self._running.values(), key=lambda v: v[1])
        return (f"compiling {name} for this machine ({time.monotonic() - start:.0f} s; once "
                "per machine and version, then loaded from the cache): values follow")


_watch: list[CompileWatch] = []


def install() -> CompileWatch:
    """Register the watch with numba (once per process) and return it."""
    if not _watch:
        from numba.core import event

        class Listener(CompileWatch, event.Listener):
            pass

        listener = Listener()
        event.register("numba:compile", listener)
        _watch.append(listener)
    return _watch[0]


def current() -> str | None:
    """The compile notice now (None when nothing compiles or the watch is not installed)."""
    return _watch[0].current() if _watch else None
