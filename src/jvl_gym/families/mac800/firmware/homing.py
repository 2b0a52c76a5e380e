"""Zero searches of the MAC800: modes 12, 13, 14 with V_HOME, T_HOME, HOME_MODE, P_HOME,
INDEX_OFFSET and CNTRL_BITS INDEX_HOME (register overview §1.2, registers 2, 9, 36–42).

The overview names the modes and registers only; the searches follow the MAC050–141's HOME1–3
(its manual 4.4.13–4.4.15), which the names match (decisions):

- 12, torque zero search: the velocity block at V_HOME with the torque limited to
  1.25·|T_HOME|; the mechanical limit is found after 50 samples with |VF_OUT| > |T_HOME|.
- 13, sensor type 1: towards the sensor (V_HOME) while it is passive, away (−V_HOME) while it is
  active; found when it becomes active.
- 14, sensor type 2: as 13, then slowly away (V_HOME/64, at least one unit) while active; found
  when it becomes passive again (the edge approached from one side at low speed).

The sensor is read on the analogue input (active level above 5 V when T_HOME ≥ 0, below when
T_HOME < 0: "the sign defines polarity of the zero search sensor"). At the zero: INDEX_OFFSET =
the counts from the nearest encoder index to the zero point; P_IST = P_HOME there, or, with
INDEX_HOME, at the index (P_IST = P_HOME + INDEX_OFFSET); P_SOLL and the function position
become P_IST (the motor holds where it is) and HOME_MODE bit 16 (Home_Done) is set. Then the
motor enters START_MODE when that is a regulated mode other than a zero search, else passive.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ....engine.jit import KERNEL
from ....physics.fixed import wrap32
from ....physics.levels import sensor_edge
from .. import constants as c
from .. import layout as L
from . import regs as R
from .blocks import velocity_block

DETECTIONS = 50  #: torque search: samples above |T_HOME| that find the limit
TORQUE_FACTOR = 1.25  #: torque search: torque limit / |T_HOME|
_SENSOR_HIGH = 5.0 / c.ANINP_VOLTS_PER_UNIT  #: ANINP above 5 V is high


@njit(cache=True, inline="always")
def sensor_active(r: np.ndarray) -> bool:
    """The zero-search sensor's level on the analogue input, polarity from T_HOME's sign."""
    high = r[R.ANINP] > _SENSOR_HIGH
    return high if r[R.T_HOME] >= 0 else not high


@njit(**KERNEL)
def home_block(r: np.ndarray, s: np.ndarray, mode: int) -> tuple[float, float]:
    """The search's profile: (FNC_OUT, torque limit)."""
    vh = float(r[R.V_HOME])
    a = float(r[R.A_SOLL])
    if mode == c.TORQUE_ZERO_SEARCH:
        return (velocity_block(r, s, vh, a),
                min(TORQUE_FACTOR * abs(float(r[R.T_HOME])), float(r[R.T_SOLL])))
    active = sensor_active(r)
    slow = float(int(-vh / 64.0))
    slow = slow if slow != 0.0 else (-1.0 if vh > 0.0 else 1.0)
    if mode == c.SENSOR1_ZERO_SEARCH or s[L.S_HOME_PHASE] < 0.5:
        target = -vh if active else vh
        if mode == c.SENSOR2_ZERO_SEARCH and active and s[L.S_HOME_LEVEL] == 0.0:
            s[L.S_HOME_PHASE] = 1.0
            target = slow
    else:
        target = slow
    return velocity_block(r, s, target, a), float(r[R.T_SOLL])


@njit(**KERNEL)
def home_found(r: np.ndarray, s: np.ndarray, mode: int, from_index: float) -> bool:
    """After the main filter: detect the zero; on it, set the zero position.

    ``from_index``: signed counts from the nearest encoder index to the shaft now."""
    found = False
    if mode == c.TORQUE_ZERO_SEARCH:
        if abs(float(r[R.VF_OUT])) > abs(float(r[R.T_HOME])):
            s[L.S_HOME_PHASE] += 1.0
        else:
            s[L.S_HOME_PHASE] = 0.0
        found = s[L.S_HOME_PHASE] >= DETECTIONS
    else:
        active = sensor_active(r)
        found = sensor_edge(active, s[L.S_HOME_LEVEL], mode == c.SENSOR1_ZERO_SEARCH,
                            s[L.S_HOME_PHASE] > 0.5)
        s[L.S_HOME_LEVEL] = 1.0 if active else 0.0
    if found:
        r[R.INDEX_OFFSET] = int(from_index)
        p = int(r[R.P_HOME])
        if r[R.CNTRL_BITS] & c.INDEX_HOME:
            p = p + int(from_index)
        r[R.P_IST] = wrap32(p)
        r[R.P_SOLL] = r[R.P_IST]
        s[L.S_PF16] = 16.0 * float(r[R.P_IST])
        s[L.S_FLW16] = 0.0
        r[R.FLWERR] = 0
        r[R.HOME_MODE] |= c.HOME_DONE
    return found
