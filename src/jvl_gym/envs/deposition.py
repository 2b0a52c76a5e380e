"""Wire deposition on a coil: the layer height profile across the coil width.

The coil width ``[0, W]`` between the flanges is cut into bins of width δ (finer than the wire
diameter). A turn of diameter ``d`` laid at traverse position ``x`` occupies the bins under
``[x − d/2, x + d/2]`` (``x`` limited to ``[d/2, W − d/2]``: the flanges stop the wire). It
rests on the highest point under it (``base = max h``) and raises those bins to ``base + d``
(a rectangular wire cross-section). Whatever lies under it below ``base`` is a void — a gap in
the layer below — of area ``Σ (base − h)·δ``. So the wound cross-section grows by exactly
``d × footprint + void`` per turn (area conservation, tested), and a turn resting on a
neighbour of its own layer is a pile-up (its base is above the layer floor).

Nesting (``nest=True``, the default of the env): a round wire pressed against its neighbour
slides sideways into the lowest place within ``±d/2`` of where the traverse lays it (the lowest
base, ties to the nearest), so a slightly wrong pitch shifts turns along the layer until the
accumulated offset exceeds half a diameter — then the turn climbs onto its neighbour.

The ``*_row`` functions work on one coil's profile (compiled: the CoilWinding env step calls
them); :func:`lay_turns`, :func:`profile_summary` and :func:`layer_flatness` apply them to rows
of an (N, B) array.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..engine.jit import KERNEL, plain_arguments

__all__ = ["bin_centres", "mean_height", "lay_turn_row", "profile_summary_row", "flatness_row",
           "lay_turns", "profile_summary", "layer_flatness"]


def bin_centres(width: float, bin_width: float) -> np.ndarray:
    """Centres of the bins covering ``[0, width]``, (B,)."""
    n = int(np.ceil(width / bin_width - 1e-9))
    return (np.arange(n) + 0.5) * bin_width


@plain_arguments
@njit(**KERNEL, forceinline=True)
def _count_below(centres: np.ndarray, v: float, or_equal: bool) -> int:  # pragma: no cover
    """Number of ``centres`` < ``v`` (``<= v`` with ``or_equal``): ``np.searchsorted(centres,
    v, side="left" / "right")`` for finite ``v``, found from the uniform spacing (a guess,
    then corrected by comparisons, so the result is exact) instead of a binary search.
    Compiled once (its callers pass ``or_equal`` as a constant) and inlined by LLVM."""
    n = centres.size
    if not v == v:
        return n  # NaN sorts last
    spacing = centres[1] - centres[0] if n > 1 else 1.0
    g = int(min(max(np.floor((v - centres[0]) / spacing) + 1.0, 0.0), float(n)))
    while g > 0 and (centres[g - 1] > v if or_equal else centres[g - 1] >= v):
        g -= 1
    while g < n and (centres[g] <= v if or_equal else centres[g] < v):
        g += 1
    return g


@njit(cache=True, inline="always")
def _span(centres: np.ndarray, xc: float, half: float) -> tuple[int, int]:  # pragma: no cover
    """Bins ``[lo, hi)`` whose centre lies within ``half`` of ``xc``; the nearest bin if none."""
    lo = _count_below(centres, xc - half, True)
    hi = _count_below(centres, xc + half, False)
    if lo < hi:
        return lo, hi
    k = _count_below(centres, xc, False)
    if k >= centres.size or (k > 0 and xc - centres[k - 1] <= centres[k] - xc):
        k -= 1
    return k, k + 1


@njit(cache=True, inline="always")
def _top(h: np.ndarray, lo: int, hi: int) -> float:  # pragma: no cover - compiled
    top = -math.inf
    for b in range(lo, hi):
        top = max(top, h[b])
    return top


@njit(**KERNEL)
def lay_turn_row(h: np.ndarray, centres: np.ndarray, x: float, d: float, width: float,
                 nest: bool) -> tuple[float, float, float]:  # pragma: no cover - compiled
    """Lay one turn on the profile ``h`` (B,) (modified in place).

    Parameters
    ----------
    h : (B,) array
        Height of the wound surface over each bin [same unit as x].
    centres : (B,) array
        Bin centres (uniform, :func:`bin_centres`).
    x, d : float
        Turn centre (traverse position) and wire diameter.
    width : float
        Coil width W (flange to flange).
    nest : bool
        Let the turn slide up to ``±d/2`` into the lowest place (see the module docstring).

    Returns
    -------
    base : float
        Height the turn rests on.
    void : float
        Void area trapped under the turn (gap) [unit²].
    x_laid : float
        Centre where the turn was laid (after the flanges and nesting).
    """
    bin_width = centres[1] - centres[0] if centres.size > 1 else width
    half = 0.5 * d
    xc = min(max(x, half), width - half)
    # the places tried: the place itself and, with nesting, the shifts −1, +1, −2, +2, … bins
    # within ±d/2 (ties to the nearest); the turn goes to the lowest, to the place itself when
    # no height is below infinity
    k_max = int(math.ceil(half / bin_width)) if nest else 0
    best = math.inf
    lo = hi = 0
    base = math.inf
    x_laid = xc
    for j in range(2 * k_max + 1):
        k = (j + 1) // 2 * (1 if j % 2 == 0 else -1)
        shift = k * bin_width
        if abs(shift) > half + 1e-12:
            continue
        cand = min(max(xc + shift, half), width - half)
        c_lo, c_hi = _span(centres, cand, half)
        top = _top(h, c_lo, c_hi)
        lower = top < best - 1e-9 * d
        if lower or j == 0:
            lo, hi, base = c_lo, c_hi, top
        if lower:
            best = top
            x_laid = cand
    void = 0.0
    for b in range(lo, hi):
        void += base - h[b]
        h[b] = base + d
    return base, void * bin_width, x_laid


@njit(**KERNEL)
def profile_summary_row(h: np.ndarray, groups: int, scale: float,
                        out: np.ndarray) -> None:  # pragma: no cover - compiled
    """``out[k]``: mean height of group ``k`` of ``groups`` equal groups of bins minus the
    overall mean, divided by ``scale``.

    One pass over the bins; each group is summed in four interleaved partial sums and the
    overall sum is the sum of the group sums (a single running sum over 400 bins is a chain
    of 400 dependent additions: a microsecond per env step).
    """
    n = h.size
    step = n / groups
    total = 0.0
    for k in range(groups):
        lo = int(k * step)
        hi = int((k + 1) * step) if k + 1 < groups else n
        out[k] = _sum4(h, lo, hi)
        total += out[k]
    mean = total / n
    for k in range(groups):
        lo = int(k * step)
        hi = int((k + 1) * step) if k + 1 < groups else n
        out[k] = (out[k] / (hi - lo) - mean) / scale


@njit(cache=True, inline="always")
def _sum4(h: np.ndarray, lo: int, hi: int) -> float:  # pragma: no cover - compiled
    """Sum of ``h[lo:hi]`` in four interleaved partial sums."""
    a0 = a1 = a2 = a3 = 0.0
    b = lo
    while b + 4 <= hi:
        a0 += h[b]
        a1 += h[b + 1]
        a2 += h[b + 2]
        a3 += h[b + 3]
        b += 4
    while b < hi:
        a0 += h[b]
        b += 1
    return (a0 + a1) + (a2 + a3)


@njit(cache=True, inline="always")
def mean_height(h: np.ndarray) -> float:  # pragma: no cover - compiled
    """The mean of the heights ``h`` (B,): numba's ``h.mean()`` (the sum from 0.0 in bin order
    over the number of bins; NaN for no bin), written as the loop it runs, which compiles in
    a fraction of the time of ``mean``'s array iterator."""
    if h.size == 0:
        return math.nan
    total = 0.0
    for b in range(h.size):
        total += h[b]
    return total / h.size


