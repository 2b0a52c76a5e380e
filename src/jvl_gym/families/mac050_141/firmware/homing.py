"""Homing modes HOME1/2/3 (manual 4.4.13–4.4.15, registers 3.2.37–3.2.42).

- HOME1: velocity block at V_HOME with the torque limited to 1.25·|T_HOME| (3.2.41; 4.4.13
  writes 1.5, which would exceed 1023 for the allowed T_HOME 800 — decision, docs/model.md §9); a
  counter counts samples with |VF_OUT| > |T_HOME|; at 50 the mechanical limit is found.
- HOME2: away from the sensor (−V_HOME) while it is active, towards it (V_HOME) while passive;
  found when it becomes active.
- HOME3: as HOME2, then slowly away (−V_HOME/64 + 1) while active; found when it deactivates.
Each writes its search velocity to V_SOLL (4.4.13–4.4.15 "V_SOLL = V_HOME", "= −V_HOME", …),
which keeps the last one after the zero; T_SOLL is untouched (HOME1's torque limit is applied
without writing it, so "T_SOLL = original value" holds).
The home sensor is wired to the analogue input; its active level is high if T_HOME > 0 and low
otherwise, T_HOME = 0 included (3.2.41). At the zero: P_IST = P_HOME (rounded to the nearest
hall index marker when CNTRL_BITS INDEX_HOME is set), P_FNC = 16·P_HOME, P_SOLL = 0,
MODE_REG = STARTMODE.

State: S_AUX4 detection counter / phase, S_AUX5 sensor level at the previous sample (−1 before
the first sample of the search).
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

DETECTIONS = 50  #: HOME1: samples above T_HOME that define the limit (4.4.13)
HOME1_TORQUE_FACTOR = 1.25


@njit(cache=True, inline="always")
def sensor_active(r: np.ndarray) -> bool:
    """Home sensor level read on the analogue input, active level from the sign of T_HOME."""
    high = r[R.ANINP] > 512
    return high if r[R.T_HOME] > 0 else not high


@njit(**KERNEL)
def home_entry(r: np.ndarray, s: np.ndarray) -> None:
    """Reset the detection counter / search phase."""
    s[L.S_AUX4] = 0.0
    s[L.S_AUX5] = -1.0  # sensor level not yet read: the first sample only records it


@njit(**KERNEL)
def home_block(r: np.ndarray, s: np.ndarray, mode: int) -> tuple[float, float]:
    """Profile of the home search; returns (FNC_OUT, torque limit)."""
    vh = float(r[R.V_HOME])
    a = float(r[R.A_SOLL])
    if mode == c.HOME1_MODE:
        r[R.V_SOLL] = r[R.V_HOME]
        return velocity_block(r, s, vh, a), HOME1_TORQUE_FACTOR * abs(float(r[R.T_HOME]))
    active = sensor_active(r)
    phase = s[L.S_AUX4]
    if mode == c.HOME2_MODE:
        target = -vh if active else vh
    else:  # HOME3: phase 0 search (away while active, towards while passive), 1 slow away
        if phase < 0.5:
            target = -vh if active else vh
            if active and s[L.S_AUX5] == 0.0:
                s[L.S_AUX4] = 1.0
                target = float(int(-vh / 64.0)) + 1.0
        else:
            target = float(int(-vh / 64.0)) + 1.0
    r[R.V_SOLL] = int(target)
    return velocity_block(r, s, target, a), float(r[R.T_SOLL])


@njit(**KERNEL)
def home_check(r: np.ndarray, s: np.ndarray, mode: int) -> bool:
    """After the speed regulator: detect the home event; on it, set the zero position."""
    found = False
    if mode == c.HOME1_MODE:
        if abs(float(r[R.VF_OUT])) > abs(float(r[R.T_HOME])):
            s[L.S_AUX4] += 1.0
        found = s[L.S_AUX4] >= DETECTIONS
    else:
        active = sensor_active(r)
        found = sensor_edge(active, s[L.S_AUX5], mode == c.HOME2_MODE, s[L.S_AUX4] > 0.5)
        s[L.S_AUX5] = 1.0 if active else 0.0
    if found:
        set_home_position(r, s)
    return found


@njit(**KERNEL)
def set_home_position(r: np.ndarray, s: np.ndarray) -> None:
    """P_IST = P_HOME (INDEX_HOME: at the nearest index marker), P_FNC = 16·P_HOME, P_SOLL = 0."""
    p_home = int(r[R.P_HOME])
    offset = 0
    if r[R.CNTRL_BITS] & c.INDEX_HOME:
        el = int(r[R.ELDEG_IST])
        offset = -el if el < 1024 else 2048 - el  # counts to the nearest index marker
    r[R.P_IST] = wrap32(p_home - offset)
    r[R.P_FNC] = wrap32(16 * p_home)
    r[R.P_SOLL] = 0
    s[L.S_G_FNC] = 0.0
