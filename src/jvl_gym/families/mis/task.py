"""What a compiled task may read and set of an MIS/SMC step motor during an env step.

A task's hooks (``jvl_gym.engine.driver``) receive the engine's
:class:`~jvl_gym.engine.view.EngineView` and reach the motors only through these inlined
accessors: register values by number (``R``, from the register table), the world inputs (load
torque and inertia, supply, gear pulses, I/O), and the physical truth an indexing process needs
(rotor angle and speed, steps lost against the command, copper loss).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ...engine.task_access import task_accessors
from ...engine.view import EngineView
from . import constants as _c
from . import layout as _L
from .firmware import regs as R
from .table import TABLE as _TABLE
from .units import COUNTS_PER_RAD as _COUNTS_PER_RAD

__all__ = ["R", "FAMILY_KEY", "DEFAULT_MOTOR_TYPE", "TERMINAL_ERRORS", "ERROR_BITS", "reg",
           "set_reg", "rotor_angle", "rotor_speed", "lost_steps", "copper_energy",
           "load_energy", "set_load_torque", "set_load_inertia", "set_supply_volts",
           "set_pulse_counts", "set_digital_inputs", "COPPER_COLUMN"]

#: the family's key, and the motor type of a task when none is given
FAMILY_KEY = "mis"
DEFAULT_MOTOR_TYPE = "MIS232"
#: ERR_BITS that end an episode: follow error, position limit, low bus voltage (§8.2.31)
TERMINAL_ERRORS = (("FOLLOW", _c.ERR_FOLLOW), ("POSITION_LIMIT", _c.ERR_POSITION_LIMIT),
                   ("LOW_BUS", _c.ERR_LOW_BUS))
ERROR_BITS = _c.ERR_FOLLOW | _c.ERR_POSITION_LIMIT | _c.ERR_LOW_BUS
#: the motors' state column of the copper energy account (``MotorArray.energy["copper"]``),
#: which an env reads alone for the copies whose episode ends
COPPER_COLUMN = _L.S_E_COPPER


#: register values, saturated stores (P_SOLL in a turn-table mode, COMMAND … go through
#: ``MotorArray.write``), the rotor angle from power-on, the load torque and the gear input
#: counts (§8.2.3 gear mode)
reg, set_reg, rotor_angle, set_load_torque, set_pulse_counts = task_accessors(
    FAMILY_KEY, __file__, _TABLE, R.MODE_REG, _L, ("reg", "set_reg", "shaft_angle",
                                                  "set_load_torque", "set_pulse_counts"))


@njit(cache=True, inline="always")
def rotor_speed(view: EngineView, i: int) -> float:  # pragma: no cover - compiled
    """Rotor speed of motor ``i`` [rad/s]."""
    return view.state[i, _L.S_OMEGA]


@njit(cache=True, inline="always")
def lost_steps(view: EngineView, i: int) -> int:  # pragma: no cover - compiled
    """Full steps motor ``i``'s rotor has lost against its commanded position (positive:
    behind), in whole electrical turns of 4 full steps."""
    lag = (view.state[i, _L.S_CMD] - view.state[i, _L.S_THETA] * _COUNTS_PER_RAD) / (
        _c.COUNTS_PER_ELECTRICAL_TURN)
    return 4 * int(np.floor(lag + 0.5))


@njit(cache=True, inline="always")
def copper_energy(view: EngineView, i: int) -> float:  # pragma: no cover - compiled
    """Copper loss of motor ``i`` since power-on [J]."""
    return view.state[i, _L.S_E_COPPER]


@njit(cache=True, inline="always")
def load_energy(view: EngineView, i: int) -> float:  # pragma: no cover - compiled
    """Work done against the load torque by motor ``i`` since power-on [J]."""
    return view.state[i, _L.S_E_LOAD]


@njit(cache=True, inline="always")
def set_load_inertia(view: EngineView, i: int, inertia: float) -> None:  # pragma: no cover
    """Load inertia on motor ``i``'s shaft [kg·m²] (≥ 0), from the next outer sample on."""
    view.params[i, _L.P_J_LOAD] = max(inertia, 0.0)


@njit(cache=True, inline="always")
def set_supply_volts(view: EngineView, i: int, volts: float) -> None:  # pragma: no cover
    """P+ supply of motor ``i`` [V]."""
    view.inputs[i, _L.I_SUPPLY_VOLTS] = volts


@njit(cache=True, inline="always")
def set_digital_inputs(view: EngineView, i: int, bits: int) -> None:  # pragma: no cover
    """IO1–IO8 levels of motor ``i`` (bits 0–7)."""
    view.inputs[i, _L.I_DIGITAL] = bits