@njit(**KERNEL)
def flatness_row(h: np.ndarray, d: float) -> tuple[float, float, float]:  # pragma: no cover
    """Flatness of a profile: std of the height / d, and the fractions of the width more than
    d/2 below (gaps) and above (pile-up) the mean height."""
    mean = mean_height(h)
    var = 0.0
    gaps = 0
    piles = 0
    for b in range(h.size):
        dev = h[b] - mean
        var += dev * dev
        gaps += dev < -0.5 * d
        piles += dev > 0.5 * d
    return math.sqrt(var / h.size) / d, gaps / h.size, piles / h.size


def lay_turns(h: np.ndarray, centres: np.ndarray, idx: np.ndarray, x: np.ndarray,
              d: np.ndarray, width: float, nest: bool = False
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Lay one turn in each row ``idx`` of the (N, B) profile ``h``: :func:`lay_turn_row` per
    row, returning (k,) arrays of ``base``, ``void`` and ``x_laid``."""
    out = np.array([lay_turn_row(h[i], centres, float(xi), float(di), float(width), bool(nest))
                    for i, xi, di in zip(idx, x, d)]).reshape(-1, 3)
    return out[:, 0], out[:, 1], out[:, 2]


def profile_summary(h: np.ndarray, groups: int, scale: np.ndarray) -> np.ndarray:
    """:func:`profile_summary_row` of every row of ``h`` (N, B), shape (N, groups)."""
    out = np.empty((h.shape[0], groups))
    for i in range(h.shape[0]):
        profile_summary_row(h[i], groups, float(scale[i]), out[i])
    return out


def layer_flatness(h: np.ndarray, idx: np.ndarray, d: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`flatness_row` of rows ``idx``: (k,) arrays of std / d, gap and pile-up
    fractions."""
    out = np.array([flatness_row(h[i], float(di)) for i, di in zip(idx, d)]).reshape(-1, 3)
    return out[:, 0], out[:, 1], out[:, 2]
