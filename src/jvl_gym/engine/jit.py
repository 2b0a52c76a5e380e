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
