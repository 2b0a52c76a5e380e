"""Zero search types 1 and 2 (MODE_REG 13, 14; MIS manual §6.5, §8.2.34–37, §8.2.125–126).

Type 1 runs at V_HOME until the home input (INPUTS & HOME_MASK) becomes active; that point is
the zero: P_IST := P_HOME there. Type 2 then reverses at the crawl velocity (V_HOME_CRAWL, or
V_HOME/64 when it is 0, §6.5.9) until the input is released, and that point is the zero. The
motor stops (D_SOLL / A_SOLL), moves to position 0 if P_HOME ≠ 0 (§6.5.8 steps 2–3), sets
STATUSBITS bit 7 and changes to STARTMODE (§8.2.3). ENCODER_POS is set with P_IST at the zero
(§8.2.15). After V_HOME_TIMEOUT ms (0: 60 s; none with ZERO_SEARCH_BITS bit 5) the search ends
with ERR_BITS bit 16 and the motor is set back in the mode it was in before the search started
(``S_HOME_PREV``; §7.2.19, "Error / Motor is set back in previous mode"; for the power-on search
that is STARTMODE, §6.5.9). This error does not make the motor passive, as the other errors
do; the motor holds still in that mode until the errors are cleared ("will not move until all
the errors have been cleared", §8.2.31; ``kernel``). docs/families/mis-sim.md, "Zero search
time-out", has the readings and the choice.

ZERO_SEARCH_BITS (§8.2.67; MacTalk's texts in §6.5.4): bit 2 "Search for opposite side of
sensor", the zero on the sensor's "back side": type 1 runs on through the sensor at V_HOME
and the zero is where the input is released; type 2 runs through likewise, then comes back at
the crawl velocity until the input is active again, and that point is the zero (the mirror of
its front-side search, so that the edge is again taken at crawl speed: a decision, the manual
names the bit only). Bit 4 "Ignore switch": no input is looked at, "the actual position [is
used] as zero" at once, in either type. Bit 1 "Change direction on limit": while the search
seeks its sensor, a limit input ahead (PL_MASK/NL_MASK, MIN_P_IST/MAX_P_IST) turns it
(``S_HOME_DIR``) instead of stopping it with the position-limit error; every later phase runs in
the turned direction, and a limit met again turns it again until the time-out. Phases
(``S_HOME_PHASE``): 0 start, 1 seek, 2 leave the sensor, 3 stop, 4 move to 0, 6 run through the
sensor (bit 2), 7 come back onto it (bit 2, type 2), 8 on to the encoder index (bit 0).

Bit 0 "Use index after zero search" (with an encoder option): where the sensor (or, with bit 4,
the motor's position) would be the zero, the search instead notes the encoder's single-turn
position there in INDEX_OFFSET (§8.2.65: "the absolute value of the internal encoder where the
Zero search/home position was found") and goes on in the direction it was moving, at the crawl
velocity, to the encoder's index, once per revolution where its single-turn position is 0; the
index is the zero (phase 8). A decision: the manual names the bit and the register only.

Torque zero search (§6.5.7, "only available with H2/H4 encoder … Closed loop and Current
control enabled"): the register list gives it no MODE_REG or HOMEMODE number (HOMEMODE takes
0, 13, 14), so the simulator runs it as a search 13 or 14 with closed loop and current control
on and no home input selected (HOME_MASK = 0): the trigger is ACTUAL_TORQUE reaching T_HOME
(0 … 2047 = 0 … 100 % of RUN_CURRENT, §8.2.36) while the follow error asks for that current
(``firmware.closed_loop``; not merely the full current the closed loop starts with) — the
mechanical collision — and that rotor
position is the zero (P_IST and ENCODER_POS := P_HOME, the commanded position moved onto the
rotor, so the motor stops pressing). A decision, not the manual's wording.
"""

from __future__ import annotations

import math

from numba import njit

