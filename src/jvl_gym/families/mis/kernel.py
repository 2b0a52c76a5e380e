"""One outer sample (1 ms) of the MIS/SMC firmware for one motor (MIS manual §6, §8.2).

Order: time, the electronics' temperature and the control voltage (a program shut down or
still waiting for its CVI does nothing more, ``firmware.supervision``); inputs; encoder, hardware
supervision, follow error and monitoring, the brake; the mode's profile velocity;
the commanded position (P_IST) advanced by it; status bits; the phase current the chopper aims
at; FLEXREGISTER (``flexreg``); the sample buffer. The plant then runs the sample's inner
samples (``plant``) with the commanded position moving linearly from ``S_CMD_PREV`` to
``S_CMD``.

Modes (§8.2.3): passive (0) and safe (15) switch the bridge off; velocity (1) runs at V_SOLL by
the profile rules (``profile``); position (2) moves P_IST to P_SOLL (the distance is
``P_SOLL − P_IST`` wrapped to 32 bits, so a relative move past 2³¹ and a write of P_IST both make
the right move, §8.2.4, §8.2.10); gear (3) adds the pulse input × GEAR1/GEAR2 to P_SOLL, carrying
the remainder (§8.2.3), then moves as position mode; stop (11) decelerates with D_SOLL (A_SOLL)
and then becomes passive; zero search (13, 14, ``homing``).

Auto-correction (§5.2, position mode with an encoder, IN_POSITION_COUNT > 0): a change of
P_SOLL loads IN_POSITION_COUNT retries and sets STATUSBITS bit 1; SETTLINGTIME ms after a move
ends, an encoder position outside IN_POSITION_WINDOW of P_SOLL makes P_IST := ENCODER_POS and
moves again (at V_SOLL_AUTO if it is not 0), until the encoder is in the window or the retries
are used up.

Standby (§8.2.8, §8.2.9): STANDBY_CURRENT replaces RUN_CURRENT STANDBY_TIME ms after the last
step; in closed loop with current control the current is ACTUAL_TORQUE/2047 of RUN_CURRENT and
the standby current is not used (§5.3.3). ACTUAL_TORQUE reads 0 in passive mode, 2047 in an
active mode without current control (§8.2.112).

TICKS counts on by one per sample from the value it holds, so a written value goes on counting
(§8.2.107, R/W). EXT_ENCODER counts the pulse input in every mode (§8.2.101), and
EXT_ENCODER_VEL holds its counts of the last 16 ms, renewed every 16 ms (§8.2.102). A turn table
keeps P_IST inside MIN_P_IST … MAX_P_IST in position mode only; in the other modes P_IST may
leave the range (§5.12.6) and a return to position mode brings it back by whole turns.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ...engine.apart import apart
from ...physics.fixed import wrap32
from . import constants as c
from . import layout as L
from .firmware import regs as R
from .firmware.closed_loop import field_step, scale_current
from .firmware.flexreg import flex_register
from .firmware.homing import zero_search
from .firmware.inputs import update_inputs
from .firmware.monitor import check_errors, read_encoder, status_bits
from .firmware.profile import position_step, velocity_step
from .firmware.supervision import (
    brake,
    control_voltage,
    program_stopped,
    supervise,
    supervision_status,
    temperature,
)
from .firmware.turntable import tt_active, tt_distance, tt_wrap
from .units import COUNTS_PER_REV

#: a motor's RUN_CURRENT unit [A RMS] → phase current amplitude [A peak] (sine microstepping)
_SQRT2 = math.sqrt(2.0)
#: ERR_BITS that do not make the motor passive: the zero-search time-out, an "Error" that sets
#: the motor back in its previous mode (§7.2.19), with the general-error bit that comes with it;
#: the motor holds still there until the errors are cleared (§8.2.31)
_NOT_STOPPING = c.ERR_ZERO_SEARCH_TIMEOUT | c.ERR_GENERAL
#: outer samples (ms) between two measurements of EXT_ENCODER_VEL (§8.2.102)
_EXT_VEL_MS = 16


@njit(cache=True, inline="always")
def _ext_encoder(regs, s, u) -> int:  # pragma: no cover - compiled
    """The pulse input's counts of this sample, added to EXT_ENCODER in every mode ("counts the
    external encoder input", §8.2.101, names no mode); SETUP_BITS bit 16 counts the input the
    other way (§8.2.68). Every 16 ms EXT_ENCODER_VEL becomes the counts of the last 16 ms
    (§8.2.102: "measured every 16ms", counts per 16 ms)."""
    counts = int(u[L.I_PULSE_COUNTS])
    if regs[R.SETUP_BITS] & c.SETUP_EXT_ENCODER_INVERSE:
        counts = -counts
    if counts != 0:
        regs[R.EXT_ENCODER] = wrap32(regs[R.EXT_ENCODER] + counts)
        s[L.S_EXT_VEL_ACC] += counts
    if int(s[L.S_TICK]) % _EXT_VEL_MS == 0:
        regs[R.EXT_ENCODER_VEL] = int(s[L.S_EXT_VEL_ACC])
        s[L.S_EXT_VEL_ACC] = 0.0
    return counts


@njit(cache=True)
def _gear_input(regs, s, counts: int) -> None:  # pragma: no cover - compiled
    """P_SOLL += the pulse input's ``counts`` × GEAR1 / GEAR2 with the remainder carried
    (§8.2.3 gear mode, §8.2.13–14); GEAR2 = 0 moves nothing."""
    g2 = regs[R.GEAR2]
    if counts == 0 or g2 == 0:
        return
    total = counts * regs[R.GEAR1] + int(s[L.S_GEAR_REM])
    q = total // g2
    s[L.S_GEAR_REM] = float(total - q * g2)
    regs[R.P_SOLL] = wrap32(regs[R.P_SOLL] + q)


@njit(cache=True)
def _auto_correction(regs, s, has_encoder: bool, v_prev: float) -> bool:  # pragma: no cover
    """Auto-correction after a move (module docstring); True while a retry is running."""
    if regs[R.P_SOLL] != int(s[L.S_SEEN_PSOLL]):
        s[L.S_SEEN_PSOLL] = regs[R.P_SOLL]
        if has_encoder and regs[R.IN_POSITION_COUNT] > 0:
            s[L.S_AC_LEFT] = regs[R.IN_POSITION_COUNT]
            s[L.S_AC_WAIT] = regs[R.SETTLINGTIME]
            regs[R.STATUSBITS] |= c.ST_AUTOCORRECTION
    if not regs[R.STATUSBITS] & c.ST_AUTOCORRECTION:
        return False
    if v_prev != 0.0 or regs[R.P_IST] != regs[R.P_SOLL]:
        return s[L.S_AC_LEFT] < regs[R.IN_POSITION_COUNT]
    if s[L.S_AC_WAIT] > 0.0:
        s[L.S_AC_WAIT] -= 1.0
        return False
    if abs(wrap32(regs[R.ENCODER_POS] - regs[R.P_SOLL])) <= regs[R.IN_POSITION_WINDOW] or \
            s[L.S_AC_LEFT] <= 0.0:
        regs[R.STATUSBITS] &= ~c.ST_AUTOCORRECTION
        return False
    s[L.S_AC_LEFT] -= 1.0
    s[L.S_AC_WAIT] = regs[R.SETTLINGTIME]
    regs[R.P_IST] = regs[R.ENCODER_POS]
    s[L.S_FRAC] = 0.0
    return True


@njit(cache=True)
def _move(regs, s, has_encoder: bool, tt: bool,
          v_prev: float) -> tuple[float, bool]:  # pragma: no cover - compiled
    """Position-mode profile velocity of this sample and whether it lands on P_SOLL."""
    retry = _auto_correction(regs, s, has_encoder, v_prev) if has_encoder else False
    vmax = abs(regs[R.V_SOLL])
    if retry and regs[R.V_SOLL_AUTO] != 0:
        vmax = abs(regs[R.V_SOLL_AUTO])
    dist = tt_distance(regs, s) if tt else _within_limits(
        regs, float(wrap32(regs[R.P_SOLL] - regs[R.P_IST])))
    return position_step(regs, s, dist - s[L.S_FRAC], vmax * c.VEL_UNIT_TO_COUNTS)


@njit(cache=True, inline="always")
def _within_limits(regs, dist: float) -> float:  # pragma: no cover - compiled
    """A move of ``dist`` counts cut at the software position limits (§5.9.3: in position and
    gear mode the motor stops at the limit; §5.9.5: braking with the normal deceleration), so
    that P_IST never passes MIN_P_IST or MAX_P_IST (both active when either is ≠ 0)."""
    lo, hi = regs[R.MIN_P_IST], regs[R.MAX_P_IST]
    if lo == 0 and hi == 0:
        return dist
    if dist > 0.0:
        return min(dist, max(float(hi - regs[R.P_IST]), 0.0))
    return max(dist, min(float(lo - regs[R.P_IST]), 0.0))


@njit(cache=True, inline="always")
def _unblocked(v: float, limits: int) -> float:  # pragma: no cover - compiled
    """``v``, or 0 if it moves towards an active limit (1: positive, 2: negative)."""
    return 0.0 if (v > 0.0 and limits & 1) or (v < 0.0 and limits & 2) else v


@njit(cache=True)
def _advance(regs, s, v: float, arrive: bool, tt: bool) -> None:  # pragma: no cover
    """Move the commanded position by ``v`` counts (exactly onto the target when
    ``arrive``): P_IST by whole counts, the fraction carried, the plant's command (the other
    way with SETUP_BITS bit 0, invert motor direction, §8.2.68), and MOTOR_REV, which counts
    every 409 600 counts run in either direction (§8.2.122)."""
    old = s[L.S_FRAC]
    x = old + v
    steps = math.floor(x)
    frac = x - steps
    if arrive:
        steps = math.floor(x + 0.5)
        frac = 0.0
    s[L.S_FRAC] = frac
    s[L.S_CMD_PREV] = s[L.S_CMD]
    if regs[R.SETUP_BITS] & c.SETUP_INVERT_DIRECTION:
        s[L.S_CMD] -= steps + frac - old
    else:
        s[L.S_CMD] += steps + frac - old
    run = s[L.S_REV_ACC] + abs(steps)
    if run >= COUNTS_PER_REV:
        revs = math.floor(run / COUNTS_PER_REV)
        regs[R.MOTOR_REV] = (regs[R.MOTOR_REV] + int(revs)) & 0xFFFFFFFF
        run -= revs * COUNTS_PER_REV
    s[L.S_REV_ACC] = run
    if s[L.S_TT_TRAVEL] != 0.0:
        left = s[L.S_TT_TRAVEL] - (steps + frac - old)
        s[L.S_TT_TRAVEL] = 0.0 if arrive or (left > 0.0) != (s[L.S_TT_TRAVEL] > 0.0) else left
    regs[R.P_IST] = wrap32(regs[R.P_IST] + int(steps))
    if tt:
        tt_wrap(regs, s)
    s[L.S_STILL_MS] = 0.0 if steps != 0 or v != 0.0 else s[L.S_STILL_MS] + 1.0


@apart
@njit(cache=True)
def outer_firmware(regs, s, p, u, buf, rec: bool) -> None:  # pragma: no cover - compiled
    """One outer sample of one motor (module docstring); rows of the engine's arrays."""
    s[L.S_TICK] += 1.0
    temperature(regs, s, u)
    if not control_voltage(regs, s, u):
        program_stopped(regs, s, p)
        return
    # TICKS counts on from whatever it holds: a written value too (R/W, §8.2.107)
    regs[R.TICKS] = (regs[R.TICKS] + 1) & 0xFFFFFFFF
    update_inputs(regs, s, p, u)
    pulses = _ext_encoder(regs, s, u)
    has_encoder = read_encoder(regs, s, p)
    supervise(regs, s, u)
    mode = regs[R.MODE_REG]
    active = mode != c.PASSIVE and mode != c.SAFE
    tt = tt_active(regs)
    limits = check_errors(regs, s, p, u, active, has_encoder, tt)
    held = brake(regs, s, p, active)
    mode = regs[R.MODE_REG]
    v_prev = s[L.S_VEL]
    target_v = 0.0
    v = 0.0
    arrive = False
    err = regs[R.ERR_BITS]
    if active and err != 0 and (err | c.ERR_GENERAL) != _NOT_STOPPING:
        s[L.S_EMERGENCY] = 1.0
    if s[L.S_EMERGENCY] != 0.0:
        v = velocity_step(regs, s, 0.0, regs[R.ACC_EMERG] * c.ACC_UNIT_TO_COUNTS)
        if v == 0.0:
            if s[L.S_EMERGENCY] == 1.0:
                regs[R.MODE_REG] = c.PASSIVE
            s[L.S_EMERGENCY] = 0.0
            s[L.S_HOME_PHASE] = 0.0
    elif active and err != 0:
        # the zero-search time-out: in its previous mode, the motor "will not move until all
        # the errors have been cleared" (§8.2.31); it brakes with its deceleration and holds
        v = velocity_step(regs, s, 0.0, s[L.S_DEC])
    elif held:
        pass  # the brake still releasing: no move yet (§5.11.2)
    elif mode == c.VELOCITY:
        target_v = _unblocked(regs[R.V_SOLL] * c.VEL_UNIT_TO_COUNTS, limits)
        v = velocity_step(regs, s, target_v, s[L.S_DEC])
    elif mode == c.POSITION or mode == c.GEAR:
        if mode == c.GEAR:
            _gear_input(regs, s, pulses)
        v, arrive = _move(regs, s, has_encoder, tt, v_prev)
        if _unblocked(v, limits) != v:
            v, arrive = velocity_step(regs, s, 0.0, s[L.S_DEC]), False
        target_v = math.copysign(abs(regs[R.V_SOLL]) * c.VEL_UNIT_TO_COUNTS, v)
    elif mode == c.STOP:
        v = velocity_step(regs, s, 0.0, s[L.S_DEC])
        if v == 0.0:
            regs[R.MODE_REG] = c.PASSIVE
    elif mode == c.ZERO_SEARCH_1 or mode == c.ZERO_SEARCH_2:
        v, arrive = zero_search(regs, s, p, mode, limits)
    s[L.S_VEL] = 0.0 if arrive else v
    # the turn table keeps P_IST in its range in position mode only (§5.12.6)
    _advance(regs, s, v, arrive, tt and mode == c.POSITION)
    regs[R.V_IST] = int(np.floor(s[L.S_VEL] / c.VEL_UNIT_TO_COUNTS + 0.5))
    regs[R.V_IST_CALC] = regs[R.V_IST]  # "the theoretical actual velocity" (§8.2.121)
    mode = regs[R.MODE_REG]
    active = mode != c.PASSIVE and mode != c.SAFE
    setup = regs[R.SETUP_BITS]
    closed_loop = has_encoder and (setup & c.SETUP_CLOSED_LOOP) != 0 and int(
        p[L.P_ENCODER]) != 2
    current_control = closed_loop and (setup & c.SETUP_CURRENT_CONTROL) != 0
    standby = (not current_control and s[L.S_STILL_MS] >= regs[R.STANDBY_TIME])
    status_bits(regs, s, s[L.S_VEL], v_prev, target_v, mode, has_encoder, closed_loop,
                standby and active)
    supervision_status(regs, u)
    if current_control:
        scale_current(regs, s, float(regs[R.FLWERR]), v / c.VEL_UNIT_TO_COUNTS * 0.01)
        units = regs[R.RUN_CURRENT] * s[L.S_CUR_SCALE] / 2047.0
    else:
        s[L.S_CUR_SCALE] = 2047.0
        # the type's own ceiling of the standby current (6 A on an MIS34x/43x, §5.1.4)
        units = min(float(regs[R.STANDBY_CURRENT]), p[L.P_STANDBY_MAX]) if standby else float(
            regs[R.RUN_CURRENT])
    # "In passive mode = 0%", active without current control 100 % (§8.2.112)
    regs[R.ACTUAL_TORQUE] = int(s[L.S_CUR_SCALE]) if active else 0
    s[L.S_FIELD_STEP] = field_step(regs, s, v) if closed_loop else 0.0
    s[L.S_I_AMP] = _SQRT2 * min(units, p[L.P_RUN_MAX]) * p[L.P_AMPS_PER_UNIT]
    s[L.S_BRIDGE] = (2.0 if closed_loop else 1.0) if active else 0.0
    flex_register(regs)
    if rec:
        _record(regs, s, buf)


@njit(cache=True)
def _record(regs, s, buf) -> None:  # pragma: no cover - compiled
    """Sample buffer (§8.2.60–63): while S_CONTROL = 2, every S_TIME ms the registers named by
    SAMPLE1–4 (0: zero) until REC_CNT samples, then S_CONTROL = 0."""
    if regs[R.S_CONTROL] != 2:
        return
    s[L.S_REC_MS] += 1.0
    if s[L.S_REC_MS] < regs[R.S_TIME]:
        return
    s[L.S_REC_MS] = 0.0
    k = int(s[L.S_REC_N])
    if k < min(regs[R.REC_CNT], buf.shape[0]):
        for ch in range(4):
            num = regs[R.SAMPLE1 + ch]
            buf[k, ch] = regs[num] if 0 < num < regs.shape[0] else 0
        s[L.S_REC_N] = k + 1
    if s[L.S_REC_N] >= min(regs[R.REC_CNT], buf.shape[0]):
        regs[R.S_CONTROL] = 0
