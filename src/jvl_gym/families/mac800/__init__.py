"""The MAC800 integrated servo motor family (MAC800 register overview and serial quick guide).

``REGISTERS`` is the family's register table (``registers.csv`` in this package, every register
of the overview at one register number, 32 bits wide); :mod:`.units` holds its sample rate,
counts per revolution and unit scalings. ``FAMILY`` is the family's record
(:class:`jvl_gym.families.Family`): the compiled step (:mod:`.compiled`), the motor array
(:class:`.motors.Mac800MotorArray`), the motor types (``configs/motors``: MAC800, MAC400), the
twin's facts, the capabilities and the tuning strategy.
"""

from __future__ import annotations

from ...registers.table import RegisterTable, load_packaged_table

__all__ = ["REGISTERS", "FAMILY"]

#: the MAC800 register table (registers 1 … 206)
REGISTERS: RegisterTable = load_packaged_table(__name__)

from ..contract import Capability, Family, TuningSpec, TwinSpec  # noqa: E402  (table first)
from . import constants  # noqa: E402
from .motors import Mac800MotorArray  # noqa: E402

_C = constants

FAMILY = Family.of_package(
    __name__, key="mac800", title="MAC800 integrated servo motors", array_class=Mac800MotorArray,
    twin=TwinSpec(
        dialects=(_C.MACTALK_DIALECT,), passive_mode=_C.PASSIVE_MODE, status_register="ERR_STAT",
        # ERR_STAT bits (register overview §1.2, register 35)
        status_bits=TwinSpec.named_bits(_C, tuple(_C.ERR_STAT_BITS)),
        error_bits=tuple(_C.ERROR_NAMES.values()),
        clearable_bits=tuple(_C.ERROR_NAMES.values())),
    capabilities=frozenset({Capability.TORQUE, Capability.ENERGY, Capability.SAMPLE_BUFFER,
                            Capability.ANALOG_TORQUE, Capability.ANALOG_GEAR,
                            Capability.SPEED_FILTER}),
    tuning=TuningSpec.of("buffer_sixth_order", constants, REGISTERS))
