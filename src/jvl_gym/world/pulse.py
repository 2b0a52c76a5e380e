"""Pulse / encoder input (manual 3.2.36 PULSEDIR, INPSIGN; 3.2.120 V_EXT).

The source is a master axis turning at a :class:`SpeedProfile` [rev/s] with an encoder of
``lines`` lines per revolution emitting either quadrature signals or pulse + direction. The
motor's interface decodes them as configured by CNTRL_BITS at the last power-on:

| source \\ decoder | quadrature (PULSEDIR = 0) | pulse + direction (PULSEDIR = 1) |
|---|---|---|
| quadrature | 4 counts per line (edges of A and B) | 1 count per line (A rising, B = dir) |
| pulse + direction | 0 (A toggles, B static: up and down counts cancel) | 1 count per pulse |

INPSIGN reverses the sign. Fractions of a count are carried over, so no count is lost.
"""

from __future__ import annotations

import numpy as np

from ..families.mac050_141 import constants as c
from .profiles import SpeedProfile


class PulseInput:
    """Counts per outer sample at the pulse input of each motor.

    Parameters
    ----------
    profile : SpeedProfile
        Master speed [rev/s].
    lines : float or (N,) array
        Encoder lines (or pulses) per master revolution.
    signal : {"quadrature", "pulse_dir"}
        What the source emits.
    """

    def __init__(self, profile: SpeedProfile, lines: float | np.ndarray = 500,
                 signal: str = "quadrature") -> None:
        if signal not in ("quadrature", "pulse_dir"):
            raise ValueError(f"signal must be 'quadrature' or 'pulse_dir', got {signal!r}")
        self.profile = profile
        self.lines = np.broadcast_to(np.asarray(lines, dtype=np.float64), (profile.n,)).copy()
        if np.any(self.lines <= 0):
            raise ValueError("lines must be > 0")
        self.signal = signal
        self.position = np.zeros(profile.n)  # master position [rev]
        self._emitted = np.zeros(profile.n)  # counts emitted so far (decoded, before INPSIGN)
        self.t = 0.0

    def counts_per_rev(self, cntrl_bits: np.ndarray) -> np.ndarray:
        """Decoded counts per master revolution for the latched CNTRL_BITS of each motor."""
        pulsedir = (cntrl_bits & c.PULSEDIR) != 0
        if self.signal == "quadrature":
            k = np.where(pulsedir, 1.0, 4.0)
        else:
            k = np.where(pulsedir, 1.0, 0.0)
        sign = np.where((cntrl_bits & c.INPSIGN) != 0, -1.0, 1.0)
        return k * sign * self.lines

    def advance(self, cntrl_bits: np.ndarray) -> np.ndarray:
        """Counts received during the next outer sample, (N,) integers as float64."""
        v0 = self.profile(self.t)
        self.t += c.OUTER_DT
        v1 = self.profile(self.t)
        self.position = self.position + 0.5 * (v0 + v1) * c.OUTER_DT
        total = np.floor(self.position * self.counts_per_rev(cntrl_bits))
        counts = total - self._emitted
        self._emitted = total
        return counts
