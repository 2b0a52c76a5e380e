"""Closed-loop current control (MIS manual §5.3.3, §5.3.7; registers §8.2.108–114).

With closed loop (SETUP_BITS bit 24) and an H2/H4 encoder, the drive commutates from the
encoder: the plant keeps the commanded electrical angle within one full step (90° electrical,
2048 counts) of the rotor, so the torque never falls past its peak and no step is lost
(``plant``). With current control (bit 25) the current is ACTUAL_TORQUE/2047 of RUN_CURRENT.
ACTUAL_TORQUE follows the follow error: 2047 at a follow error of one full step or more,
proportionally less below, rounded down to whole steps ("when the position error becomes
below 2048 counts (1 full step) the current is also proportionally decreased", §5.3.3), and
inside CUR_SCALE_MIN … CUR_SCALE_MAX. It moves by one step per
``T_INC = CUR_SCALE_INC / 36 MHz`` up and per ``T_DEC = DEC_CNT / 36 MHz`` down, with
``DEC_CNT = |RPM|·100/4096·CUR_SCALE_FACTOR + CUR_SCALE_DEC`` (§5.3.7: 55.56 µs up, 111 µs
down at 0 RPM, 0 → 100 % in 113 ms). The 36 MHz ticks of a 1 ms outer sample left over from
whole steps are carried to the next sample.

Catch-up (CL_CATCH_UP, §8.2.128; §5.3.4): the field the currents are commutated to moves at no
more than V_SOLL (or the profile's speed, if higher), so a rotor that has fallen behind does not
exceed V_SOLL to catch up — unless the follow error is above bits 8–31 of CL_CATCH_UP, when the
limit is V_SOLL raised by bits 0–7 percent. A position move that has ended still brings the
rotor to the target at up to that speed.
"""

from __future__ import annotations

import math

from numba import njit

from .. import constants as c
from .. import layout as L
from ..units import CUR_SCALE_CLOCK_HZ, CUR_SCALE_FULL, OUTER_DT
from . import regs as R

#: 36 MHz clock ticks per outer sample
TICKS_PER_OUTER = CUR_SCALE_CLOCK_HZ * OUTER_DT


@njit(cache=True)
def scale_current(regs, s, follow_error: float, rpm: float) -> None:  # pragma: no cover
    """Advance ACTUAL_TORQUE (``S_CUR_SCALE``) by one outer sample towards the follow
    error's current (module docstring)."""
    lo = float(regs[R.CUR_SCALE_MIN])
    hi = float(max(regs[R.CUR_SCALE_MAX], regs[R.CUR_SCALE_MIN]))
    share = min(abs(follow_error) / c.COUNTS_PER_FULL_STEP, 1.0)
    goal = min(max(math.floor(CUR_SCALE_FULL * share), lo), hi)
    now = s[L.S_CUR_SCALE]
    ticks = s[L.S_SCALE_CLOCK] + TICKS_PER_OUTER
    if goal > now:
        per = float(regs[R.CUR_SCALE_INC])
    elif goal < now:
        per = abs(rpm) * 100.0 / 4096.0 * regs[R.CUR_SCALE_FACTOR] + regs[R.CUR_SCALE_DEC]
    else:
        s[L.S_SCALE_CLOCK] = 0.0
        return
    n = math.floor(ticks / per)
    s[L.S_SCALE_CLOCK] = ticks - n * per
    s[L.S_CUR_SCALE] = min(now + n, goal) if goal > now else max(now - n, goal)
    if s[L.S_CUR_SCALE] == goal:
        s[L.S_SCALE_CLOCK] = 0.0


@njit(cache=True)
def field_step(regs, s, v: float) -> float:  # pragma: no cover - compiled
    """Largest advance of the commutation field per inner sample [counts] (module docstring):
    ``v`` is this outer sample's profile velocity [counts per outer sample]."""
    catch = regs[R.CL_CATCH_UP]
    limit = max(abs(regs[R.V_SOLL]) * c.VEL_UNIT_TO_COUNTS, abs(v))
    if abs(regs[R.FLWERR]) > (catch >> 8):
        limit *= 1.0 + min(catch & 0xFF, 100) / 100.0
    return limit / c.INNER_PER_OUTER
