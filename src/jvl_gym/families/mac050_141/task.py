"""What a compiled task may read and set of a MAC050–141 motor during an env step.

A task's hooks (``jvl_gym.engine.driver``) receive the engine's
:class:`~jvl_gym.engine.view.EngineView` and reach the motors only through these inlined
accessors: register values by number (``R``, taken from the register table), the world inputs
the motor's connectors and shaft see, and the physical truth a process model around the motor
needs (the shaft angle, the COIL block's direction). Beside them, the modes and registers the
tasks drive, under names every family's task module shares (``POSITION_MODE`` …
``AG_CENTRE_FACTOR``), so that a task written once runs on each family (docs/envs.md).
"""

from __future__ import annotations

import numpy as _np
from numba import njit

from ...engine.task_access import task_accessors
from ...engine.view import EngineView
from . import constants as _c
from . import layout as _L
from .firmware import regs as R
from .firmware.gear_blocks import analog_gear_factor as _analog_gear_factor
from .table import TABLE as _TABLE

__all__ = ["R", "FAMILY_KEY", "DEFAULT_MOTOR_TYPE", "TERMINAL_ERRORS", "ERROR_BITS", "reg",
           "set_reg", "shaft_angle", "coil_direction", "set_analog_volts",
           "set_load_torque", "set_pulse_counts", "POSITION_MODE", "VELOCITY_MODE",
           "ANALOG_TORQUE_MODE", "ANALOG_GEAR_MODE", "rpm_to_v_soll", "SPEED_PI", "GEARF",
           "AG_CENTRE_VOLTS", "AG_SPAN_VOLTS", "AG_CENTRE_FACTOR", "GEAR_MODE", "ag_factor",
           "KVOUT_FROM_LOAD",
           "COPPER_COLUMN"]


#: the family's key, and the motor type of a task when none is given
FAMILY_KEY = "mac050_141"
DEFAULT_MOTOR_TYPE = "MAC140"
#: ERR_STAT bits that end an episode: I2T, FLW, FNC, UIT and position-limit errors (3.2.35)
TERMINAL_ERRORS = (("I2T_ERR", _c.I2T_ERR), ("FLW_ERR", _c.FLW_ERR), ("FNC_ERR", _c.FNC_ERR),
                   ("UIT_ERR", _c.UIT_ERR), ("PLIM_ERR", _c.PLIM_ERR))
ERROR_BITS = _c.I2T_ERR | _c.FLW_ERR | _c.FNC_ERR | _c.UIT_ERR | _c.PLIM_ERR

# --- the modes and registers the tasks drive (docs/envs.md) ----------------------------------
POSITION_MODE = _c.P_MODE  #: point-to-point moves (manual 4.4.3)
VELOCITY_MODE = _c.V_MODE  #: velocity (manual 4.4.2)
#: the analogue input commands the torque: VF_OUT = ANINP·T_SOLL/1023 (manual 4.4.5)
ANALOG_TORQUE_MODE = _c.AT_MODE
#: the pulse input geared by GEARF1/GEARF2, scaled by the analogue input (manual 4.1.9, 4.4.19)
ANALOG_GEAR_MODE = _c.AG_MODE
rpm_to_v_soll = _c.rpm_to_v_soll  #: rpm → V_SOLL units (manual 3.2.5)
#: the speed regulator's PI taps of the default setup: KVFX4 = c·(kp + ki), KVFX3 = −c·kp
#: (manual 4.2, docs/model.md §8)
SPEED_PI = ("KVFX4", "KVFX3")
GEARF = ("GEARF1", "GEARF2")  #: the gear factor's numerator and denominator (manual 3.2.13)
#: a task's analogue gear trim: input = AG_CENTRE_VOLTS + AG_SPAN_VOLTS·a for a ∈ [−1, 1], the
#: whole ±10 V input (manual 4.1.9: −10 V ↔ 0.87, +10 V ↔ 1.15)
AG_CENTRE_VOLTS = 0.0
AG_SPAN_VOLTS = _c.ANINP_VOLTS
#: whether a task sets KVOUT = (J_m + J_load)/J_m for its load (manual 3.2.13): no, the tasks
#: run the default setups as they are
KVOUT_FROM_LOAD = False
#: the motors' state column of the copper energy account (``MotorArray.energy["copper"]``),
#: which an env reads alone for the copies whose episode ends
COPPER_COLUMN = _L.S_E_COPPER
#: the AG factor at AG_CENTRE_VOLTS, as the firmware computes it (ANINP = 0)
AG_CENTRE_FACTOR = float(_analog_gear_factor.py_func(_np.zeros(_TABLE.last + 1, dtype=_np.int64)))
#: the mode whose gear is GEARF1/GEARF2 alone, run by AG_MODE's gear position block: GP_MODE
#: (manual 4.4.4, 4.1.12), where a controller on the bus sets the trimmed gear itself
GEAR_MODE = _c.GP_MODE


def ag_factor(aninp: int) -> float:
    """AG_MODE's factor at the analogue input ``aninp`` (ANINP counts, ±1023 = ±10 V; manual
    4.1.9), as the firmware computes it."""
    regs = _np.zeros(_TABLE.last + 1, dtype=_np.int64)
    regs[R.ANINP] = int(aninp)
    return float(_analog_gear_factor.py_func(regs))


#: register values, saturated stores, the shaft angle and the world inputs (``set_analog_volts``:
#: ANINP, manual 3.2.122; ``set_pulse_counts``: V_EXT, manual 3.2.120)
reg, set_reg, shaft_angle, set_analog_volts, set_load_torque, set_pulse_counts = task_accessors(
    FAMILY_KEY, __file__, _TABLE, R.MODE_REG, _L, ("reg", "set_reg", "shaft_angle",
                                                  "set_analog_volts", "set_load_torque",
                                                  "set_pulse_counts"))


@njit(cache=True, inline="always")
def coil_direction(view: EngineView, i: int) -> float:  # pragma: no cover - compiled
    """Direction of the COIL block's traverse of motor ``i`` (+1, −1; 0 before COIL_MODE ran,
    manual 4.4.18)."""
    return view.state[i, _L.S_AUX1]
