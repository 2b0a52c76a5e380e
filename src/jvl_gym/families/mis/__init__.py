"""The MIS/SMC integrated step motor family (MIS17x, 23x, 34x, 43x; SMC66/SMC85; MIS manual).

``REGISTERS`` is the family's register table (``registers.csv`` in this package, every register
of the MIS manual §8.2 at one register number, 32 bits wide); :mod:`.units` holds its counts per
revolution and unit scalings. ``FAMILY`` is the family's record
(:class:`jvl_gym.families.Family`): firmware (``firmware/``), the step motor plant
(``plant``), motor configs (``configs/motors``), the motor array (``motors``), the task
interface (``task``), the twin's facts and the capabilities (``family.yaml``), stored
programs (``program``) and the CANopen slave's facts (``canopen``); it has no tuning
procedure.
"""

from __future__ import annotations

from ..contract import Family
from . import program
from .canopen import CANOPEN
from .motors import MisMotorArray
from .table import TABLE as REGISTERS

__all__ = ["REGISTERS", "FAMILY"]

FAMILY = Family.of_package(__name__, array_class=MisMotorArray, programs=program,
                           canopen=CANOPEN)
