"""One value written into several columns of a register or state row (compiled).

A family's firmware resets groups of registers and state columns together (the filter
histories on entry into a regulated mode, the outputs and follow error on going passive);
it names each group once, as a tuple of column indices, and :func:`fill` writes it. numba
unrolls the loop over the tuple, so the compiled code is the same as the writes one by one.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ..engine.jit import KERNEL

__all__ = ["fill"]


@njit(**KERNEL)
def fill(row: np.ndarray, columns: tuple[int, ...], value: float) -> None:
    """Write ``value`` into ``row[c]`` for every column ``c`` of ``columns``.

    Parameters
    ----------
    row : numpy.ndarray, shape (n,)
        One motor's register row (integers) or state row (float64).
    columns : tuple of int
        Column indices into ``row``, each in ``0 … n − 1``.
    value : float
        The value written (converted to ``row``'s dtype as an assignment converts it).
    """
    for c in columns:
        row[c] = value
