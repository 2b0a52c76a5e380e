"""Draws of many numpy generators in one compiled call: the uniform numbers and raw 64-bit
words of an env's reset, one generator per copy.

An env keeps one ``numpy.random.Generator`` per copy (``envs.randomisation``), and a reset of M
copies draws from each of them. Calling ``Generator.random`` and ``BitGenerator.random_raw``
once per copy costs a Python call each; :func:`draw_rows` (and :func:`uniform_rows`, its
uniform half) make the same draws in one compiled loop instead. The loop calls numpy's own
C functions, through the addresses its bit generators publish (``BitGenerator.ctypes``:
``next_double``, ``next_uint64`` and the state): ``Generator.random`` fills an array with
``next_double`` and ``random_raw`` with the generator's raw output, which is ``next_uint64``
for PCG64 (the bit generator of ``numpy.random.default_rng``). The numbers and the generators'
states are therefore those of the numpy calls, bit for bit, and a generator may go on with
numpy calls after a compiled draw. A generator of another kind is drawn from by the numpy calls
themselves.
"""

from __future__ import annotations

import ctypes
from collections.abc import Sequence

import llvmlite.ir as llvm_ir
import numpy as np
from numba import njit, types
from numba.extending import intrinsic

__all__ = ["draw_rows", "uniform_rows"]


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
def _fill(next_double: int, next_uint64: int, states: np.ndarray, uniform: np.ndarray,
          raw: np.ndarray) -> None:  # pragma: no cover - compiled
    """Row ``j`` of ``uniform`` ((M, W) float64), then row ``j`` of ``raw`` ((M, V) uint64),
    from the generator whose state is at ``states[j]``: what ``Generator.random(out=row)``
    and then ``BitGenerator.random_raw(V)`` (PCG64) give."""
    for j in range(states.shape[0]):
        state = states[j]
        for k in range(uniform.shape[1]):
            uniform[j, k] = _next_double(next_double, state)
        for k in range(raw.shape[1]):
            raw[j, k] = _next_uint64(next_uint64, state)


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


def draw_rows(rngs: Sequence[np.random.Generator], width: int, raw_width: int
              ) -> tuple[np.ndarray, np.ndarray]:
    """Per generator of ``rngs``, ``width`` uniform numbers in [0, 1) and then ``raw_width``
    raw 64-bit words: ``(uniform, raw)``, (len(rngs), width) float64 and (len(rngs),
    raw_width) uint64, row ``j`` what ``rngs[j].random(width)`` and then
    ``rngs[j].bit_generator.random_raw(raw_width)`` return; each generator moves on as it
    would."""
    uniform = np.empty((len(rngs), width))
    raw = np.empty((len(rngs), raw_width), dtype=np.uint64)
    states = _states(rngs)
    if states is None:
        for j, rng in enumerate(rngs):
            rng.random(out=uniform[j])
            raw[j] = rng.bit_generator.random_raw(raw_width)
    else:
        _fill(_NEXT_DOUBLE, _NEXT_UINT64, states, uniform, raw)
    return uniform, raw


def uniform_rows(rngs: Sequence[np.random.Generator], width: int) -> np.ndarray:
    """Uniform numbers in [0, 1), (len(rngs), width) float64: row ``j`` is what
    ``rngs[j].random(width)`` returns (:func:`draw_rows`)."""
    return draw_rows(rngs, width, 0)[0]
