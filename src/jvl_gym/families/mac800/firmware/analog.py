"""Analogue function blocks of the MAC800: modes 4, 5, 6, 16, 17, 18, 21 (register overview
§1.2, register 2), reading ANINP (register 170: ±2047 ↔ ±10 V).

The overview names the modes only; each follows the MAC050–141 mode of the same name (its
manual 4.1.4–4.1.6, 4.1.10, 4.4.18) scaled to the MAC800's ±2047 input (decisions):

- 4 analogue torque: VF_OUT = ANINP·T_SOLL/2047, limited to ±T_SOLL (no function block);
- 5 analogue velocity: target = ANINP·V_SOLL/2047 (±10 V ↔ ±V_SOLL);
- 6 analogue velocity/gear: target = GV_EXT + ANINP/2047·(300 RPM), the MAC050–141's AVG block
  (its manual 4.1.7, 4.4.7: ±10 V adds ±300 RPM to the geared velocity); V_SOLL, "the maximum
  velocity for compensating for follow error", bounds nothing, as the mode has no function
  correction (docs/families/mac800.md, "Modes 6, 18 and 21");
- 16 analogue velocity with dead band: ±128 (±0.625 V) gives 0, beyond it linear to ±V_SOLL
  at ±2047;
- 17 velocity/analogue torque: the velocity block at V_SOLL with the torque limit
  |ANINP|·T_SOLL/2047;
- 18 analogue gear: the gear block with the ratio times the analogue gear factor
  1.01 + 0.14·ANINP/2047, −10 V ↔ 0.87 … +10 V ↔ 1.15 (MAC050–141 manual 4.1.9, as its AG
  block): the motor follows the pulses at any input voltage;
- 21 analogue to position: the input as a logic level with hysteresis (high above 5.4 V, low
  below 4.4 V); a rising edge sets the target to POS1, a falling one to POS0 (with CNTRL_BITS
  RELPOSPSOLL added to P_SOLL, with RELPOSPFNC to the function position); on entry the level
  is taken without an edge and, in absolute positioning, sets the target.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ....engine.jit import KERNEL
from ....physics.fixed import clamp, rnd, wrap32
from ....physics.levels import hysteresis_level
from .. import constants as c
from .. import layout as L
from ..units import V_SOLL_UNITS_PER_RPM
from . import regs as R

_FULL = float(c.ANINP_FULL)
#: mode 6: the analogue velocity at ANINP = 2047 (≈ 10 V) [1/16 count/sample], 300 RPM
AVG_VELOCITY = 300.0 * V_SOLL_UNITS_PER_RPM
#: mode 18: the analogue gear factor at 0 V and its change at ±10 V (0.87 … 1.15)
AG_CENTRE = 1.01
AG_SPAN = 0.14
DEAD_BAND = 128.0  #: mode 16's dead band [ANINP units], 0.625 V
_HIGH = 5.4 / c.ANINP_VOLTS_PER_UNIT
_LOW = 4.4 / c.ANINP_VOLTS_PER_UNIT


@njit(cache=True, inline="always")
def analog_torque(r: np.ndarray) -> float:
    """Mode 4: VF_OUT."""
    t = float(r[R.T_SOLL])
    return clamp(rnd(r[R.ANINP] * t / _FULL), -t, t)


@njit(cache=True, inline="always")
def analog_velocity(r: np.ndarray) -> float:
    """Mode 5: ±10 V ↔ ±V_SOLL."""
    return float(int(r[R.ANINP] * float(r[R.V_SOLL]) / _FULL))


@njit(cache=True, inline="always")
def analog_velocity_gear(r: np.ndarray) -> float:
    """Mode 6's analogue part, added to the geared velocity: ±10 V ↔ ±300 RPM."""
    return float(int(r[R.ANINP] * AVG_VELOCITY / _FULL))


@njit(cache=True, inline="always")
def dead_band_velocity(r: np.ndarray) -> float:
    """Mode 16: zero within ±DEAD_BAND, linear to ±V_SOLL at ±2047 beyond it."""
    a = float(r[R.ANINP])
    k = float(r[R.V_SOLL]) / (_FULL - DEAD_BAND)
    if a > DEAD_BAND:
        return float(int((a - DEAD_BAND) * k))
    if a < -DEAD_BAND:
        return float(int((a + DEAD_BAND) * k))
    return 0.0


@njit(cache=True, inline="always")
def torque_limit(r: np.ndarray) -> float:
    """Mode 17: |ANINP|·T_SOLL/2047."""
    return abs(r[R.ANINP] * float(r[R.T_SOLL]) / _FULL)


@njit(cache=True, inline="always")
def gear_factor(r: np.ndarray) -> float:
    """Mode 18: the gear ratio's analogue factor, −10 V ↔ 0.87, 0 V ↔ 1.01, +10 V ↔ 1.15."""
    return AG_CENTRE + AG_SPAN * r[R.ANINP] / _FULL


@njit(**KERNEL)
def analog_position(r: np.ndarray, s: np.ndarray) -> None:
    """Mode 21: set the target from the input's level changes."""
    a = float(r[R.ANINP])
    level = s[L.S_A2P_LEVEL]
    relative = (r[R.CNTRL_BITS] & (c.RELPOSPSOLL | c.RELPOSPFNC)) != 0
    if level < 0.0:  # entry: the level without an edge
        level = 1.0 if a > _HIGH else 0.0
        s[L.S_A2P_LEVEL] = level
        if not relative:
            r[R.P_SOLL] = r[R.POS0 + 2] if level > 0.5 else r[R.POS0]
        return
    new = hysteresis_level(level, a, _HIGH, _LOW)
    if new == level:
        return
    s[L.S_A2P_LEVEL] = new
    px = r[R.POS0 + 2] if new > 0.5 else r[R.POS0]
    cb = r[R.CNTRL_BITS]
    if cb & c.RELPOSPFNC:
        r[R.P_SOLL] = wrap32(int(rnd(s[L.S_PF16] / 16.0)) + px)
    elif cb & c.RELPOSPSOLL:
        r[R.P_SOLL] = wrap32(r[R.P_SOLL] + px)
    else:
        r[R.P_SOLL] = px
