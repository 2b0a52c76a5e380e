"""Analogue input: a voltage profile at the motor's analogue terminal, with optional noise.

The input's range and its ADC (on the MAC050–141: ±10 V ↔ ±1023, ANINP_OFFSET added,
quantised, manual 3.2.122) belong to the motor's firmware, which clips; this source gives the
voltage at the terminal. Noise is drawn per motor from its own generator (``seed`` + motor
index), so motors do not share a stream.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np


class AnalogInput:
    """Voltage at the analogue input of each motor [V].

    Parameters
    ----------
    volts : callable or float or (N,) array
        ``volts(t) -> (N,)`` or a constant.
    n : int
        Number of motors.
    noise_std : float
        Standard deviation of additive white noise [V].
    seed : int or None
        Seed of the noise generators.
    """

    def __init__(self, volts: Callable[[float], np.ndarray] | float | np.ndarray, n: int,
                 noise_std: float = 0.0, seed: int | None = None) -> None:
        if noise_std < 0:
            raise ValueError("noise_std must be >= 0")
        const = None if callable(volts) else np.asarray(volts, dtype=np.float64)
        self._fn = volts if callable(volts) else (lambda t: const)
        self.n = n
        self.noise_std = noise_std
        self._rngs = [np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(n)]
        self.t = 0.0

    def advance(self, dt: float) -> np.ndarray:
        """Voltage during the next sample of ``dt`` seconds, (N,) [V]."""
        v = np.broadcast_to(np.asarray(self._fn(self.t), dtype=np.float64), (self.n,)).copy()
        if self.noise_std > 0:
            v += self.noise_std * np.array([g.standard_normal() for g in self._rngs])
        self.t += dt
        return v
