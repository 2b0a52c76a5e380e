"""Compile options of the simulation kernel and the compiled environment steps (numba).

``KERNEL`` compiles without numba's reference-counting runtime (NRT). With NRT every
non-inlined call that takes arrays increments and decrements the reference count of each
array's memory block: atomic operations on a counter that every motor view of the same (N, ·)
array shares, so two threads stepping different motors fight over one cache line. Kernel code
therefore never allocates arrays (no NRT) and works on views and scalars. No fast-math flag:
even ``arcp`` alone (divisions as multiplications by reciprocals) made results depend on where
the compiler inlined a function: the threaded vector env and the single env then differed in
the last bit of a reward (docs/model.md §17).
"""

from __future__ import annotations

from typing import Any

from numba.core import types
from numba.core.base import BaseContext

#: keyword arguments of ``numba.njit`` for kernel functions (``@njit(**KERNEL)``)
KERNEL: dict[str, Any] = {"cache": True, "_nrt": False}
#: the same for the multi-threaded drivers
KERNEL_PARALLEL: dict[str, Any] = {**KERNEL, "parallel": True}
#: the functions of the current-loop samples (``mac050_141.lanes.inner_samples``, which steps
#: motors in SIMD lanes, and ``mac050_141.inner.inner_samples_one``, its one-motor path): numpy's
#: error model, so that a float division is a plain division, not a test for a zero divisor
#: with a branch to a ZeroDivisionError that keeps LLVM from vectorising the loop over lanes.
#: (A lane's divisors are parameters validated on the Python side and the bus voltage, which
#: the plant only divides by above 1 V.)
LANE_KERNEL: dict[str, Any] = {**KERNEL, "error_model": "numpy"}


def plain_arguments(dispatcher: Any) -> Any:
    """Make a compiled function (a numba dispatcher) compile once per plain argument types, not
    once per constant its compiled callers pass: numba types a constant argument (``True``,
    ``0``) as a literal and compiles the callee anew for each value, each time in full. With
    the callers' constants typed as plain bools and integers, one compiled body serves every
    call; a ``forceinline`` callee still gets the caller's constants, as LLVM inlines it and
    folds the branches on them. Returns ``dispatcher``, so that it decorates a function
    (``@plain_arguments`` above ``@njit``)."""
    resolve = dispatcher.get_call_template

    def get_call_template(args: tuple, kws: dict) -> Any:
        return resolve(tuple(types.unliteral(a) for a in args),
                       {k: types.unliteral(v) for k, v in kws.items()})

    dispatcher.get_call_template = get_call_template
    return dispatcher


#: the SIMD width [bits] LLVM may use in the loops of a :func:`widest_vectors` function: on a
#: machine with narrower registers LLVM uses its widest
WIDEST_VECTOR_BITS = 512
#: the functions made :func:`widest_vectors`, by (module, qualified name)
_WIDEST: set[tuple[str, str]] = set()


def widest_vectors(dispatcher: Any) -> Any:
    """Let LLVM vectorise the loops of a compiled function (a numba dispatcher, not compiled
    yet) with the machine's widest SIMD registers. Returns ``dispatcher``, so that it
    decorates a function (``@widest_vectors`` above ``@njit``).

    LLVM's tuning for recent Intel cores with AVX-512 (Skylake-X to Emerald Rapids) prefers
    256-bit vectors in loops, so numba's code of a lane loop uses 4 of its 8 float64 lanes.
    The lane loops of the motor families step 16 motors of a block in the same arithmetic:
    on the 2-core Emerald Rapids machine, with 512-bit vectors, a MAC140 array of 1024 motors
    runs about a third more inner samples per second on one thread (docs/envs.md, "SIMD
    lanes"). The results are the same bits: each lane's operations are the same IEEE
    operations in the same order, whatever the width (no fast-math flag, :data:`KERNEL`).

    numba has no option for it: the function's LLVM definition gets LLVM's
    ``"prefer-vector-width"`` attribute (:data:`WIDEST_VECTOR_BITS`) where numba declares
    it (``BaseContext.declare_function``), for this function only. The attribute is part of
    the compiled code, not of numba's cache key: numba compiles the function again when its
    file changes, and the decorator is in that file.
    """
    if dispatcher.overloads:
        raise ValueError(f"{dispatcher.py_func.__qualname__} is compiled already")
    _WIDEST.add((dispatcher.py_func.__module__, dispatcher.py_func.__qualname__))
    return dispatcher


_declare_function = BaseContext.declare_function


def _declare_widest(self: BaseContext, module: Any, fndesc: Any) -> Any:
    """``BaseContext.declare_function``, with the width attribute of :func:`widest_vectors`."""
    fn = _declare_function(self, module, fndesc)
    if (fndesc.modname, fndesc.qualname) in _WIDEST:
        # llvmlite's attribute set accepts LLVM's enumerated attributes only: a string
        # attribute is added to the underlying set and printed as it is
        set.add(fn.attributes, f'"prefer-vector-width"="{WIDEST_VECTOR_BITS}"')
    return fn


BaseContext.declare_function = _declare_widest  # type: ignore[method-assign]
