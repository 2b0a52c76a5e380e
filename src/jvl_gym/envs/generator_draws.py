"""Draws of many numpy generators in one compiled call: the uniform numbers and raw 64-bit
words of an env's reset, one generator per copy.

An env keeps one ``numpy.random.Generator`` per copy (``envs.randomisation``), and a reset of M
copies draws from each of them. Calling ``Generator.random`` and ``BitGenerator.random_raw``
once per copy costs a Python call each; :func:`uniform_rows` and :func:`raw_rows` make the same
draws in one compiled loop instead. The loop calls numpy's own C functions, through the
addresses its bit generators publish (``BitGenerator.ctypes``: ``next_double``,
``next_uint64`` and the state): ``Generator.random`` fills an array with ``next_double`` and
``random_raw`` with the generator's raw output, which is ``next_uint64`` for PCG64 (the
bit generator of ``numpy.random.default_rng``). The numbers and the generators' states are
therefore those of the numpy calls, bit for bit, and a generator may go on with numpy calls
after a compiled draw. A generator of another kind is drawn from by the numpy calls themselves.
"""

from __future__ import annotations

import ctypes
from collections.abc import Sequence

import llvmlite.ir as llvm_ir
import numpy as np
from numba import njit, types
from numba.extending import intrinsic

__all__ = ["raw_rows", "uniform_rows"]


def _call_state_function(builder, result, fn, state):  # pragma: no cover - compiled
    """The call ``fn(state)`` of a C function ``result (*)(void *)`` at address ``fn``."""
    void_p = llvm_ir.IntType(8).as_pointer()
    ftype = llvm_ir.FunctionType(result, [void_p])
    return builder.call(builder.inttoptr(fn, ftype.as_pointer()),
                        [builder.inttoptr(state, void_p)])


@intrinsic
def _next_double(typingctx, fn, state):  # pragma: no cover - compiled
    """``fn(state)`` for a bit generator's ``next_double`` at address ``fn`` (intp)."""
    return types.float64(types.intp, types.intp), lambda context, builder, signature, args: (
        _call_state_function(builder, llvm_ir.DoubleType(), *args))


@intrinsic
def _next_uint64(typingctx, fn, state):  # pragma: no cover - compiled
    """``fn(state)`` for a bit generator's ``next_uint64`` at address ``fn`` (intp)."""
    return types.uint64(types.intp, types.intp), lambda context, builder, signature, args: (
        _call_state_function(builder, llvm_ir.IntType(64), *args))


@njit(cache=True)
def _fill_uniform(fn: int, states: np.ndarray, out: np.ndarray) -> None:  # pragma: no cover
    """Row ``j`` of ``out`` ((M, W) float64) from the generator whose state is at
    ``states[j]``, in order, as ``Generator.random(out=row)`` fills it."""
    for j in range(out.shape[0]):
        state = states[j]
        for k in range(out.shape[1]):
            out[j, k] = _next_double(fn, state)


@njit(cache=True)
def _fill_raw(fn: int, states: np.ndarray, out: np.ndarray) -> None:  # pragma: no cover
    """Row ``j`` of ``out`` ((M, W) uint64) from the generator whose state is at ``states[j]``,
    as ``BitGenerator.random_raw(W)`` returns it for PCG64."""
    for j in range(out.shape[0]):
        state = states[j]
        for k in range(out.shape[1]):
            out[j, k] = _next_uint64(fn, state)


def _address(fn: ctypes._CFuncPtr) -> int:
    return ctypes.cast(fn, ctypes.c_void_p).value or 0


#: numpy's PCG64 ``next_double`` and ``next_uint64`` (one pair per process)
_PCG64_TYPE = np.random.PCG64
_PCG64 = _PCG64_TYPE(0).ctypes
_NEXT_DOUBLE = _address(_PCG64.next_double)
_NEXT_UINT64 = _address(_PCG64.next_uint64)


def _states(rngs: Sequence[np.random.Generator]) -> np.ndarray | None:
    """The state addresses of the generators ``rngs``, (M,) intp; None unless every one is a
    PCG64 generator (whose raw output is ``next_uint64``)."""
    addresses = []
    for rng in rngs:
        bit = rng.bit_generator
        if type(bit) is not _PCG64_TYPE:
            return None
        addresses.append(bit.ctypes.state_address)
    return np.array(addresses, dtype=np.intp)


def uniform_rows(rngs: Sequence[np.random.Generator], width: int) -> np.ndarray:
    """Uniform numbers in [0, 1), (len(rngs), width) float64: row ``j`` is what
    ``rngs[j].random(width)`` returns, and each generator moves on as it would."""
    u = np.empty((len(rngs), width))
    states = _states(rngs)
    if states is None:
        for row, rng in zip(u, rngs):
            rng.random(out=row)
    else:
        _fill_uniform(_NEXT_DOUBLE, states, u)
    return u


def raw_rows(rngs: Sequence[np.random.Generator], width: int) -> np.ndarray:
    """Raw 64-bit words, (len(rngs), width) uint64: row ``j`` is what
    ``rngs[j].bit_generator.random_raw(width)`` returns, and each generator moves on as it
    would."""
    out = np.empty((len(rngs), width), dtype=np.uint64)
    states = _states(rngs)
    if states is None:
        for row, rng in zip(out, rngs):
            row[:] = rng.bit_generator.random_raw(width)
    else:
        _fill_raw(_NEXT_UINT64, states, out)
    return out
