"""MODE_REG (register 2) and START_MODE (register 37) of the MAC800: entering a mode, going
passive, and the reaction to an error (register overview §1.2; decisions in the docstrings).

- Entering a regulated mode from passive starts the profile at the motor's state: the function
  position is P_IST, V_OLD is 16·V_IST, the filter histories and the follow error are empty.
  Changing between regulated modes keeps the profile (bumpless).
- Passive (mode 0): no function block, VF_OUT = 0, the power stage off.
- An error of :data:`constants.STOPPING_ERRORS` stops the motor with ACC_EMERG (the mode stays
  in MODE_REG while the stop ramp replaces its function block) and then goes passive; an error of
  :data:`constants.PASSIVE_ERRORS` goes passive at once (decision: the overview names
  ACC_EMERG "the maximum allowed deceleration when a fatal error" occurs; over-voltage,
  over-current, encoder, filter and control-supply errors leave nothing to brake with safely).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ....engine.jit import KERNEL
from ....registers.fill import fill
from .. import constants as c
from .. import layout as L
from . import regs as R
from .main_filter import clear_filter

#: modes with the function block and the main filter (all runnable modes but 0 and 4)
_REGULATED = np.zeros(32, dtype=np.bool_)
for _m in c.RUNNABLE_MODES - {c.PASSIVE_MODE, c.ANALOG_TORQUE_MODE}:
    _REGULATED[_m] = True
#: modes with the function correction: the position and gear modes, whose profile is a
#: position that must not run away from a torque-limited motor (decision, as the MAC050–141)
_CORRECTING = np.zeros(32, dtype=np.bool_)
for _m in (c.POSITION_MODE, c.GEAR_MODE, c.ANALOG_GEAR_MODE, c.ANALOG_POSITION_MODE):
    _CORRECTING[_m] = True
#: modes with a follow error (FLWERR, register 20): the position, gear and zero-search modes,
#: and the velocity modes, where the follow error accumulates the velocity errors so that
#: FLWERRMAX stops a blocked or overloaded motor (the overview: "if the follow error passes this
#: limit the motor will be stopped", no mode excepted; as the MAC050–141, its manual 3.2.20:
#: "FLWERR is thus used here to detect abnormal loading of the motor or blockages")
_FOLLOWING = np.zeros(32, dtype=np.bool_)
for _m in (c.POSITION_MODE, c.GEAR_MODE, c.ANALOG_GEAR_MODE, c.ANALOG_POSITION_MODE,
           c.ANALOG_VELOCITY_GEAR_MODE, c.VELOCITY_MODE, c.ANALOG_VELOCITY_MODE,
           c.ANALOG_VELOCITY_DEADBAND_MODE, c.VELOCITY_ANALOG_TORQUE_MODE):
    _FOLLOWING[_m] = True


@njit(cache=True, inline="always")
def regulated(mode: int) -> bool:
    """The mode runs a function block and the main filter."""
    return 0 <= mode < 32 and _REGULATED[mode]


@njit(cache=True, inline="always")
def correcting(mode: int) -> bool:
    """The mode corrects its profile when the torque is limited."""
    return 0 <= mode < 32 and _CORRECTING[mode]


@njit(cache=True, inline="always")
def following(mode: int) -> bool:
    """The mode keeps a follow error."""
    return 0 <= mode < 32 and _FOLLOWING[mode]


#: registers passive mode clears: the speed loop's output, the function block's, the follow error
_PASSIVE_REGISTERS = (R.VF_OUT, R.FNC_OUT, R.FLWERR)
#: state passive mode clears: an emergency stop, the profile speed, the follow error's fraction
_PASSIVE_STATE = (L.S_EMERG, L.S_V_OLD, L.S_FLW16)


@njit(**KERNEL)
def go_passive(r: np.ndarray, s: np.ndarray) -> None:
    """MODE_REG = 0: no function block, VF_OUT = 0, the power stage off."""
    r[R.MODE_REG] = c.PASSIVE_MODE
    fill(r, _PASSIVE_REGISTERS, 0)
    fill(s, _PASSIVE_STATE, 0.0)
    s[L.S_HOME_AFTER] = -1.0


@njit(**KERNEL)
def enter_mode(r: np.ndarray, s: np.ndarray, mode: int) -> None:
    """Enter ``mode`` (a runnable MODE_REG value) with its entry actions."""
    old = int(r[R.MODE_REG])
    if mode == c.PASSIVE_MODE:
        go_passive(r, s)
        return
    if not regulated(old):
        s[L.S_PF16] = 16.0 * float(r[R.P_IST])
        s[L.S_V_OLD] = 16.0 * float(r[R.V_IST])
        s[L.S_FLW16] = 0.0
        s[L.S_G_FNC] = 0.0
        s[L.S_GEAR_REM] = 0.0
        r[R.FLWERR] = 0
        clear_filter(s)
    if mode == c.TORQUE_ZERO_SEARCH or mode == c.SENSOR1_ZERO_SEARCH or (
            mode == c.SENSOR2_ZERO_SEARCH):
        s[L.S_HOME_PHASE] = 0.0
        s[L.S_HOME_LEVEL] = -1.0
    if mode == c.ANALOG_POSITION_MODE:
        s[L.S_A2P_LEVEL] = -1.0
    s[L.S_EMERG] = 0.0
    s[L.S_INPOS_CNT] = 0.0
    r[R.MODE_REG] = mode


@njit(**KERNEL)
def trip(r: np.ndarray, s: np.ndarray, bit: int) -> None:
    """Set the error ``bit`` of ERR_STAT and react: passive at once, or an ACC_EMERG stop."""
    r[R.ERR_STAT] |= bit
    if int(r[R.MODE_REG]) == c.PASSIVE_MODE:
        return
    if bit & c.PASSIVE_ERRORS:
        go_passive(r, s)
    elif regulated(int(r[R.MODE_REG])):
        s[L.S_EMERG] = 1.0
    else:  # analogue torque: no profile to ramp down
        go_passive(r, s)


@njit(**KERNEL)
def start_mode(r: np.ndarray, s: np.ndarray) -> None:
    """The mode after power-on: the zero search of HOME_MODE's low bits (12, 13, 14) first, if
    any, then START_MODE (decision: HOME_MODE read as the power-on zero search)."""
    go_passive(r, s)
    home = int(r[R.HOME_MODE]) & c.HOME_MODE_MASK
    start = int(r[R.START_MODE])
    if home in (c.TORQUE_ZERO_SEARCH, c.SENSOR1_ZERO_SEARCH, c.SENSOR2_ZERO_SEARCH):
        enter_mode(r, s, home)
        s[L.S_HOME_AFTER] = float(start)
    elif 0 < start < 32 and (regulated(start) or start == c.ANALOG_TORQUE_MODE):
        enter_mode(r, s, start)
