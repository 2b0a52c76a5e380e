"""The MIS/SMC integrated step motor family (MIS17x, 23x, 34x, 43x; SMC66/SMC85; MIS manual).

``REGISTERS`` is the family's register table (``registers.csv`` in this package, every register
of the MIS manual §8.2 at one register number, 32 bits wide); :mod:`.units` holds its counts per
revolution and unit scalings. ``FAMILY`` is the family's record
(:class:`jvl_gym.families.Family`): firmware (``firmware/``), the step motor plant
(``plant``), motor configs (``configs/motors``), the motor array (``motors``), the task
interface (``task``), the twin's facts and the capabilities, stored programs (``program``) and
the CANopen slave's facts (``canopen``); it has no tuning procedure.
"""

from __future__ import annotations

from ...registers.table import RegisterTable, load_packaged_table

__all__ = ["REGISTERS", "FAMILY"]

#: the MIS/SMC register table (registers 1 … 253)
REGISTERS: RegisterTable = load_packaged_table(__name__)

from ..contract import Capability, Family, TwinSpec  # noqa: E402  (the table first)
from . import constants, program  # noqa: E402
from .canopen import CANOPEN  # noqa: E402
from .motors import MisMotorArray  # noqa: E402

_C = constants

FAMILY = Family.of_package(
    __name__, key="mis", title="MIS/SMC integrated step motors", array_class=MisMotorArray,
    twin=TwinSpec(
        dialects=(_C.MACTALK_DIALECT,), safe_mode=_C.SAFE, init_mode=_C.PASSIVE,
        passive_mode=_C.PASSIVE,
        # STATUSBITS (§8.2.24); ERR_BITS (§8.2.31) holds the errors
        status_register="STATUSBITS",
        status_bits=TwinSpec.named_bits(_C, (
            "ST_AUTOCORRECTION", "ST_IN_PHYSICAL_POSITION", "ST_AT_VELOCITY", "ST_IN_POSITION",
            "ST_ACCELERATING", "ST_DECELERATING", "ST_ZERO_SEARCH_DONE", "ST_GENERAL_ERROR",
            "ST_CLOSED_LOOP_LAG", "ST_CLOSED_LOOP", "ST_ENCODER_CALIBRATED",
            "ST_STANDBY_CURRENT", "ST_ENCODER_OK", "ST_IN_TARGET_POSITION")),
        error_bits=("ST_GENERAL_ERROR",),
        # user commands of the COMMAND register (§8.2.21, §8.2.22)
        commands={"clear_errors": _C.CMD_CLEAR_ERRORS, "reset": _C.CMD_RESET,
                  "save_reset": _C.CMD_SAVE_RESET, "save": _C.CMD_SAVE,
                  "emergency_stop": _C.CMD_EMERGENCY_STOP,
                  "emergency_halt": _C.CMD_EMERGENCY_HALT}),
    capabilities=frozenset({Capability.TORQUE, Capability.ENERGY, Capability.SAFE_MODE,
                            Capability.SOFTWARE_RESET, Capability.FLASH,
                            Capability.SAMPLE_BUFFER, Capability.STEP_INDEXING,
                            # stored programs (chapter 9), CANopen (§11), J1939 (§11.8),
                            # DMX512 (§13)
                            Capability.PROGRAMS, Capability.CANOPEN, Capability.J1939,
                            Capability.DMX512}),
    programs=program, canopen=CANOPEN, j1939_name=_C.J1939_NAME)
