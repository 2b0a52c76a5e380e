"""The MAC800's sample buffer: SAMPLE1–4 and REC_CNT (registers 158–162) with CNTRL_BITS
RECORDBIT, REWINDBIT and RECINNERBIT (register 36; bits 0–2).

The overview gives the names only; the buffer works as the MAC050–141's (its manual
3.2.112–3.2.116, decision): while RECORDBIT is set the registers numbered SAMPLE1 … SAMPLE4 are
stored at REC_CNT, which then counts up, every servo sample or, with RECINNERBIT, every
current-loop sample; RECORDBIT clears itself when the buffer holds 895 samples; REWINDBIT sets
REC_CNT = 0 and clears itself. Every register is 32 bits, so a sample is the stored value.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ....engine.jit import KERNEL
from .. import constants as c
from . import regs as R


@njit(cache=True, inline="always")
def _value(r: np.ndarray, num: int) -> int:
    return int(r[num]) if 1 <= num <= R.LAST else 0


@njit(**KERNEL)
def record(r: np.ndarray, buf: np.ndarray, store: bool) -> None:
    """Record one sample of SAMPLE1 … SAMPLE4 at REC_CNT; stop when full. ``store`` is False
    while no buffer is allocated (REC_CNT and RECORDBIT behave the same)."""
    n = int(r[R.REC_CNT])
    if n >= c.REC_CNT_MAX:
        r[R.CNTRL_BITS] &= ~c.RECORDBIT
        return
    if store:
        buf[n, 0] = _value(r, int(r[R.SAMPLE1]))
        buf[n, 1] = _value(r, int(r[R.SAMPLE2]))
        buf[n, 2] = _value(r, int(r[R.SAMPLE3]))
        buf[n, 3] = _value(r, int(r[R.SAMPLE4]))
    r[R.REC_CNT] = n + 1
    if n + 1 >= c.REC_CNT_MAX:
        r[R.CNTRL_BITS] &= ~c.RECORDBIT
