"""Sine and cosine in plain arithmetic (no library call, no branch), for the plant's rotor angle.

The coil needs ``e^{jθe}`` every 128 µs. The C library's ``sincos`` saves and restores the
floating-point control register on every call (a slow instruction on some x86 cores, AMD's
among them) and, being a call, keeps the compiler from stepping several motors in SIMD lanes
(``jvl_gym.families.mac050_141.lanes``). This is the classic fdlibm method instead:

- reduction to ``r ∈ [−π/4, π/4]``: ``n = round(x·2/π)``, ``r = x − n·π/2`` with π/2 split in
  three parts whose products with ``n`` are exact for ``|n| < 2²⁰`` (Cody–Waite);
- the fdlibm minimax polynomials of sin and cos on that interval (``__kernel_sin``,
  ``__kernel_cos``, error below 1 ulp of the result);
- the quadrant ``n mod 4`` picks ±sin r / ±cos r by selects.

Error against the correctly rounded values (tests/test_plant.py): at most a few units in the
last place for ``|x| < 1.6e6`` rad. Beyond, the reduction loses what ``x`` itself can no longer
resolve (its spacing grows to 2⁻³² rad at 1.6e6): the error stays of the order of that spacing.
"""

from __future__ import annotations

import llvmlite.ir as llvm_ir
import numpy as np
from numba import njit, types
from numba.extending import intrinsic

from ..engine.jit import KERNEL


@intrinsic
def fma(typingctx, a, b, c):  # pragma: no cover - compiled
    """``a·b + c`` with one rounding (LLVM's ``llvm.fma.f64``: the FMA instruction)."""
    sig = types.float64(types.float64, types.float64, types.float64)

    def codegen(context, builder, signature, args):
        double = llvm_ir.DoubleType()
        fn = builder.module.declare_intrinsic(
            "llvm.fma", [double], llvm_ir.FunctionType(double, [double, double, double]))
        return builder.call(fn, args)

    return sig, codegen

_TWO_OVER_PI = 6.36619772367581382433e-01
# π/2 = _PIO2_1 + _PIO2_2 + _PIO2_3 (+ 2e-40); _PIO2_1 and _PIO2_2 have 33 significant bits
_PIO2_1 = 1.57079632673412561417e+00
_PIO2_2 = 6.07710050630396597660e-11
_PIO2_3 = 2.02226624871116645580e-21
# fdlibm __kernel_sin / __kernel_cos coefficients
_S1 = -1.66666666666666324348e-01
_S2 = 8.33333333332248946124e-03
_S3 = -1.98412698298579493134e-04
_S4 = 2.75573137070700676789e-06
_S5 = -2.50507602534068634195e-08
_S6 = 1.58969099521155010221e-10
_C1 = 4.16666666666666019037e-02
_C2 = -1.38888888888741095749e-03
_C3 = 2.48015872894767294178e-05
_C4 = -2.75573143513906633035e-07
_C5 = 2.08757232129817482790e-09
_C6 = -1.13596475577881948265e-11


@njit(cache=True, inline="always")
def sincos(x: float) -> tuple[float, float]:
    """``(sin x, cos x)`` for a finite angle ``x`` [rad] (module docstring: method, error)."""
    n = np.floor(x * _TWO_OVER_PI + 0.5)
    r = ((x - n * _PIO2_1) - n * _PIO2_2) - n * _PIO2_3
    z = r * r
    sin_r = r + r * z * fma(z, fma(z, fma(z, fma(z, fma(z, _S6, _S5), _S4), _S3), _S2), _S1)
    hz = 0.5 * z
    w = 1.0 - hz
    cos_r = w + (((1.0 - w) - hz)
                 + z * z * fma(z, fma(z, fma(z, fma(z, fma(z, _C6, _C5), _C4), _C3), _C2), _C1))
    q = n - 4.0 * np.floor(n * 0.25)  # quadrant 0..3
    s = sin_r if q == 0.0 else (cos_r if q == 1.0 else (-sin_r if q == 2.0 else -cos_r))
    co = cos_r if q == 0.0 else (-sin_r if q == 1.0 else (-cos_r if q == 2.0 else sin_r))
    return s, co


@njit(**KERNEL, forceinline=True)
def sine(x: float) -> float:
    """``sin x`` for a finite angle ``x`` [rad]: :func:`sincos`'s sine, compiled once as a
    function of its own that LLVM inlines into each caller, so that a caller with several sines
    types and lowers one copy of :func:`sincos`, not one per call."""
    return sincos(x)[0]
