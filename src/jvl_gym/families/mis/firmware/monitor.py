"""Monitoring: encoder position, follow error, bus voltage, position limits, error stop and the
status bits (MIS manual §8.2.15, §8.2.18–19, §8.2.24, §8.2.31–32, §5.9, §5.10, §7.2).

- ENCODER_POS: the rotor angle quantised to the encoder option's resolution (ENCODER_TYPE,
  §8.2.49), reported in 409 600 counts/rev, plus an offset the firmware moves when it sets the
  position (zero search, FastMac 119–121). Without an encoder it keeps its value.
- ABSENCODER: the rotor angle from power-on as the encoder reads it, single turn
  (0 … 409599) for H2, multiturn for H3/H4 (§8.2.38, §5.12.5); not moved by zeroing; an H3's
  moved by its preset (command 316, §5.8.4).
- FLWERR = P_IST − ENCODER_POS (positive when the rotor lags behind a positive move; §8.2.18
  names no sign); 0 without an encoder. In an active mode |FLWERR| > FLWERRMAX > 0 sets ERR_BITS
  bits 1 and 0 (§8.2.19, §7.2.4).
- BUSVOL from the supply; below MIN_BUSVOL: WARN_BITS bit 4 always, and by SETUP_BITS 21/22/23
  the error bit, a controlled stop to passive, or V_SOLL = 0 (§5.10.2). The error bit waits
  until the voltage has been low in more than LOWBUSCVI_CNT measurements in a row, one per
  50 µs (§8.2.130): the supply is held for a whole outer sample, so each low sample counts 20.
- Position limits (§5.9): software limits when MIN_P_IST or MAX_P_IST ≠ 0 and no turn table;
  hardware limits on the inputs of PL_MASK / NL_MASK. Moving into a limit sets WARN_BITS 0/1
  (active) and 2/3 (has been active) and ERR_BITS bit 3, unless SETUP_BITS bit 17 disables the
  error; either way the motor stops, and while a limit is active the profile does not move
  towards it. A limit is reached when the motor is at or past it while moving towards it, or
  stands at it while asked to move towards it (P_SOLL beyond it in position and gear mode,
  V_SOLL towards it in velocity mode): §7.2.6 sets the error whenever a sensor is active or
  P_IST is at a software limit, so a motor that enters an active mode at its limit and is sent
  on towards it gets the error too; with bit 17 a moving motor then brakes with ACC_EMERG and
  stays active (§5.9.5). In position and gear mode the move itself ends at a software limit,
  braking with the normal deceleration (``outer``), so P_IST never passes it. With SETUP_BITS
  bit 28 (limits without memory, §5.9.6) a has-been-active warning clears when the motor moves
  away from its limit and the limit is no longer active. During a zero search a limit input
  that is also the home input (HOME_MASK) is the search's switch, not a limit: "the limit
  switch will not raise an error when activated during home sequence" (§11.5.6).
- An error (ERR_BITS ≠ 0) in an active mode stops the motor with ACC_EMERG and then makes it
  passive (§8.2.28, §8.2.31: "will not move until all the errors have been cleared"), except
  the zero-search time-out (bit 16), which sets the motor back in its previous mode, where it
  brakes with its deceleration and holds still until the errors are cleared (§7.2.19, §8.2.31;
  ``kernel``, ``homing``). The hardware errors (over-voltage, temperature, STO, control voltage,
  injected faults) are set by ``supervision``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ....physics.fixed import wrap32
from .. import constants as c
from .. import layout as L
from ..units import COUNTS_PER_REV
from . import regs as R
from .supervision import busvol_units, over_voltage

#: encoder counts per revolution by ENCODER_TYPE code (0: none)
_CPR = np.array([c.ENCODER_CPR.get(k, 0) for k in range(11)], dtype=np.int64)
COUNTS_PER_RAD = COUNTS_PER_REV / (2.0 * math.pi)
#: the firmware measures the bus voltage every 50 µs (§8.2.130): 20 times per outer sample
_LOW_BUS_MEASUREMENTS_PER_MS = 20.0


@njit(cache=True, inline="always")
def encoder_cpr(p) -> int:  # pragma: no cover - compiled
    """Encoder counts per revolution of the motor's encoder option (0: none)."""
    return _CPR[int(p[L.P_ENCODER])]


@njit(cache=True, inline="always")
def rotor_counts_quantised(theta: float, cpr: int) -> float:  # pragma: no cover - compiled
    """The rotor angle [rad] as the encoder reports it, in motor counts (a multiple of
    409600/cpr)."""
    per = COUNTS_PER_REV // cpr
    return np.floor(theta * COUNTS_PER_RAD / per) * per


@njit(cache=True, inline="always")
def firmware_angle(regs, s) -> float:  # pragma: no cover - compiled
    """The rotor angle [rad] in the firmware's direction: mirrored with SETUP_BITS bit 0
    (invert motor direction, §8.2.68), under which positive counts turn the shaft the other
    way and the encoder counts with them."""
    return -s[L.S_THETA] if regs[R.SETUP_BITS] & c.SETUP_INVERT_DIRECTION else s[L.S_THETA]


