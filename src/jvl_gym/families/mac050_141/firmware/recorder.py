"""The sample buffer (manual 3.2.112–3.2.116, CNTRL_BITS RECORDBIT/REWINDBIT/RECINNERBIT).

While RECORDBIT is set, the registers named by SAMPLE1..SAMPLE4 are stored at REC_CNT, which then
increments, at the outer rate (520.8 Hz) or, with RECINNERBIT, at the inner rate (7812.5 Hz).
RECORDBIT clears itself when the buffer holds 895 samples. REWINDBIT sets REC_CNT = 0 and clears
itself. A sampled LongInt number stores the full 32-bit value; its high-word number stores the
high word.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ....engine.jit import KERNEL
from .. import constants as c
from . import regs as R


@njit(cache=True, inline="always")
def register_value(r: np.ndarray, num: int, fmt: np.ndarray) -> int:
    """Stored value of register ``num`` as the buffer sees it."""
    if num < 1 or num > 164:
        return 0
    if fmt[num] == 4:  # LongInt high word
        return (int(r[num - 1]) >> 16) & 0xFFFF
    return int(r[num])


@njit(**KERNEL)
def record(r: np.ndarray, buf: np.ndarray, fmt: np.ndarray, store: bool) -> None:
    """Record one sample of SAMPLE1..4 at REC_CNT; stop when full.

    ``store`` is False while the simulator has not allocated the buffer (no recording was ever
    requested through a write); REC_CNT and RECORDBIT behave the same either way.
    """
    n = int(r[R.REC_CNT])
    if n >= c.REC_CNT_MAX:
        r[R.CNTRL_BITS] &= ~c.RECORDBIT
        return
    if store:
        buf[n, 0] = register_value(r, int(r[R.SAMPLE1]), fmt)
        buf[n, 1] = register_value(r, int(r[R.SAMPLE2]), fmt)
        buf[n, 2] = register_value(r, int(r[R.SAMPLE3]), fmt)
        buf[n, 3] = register_value(r, int(r[R.SAMPLE4]), fmt)
    r[R.REC_CNT] = n + 1
    if n + 1 >= c.REC_CNT_MAX:
        r[R.CNTRL_BITS] &= ~c.RECORDBIT
