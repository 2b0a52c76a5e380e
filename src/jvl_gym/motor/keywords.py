"""Per-motor reset keywords: their value rules, checked in one compiled pass.

A family declares its reset keywords (``MotorArray.PARAMETER_KEYWORDS`` and
``STATE_KEYWORDS``: name → column) and a rule per keyword, an OR of the flags below; the
values of a reset are checked row by row before anything changes.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..engine.jit import KERNEL

__all__ = ["FINITE", "NONNEGATIVE", "POSITIVE", "BINARY", "RULE_TEXT", "first_bad_value"]

FINITE = 1  #: finite
NONNEGATIVE = 2  #: >= 0
POSITIVE = 4  #: > 0
BINARY = 8  #: 0 or 1
#: how a broken rule is worded
RULE_TEXT = {FINITE: "finite", NONNEGATIVE: ">= 0", POSITIVE: "> 0", BINARY: "0 or 1"}


@njit(**KERNEL)
def first_bad_value(values: np.ndarray, rules: np.ndarray) -> int:  # pragma: no cover
    """The first value that breaks its row's rules, as ``16·row + rule``, or −1.

    Parameters
    ----------
    values : numpy.ndarray
        (P, M) float64, one row per reset keyword.
    rules : numpy.ndarray
        (P,) int64: the rules of each row, an OR of :data:`FINITE`, :data:`NONNEGATIVE`,
        :data:`POSITIVE` and :data:`BINARY`, checked row by row in this order.
    """
    for q in range(values.shape[0]):
        for rule in (FINITE, NONNEGATIVE, POSITIVE, BINARY):
            if rules[q] & rule:
                for j in range(values.shape[1]):
                    x = values[q, j]
                    ok = (math.isfinite(x) if rule == FINITE else not x < 0.0
                          if rule == NONNEGATIVE else not x <= 0.0 if rule == POSITIVE
                          else x == 0.0 or x == 1.0)
                    if not ok:
                        return 16 * q + rule
    return -1
