"""Wire deposition on a coil: the layer height profile across the coil width (pure numpy).

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

All functions work on the rows ``idx`` of (N, B) arrays, vectorised.
"""

from __future__ import annotations

import numpy as np

__all__ = ["bin_centres", "lay_turns", "profile_summary", "layer_flatness"]


def bin_centres(width: float, bin_width: float) -> np.ndarray:
    """Centres of the bins covering ``[0, width]``, (B,)."""
    n = int(np.ceil(width / bin_width - 1e-9))
    return (np.arange(n) + 0.5) * bin_width


def _footprint(centres: np.ndarray, xc: np.ndarray, half: np.ndarray) -> np.ndarray:
    fp = np.abs(centres[None, :] - xc[:, None]) < half[:, None]
    empty = ~fp.any(axis=1)
    if empty.any():  # a turn always covers at least its nearest bin
        nearest = np.argmin(np.abs(centres[None, :] - xc[empty, None]), axis=1)
        fp[np.flatnonzero(empty), nearest] = True
    return fp


def lay_turns(h: np.ndarray, centres: np.ndarray, idx: np.ndarray, x: np.ndarray,
              d: np.ndarray, width: float, nest: bool = False
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Lay one turn in each row ``idx`` of the height profile ``h`` (modified in place).

    Parameters
    ----------
    h : (N, B) array
        Height of the wound surface over each bin [same unit as x].
    centres : (B,) array
        Bin centres.
    idx : (k,) int array
        Rows receiving a turn.
    x, d : (k,) arrays
        Turn centre (traverse position) and wire diameter.
    width : float
        Coil width W (flange to flange).
    nest : bool
        Let the turn slide up to ``±d/2`` into the lowest place (see the module docstring).

    Returns
    -------
    base : (k,) array
        Height the turn rests on.
    void : (k,) array
        Void area trapped under the turn (gap) [unit²].
    x_laid : (k,) array
        Centre where the turn was laid (after the flanges).
    """
    bin_width = centres[1] - centres[0] if centres.size > 1 else width
    half = 0.5 * d
    xc = np.clip(x, half, width - half)
    rows = h[idx]
    if nest:
        k_max = int(np.ceil(np.max(half) / bin_width))
        best = np.full(xc.shape, np.inf)
        best_x = xc.copy()
        for k in sorted(range(-k_max, k_max + 1), key=abs):
            shift = k * bin_width
            ok = np.abs(shift) <= half + 1e-12
            cand = np.clip(xc + shift, half, width - half)
            b = np.max(np.where(_footprint(centres, cand, half), rows, -np.inf), axis=1)
            better = ok & (b < best - 1e-9 * d)
            best = np.where(better, b, best)
            best_x = np.where(better, cand, best_x)
        xc = best_x
    fp = _footprint(centres, xc, half)
    base = np.max(np.where(fp, rows, -np.inf), axis=1)
    void = np.sum(np.where(fp, base[:, None] - rows, 0.0), axis=1) * bin_width
    h[idx] = np.where(fp, (base + d)[:, None], rows)
    return base, void, xc


def profile_summary(h: np.ndarray, groups: int, scale: np.ndarray) -> np.ndarray:
    """Deviation of the mean height of ``groups`` equal groups of bins from the overall mean,
    divided by ``scale`` (N,), shape (N, groups)."""
    n, b = h.shape
    edges = np.linspace(0, b, groups + 1).astype(int)
    means = np.add.reduceat(h, edges[:-1], axis=1) / np.diff(edges)[None, :]
    return (means - h.mean(axis=1, keepdims=True)) / scale[:, None]


def layer_flatness(h: np.ndarray, idx: np.ndarray, d: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Flatness of rows ``idx``: std of the height / d, and the fractions of the width more
    than d/2 below (gaps) and above (pile-up) the mean height."""
    rows = h[idx]
    mean = rows.mean(axis=1, keepdims=True)
    std = rows.std(axis=1) / d
    gaps = np.mean(rows < mean - 0.5 * d[:, None], axis=1)
    piles = np.mean(rows > mean + 0.5 * d[:, None], axis=1)
    return std, gaps, piles
