"""What a compiled task may read and set of a MAC800-family motor during an env step (public
module): the names of ``families/mac050_141/task.py`` where the meaning is the same, so that
an env written against that interface runs on this family.

Register values by number (``R``, from the register table), the world inputs the motor's
connectors and shaft see, and the shaft angle. (The MAC050–141's ``coil_direction`` has no
counterpart: the MAC800's coil mode is not modelled.)
"""

from __future__ import annotations

from numba import njit

from ...engine.view import EngineView
from . import constants as _c
from . import layout as _L
from .firmware import regs as R
from .table import TABLE as _TABLE

__all__ = ["R", "FAMILY_KEY", "DEFAULT_MOTOR_TYPE", "TERMINAL_ERRORS", "ERROR_BITS", "reg",
           "set_reg", "shaft_angle", "set_analog_volts", "set_load_torque", "set_pulse_counts"]

#: the family's key, and the motor type of a task when none is given
FAMILY_KEY = "mac800"
DEFAULT_MOTOR_TYPE = "MAC800"
#: ERR_STAT bits that end an episode: every error bit (register 35)
TERMINAL_ERRORS = tuple((name, bit) for bit, name in _c.ERROR_NAMES.items())
ERROR_BITS = 0
for _bit in _c.ERROR_NAMES:
    ERROR_BITS |= _bit


@njit(cache=True, inline="always")
def reg(view: EngineView, i: int, number: int) -> int:  # pragma: no cover - compiled
    """Stored 32-bit integer of register ``number`` of motor ``i``."""
    return view.regs[i, number]


_RAW_MIN, _RAW_MAX = _TABLE.data_write_limits(R.MODE_REG)


@njit(cache=True, inline="always")
def set_reg(view: EngineView, i: int, number: int, raw: int) -> None:  # pragma: no cover
    """Store ``raw`` in the read-write data register ``number`` of motor ``i``, saturated to the
    register's range; the firmware uses it from the next servo sample. Mode requests and the
    registers with write rules go through ``MotorArray.write``."""
    view.regs[i, number] = min(max(raw, _RAW_MIN[number]), _RAW_MAX[number])


@njit(cache=True, inline="always")
def shaft_angle(view: EngineView, i: int) -> float:  # pragma: no cover - compiled
    """Shaft angle of motor ``i`` relative to the world zero [rad]."""
    return view.state[i, _L.S_THETA]


@njit(cache=True, inline="always")
def set_analog_volts(view: EngineView, i: int, volts: float) -> None:  # pragma: no cover
    """Analogue input of motor ``i`` [V] from the next servo sample on (register 170)."""
    view.inputs[i, _L.I_ANALOG_VOLTS] = volts


@njit(cache=True, inline="always")
def set_load_torque(view: EngineView, i: int, torque: float) -> None:  # pragma: no cover
    """External load torque on the shaft of motor ``i``, opposing positive rotation [N·m]."""
    view.inputs[i, _L.I_LOAD_TORQUE] = torque


@njit(cache=True, inline="always")
def set_pulse_counts(view: EngineView, i: int, counts: float) -> None:  # pragma: no cover
    """External pulse input counts of motor ``i`` during the next servo sample (V_EXT,
    register 163)."""
    view.inputs[i, _L.I_PULSE_COUNTS] = counts
