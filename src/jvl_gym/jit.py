"""Compile options of the simulation kernel and the compiled environment steps (numba).

``KERNEL`` compiles without numba's reference-counting runtime (NRT). With NRT every
non-inlined call that takes arrays increments and decrements the reference count of each
array's memory block: atomic operations on a counter that every motor view of the same (N, ·)
array shares, so two threads stepping different motors fight over one cache line. Measured on
the 2-core development machine (2026-12-01): one current-loop sample 199 → 162 ns, Positioning
vector env with 1024 copies 520 000 → 655 000 env-steps/s, the two threads 1.54× → 1.94× one
thread. Kernel code therefore never allocates arrays (no NRT) and works on views and scalars.
"""

from __future__ import annotations

from typing import Any

#: keyword arguments of ``numba.njit`` for kernel functions (``@njit(**KERNEL)``)
KERNEL: dict[str, Any] = {"cache": True, "_nrt": False}
#: the same for the multi-threaded drivers
KERNEL_PARALLEL: dict[str, Any] = {**KERNEL, "parallel": True}
