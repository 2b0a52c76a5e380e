"""The step profile generator: start velocity, ramps and stops (MIS manual §8.2.3–§8.2.12).

Velocities are counts per outer sample (1 ms), accelerations counts per outer sample², the units
of :mod:`..constants`. The rules:

- a movement starts by jumping to the start velocity V_START (§8.2.12) and ends by jumping from
  it to 0; if the target speed is below V_START, the internal start velocity is the target
  speed itself ("the motor will actually start the movement with an internal V_START =
  V_SOLL"), so the motor runs without a ramp;
- A_SOLL, D_SOLL (0: A_SOLL, §8.2.6) and V_START are taken over ("latched") only at standstill,
  so a change made during a movement acts after the motor has stopped or reversed (§8.2.3);
- a target speed below the start velocity during a movement decelerates to the start velocity
  and runs there (§8.2.12's example);
- a target of the other sign decelerates to the start velocity, stops, then starts the other
  way (§8.2.12).
"""

from __future__ import annotations

import math

from numba import njit

from .. import constants as c
from .. import layout as L
from . import regs as R


@njit(cache=True)
def latch_profile(regs, s) -> None:  # pragma: no cover - compiled
    """Take V_START, A_SOLL and D_SOLL over at standstill (§8.2.3, §8.2.6, §8.2.12)."""
    s[L.S_VS] = regs[R.V_START] * c.VEL_UNIT_TO_COUNTS
    s[L.S_ACC] = regs[R.A_SOLL] * c.ACC_UNIT_TO_COUNTS
    d = regs[R.D_SOLL]
    s[L.S_DEC] = (d if d > 0 else regs[R.A_SOLL]) * c.ACC_UNIT_TO_COUNTS


@njit(cache=True)
def velocity_step(regs, s, target: float, dec: float) -> float:  # pragma: no cover
    """The profile velocity of the next outer sample towards the signed ``target`` speed.

    ``dec``: the deceleration to use (``S_DEC``, or ACC_EMERG's for an error stop), counts
    per outer sample².
    """
    v = s[L.S_VEL]
    if v == 0.0:
        if target == 0.0:
            return 0.0
        latch_profile(regs, s)
        vs = min(s[L.S_VS], abs(target))
        s[L.S_VS] = vs
        return math.copysign(vs, target)
    vs = s[L.S_VS]
    speed = abs(v)
    if target == 0.0 or (target > 0.0) != (v > 0.0):  # stop (and reverse afterwards)
        if speed <= vs:
            return 0.0
        return math.copysign(max(speed - dec, vs), v)
    goal = max(abs(target), vs)
    if speed < goal:
        speed = min(speed + s[L.S_ACC], goal)
    elif speed > goal:
        speed = max(speed - dec, goal)
    return math.copysign(speed, v)


@njit(cache=True)
def position_step(regs, s, remaining: float,
                  vmax: float) -> tuple[float, bool]:  # pragma: no cover - compiled
    """The profile velocity of the next outer sample of a move ``remaining`` counts long
    (signed) at up to ``vmax`` counts per outer sample; True when it lands on the target.

    The move brakes so that it reaches the start velocity at the target
    (``v ≤ sqrt(vs² + 2·dec·|remaining|)``) and lands exactly on it (§8.2.3, position mode);
    a target behind the motion stops the motor first.
    """
    v = s[L.S_VEL]
    if remaining == 0.0:
        return 0.0, v == 0.0
    if v == 0.0:
        latch_profile(regs, s)
        vs = min(s[L.S_VS], vmax)
        s[L.S_VS] = vs
        if abs(remaining) <= vs:
            return remaining, True
        return math.copysign(vs, remaining), False
    if (remaining > 0.0) != (v > 0.0):  # the target is behind: stop first
        return velocity_step(regs, s, 0.0, s[L.S_DEC]), False
    vs = s[L.S_VS]
    speed = abs(v)
    goal = max(vmax, vs)
    if speed < goal:
        speed = min(speed + s[L.S_ACC], goal)
    elif speed > goal:
        speed = max(speed - s[L.S_DEC], goal)
    brake = math.sqrt(vs * vs + 2.0 * s[L.S_DEC] * abs(remaining))
    speed = max(min(speed, brake), vs)
    if speed >= abs(remaining):
        return remaining, True
    return math.copysign(speed, v), False
