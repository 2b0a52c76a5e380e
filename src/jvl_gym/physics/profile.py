"""Profile arithmetic shared by the servo families' function blocks (MAC050–141 manual 4.1.2):
the braking distance of a sampled deceleration and the largest speed that lands on a target.

Integer-valued arithmetic in float64, as the firmware's registers hold it.
"""

from __future__ import annotations

import math

from numba import njit

from ..engine.jit import KERNEL


@njit(cache=True, inline="always")
def stopping_distance(v: float, a: float) -> float:
    """Distance covered from speed ``v`` ≥ 0 braking by ``a`` per sample: v + (v−a) + … > 0."""
    if v <= 0.0:
        return 0.0
    n = math.ceil(v / a) - 1.0
    return (n + 1.0) * v - a * n * (n + 1.0) / 2.0


@njit(**KERNEL)
def max_landing_speed(dp: float, a: float) -> float:
    """Largest integer speed whose discrete braking profile fits in ``dp`` ≥ 0 [1/16 count].

    This is the manual's ``FNC_OUT = 2·DP/T`` with ``T = V_OLD/A_SOLL`` (4.1.2) made exact for
    the sampled profile, so the block lands on P_SOLL without overshooting its own profile and
    never divides by zero (docs/model.md §9).
    """
    if dp <= 0.0:
        return 0.0
    if a <= 0.0:
        return dp
    v = math.floor(math.sqrt(2.0 * a * dp + 0.25 * a * a) - 0.5 * a)
    if v < 0.0:
        v = 0.0
    while stopping_distance(v + 1.0, a) <= dp:
        v += 1.0
    while v > 0.0 and stopping_distance(v, a) > dp:
        v -= 1.0
    return v