@njit(cache=True)
def read_encoder(regs, s, p) -> bool:  # pragma: no cover - compiled
    """ENCODER_POS, V_ENCODER and FLWERR of this sample; True if the motor has an encoder."""
    cpr = encoder_cpr(p)
    if cpr == 0:
        regs[R.FLWERR] = 0
        return False
    absolute = int(rotor_counts_quantised(firmware_angle(regs, s), cpr))
    single_turn = int(p[L.P_ENCODER]) in (1, 3)  # H2 (§5.12.5: 0 … 409599, §8.2.38)
    # the H3 keeps its own preset (command 316, §5.8.4) in its battery-backed memory
    regs[R.ABSENCODER] = absolute % COUNTS_PER_REV if single_turn else wrap32(
        absolute + int(p[L.P_H3_PRESET]))
    pos = wrap32(int(absolute + s[L.S_ENC_OFFSET]))
    regs[R.V_ENCODER] = int(np.floor(wrap32(pos - int(s[L.S_ENC_PREV]))
                                     / c.VEL_UNIT_TO_COUNTS + 0.5))
    s[L.S_ENC_PREV] = pos
    regs[R.ENCODER_POS] = pos
    regs[R.FLWERR] = wrap32(regs[R.P_IST] - pos)
    return True


@njit(cache=True)
def set_encoder(regs, s, p, value: int) -> None:  # pragma: no cover - compiled
    """Make ENCODER_POS read ``value`` at the present rotor angle."""
    cpr = encoder_cpr(p)
    if cpr > 0:
        s[L.S_ENC_OFFSET] = value - rotor_counts_quantised(firmware_angle(regs, s), cpr)
        s[L.S_ENC_PREV] = value
    regs[R.ENCODER_POS] = value


@njit(cache=True)
def check_errors(regs, s, p, u, active: bool, has_encoder: bool,
                 tt: bool) -> int:  # pragma: no cover - compiled
    """Follow error, bus voltage (and over-voltage) and limits (module docstring); returns the
    active limits (1: positive, 2: negative), which block motion towards them."""
    err = regs[R.ERR_BITS]
    warn = regs[R.WARN_BITS]
    setup = regs[R.SETUP_BITS]
    maxerr = regs[R.FLWERRMAX]
    if active and has_encoder and maxerr > 0 and abs(regs[R.FLWERR]) > maxerr:
        err |= c.ERR_FOLLOW
    busvol = busvol_units(u)
    regs[R.BUSVOL] = busvol
    if over_voltage(p, busvol):
        err |= c.ERR_OVER_VOLTAGE  # §7.2.8, §8.2.93
    if busvol < regs[R.MIN_BUSVOL]:
        warn |= c.WARN_LOW_BUS
        s[L.S_LOW_BUS_N] += _LOW_BUS_MEASUREMENTS_PER_MS
        if setup & (1 << 21) and s[L.S_LOW_BUS_N] > regs[R.LOWBUSCVI_CNT]:
            err |= c.ERR_LOW_BUS
        if setup & (1 << 22) and active:
            regs[R.MODE_REG] = c.STOP
        if setup & (1 << 23):
            regs[R.V_SOLL] = 0
    else:
        warn &= ~c.WARN_LOW_BUS
        s[L.S_LOW_BUS_N] = 0.0
    v = s[L.S_VEL]
    lo, hi = regs[R.MIN_P_IST], regs[R.MAX_P_IST]
    soft = (lo != 0 or hi != 0) and not tt
    inputs = regs[R.INPUTS]
    mode = regs[R.MODE_REG]
    if mode == c.ZERO_SEARCH_1 or mode == c.ZERO_SEARCH_2:
        inputs &= ~regs[R.HOME_MASK]  # a limit switch used as the home switch (§11.5.6)
    soft_pos = soft and regs[R.P_IST] >= hi
    soft_neg = soft and regs[R.P_IST] <= lo
    pos_hit = (inputs & regs[R.PL_MASK]) != 0 or soft_pos
    neg_hit = (inputs & regs[R.NL_MASK]) != 0 or soft_neg
    warn = (warn & ~(c.WARN_POS_LIMIT | c.WARN_NEG_LIMIT))
    if pos_hit:
        warn |= c.WARN_POS_LIMIT | c.WARN_POS_LIMIT_SEEN
    if neg_hit:
        warn |= c.WARN_NEG_LIMIT | c.WARN_NEG_LIMIT_SEEN
    if setup & c.SETUP_LIMITS_WITHOUT_MEMORY:
        if v < 0.0 and not pos_hit:
            warn &= ~c.WARN_POS_LIMIT_SEEN
        if v > 0.0 and not neg_hit:
            warn &= ~c.WARN_NEG_LIMIT_SEEN
    # the way the motor is asked to move: to P_SOLL, or at V_SOLL (0: nowhere)
    ahead = wrap32(regs[R.P_SOLL] - regs[R.P_IST]) if (
        mode == c.POSITION or mode == c.GEAR) else (regs[R.V_SOLL] if mode == c.VELOCITY
                                                    else 0)
    passing = (pos_hit and v > 0.0) or (neg_hit and v < 0.0)
    if active and not seeking_turns(regs, s, mode) and (
            passing or (pos_hit and ahead > 0) or (neg_hit and ahead < 0)):
        if not setup & c.SETUP_NO_LIMIT_ERROR:
            err |= c.ERR_POSITION_LIMIT
        elif passing:
            s[L.S_EMERGENCY] = 2.0  # stop with ACC_EMERG, stay active
    if err & ~c.ERR_GENERAL:
        err |= c.ERR_GENERAL
    regs[R.ERR_BITS] = err
    regs[R.WARN_BITS] = warn
    return (1 if pos_hit else 0) | (2 if neg_hit else 0)


