"""Speed profiles of the line masters (master roll, spindle), vectorised over copies.

A profile is ``v(t) = v_nom · ramp(t) · (1 + step(t)) · (1 + walk(t)) · (1 + a·sin θ)``:

- run-up ``ramp(t) = min(t / t_ramp, 1)``;
- a speed change ``step(t) = Δ · clip((t − t_step) / t_change, 0, 1)`` (``Δ = −1`` is a stop);
- a smooth random walk ``walk(t)``: a sum of three sines of random frequency (0.1–1 Hz) and
  phase, scaled so its standard deviation is the ``walk`` amplitude;
- eccentric-roll ripple ``a·sin θ`` with the roll angle ``θ``.

The random parts are drawn once per episode from the copy's generator, so a profile is a pure
function of time and roll angle (no per-step random numbers). :meth:`SpeedProfile.speed` works on
all copies in numpy; :func:`row_speed` is the same formula per copy for the compiled env steps
(tested equal).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..engine.jit import KERNEL
from ..physics.trig import sine
from .generator_draws import uniform_rows

__all__ = ["SpeedProfile", "row_speed"]

#: columns of the per-copy parameter matrix
(V_NOM, T_RAMP, STEP, T_STEP, WALK, RIPPLE, PHASE, F0, F1, F2, Q0, Q1, Q2, N_COLS) = range(14)
_WALK_SCALE = math.sqrt(2.0 / 3.0)


@njit(**KERNEL, forceinline=True)
def row_speed(p: np.ndarray, t: float, theta: float,
              t_change: float) -> float:  # pragma: no cover - compiled
    """Speed of one copy from its parameter row ``p`` (compiled callers: compiled once, and
    LLVM inlines it into each)."""
    ramp = min(t / p[T_RAMP], 1.0)
    change = p[STEP] * min(max((t - p[T_STEP]) / t_change, 0.0), 1.0)
    # sines by jvl_gym.physics.trig (no library call, which the compiled step cannot inline), and
    # none for a zero amplitude (the factor 1 + (±0) is 1 either way)
    w = 0.0
    if p[WALK] != 0.0:
        w = p[WALK] * _WALK_SCALE * (sine(2.0 * math.pi * p[F0] * t + p[Q0])
                                     + sine(2.0 * math.pi * p[F1] * t + p[Q1])
                                     + sine(2.0 * math.pi * p[F2] * t + p[Q2]))
    r = 0.0
    if p[RIPPLE] != 0.0:
        r = p[RIPPLE] * sine(theta + p[PHASE])
    return max(p[V_NOM] * ramp * (1.0 + change) * (1.0 + w) * (1.0 + r), 0.0)


@njit(**KERNEL)
def _reset_rows(params: np.ndarray, idx: np.ndarray, v_nom: np.ndarray, t_ramp: np.ndarray,
                step: np.ndarray, t_step: np.ndarray, walk: np.ndarray, ripple: np.ndarray,
                u: np.ndarray) -> None:  # pragma: no cover - compiled
    """Parameter rows ``idx`` of ``params`` from the (M,) draws and (M, 7) uniform numbers
    ``u`` (the walk's three frequencies 0.1–1 Hz and phases, the ripple phase)."""
    for j in range(idx.shape[0]):
        p = params[idx[j]]
        p[V_NOM] = v_nom[j]
        p[T_RAMP] = max(t_ramp[j], 1e-3)
        p[STEP] = step[j]
        p[T_STEP] = t_step[j]
        p[WALK] = walk[j]
        p[RIPPLE] = ripple[j]
        for q in range(3):
            p[F0 + q] = 0.1 + 0.9 * u[j, q]
            p[Q0 + q] = 2 * np.pi * u[j, 3 + q]
        p[PHASE] = 2 * np.pi * u[j, 6]


class SpeedProfile:
    """Per-copy speed profiles for ``n`` copies (parameters as rows of :attr:`params`)."""

    def __init__(self, n: int, t_change: float = 0.2) -> None:
        self.params = np.zeros((n, N_COLS))
        self.params[:, T_RAMP] = 1.0
        self.params[:, T_STEP] = np.inf
        self.t_change = float(t_change)

    def reset(self, idx: np.ndarray, rngs: list[np.random.Generator], v_nom: np.ndarray,
              t_ramp: np.ndarray, step: np.ndarray, t_step: np.ndarray, walk: np.ndarray,
              ripple: np.ndarray) -> None:
        """New profiles for copies ``idx``; the sines' frequencies and phases come from
        ``rngs`` (one generator per copy, in the order of ``idx``)."""
        u = uniform_rows(rngs, 7)
        _reset_rows(self.params, idx, v_nom, t_ramp, step, t_step, walk, ripple, u)

    def speed(self, t: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """Speed at time ``t`` [s] and roll angle ``theta`` [rad], (n,), never negative."""
        p = self.params
        ramp = np.minimum(t / p[:, T_RAMP], 1.0)
        change = p[:, STEP] * np.clip((t - p[:, T_STEP]) / self.t_change, 0.0, 1.0)
        walk = p[:, WALK] * _WALK_SCALE * np.sin(
            2 * np.pi * p[:, F0:F2 + 1] * np.asarray(t)[..., None] + p[:, Q0:Q2 + 1]).sum(axis=-1)
        ripple = p[:, RIPPLE] * np.sin(theta + p[:, PHASE])
        return np.maximum(p[:, V_NOM] * ramp * (1.0 + change) * (1.0 + walk) * (1.0 + ripple),
                          0.0)
