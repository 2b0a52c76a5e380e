"""Signals the motor sees from the outside world (docs/model.md §14).

Each source is vectorised over the N motors of a :class:`~jvl_gym.MotorArray` and advances with
the simulation: attach a :class:`World` to ``MotorArray.world`` and every ``step(n)`` feeds the
kernel one input sample per outer sample. ``MotorArray.set_input`` remains the way to hold a
value; the home sensor and end stops are motor parameters evaluated inside the kernel at the
inner rate (``home_position``, ``end_stop_low/high``).
"""

from .analog import AnalogInput
from .profiles import SpeedProfile
from .pulse import PulseInput
from .supply import SupplyEvents
from .world import World

__all__ = ["AnalogInput", "PulseInput", "SpeedProfile", "SupplyEvents", "World"]
