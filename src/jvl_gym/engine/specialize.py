"""Compiled functions written once and specialised for a motor family and a task.

The engine's drivers (:mod:`jvl_gym.engine.driver`) are plain Python functions that call a few
names they do not define: the family's compiled outer sample and block of inner samples, and a
task's hooks. :func:`specialise` binds those names and compiles the result with numba, so that
every call is resolved at compile time and inlined as if the driver had been written for that
family and task (no function pointers, no per-call argument transfer), while the driver's
source exists once.

Each specialisation is cached by numba like any ``cache=True`` function: under its own name
(``<driver>__<tag>``), next to the source file that defines what is bound into it (a task's
module, a family's module), so that an edit of that file or of the driver's code recompiles it.
"""

from __future__ import annotations

import types
from collections.abc import Callable, Mapping
from typing import Any

from numba import njit

from .apart import apart

__all__ = ["specialise"]


def specialise(templates: Mapping[str, Callable[..., Any]], bindings: Mapping[str, Any],
               tag: str, source: str, options: Mapping[str, Mapping[str, Any]]
               ) -> dict[str, Any]:
    """Compile-ready copies of the driver functions ``templates`` with ``bindings`` bound.

    Parameters
    ----------
    templates : mapping of str to function
        Driver functions by the name other templates call them by; their module's globals are
        the base of the namespace (a template that calls another gets its specialisation).
    bindings : mapping of str to object
        Names the templates use and do not define (compiled functions, integer constants).
    tag : str
        Identifies the specialisation in cache file names (an identifier: family and task).
    source : str
        Path of the Python file whose edits must invalidate the cached specialisations.
    options : mapping of str to mapping
        ``numba.njit`` keyword arguments per template name; ``apart=True`` among them makes
        the specialisation :func:`jvl_gym.engine.apart.apart` (its callers call it, not a copy).

    Returns
    -------
    dict of str to numba dispatcher
        The specialised functions by template name.
    """
    first = next(iter(templates.values()))
    namespace: dict[str, Any] = dict(first.__globals__)
    namespace.update(bindings)
    compiled: dict[str, Any] = {}
    for name, fn in templates.items():
        qualname = f"{fn.__name__}__{tag}"
        code = fn.__code__.replace(co_filename=source, co_name=qualname)
        copy = types.FunctionType(code, namespace, qualname, fn.__defaults__, fn.__closure__)
        copy.__qualname__ = qualname
        copy.__module__ = fn.__module__
        copy.__doc__ = fn.__doc__
        njit_options = dict(options[name])
        separate = njit_options.pop("apart", False)
        compiled[name] = njit(**njit_options)(copy)
        if separate:
            apart(compiled[name])
        namespace[name] = compiled[name]
    return compiled
