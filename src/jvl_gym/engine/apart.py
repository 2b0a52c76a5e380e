"""Compiled functions that compiled callers call, not copy (:func:`apart`).

numba compiles a call from one compiled function to another by linking the callee's whole
machine-independent code (LLVM IR) into the caller's module and optimising the result again,
so that LLVM may inline the callee. For a large callee called once per sample — a family's
firmware step, a block's inner samples — LLVM inlines nothing, but every caller pays the
optimisation of the callee and of everything it calls once more: an env's compiled step, with
the family kernel compiled and cached already, spent most of its compile time optimising the
kernel again, and each driver level (block, serial, threaded) did the same.

A function made :func:`apart` is compiled (or loaded from numba's cache) once, on its own, and
its compiled callers call its machine code: a direct call of a symbol whose name stands for
the function and its argument types (:func:`symbol`), not a copy. Each process gives that
symbol the address of the function's machine code when the function is compiled or loaded
for those types; a caller loaded from numba's cache first loads its apart callees (numba runs
the loaders a cached function records before it loads the function's machine code), so the
symbol is always defined before code that calls it is loaded. The symbol's name does not
depend on the process (numba's own names of compiled functions do), so a caller compiled in
one process calls the callee compiled in another.

The callee's code is the same machine code either way (a plain call, as numba compiles a call
LLVM does not inline); only where it lives changes.
"""

from __future__ import annotations

import hashlib
import importlib
from typing import Any

from llvmlite import binding as ll
from numba.core import cgutils, imputils
from numba.core.registry import CPUDispatcher

__all__ = ["apart", "symbol"]

#: apart functions by (module, qualified name), for the loaders of cached callers
_APART: dict[tuple[str, str], Any] = {}


def symbol(fndesc: Any) -> str:
    """The symbol compiled callers call a compiled function by (numba's function descriptor
    ``fndesc``): its module, qualified name and a digest of its argument and return types'
    descriptions (numba's own names of compiled functions differ between processes: they
    count compiled functions and record types)."""
    types = repr((tuple(str(a) for a in fndesc.argtypes), str(fndesc.restype)))
    digest = hashlib.sha256(types.encode()).hexdigest()[:24]
    return f"jvl_gym.apart.{fndesc.modname}.{fndesc.qualname}.{digest}"


class _Load:
    """Compile or load apart function ``qualname`` of module ``module`` for ``argtypes`` and
    give its machine code the symbol ``name`` (the one a caller calls): a loader a cached
    caller records (picklable, hashable)."""

    def __init__(self, module: str, qualname: str, argtypes: tuple, name: str) -> None:
        self.module = module
        self.qualname = qualname
        self.argtypes = argtypes
        self.name = name

    def _key(self) -> tuple:
        return (self.module, self.qualname, self.name)

    def __eq__(self, other: object) -> bool:
        return isinstance(other, _Load) and self._key() == other._key()

    def __hash__(self) -> int:
        return hash(self._key())

    def __call__(self) -> None:
        if ll.address_of_symbol(self.name):
            return
        dispatcher = _APART.get((self.module, self.qualname))
        if dispatcher is None:
            importlib.import_module(self.module)
            dispatcher = _APART.get((self.module, self.qualname))
        if dispatcher is None:
            raise RuntimeError(f"compiled code calls {self.module}.{self.qualname}, which is "
                               "not defined yet in this process (define it before its callers)")
        dispatcher.compile(self.argtypes)
        _define(self.name, dispatcher.overloads[tuple(self.argtypes)])


def _define(name: str, cres: Any) -> None:
    """Give the machine code of compile result ``cres`` the symbol ``name``."""
    address = cres.library.get_pointer_to_function(cres.fndesc.llvm_func_name)
    if not address:
        raise RuntimeError(f"no machine code for {cres.fndesc.qualname}")
    ll.add_symbol(name, address)


def _call(fndesc: Any, load: _Load) -> Any:
    """numba's lowering of a call of ``fndesc``: a direct call of its symbol ``load.name``
    (numba's own lowering, ``imputils.user_function``, links a copy of the callee's code)."""
    name = load.name

    def imp(context: Any, builder: Any, sig: Any, args: Any) -> Any:
        load()  # defined in this process before the caller is loaded
        context.active_code_library._reload_init.add(load)  # and in every later one
        fnty = context.call_conv.get_function_type(fndesc.restype, fndesc.argtypes)
        fn = cgutils.get_or_insert_function(builder.module, fnty, name)
        context.apply_target_attributes(fn, fndesc.argtypes, fndesc.restype)
        context.call_conv.decorate_function(fn, fndesc.args, fndesc.argtypes,
                                            noalias=fndesc.noalias)
        status, retval = context.call_conv.call_function(builder, fn, fndesc.restype,
                                                         fndesc.argtypes, args)
        with cgutils.if_unlikely(builder, status.is_error):
            context.call_conv.return_status_propagate(builder, status)
        retval = imputils.fix_returning_optional(context, builder, sig, status, retval)
        return imputils.impl_ret_new_ref(context, builder, fndesc.restype, retval)

    imp.signature = fndesc.argtypes
    imp.libs = ()
    return imp


class Apart(CPUDispatcher):
    """A compiled function whose compiled callers call its machine code (:func:`apart`)."""

    def add_overload(self, cres: Any) -> None:
        super().add_overload(cres)
        fndesc = cres.fndesc
        name = symbol(fndesc)
        _define(name, cres)
        context = cres.target_context
        context.remove_user_function(cres.entry_point)
        impl = _call(fndesc, _Load(fndesc.modname, fndesc.qualname, fndesc.argtypes, name))
        context._defns[cres.entry_point].append(impl, impl.signature)


def apart(dispatcher: Any) -> Any:
    """Make the compiled function ``dispatcher`` (a ``numba.njit`` dispatcher, not compiled
    yet, not ``inline="always"``) one that compiled callers call instead of linking a copy
    (the module docstring). Returns it; it is known by its module and qualified name, which
    must be unique among such functions."""
    if dispatcher.overloads:
        raise ValueError(f"{dispatcher.py_func.__qualname__} is compiled already")
    dispatcher.__class__ = Apart
    _APART[(dispatcher.py_func.__module__, dispatcher.py_func.__qualname__)] = dispatcher
    return dispatcher
