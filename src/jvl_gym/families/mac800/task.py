"""What a compiled task may read and set of a MAC800-family motor during an env step (public
module): the names of ``families/mac050_141/task.py`` where the meaning is the same, so that
an env written against that interface runs on this family.

Register values by number (``R``, from the register table), the world inputs the motor's
connectors and shaft see, and the shaft angle; the modes and registers the tasks drive. (The
MAC050–141's ``coil_direction`` has no counterpart: the MAC800's coil mode is not modelled.)
"""

from __future__ import annotations

import numpy as _np

from ...engine.task_access import task_accessors
from . import constants as _c
from . import layout as _L
from .firmware import regs as R
from .firmware.analog import gear_factor as _gear_factor
from .table import TABLE as _TABLE
from .units import ANINP_VOLTS_PER_UNIT as _ANINP_VOLTS_PER_UNIT
from .units import rpm_to_v_soll

__all__ = ["R", "FAMILY_KEY", "DEFAULT_MOTOR_TYPE", "TERMINAL_ERRORS", "ERROR_BITS", "reg",
           "set_reg", "shaft_angle", "set_analog_volts", "set_load_torque", "set_pulse_counts",
           "POSITION_MODE", "VELOCITY_MODE", "ANALOG_TORQUE_MODE", "ANALOG_GEAR_MODE",
           "rpm_to_v_soll", "SPEED_PI", "SPEED_FEEDBACK", "GEARF", "AG_CENTRE_VOLTS",
           "AG_SPAN_VOLTS", "AG_CENTRE_FACTOR", "KVOUT_FROM_LOAD", "COPPER_COLUMN"]

#: the family's key, and the motor type of a task when none is given
FAMILY_KEY = "mac800"
DEFAULT_MOTOR_TYPE = "MAC800"
#: ERR_STAT bits that end an episode: every error bit (register 35)
TERMINAL_ERRORS = tuple((name, bit) for bit, name in _c.ERROR_NAMES.items())
ERROR_BITS = 0
for _bit in _c.ERROR_NAMES:
    ERROR_BITS |= _bit

# --- the modes and registers the tasks drive (register 2 MODE_REG; docs/envs.md) -------------
POSITION_MODE = _c.POSITION_MODE  #: mode 2, Position
VELOCITY_MODE = _c.VELOCITY_MODE  #: mode 1, Velocity
#: mode 4, Analog torque: VF_OUT = ANINP·T_SOLL/2047 (firmware/analog.py)
ANALOG_TORQUE_MODE = _c.ANALOG_TORQUE_MODE
#: mode 18, Analog gear: the pulse input geared by GEARF_1/GEARF_2 times the analogue gear
#: factor, −10 V ↔ 0.87 … +10 V ↔ 1.15 (firmware/analog.py)
ANALOG_GEAR_MODE = _c.ANALOG_GEAR_MODE
#: the main filter's PI taps: KVFX6 = kp + ki, KVFX5 = −kp (register overview §1.2 "Filters")
SPEED_PI = ("KVFX6", "KVFX5")
#: the feedback filter's leading taps, which the default setup's I-P arrangement uses for the
#: proportional part: KVB4 = 1 + kp/ki, KVB3 = −kp/ki with KVFX6 = ki, KVFX5 = 0
#: (configs/setups/MAC800.yaml)
SPEED_FEEDBACK = ("KVB4", "KVB3")
GEARF = ("GEARF_1", "GEARF_2")  #: the gear factor's numerator and denominator (registers 14, 15)
#: a task's analogue gear trim: input = AG_CENTRE_VOLTS + AG_SPAN_VOLTS·a for a ∈ [−1, 1], the
#: whole ±10 V input (mode 18's factor 0.87 … 1.15, as the MAC050–141's AG block)
AG_CENTRE_VOLTS = 0.0
AG_SPAN_VOLTS = _c.ANINP_VOLTS
#: whether a task sets KVOUT = (J_motor + J_load)/J_motor for its load (register 13): yes, the
#: default setup's speed loop is designed for the bare rotor at KVOUT = 1
#: (configs/setups/MAC800.yaml) and is too slow to follow a gear under a load of several rotor
#: inertias without it (decision)
KVOUT_FROM_LOAD = True
#: the motors' state column of the copper energy account (``MotorArray.energy["copper"]``),
#: which an env reads alone for the copies whose episode ends
COPPER_COLUMN = _L.S_E_COPPER


def _ag_centre_factor() -> float:
    """Mode 18's factor at AG_CENTRE_VOLTS, as the firmware computes it from ANINP (register
    170: V = ANINP × 0.0048828, ANINP_OFFSET 0)."""
    row = _np.zeros(_TABLE.last + 1, dtype=_np.int64)
    row[R.ANINP] = round(AG_CENTRE_VOLTS / _ANINP_VOLTS_PER_UNIT)
    return float(_gear_factor.py_func(row))


AG_CENTRE_FACTOR = _ag_centre_factor()  #: mode 18's factor at AG_CENTRE_VOLTS


#: register values, saturated stores, the shaft angle and the world inputs (``set_analog_volts``:
#: ANINP, register 170; ``set_pulse_counts``: V_EXT, register 163)
reg, set_reg, shaft_angle, set_analog_volts, set_load_torque, set_pulse_counts = task_accessors(
    FAMILY_KEY, __file__, _TABLE, R.MODE_REG, _L, ("reg", "set_reg", "shaft_angle",
                                                  "set_analog_volts", "set_load_torque",
                                                  "set_pulse_counts"))
