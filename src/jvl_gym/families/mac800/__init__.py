"""The MAC800 integrated servo motor family (MAC800 register overview and serial quick guide).

``REGISTERS`` is the family's register table (``registers.csv`` in this package, every register
of the overview at one register number, 32 bits wide); :mod:`.units` holds its sample rate,
counts per revolution and unit scalings. ``FAMILY`` is the family's record for the engine: the
compiled step (:mod:`.compiled`), the motor array (:class:`.motors.Mac800MotorArray`) and the
motor types (``configs/motors``: MAC800, MAC400).
"""

from __future__ import annotations

from ...registers.table import RegisterTable, load_packaged_table

__all__ = ["REGISTERS", "FAMILY"]

#: the MAC800 register table (registers 1 … 206)
REGISTERS: RegisterTable = load_packaged_table(__name__)

from .. import Family  # noqa: E402  (the table first: the modules below read it)
from . import compiled  # noqa: E402
from .config import motor_types  # noqa: E402
from .motors import Mac800MotorArray  # noqa: E402

FAMILY = Family(key="mac800", title="MAC800 integrated servo motors", compiled=compiled,
                array_class=Mac800MotorArray, motor_types=motor_types)
