"""Pulse / encoder input of a motor's gear interface.

The source is a master axis turning at a :class:`SpeedProfile` [rev/s] with an encoder of
``lines`` lines per revolution emitting either quadrature signals or pulse + direction. The
motor's interface decodes them as its configuration says (``MotorArray.pulse_decoding()``; on
the MAC050–141 the CNTRL_BITS PULSEDIR and INPSIGN latched at the last power-on, manual 3.2.36,
3.2.120):

| source \\ decoder | quadrature | pulse + direction |
|---|---|---|
| quadrature | 4 counts per line (edges of A and B) | 1 count per line (A rising, B = dir) |
| pulse + direction | 0 (A toggles, B static: up and down counts cancel) | 1 count per pulse |

An inverted input reverses the sign. Fractions of a count are carried over, so no count is lost.
"""

from __future__ import annotations

import numpy as np

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

    def counts_per_rev(self, pulse_dir: np.ndarray, inverted: np.ndarray) -> np.ndarray:
        """Decoded counts per master revolution of each motor.

        Parameters
        ----------
        pulse_dir, inverted : (N,) bool arrays
            The motor decodes pulse + direction (else quadrature); it reverses the count.
        """
        if self.signal == "quadrature":
            k = np.where(pulse_dir, 1.0, 4.0)
        else:
            k = np.where(pulse_dir, 1.0, 0.0)
        return k * np.where(inverted, -1.0, 1.0) * self.lines

    def advance(self, dt: float, pulse_dir: np.ndarray, inverted: np.ndarray) -> np.ndarray:
        """Counts received during the next sample of ``dt`` seconds, (N,) integers as float64;
        ``pulse_dir`` and ``inverted`` as in :meth:`counts_per_rev`."""
        v0 = self.profile(self.t)
        self.t += dt
        v1 = self.profile(self.t)
        self.position = self.position + 0.5 * (v0 + v1) * dt
        total = np.floor(self.position * self.counts_per_rev(pulse_dir, inverted))
        counts = total - self._emitted
        self._emitted = total
        return counts
