"""Register arithmetic of the firmware (manual 3.1): rounding, saturation, fixed-point reads.

A value the firmware stores in a register is rounded (half away from zero) and saturated to the
register's format at the moment it is stored (docs/model.md §4); blocks then read the stored value.
"""

from __future__ import annotations

import llvmlite.ir as llvm_ir
from numba import njit, types
from numba.extending import intrinsic


def _double_intrinsic(builder, name: str, args):  # pragma: no cover - compiled
    """A call of LLVM's intrinsic ``name`` on a double, in the code an intrinsic emits."""
    double = llvm_ir.DoubleType()
    fn = builder.module.declare_intrinsic(name, [double], llvm_ir.FunctionType(double, [double]))
    return builder.call(fn, args)


@intrinsic
def _round(typingctx, x):  # pragma: no cover - compiled
    """LLVM's ``llvm.round.f64``: C's ``round``, half away from zero, exact for every double."""
    return types.float64(types.float64), lambda context, builder, signature, args: (
        _double_intrinsic(builder, "llvm.round", args))


@intrinsic
def _rint(typingctx, x):  # pragma: no cover - compiled
    """LLVM's ``llvm.rint.f64``: round half to even (the default rounding mode)."""
    return types.float64(types.float64), lambda context, builder, signature, args: (
        _double_intrinsic(builder, "llvm.rint", args))


@njit(cache=True, inline="always")
def rint(x: float) -> float:
    """Round half to even, as ``np.round(x)`` (``np.rint``) of a float, returned as float64.

    The same instruction numba emits for ``np.round`` of a scalar float, without the code of
    ``np.round``'s ``decimals`` argument, which numba compiles into every caller (about a
    quarter of a second of each compiled env reset that used it).
    """
    return _rint(x)


@njit(cache=True, inline="always")
def rnd(x: float) -> float:
    """Round half away from zero, returned as float64 holding an integer.

    C's ``round`` as an LLVM intrinsic: no library call and no branch on the sign (the
    current loops round signals whose sign changes at random, and a mispredicted branch costs
    more than the whole rounding); the compiler emits ``trunc(x + copysign(0.5 − 2⁻⁵⁴, x))``,
    also in SIMD lanes.
    """
    return _round(x)


@njit(cache=True, inline="always")
def clamp(x: float, lo: float, hi: float) -> float:
    """Limit ``x`` to ``[lo, hi]`` (``lo`` when ``x < lo``, else ``hi`` when ``x > hi``).

    ``hi if hi < x else x`` is the form of the processor's minimum instruction (MINPD
    returns its second operand when either is NaN), which the compiler then emits instead of
    a compare and a blend; the result is the same for every ``x``, NaN included.
    """
    upper = hi if hi < x else x
    return lo if x < lo else upper


@njit(cache=True, inline="always")
def sat16(x: float) -> float:
    """Round and saturate to the Integer format (−32767..32767)."""
    return clamp(rnd(x), -32767.0, 32767.0)


@njit(cache=True, inline="always")
def wrap32(x: int) -> int:
    """Wrap an integer to signed 32 bits, as a LongInt register does."""
    return ((x + 2147483648) % 4294967296) - 2147483648


@njit(cache=True, inline="always")
def fx4(raw: int) -> float:
    """Fixed4 register value (raw / 4096)."""
    return raw / 4096.0


@njit(cache=True, inline="always")
def fx8(raw: int) -> float:
    """Fixed8 register value (raw / 256)."""
    return raw / 256.0


@njit(cache=True, inline="always")
def sign(x: float) -> float:
    """−1, 0 or 1."""
    return 1.0 if x > 0.0 else (-1.0 if x < 0.0 else 0.0)