@njit(cache=True)
def seeking_turns(regs, s, mode: int) -> bool:  # pragma: no cover - compiled
    """A zero search still seeking its sensor with ZERO_SEARCH_BITS bit 1 (§8.2.67, "change
    direction on limit"): a limit input turns it (``firmware.homing``) instead of stopping the
    motor with the position-limit error."""
    return ((mode == c.ZERO_SEARCH_1 or mode == c.ZERO_SEARCH_2)
            and (regs[R.ZERO_SEARCH_BITS] & c.ZS_TURN_AT_LIMIT) != 0
            and s[L.S_HOME_PHASE] <= 1.0)


@njit(cache=True)
def status_bits(regs, s, v: float, prev_v: float, target_v: float, mode: int,
                has_encoder: bool, closed_loop: bool, standby: bool) -> None:  # pragma: no cover
    """STATUSBITS of this sample (§8.2.24) and the dedicated outputs.

    Bit 2 (in physical position) in position and gear mode while the encoder is within
    IN_POSITION_WINDOW of P_SOLL: evaluated at standstill, or continuously with SETUP_BITS bit
    6 (§8.2.68). Bit 22 (in target position) once the motor has stood still for
    INTARGETPOSITIONTIME ms (§8.2.105) with the encoder in that window. The dedicated outputs
    (§8.2.77–78): the IO pins of INPOS_MASK and ERROR_MASK that IOSETUP bits 8–15 make
    outputs follow bit 4 (in position: a movement has completed), or bit 2 (in physical
    position) with INPOS_MASK bit 8 (§5.6.3), and ERR_BITS ≠ 0 in OUTPUTS.
    """
    st = regs[R.STATUSBITS] & (c.ST_ZERO_SEARCH_DONE | c.ST_AUTOCORRECTION | c.ST_BRAKE_ACTIVE)
    moving_mode = mode == c.VELOCITY or mode == c.POSITION or mode == c.GEAR
    if moving_mode and v == target_v:
        st |= c.ST_AT_VELOCITY
    if abs(v) > abs(prev_v) and (prev_v == 0.0 or (v > 0.0) == (prev_v > 0.0)):
        st |= c.ST_ACCELERATING
    elif abs(v) < abs(prev_v) or (v != 0.0 and prev_v != 0.0 and (v > 0.0) != (prev_v > 0.0)):
        st |= c.ST_DECELERATING
    in_target = has_encoder and abs(wrap32(regs[R.ENCODER_POS] - regs[R.P_SOLL])) <= regs[
        R.IN_POSITION_WINDOW]
    positional = mode == c.POSITION or mode == c.GEAR
    if positional and v == 0.0:
        if closed_loop:
            if in_target:
                st |= c.ST_IN_POSITION
        elif regs[R.P_IST] == regs[R.P_SOLL]:
            st |= c.ST_IN_POSITION
    if positional and in_target and (
            v == 0.0 or regs[R.SETUP_BITS] & c.SETUP_IN_PHYS_POS_CONTINUOUS):
        st |= c.ST_IN_PHYSICAL_POSITION
    if in_target and s[L.S_STILL_MS] >= regs[R.INTARGETPOSITIONTIME]:
        st |= c.ST_IN_TARGET_POSITION
    if regs[R.ERR_BITS] != 0:
        st |= c.ST_GENERAL_ERROR
    if closed_loop:
        st |= c.ST_CLOSED_LOOP
    if has_encoder:
        st |= c.ST_ENCODER_OK | c.ST_ENCODER_CALIBRATED
    if standby:
        st |= c.ST_STANDBY_CURRENT
    regs[R.STATUSBITS] = st
    outputs = (regs[R.IOSETUP] >> 8) & 0xFF
    inpos = regs[R.INPOS_MASK] & outputs
    error = regs[R.ERROR_MASK] & outputs
    if inpos | error:
        o = regs[R.OUTPUTS] & ~(inpos | error)
        if st & (c.ST_IN_PHYSICAL_POSITION if regs[R.INPOS_MASK] & c.INPOS_PHYSICAL
                 else c.ST_IN_POSITION):
            o |= inpos
        if regs[R.ERR_BITS] != 0:
            o |= error
        regs[R.OUTPUTS] = o
