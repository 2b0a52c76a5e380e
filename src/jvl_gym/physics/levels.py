"""Logic levels the firmware reads from an analogue input: a level with hysteresis and the edge
of a zero-search sensor (no registers; a family's firmware stores the level in its state).

- :func:`hysteresis_level`: the analogue input as a logic input with hysteresis, high above one
  voltage and low below another (MAC050–141 manual 4.1.10 A2POS: 5.4 V / 4.4 V; the MAC800's
  mode 21, analogue to position, register overview §1.2, register 2, follows it).
- :func:`sensor_edge`: the event that ends a sensor zero search (MAC050–141 manual 4.4.14
  HOME2: the sensor becomes active; 4.4.15 HOME3: after it was found, the sensor becomes
  passive again; the MAC800's modes 13 and 14, register overview §1.2, register 2, follow them).
"""

from __future__ import annotations

from numba import njit

from ..engine.jit import KERNEL


@njit(**KERNEL)
def hysteresis_level(level: float, x: float, high: float, low: float) -> float:
    """The logic level after input ``x``: 1.0 once ``x`` rises above ``high`` from low (0.0),
    0.0 once it falls below ``low`` from high, else ``level`` unchanged (``low < high``, in the
    unit of ``x``)."""
    if level < 0.5 and x > high:
        return 1.0
    if level > 0.5 and x < low:
        return 0.0
    return level


@njit(**KERNEL)
def sensor_edge(active: bool, last: float, rising: bool, armed: bool) -> bool:
    """Whether a sensor zero search finds its zero in this sample.

    Parameters
    ----------
    active : bool
        The sensor's level now (its polarity applied).
    last : float
        Its level in the last sample: 1.0 active, 0.0 passive, negative in the search's first
        sample (no edge then).
    rising : bool
        True: found when the sensor becomes active; False: found when it becomes passive,
        and only once ``armed`` (the search has met the sensor).
    armed : bool
        See ``rising``.
    """
    was = active if last < 0.0 else last > 0.5
    if rising:
        return active and not was
    return armed and was and not active
