"""The MIS/SMC integrated step motor family (MIS17x, 23x, 34x, 43x; SMC66/SMC85; MIS manual).

``REGISTERS`` is the family's register table (``registers.csv`` in this package, every register
of the MIS manual §8.2 at one register number, 32 bits wide); :mod:`.units` holds its counts per
revolution and unit scalings. ``FAMILY`` is the runnable family: firmware (``firmware/``), the
step motor plant (``plant``), motor configs (``configs/``), the motor array (``motors``) and the
task interface (``task``).
"""

from __future__ import annotations

from ...registers.table import RegisterTable, load_packaged_table

__all__ = ["REGISTERS", "FAMILY"]

#: the MIS/SMC register table (registers 1 … 253)
REGISTERS: RegisterTable = load_packaged_table(__name__)

from .. import Family  # noqa: E402  (the table first: the modules below read it)
from . import compiled  # noqa: E402
from .config import motor_types  # noqa: E402
from .motors import MisMotorArray  # noqa: E402

FAMILY = Family(key="mis", title="MIS/SMC integrated step motors", compiled=compiled,
                array_class=MisMotorArray, motor_types=motor_types)
