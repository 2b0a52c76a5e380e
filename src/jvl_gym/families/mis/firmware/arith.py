"""Integer helpers of the firmware: the 32-bit wrap of positions (MIS manual §8.2.4, §8.2.10)."""

from __future__ import annotations

from numba import njit


@njit(cache=True, inline="always")
def wrap32(x: int) -> int:  # pragma: no cover - compiled
    """``x`` wrapped to a signed 32-bit value: 2³¹ − 1 + 1 → −2³¹ (§8.2.10)."""
    return ((x + 2147483648) & 0xFFFFFFFF) - 2147483648