from ....engine.jit import plain_arguments
from ....physics.fixed import wrap32
from .. import constants as c
from .. import layout as L
from ..units import COUNTS_PER_REV, ZERO_SEARCH_TIMEOUT_DEFAULT_S
from . import regs as R
from .monitor import (
    COUNTS_PER_RAD,
    encoder_cpr,
    firmware_angle,
    rotor_counts_quantised,
    seeking_turns,
    set_encoder,
)
from .profile import position_step, velocity_step


@plain_arguments
@njit(cache=True)
def _set_zero(regs, s, p, at_rotor: bool) -> None:  # pragma: no cover - compiled
    """P_IST and ENCODER_POS := P_HOME here; ``at_rotor``: the commanded position (and the
    closed-loop field) moved onto the rotor first."""
    if at_rotor:
        rotor = s[L.S_THETA] * COUNTS_PER_RAD
        s[L.S_CMD] = rotor
        s[L.S_FIELD] = rotor
    regs[R.P_IST] = regs[R.P_HOME]
    s[L.S_FRAC] = 0.0
    set_encoder(regs, s, p, regs[R.P_HOME])


@njit(cache=True)
def _found(regs, s, p, v: float) -> None:  # pragma: no cover - compiled
    """The sensor's point reached while moving at ``v``: the zero here (phase 3), or with
    ZERO_SEARCH_BITS bit 0 and an encoder, INDEX_OFFSET := the encoder's single-turn position
    here and on to the index (phase 8)."""
    cpr = encoder_cpr(p)
    if regs[R.ZERO_SEARCH_BITS] & c.ZS_USE_INDEX and cpr > 0:
        absolute = rotor_counts_quantised(firmware_angle(regs, s), cpr)
        regs[R.INDEX_OFFSET] = int(absolute % COUNTS_PER_REV)
        s[L.S_INDEX_TURN] = math.floor(absolute / COUNTS_PER_REV)
        s[L.S_INDEX_DIR] = 1.0 if v >= 0.0 else -1.0
        s[L.S_HOME_PHASE] = 8.0
    else:
        _set_zero(regs, s, p, False)
        s[L.S_HOME_PHASE] = 3.0


@njit(cache=True)
def _at_index(regs, s, p) -> bool:  # pragma: no cover - compiled
    """The encoder has passed its index (single-turn position 0) since the sensor."""
    absolute = rotor_counts_quantised(firmware_angle(regs, s), encoder_cpr(p))
    turn = math.floor(absolute / COUNTS_PER_REV)
    return turn != s[L.S_INDEX_TURN]


