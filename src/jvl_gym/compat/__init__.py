"""The names of the previous release, kept for one release as deprecated aliases: the module
names of the previous layout (:data:`MOVED`) and renamed methods (:func:`renamed_method`).

Before the package was laid out by concept, the motor array, the command line and the MacTalk
and Modbus modules were loose modules (``jvl_gym.sim``, ``jvl_gym.cli_serve``,
``jvl_gym.protocol.client`` …). Importing one of those names still works: it returns the module
at its new place (the same module object, so classes and state are shared) and warns with a
:class:`DeprecationWarning` naming the new place; ``python -m`` with an old name runs the new
module. :data:`MOVED` maps each old name to its new one (docs/architecture.md). A renamed method
keeps its old name as a method that warns and calls the new one.
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.machinery
import importlib.util
import sys
import warnings
from collections.abc import Callable
from types import CodeType, ModuleType
from typing import Any

__all__ = ["MOVED", "install", "renamed_method"]

#: old module name → its module in the present layout
MOVED: dict[str, str] = {
    "jvl_gym.sim": "jvl_gym.motor.array",
    "jvl_gym.bank": "jvl_gym.motor.bank",
    "jvl_gym.flash": "jvl_gym.motor.flash",
    "jvl_gym.inputs": "jvl_gym.motor.inputs",
    "jvl_gym.stepping": "jvl_gym.motor.stepping",
    "jvl_gym.arguments": "jvl_gym.motor.arguments",
    "jvl_gym.keywords": "jvl_gym.motor.keywords",
    "jvl_gym.noise": "jvl_gym.motor.noise",
    "jvl_gym.cli_app": "jvl_gym.cli.app",
    "jvl_gym.cli_serve": "jvl_gym.cli.serve",
    "jvl_gym.cli_studio": "jvl_gym.cli.studio",
    "jvl_gym.cli_program": "jvl_gym.cli.program",
    "jvl_gym.precompile": "jvl_gym.cli.precompile",
    "jvl_gym.demo": "jvl_gym.cli.demo",
    "jvl_gym.trig": "jvl_gym.physics.trig",
    "jvl_gym.jit": "jvl_gym.engine.jit",
    "jvl_gym.config": "jvl_gym.families.config",
    "jvl_gym.coupling": "jvl_gym.physics.coupling",
    "jvl_gym.protocol.mactalk32": "jvl_gym.protocol.mactalk.codec32",
    "jvl_gym.protocol.fastmac": "jvl_gym.protocol.mactalk.fastmac",
    "jvl_gym.protocol.flexmac": "jvl_gym.protocol.mactalk.flexmac",
    "jvl_gym.protocol.stream": "jvl_gym.protocol.mactalk.stream",
    "jvl_gym.protocol.client": "jvl_gym.protocol.mactalk.client16",
    "jvl_gym.protocol.client32": "jvl_gym.protocol.mactalk.client32",
    "jvl_gym.protocol.master": "jvl_gym.protocol.mactalk.master",
    "jvl_gym.protocol.dialect": "jvl_gym.protocol.mactalk.dialect",
    "jvl_gym.protocol.probe": "jvl_gym.protocol.mactalk.probe",
    "jvl_gym.protocol.twin": "jvl_gym.protocol.mactalk.twin16",
    "jvl_gym.protocol.twin32": "jvl_gym.protocol.mactalk.twin32",
    "jvl_gym.protocol.bus": "jvl_gym.protocol.mactalk.line",
    "jvl_gym.protocol.transport": "jvl_gym.protocol.serving.transport",
    "jvl_gym.protocol.modbus_server": "jvl_gym.protocol.modbus.server",
    "jvl_gym.protocol.modbus_twin": "jvl_gym.protocol.modbus.twin",
}


def _warn(old: str, new: str) -> None:
    warnings.warn(f"{old} is deprecated and goes in the next release; import {new}",
                  DeprecationWarning, stacklevel=4)


class _AliasLoader(importlib.abc.Loader):
    """Loads an old name as the module at its new place."""

    def __init__(self, old: str, new: str) -> None:
        self.old, self.new = old, new

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> ModuleType:
        _warn(self.old, self.new)
        module = importlib.import_module(self.new)
        self._spec = module.__spec__  # the import system sets __spec__ to the alias's spec
        return module

    def exec_module(self, module: ModuleType) -> None:
        module.__spec__ = self._spec

    def get_code(self, fullname: str) -> CodeType:
        # ``python -m <old name>``: run the new module as __main__ (its own package, so that its
        # relative imports resolve)
        source = (f"import runpy, warnings\nwarnings.warn({self.old!r} + ' is deprecated: run '"
                  f" + {self.new!r}, DeprecationWarning, stacklevel=2)\n"
                  f"runpy.run_module({self.new!r}, run_name='__main__', alter_sys=True)\n")
        return compile(source, f"<{self.old}>", "exec")


class _AliasFinder(importlib.abc.MetaPathFinder):
    """Finds the old names of :data:`MOVED`."""

    def find_spec(self, fullname: str, path: object = None,
                  target: object = None) -> importlib.machinery.ModuleSpec | None:
        new = MOVED.get(fullname)
        if new is None:
            return None
        return importlib.util.spec_from_loader(fullname, _AliasLoader(fullname, new))


def install() -> None:
    """Put the finder of the old names on ``sys.meta_path`` (once)."""
    if not any(isinstance(f, _AliasFinder) for f in sys.meta_path):
        sys.meta_path.append(_AliasFinder())


def renamed_method(new: str, old: str) -> Callable[..., Any]:
    """A method named ``old`` that warns (DeprecationWarning) and calls ``self.<new>``, so that
    a subclass's override of ``new`` is what runs: ``go_safe_mode = renamed_method(
    "enter_safe_mode", "go_safe_mode")`` in a class body."""

    def method(self: Any, *args: Any, **kwargs: Any) -> Any:
        warnings.warn(f"{type(self).__name__}.{old} is deprecated and goes in the next release;"
                      f" use {new}", DeprecationWarning, stacklevel=2)
        return getattr(self, new)(*args, **kwargs)

    method.__name__ = method.__qualname__ = old
    method.__doc__ = f"Deprecated name of :meth:`{new}` (warns, then calls it)."
    return method
