"""Analogue input ±10 V (manual 3.2.122): a voltage profile with optional noise.

The ADC (±10 V ↔ ±1023, ANINP_OFFSET added, quantised) is in the firmware; this source gives
the voltage at the terminal. Noise is drawn per motor from its own generator (``seed`` + motor
index), so motors do not share a stream.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ..families.mac050_141 import constants as c


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

    def advance(self) -> np.ndarray:
        """Voltage during the next outer sample, clipped to ±10 V, (N,)."""
        v = np.broadcast_to(np.asarray(self._fn(self.t), dtype=np.float64), (self.n,)).copy()
        if self.noise_std > 0:
            v += self.noise_std * np.array([g.standard_normal() for g in self._rngs])
        self.t += c.OUTER_DT
        return np.clip(v, -c.ANINP_VOLTS, c.ANINP_VOLTS)
