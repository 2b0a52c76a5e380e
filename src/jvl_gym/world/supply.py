"""Supply voltage events: sags and dropouts of the source (manual 4.5.6 undervoltage)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ..families.mac050_141 import constants as c


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
            if not (0 <= start < end) or not 0 <= volts <= 60:
                raise ValueError(f"bad supply event {(start, end, volts)!r}")
        self.events = list(events)
        self.nominal = np.broadcast_to(np.asarray(nominal, dtype=np.float64), (n,)).copy()
        self.t = 0.0

    def advance(self) -> np.ndarray:
        """Source voltage during the next outer sample, (N,)."""
        v = self.nominal.copy()
        for start, end, volts in self.events:
            if start <= self.t < end:
                v[:] = volts
        self.t += c.OUTER_DT
        return v