@njit(cache=True)
def zero_search(regs, s, p, mode: int,
                limits: int) -> tuple[float, bool]:  # pragma: no cover - compiled
    """The profile velocity of this sample of a zero search, and whether it lands exactly;
    ``limits``: the active limit inputs (1: positive, 2: negative; ``monitor.check_errors``)."""
    phase = s[L.S_HOME_PHASE]
    s[L.S_HOME_MS] += 1.0
    limit = regs[R.V_HOME_TIMEOUT]
    limit_ms = limit if limit > 0 else ZERO_SEARCH_TIMEOUT_DEFAULT_S * 1000.0
    if not regs[R.ZERO_SEARCH_BITS] & c.ZS_NO_TIME_OUT and s[L.S_HOME_MS] > limit_ms:
        regs[R.ERR_BITS] |= c.ERR_ZERO_SEARCH_TIMEOUT | c.ERR_GENERAL
        s[L.S_HOME_PHASE] = 0.0
        regs[R.MODE_REG] = int(s[L.S_HOME_PREV])
        return velocity_step(regs, s, 0.0, s[L.S_DEC]), False
    setup = regs[R.SETUP_BITS]
    torque_search = (regs[R.HOME_MASK] == 0 and (setup & c.SETUP_CLOSED_LOOP) != 0
                     and (setup & c.SETUP_CURRENT_CONTROL) != 0)
    if torque_search:
        demand = c.CUR_SCALE_FULL * min(abs(regs[R.FLWERR]) / c.COUNTS_PER_FULL_STEP, 1.0)
        home = regs[R.ACTUAL_TORQUE] >= regs[R.T_HOME] and demand >= regs[R.T_HOME]
    else:
        home = (regs[R.INPUTS] & regs[R.HOME_MASK]) != 0
    if phase == 0.0:
        regs[R.STATUSBITS] &= ~c.ST_ZERO_SEARCH_DONE
        s[L.S_HOME_PHASE] = phase = 1.0
        s[L.S_HOME_DIR] = 1.0
    bits = regs[R.ZERO_SEARCH_BITS]
    vh = regs[R.V_HOME] * c.VEL_UNIT_TO_COUNTS * s[L.S_HOME_DIR]
    if phase == 1.0 and seeking_turns(regs, s, mode) and limits & (1 if vh > 0.0 else 2):
        s[L.S_HOME_DIR] = -s[L.S_HOME_DIR]
        vh = -vh
    crawl = regs[R.V_HOME_CRAWL] * c.VEL_UNIT_TO_COUNTS
    crawl = crawl if crawl > 0.0 else abs(vh) / 64.0
    back = -math.copysign(crawl, vh)  # the crawl velocity, against the search direction
    reversed_ = s[L.S_VEL] == 0.0 or (s[L.S_VEL] > 0.0) != (vh > 0.0)
    if phase == 1.0:
        if bits & c.ZS_IGNORE_SWITCH and not torque_search:
            _found(regs, s, p, vh)
        elif home:
            if torque_search:
                _set_zero(regs, s, p, True)
                s[L.S_VEL] = 0.0
                s[L.S_HOME_PHASE] = 3.0
            elif mode == c.ZERO_SEARCH_1 and not bits & c.ZS_OPPOSITE_SIDE:
                _found(regs, s, p, vh)
            elif bits & c.ZS_OPPOSITE_SIDE:
                s[L.S_HOME_PHASE] = 6.0
                return velocity_step(regs, s, vh, s[L.S_DEC]), False
            else:
                s[L.S_HOME_PHASE] = 2.0
        else:
            return velocity_step(regs, s, vh, s[L.S_DEC]), False
    if s[L.S_HOME_PHASE] == 6.0:
        if home:
            return velocity_step(regs, s, vh, s[L.S_DEC]), False
        if mode == c.ZERO_SEARCH_1:
            _found(regs, s, p, vh)
        else:
            s[L.S_HOME_PHASE] = 7.0
    if s[L.S_HOME_PHASE] == 7.0:
        if not (home and reversed_):
            return velocity_step(regs, s, back, s[L.S_DEC]), False
        _found(regs, s, p, back)
    if s[L.S_HOME_PHASE] == 2.0:
        if not home and reversed_:
            _found(regs, s, p, back)
        else:
            return velocity_step(regs, s, back, s[L.S_DEC]), False
    if s[L.S_HOME_PHASE] == 8.0:
        if not _at_index(regs, s, p):
            return velocity_step(regs, s, math.copysign(crawl, s[L.S_INDEX_DIR]),
                                 s[L.S_DEC]), False
        _set_zero(regs, s, p, False)
        s[L.S_HOME_PHASE] = 3.0
    if s[L.S_HOME_PHASE] == 3.0:
        v = velocity_step(regs, s, 0.0, s[L.S_DEC])
        if v != 0.0:
            return v, False
        s[L.S_HOME_PHASE] = 4.0 if regs[R.P_HOME] != 0 else 5.0
        return 0.0, False
    if s[L.S_HOME_PHASE] == 4.0:
        remaining = float(wrap32(0 - regs[R.P_IST])) - s[L.S_FRAC]
        v, arrive = position_step(regs, s, remaining,
                                  abs(regs[R.V_SOLL]) * c.VEL_UNIT_TO_COUNTS)
        if not (arrive or (remaining == 0.0 and v == 0.0)):
            return v, arrive
        s[L.S_HOME_PHASE] = 5.0
        return v, arrive
    regs[R.STATUSBITS] |= c.ST_ZERO_SEARCH_DONE
    regs[R.P_SOLL] = regs[R.P_IST]
    s[L.S_HOME_PHASE] = 0.0
    s[L.S_HOME_MS] = 0.0
    regs[R.MODE_REG] = regs[R.STARTMODE]
    return 0.0, False
