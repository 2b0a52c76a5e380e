"""The MAC800 integrated servo motor family (MAC800 register overview and serial quick guide).

``REGISTERS`` is the family's register table (``registers.csv`` in this package, every register
of the overview at one register number, 32 bits wide); :mod:`.units` holds its sample rate,
counts per revolution and unit scalings. ``FAMILY`` is the family's record
(:class:`jvl_gym.families.Family`): the compiled step (:mod:`.compiled`), the motor array
(:class:`.motors.Mac800MotorArray`), the motor types (``configs/motors``: MAC800, MAC400), the
twin's facts, the capabilities (``family.yaml``) and the tuning strategy.
"""

from __future__ import annotations

from ...registers.table import RegisterTable, load_packaged_table

__all__ = ["REGISTERS", "FAMILY"]

#: the MAC800 register table (registers 1 … 206)
REGISTERS: RegisterTable = load_packaged_table(__name__)

from ..contract import Family, TuningSpec  # noqa: E402  (table first)
from . import constants  # noqa: E402
from .motors import Mac800MotorArray  # noqa: E402

FAMILY = Family.of_package(__name__, array_class=Mac800MotorArray,
                           tuning=TuningSpec.of("buffer_sixth_order", constants, REGISTERS))
