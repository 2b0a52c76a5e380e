"""Say on stderr when numba starts compiling jvl_gym code, and how long it took.

numba compiles a function on its first call in a process unless its machine code is in the
on-disk cache (``__pycache__`` beside the source); a cache miss means a compile of up to a
minute or more for the kernel. A listener on numba's ``numba:compile`` event, which numba
raises only on a cache miss and before compiling, prints one line before each top-level
compile of a jvl_gym or tuning function and, when it took more than a second, one line after.
Set ``JVL_QUIET_COMPILE=1`` to silence it.
"""

from __future__ import annotations

import importlib.abc
import importlib.util
import os
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

__all__ = ["install", "install_on_import"]

_PACKAGES = ("jvl_gym", "tuning")
#: compiles shorter than this are not reported when they end [s]
_REPORT_AFTER = 1.0


class _CompileNotice:
    """Prints a line per top-level compile of a jvl_gym function (nested compiles of the
    functions it calls are part of it); registered as a ``numba.core.event.Listener``
    (:func:`install`)."""

    def __init__(self) -> None:
        self._local = threading.local()
        self._announced = False

    def _stack(self) -> list[tuple[str, float] | None]:
        stack = getattr(self._local, "stack", None)
        if stack is None:
            stack = self._local.stack = []
        return stack

    def on_start(self, ev: Any) -> None:
        stack = self._stack()
        name = _name(ev.data.get("dispatcher"))
        if stack or name is None:
            stack.append(None)
            return
        if not self._announced:
            self._announced = True
            _say("compiling numba code for this machine: once per machine and source "
                 f"version, then loaded from the cache ({_cache_dir()}) in about a second")
        _say(f"compiling {name} ...")
        stack.append((name, time.perf_counter()))

    def on_end(self, ev: Any) -> None:
        stack = self._stack()
        if not stack:
            return
        top = stack.pop()
        if top is not None and not stack:
            name, start = top
            elapsed = time.perf_counter() - start
            if elapsed >= _REPORT_AFTER:
                _say(f"compiled {name} in {elapsed:.1f} s")


def _name(dispatcher: Any) -> str | None:
    """``module.function`` of a jvl_gym dispatcher, else None."""
    fn = getattr(dispatcher, "py_func", None)
    module = getattr(fn, "__module__", "") or ""
    if module.split(".")[0] not in _PACKAGES:
        return None
    return f"{module}.{fn.__qualname__}"


def _cache_dir() -> str:
    here = Path(__file__).resolve().parent.parent
    return os.environ.get("NUMBA_CACHE_DIR") or str(here / "**" / "__pycache__")


def _say(text: str) -> None:
    print(f"jvl_gym: {text}", file=sys.stderr, flush=True)


_installed: list[Any] = []


def install() -> None:
    """Register the notice with numba (once per process; no-op with JVL_QUIET_COMPILE=1)."""
    if _installed or os.environ.get("JVL_QUIET_COMPILE") == "1":
        return
    from numba.core import event

    class Listener(_CompileNotice, event.Listener):
        pass

    listener = Listener()
    event.register("numba:compile", listener)
    _installed.append(listener)


class _AfterImport(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """A one-shot meta-path hook that calls ``then()`` once the module ``name`` is imported
    (the module is found by the other finders and executed by its own loader)."""

    def __init__(self, name: str, then: Callable[[], None]) -> None:
        self.name, self.then = name, then
        self.loader: Any = None

    def find_spec(self, fullname: str, path: Any = None, target: Any = None) -> Any:
        if fullname != self.name:
            return None
        sys.meta_path.remove(self)
        spec = importlib.util.find_spec(fullname)
        if spec is not None and spec.loader is not None:
            self.loader, spec.loader = spec.loader, self
        return spec

    def create_module(self, spec: Any) -> Any:
        return self.loader.create_module(spec)

    def exec_module(self, module: Any) -> None:
        # the module keeps its own loader (resources, reloads); this hook only runs it
        module.__loader__ = module.__spec__.loader = self.loader
        self.loader.exec_module(module)
        self.then()


def install_on_import() -> None:
    """:func:`install` now if numba is loaded, else as soon as it is: nothing compiles before
    numba is imported, and a command that compiles nothing (``--help``) never loads it."""
    if "numba" in sys.modules:
        install()
    elif not any(isinstance(f, _AfterImport) for f in sys.meta_path):
        sys.meta_path.insert(0, _AfterImport("numba", install))
