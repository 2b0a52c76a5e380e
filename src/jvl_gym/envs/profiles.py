"""Speed profiles of the line masters (master roll, spindle), vectorised over copies.

A profile is ``v(t) = v_nom · ramp(t) · (1 + step(t)) · (1 + walk(t)) · (1 + a·sin θ)``:

- run-up ``ramp(t) = min(t / t_ramp, 1)``;
- a speed change ``step(t) = Δ · clip((t − t_step) / t_change, 0, 1)`` (``Δ = −1`` is a stop);
- a smooth random walk ``walk(t)``: a sum of three sines of random frequency (0.1–1 Hz) and
  phase, scaled so its standard deviation is the ``walk`` amplitude;
- eccentric-roll ripple ``a·sin θ`` with the roll angle ``θ``.

The random parts are drawn once per episode from the copy's generator, so a profile is a pure
function of time and roll angle (no per-step random numbers).
"""

from __future__ import annotations

import numpy as np

__all__ = ["SpeedProfile"]

_N_SINES = 3


class SpeedProfile:
    """Per-copy speed profiles for ``n`` copies (parameters as (n,) arrays)."""

    def __init__(self, n: int, t_change: float = 0.2) -> None:
        self.v_nom = np.zeros(n)
        self.t_ramp = np.ones(n)
        self.step = np.zeros(n)
        self.t_step = np.full(n, np.inf)
        self.walk = np.zeros(n)
        self.ripple = np.zeros(n)
        self.phase = np.zeros(n)
        self.freq = np.zeros((n, _N_SINES))
        self.sine_phase = np.zeros((n, _N_SINES))
        self.t_change = float(t_change)

    def reset(self, idx: np.ndarray, rngs: list[np.random.Generator], v_nom: np.ndarray,
              t_ramp: np.ndarray, step: np.ndarray, t_step: np.ndarray, walk: np.ndarray,
              ripple: np.ndarray) -> None:
        """New profiles for copies ``idx``; the sines' frequencies and phases come from
        ``rngs`` (one generator per copy, in the order of ``idx``)."""
        self.v_nom[idx] = v_nom
        self.t_ramp[idx] = np.maximum(t_ramp, 1e-3)
        self.step[idx] = step
        self.t_step[idx] = t_step
        self.walk[idx] = walk
        self.ripple[idx] = ripple
        u = np.array([rng.random(2 * _N_SINES + 1) for rng in rngs]).reshape(idx.size, -1)
        self.freq[idx] = 0.1 + 0.9 * u[:, :_N_SINES]
        self.sine_phase[idx] = 2 * np.pi * u[:, _N_SINES:2 * _N_SINES]
        self.phase[idx] = 2 * np.pi * u[:, -1]

    def speed(self, t: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """Speed at time ``t`` [s] and roll angle ``theta`` [rad], (n,), never negative."""
        ramp = np.minimum(t / self.t_ramp, 1.0)
        change = self.step * np.clip((t - self.t_step) / self.t_change, 0.0, 1.0)
        walk = self.walk * np.sqrt(2.0 / _N_SINES) * np.sin(
            2 * np.pi * self.freq * t[:, None] + self.sine_phase).sum(axis=1)
        ripple = self.ripple * np.sin(theta + self.phase)
        return np.maximum(self.v_nom * ramp * (1.0 + change) * (1.0 + walk) * (1.0 + ripple),
                          0.0)
