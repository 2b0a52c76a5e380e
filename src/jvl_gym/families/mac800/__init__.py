"""The MAC800 integrated servo motor family (MAC800 register overview and serial quick guide).

``REGISTERS`` is the family's register table (``registers.csv`` in this package, every register
of the overview at one register number, 32 bits wide); :mod:`.units` holds its sample rate,
counts per revolution and unit scalings. ``FAMILY`` is the family's record
(:class:`jvl_gym.families.Family`): the compiled step (:mod:`.compiled`), the motor array
(:class:`.motors.Mac800MotorArray`), the motor types (``configs/motors``: MAC800, MAC400), the
twin's facts, the capabilities (``family.yaml``) and the tuning strategy.
"""

from __future__ import annotations

from ..contract import Family, TuningSpec
from . import constants
from .motors import Mac800MotorArray
from .table import TABLE as REGISTERS

__all__ = ["REGISTERS", "FAMILY"]

FAMILY = Family.of_package(__name__, array_class=Mac800MotorArray,
                           tuning=TuningSpec.of("buffer_sixth_order", constants, REGISTERS))
