"""Supply voltage events: sags and dropouts of the source (on the MAC050–141: the undervoltage
handling of manual 4.5.6)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np


class SupplyEvents:
    """Source voltage over time: ``nominal`` except during events ``(t_start, t_end, volts)``.

    Parameters
    ----------
    events : sequence of (float, float, float)
        Start [s], end [s] and the source voltage during the event [V] (0 for a dropout).
    nominal : float or (N,) array
        Source voltage outside the events [V].
    n : int
        Number of motors.
    """

    def __init__(self, events: Sequence[tuple[float, float, float]], nominal: float | np.ndarray,
                 n: int) -> None:
        for start, end, volts in events:
            if not (0 <= start < end < np.inf) or not 0 <= volts < np.inf:
                raise ValueError(f"bad supply event {(start, end, volts)!r}")
        self.events = list(events)
        self.nominal = np.broadcast_to(np.asarray(nominal, dtype=np.float64), (n,)).copy()
        self.t = 0.0

    def advance(self, dt: float) -> np.ndarray:
        """Source voltage during the next sample of ``dt`` seconds, (N,) [V]."""
        v = self.nominal.copy()
        for start, end, volts in self.events:
            if start <= self.t < end:
                v[:] = volts
        self.t += dt
        return v
