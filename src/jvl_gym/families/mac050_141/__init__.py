"""The MAC050, MAC095, MAC140 and MAC141 integrated servo motors (technical manual)."""

from __future__ import annotations

from ..contract import Capability, Family, TuningSpec, TwinSpec
from . import constants, units
from .motors import MacMotorArray
from .table import TABLE

__all__ = ["FAMILY"]

_C = constants

FAMILY = Family.of_package(
    __name__, key="mac050_141", title="MAC050–141 integrated servo motors",
    array_class=MacMotorArray,
    twin=TwinSpec(
        dialects=(_C.MACTALK_DIALECT,), safe_mode=_C.SAFE_MODE, init_mode=_C.INIT_MODE,
        passive_mode=_C.INIT_MODE,  # INIT_MODE: passive (manual 4.4.1)
        status_register="ERR_STAT",
        # ERR_STAT bits (manual 3.2.35); the FastMAC status byte's error bit is any of the
        # first four, and "reset errors" clears the latched errors (manual 5.2.1.4, 5.2.1.6)
        status_bits=TwinSpec.named_bits(_C, tuple(_C.ERR_STAT_BITS)),
        error_bits=("I2T_ERR", "FLW_ERR", "FNC_ERR", "UIT_ERR"),
        clearable_bits=("I2T_ERR", "FLW_ERR", "FNC_ERR", "UIT_ERR", "PLIM_ERR", "FRAME_ERR_TX",
                        "IX_ERR", "UV_ERR"),
        # MODE_REG commands in SAFE_MODE (manual 4.4.16)
        commands={"load_defaults_save": _C.SAFE_LOAD_DEFAULTS_SAVE,
                  "load_defaults": _C.SAFE_LOAD_DEFAULTS, "load_flash": _C.SAFE_LOAD_FLASH}),
    capabilities=frozenset({
        Capability.TORQUE, Capability.ENERGY, Capability.SAFE_MODE, Capability.INIT_MODE,
        Capability.SOFTWARE_RESET, Capability.FLASH, Capability.SAMPLE_BUFFER,
        Capability.TEST_MODES, Capability.USER_INTERFACE, Capability.ANALOG_TORQUE,
        Capability.ANALOG_GEAR, Capability.SPEED_FILTER, Capability.COIL_MODE}),
    tuning=TuningSpec.of("testu_pi", units, TABLE))
