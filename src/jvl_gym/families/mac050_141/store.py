"""Register stores of motor rows, compiled: the firmware's write rules, then the store.

:meth:`jvl_gym.MotorArray.write` and the batched ``MotorArray.write_many`` validate the values
(range, format, shape: ``jvl_gym.registers.formats``) in Python and hand the stored integers of
one or more registers to :func:`store_rows`, which checks and stores them register by register
for the selected motors: a plain register after the write rules of
``mac050_141.firmware.write_rules`` (GEARF2, COIL P1..P6, HOME_MODE, P_REG_P), a LongInt's high
word into its 32-bit value (manual 3.1), MODE_REG through the mode-change rules of manual 4.4
(``mac050_141.firmware.modes``) and the register rules, then the mode's entry actions. An env
resets one or two copies at a time: per motor these are a few scalar operations, which in numpy
over a handful of rows cost more in per-call overhead than the work.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ...engine.jit import KERNEL
from .firmware import regs as R
from .firmware.modes import OK, apply_request, check_request
from .firmware.write_rules import first_mode_refusal, first_write_refusal

__all__ = ["store_rows"]


@njit(**KERNEL)
def _store_word(regs: np.ndarray, i: int, num: int, high: bool,
                raw: int) -> None:  # pragma: no cover - compiled
    """Store ``raw`` in register ``num`` of motor ``i``; a LongInt high word (``high``) goes into
    bits 16–31 of the 32-bit value held in register ``num − 1`` (manual 3.1)."""
    if high:
        full = (raw << 16) | (regs[i, num - 1] & 0xFFFF)
        regs[i, num - 1] = ((full + 2**31) % 2**32) - 2**31
    else:
        regs[i, num] = raw


@njit(**KERNEL)
def store_rows(regs: np.ndarray, state: np.ndarray, idx: np.ndarray, nums: np.ndarray,
               high: np.ndarray, raws: np.ndarray) -> int:  # pragma: no cover - compiled
    """Check and store registers ``nums`` (in this order) of motors ``idx``.

    Parameters
    ----------
    regs, state : numpy.ndarray
        Register bank (N, N_REGS) int64 and firmware/plant state (N, N_STATE) float64 of all
        motors (``jvl_gym.families.mac050_141.layout``).
    idx : numpy.ndarray
        Motor indices, (M,) int64.
    nums : numpy.ndarray
        Register numbers, (K,) int64: no register-mode pointer (``write_rules.POINTERS``), and
        MODE_REG only with a mode request 0..24 (not the SAFE_MODE commands 256..258).
    high : numpy.ndarray
        (K,) bool: register ``nums[k]`` is a LongInt's high word.
    raws : numpy.ndarray
        Stored integers, (K, M) int64, range-checked: ``raws[k, j]`` goes to motor ``idx[j]``.

    Returns
    -------
    int
        −1 when every register was stored; else the position ``k`` of the first register the
        rules refuse for some motor. Registers ``nums[:k]`` are then stored and ``nums[k:]``
        not: the caller words the refusal and restores the motors' rows.
    """
    for k in range(nums.shape[0]):
        num = nums[k]
        raw = raws[k]
        if num == R.MODE_REG:
            for j in range(idx.shape[0]):
                if check_request(regs[idx[j]], state[idx[j]], raw[j]) != OK:
                    return k
            if first_mode_refusal(regs, idx, raw) >= 0:
                return k
            for j in range(idx.shape[0]):
                apply_request(regs[idx[j]], state[idx[j]], raw[j])
        else:
            if first_write_refusal(regs, idx, num, raw) >= 0:
                return k
            for j in range(idx.shape[0]):
                _store_word(regs, idx[j], num, high[k], raw[j])
    return -1
