"""One MAC800 servo sample (1.2987 ms): the firmware's outer loop, then 15 current-loop samples.

Order within a servo sample (the MAC050–141's sampled-system order, its manual 1.2):

1. the encoder: V_IST = ΔP, P_IST += V_IST, V_IST16, the index pulse; the world inputs (ANINP,
   V_EXT, U_BUS, U_24V); CNTRL_BITS REWINDBIT / SYNCPOSMAN / SYNCPOSAUTO;
2. the active mode's function block → FNC_OUT; the main filter → VF_OUT (with the function
   correction in the correcting modes); FLWERR, FNCERR, the zero search's detection;
3. the monitors (ERR_STAT), IN_POS; the sample buffer at the servo rate;
4. the current-loop samples and the plant (:mod:`jvl_gym.families.mac800.inner`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ...engine.apart import apart
from ...engine.jit import KERNEL
from ...motor.noise import gauss
from ...physics.bus import bus_constants
from ...physics.coil import coil_constants
from ...physics.fixed import clamp, rnd, wrap32
from ...physics.mechanics import mech_constants
from . import constants as c
from . import layout as L
from .firmware import analog as A
from .firmware import regs as R
from .firmware.blocks import gear_block, geared_velocity, position_block, stop_block, velocity_block
from .firmware.homing import home_block, home_found
from .firmware.main_filter import main_filter
from .firmware.modes import correcting, enter_mode, following, go_passive, regulated, trip
from .firmware.monitor import check_errors, in_position, loads
from .firmware.recorder import record
from .plant.encoder import counts_from_index, encoder_count, turn
from .units import COUNTS_PER_REV

_ANINP_PER_VOLT = 1.0 / c.ANINP_VOLTS_PER_UNIT
_U_BUS_PER_VOLT = 1.0 / c.U_BUS_VOLTS
_U_24V_PER_VOLT = 1.0 / c.U_24V_VOLTS
_INT32 = 2147483647.0
_TURN = float(COUNTS_PER_REV)


@njit(cache=True, inline="always")
def _analog_volts(s: np.ndarray, p: np.ndarray, u: np.ndarray) -> float:
    """The analogue input [V]; a zero-search sensor at ``home_position`` is wired to it
    (10 V active-high at and beyond the position, 0 V before it) unless forced by the ``home``
    input (0/1), else the ``analog_volts`` input."""
    home = u[L.I_HOME]
    if home < 0.0 and math.isfinite(p[L.P_HOME_POS]):
        home = 1.0 if s[L.S_THETA] >= p[L.P_HOME_POS] else 0.0
    if home >= 0.0:
        return 10.0 if home > 0.5 else 0.0
    return u[L.I_ANALOG_VOLTS]


@njit(**KERNEL)
def _encoder(r: np.ndarray, s: np.ndarray, p: np.ndarray, u: np.ndarray,
             key: np.uint64) -> float:
    """Step 1's encoder: the count (an encoder fault loses every second count; with
    ``position_noise`` the reading has Gaussian noise of that many counts, from the motor's
    noise key), V_IST, P_IST, V_IST16 and the index check (INDEX_ERR); returns V_IST."""
    theta = s[L.S_THETA]
    true = encoder_count(theta)
    d_true = true - (s[L.S_ENC_PREV] + s[L.S_SLIP])
    if u[L.I_ENCODER_FAULT] > 0.5:
        s[L.S_SLIP] += float(int(d_true / 2.0))
    fw = true - s[L.S_SLIP]
    if p[L.P_POSITION_NOISE] > 0.0:
        fw += rnd(p[L.P_POSITION_NOISE] * gauss(key, s[L.S_TICK], 3))
    v = clamp(fw - s[L.S_ENC_PREV], -_INT32, _INT32)
    s[L.S_ENC_PREV] = fw
    r[R.V_IST] = int(v)
    r[R.P_IST] = wrap32(r[R.P_IST] + int(v))
    pos = int(s[L.S_VH_POS])
    r[R.V_IST16] = r[R.V_IST16] + int(v) - int(s[L.S_VH0 + pos])  # the last 16 V_IST summed
    s[L.S_VH0 + pos] = v
    s[L.S_VH_POS] = float((pos + 1) % 16)
    t = turn(theta, p[L.P_INDEX_POS])
    if t != s[L.S_INDEX_TURN]:
        edge = t if t > s[L.S_INDEX_TURN] else s[L.S_INDEX_TURN]
        latch = encoder_count(p[L.P_INDEX_POS] + 2.0 * math.pi * edge) - s[L.S_SLIP]
        if not math.isnan(s[L.S_INDEX_COUNT]):
            d = latch - s[L.S_INDEX_COUNT]
            d -= _TURN * math.floor(d / _TURN + 0.5)
            if abs(d) > 2.0:
                trip(r, s, c.INDEX_ERR)
        s[L.S_INDEX_COUNT] = latch
        s[L.S_INDEX_TURN] = t
    return v


@njit(**KERNEL)
def _profile(r: np.ndarray, s: np.ndarray, mode: int, gv: float) -> tuple[float, float]:
    """The function block of a regulated mode: (FNC_OUT, torque limit)."""
    t_lim = float(r[R.T_SOLL])
    a = float(r[R.A_SOLL])
    if s[L.S_EMERG] > 0.5:
        return stop_block(r, s), t_lim
    if mode == c.VELOCITY_MODE:
        return velocity_block(r, s, float(r[R.V_SOLL]), a), t_lim
    if mode == c.POSITION_MODE:
        return position_block(r, s, float(r[R.V_SOLL]), a), t_lim
    if mode == c.GEAR_MODE or mode == c.ANALOG_GEAR_MODE:
        return gear_block(r, s, gv), t_lim
    if mode == c.ANALOG_VELOCITY_MODE:
        return velocity_block(r, s, A.analog_velocity(r), a), t_lim
    if mode == c.ANALOG_VELOCITY_GEAR_MODE:
        return velocity_block(r, s, A.analog_velocity_gear(r) + gv, a), t_lim
    if mode == c.ANALOG_VELOCITY_DEADBAND_MODE:
        return velocity_block(r, s, A.dead_band_velocity(r), a), t_lim
    if mode == c.VELOCITY_ANALOG_TORQUE_MODE:
        return velocity_block(r, s, float(r[R.V_SOLL]), a), min(A.torque_limit(r), t_lim)
    if mode == c.ANALOG_POSITION_MODE:
        A.analog_position(r, s)
        return position_block(r, s, float(r[R.V_SOLL]), a), t_lim
    return home_block(r, s, mode)


@njit(**KERNEL)
def _after_search(r: np.ndarray, s: np.ndarray) -> None:
    """The mode after a finished zero search: START_MODE if it is a regulated mode other than a
    zero search, else passive."""
    after = int(s[L.S_HOME_AFTER]) if s[L.S_HOME_AFTER] >= 0.0 else int(r[R.START_MODE])
    s[L.S_HOME_AFTER] = -1.0
    if regulated(after) and not (c.TORQUE_ZERO_SEARCH <= after <= c.SENSOR2_ZERO_SEARCH):
        enter_mode(r, s, after)
    else:
        go_passive(r, s)


@apart
@njit(**KERNEL)
def outer_firmware(r: np.ndarray, s: np.ndarray, p: np.ndarray, u: np.ndarray, key: np.uint64,
                   buf: np.ndarray, rec: bool) -> None:
    """Steps 1–3 of a servo sample of one motor (module docstring)."""
    v = _encoder(r, s, p, u, key)
    r[R.ANINP] = int(clamp(rnd(_analog_volts(s, p, u) * _ANINP_PER_VOLT) - r[R.ANINP_OFFSET],
                           -2048.0, 2047.0))  # the register's range (overview, register 170)
    pulses = clamp(rnd(u[L.I_PULSE_COUNTS]), -_INT32, _INT32)
    r[R.V_EXT] = int(-pulses if r[R.HW_SETUP] & c.INVXDIR else pulses)
    r[R.U_BUS] = int(clamp(rnd(s[L.S_UBUS] * _U_BUS_PER_VOLT), 0.0, _INT32))
    r[R.U_24V] = int(clamp(rnd(u[L.I_CONTROL_VOLTS] * _U_24V_PER_VOLT), 0.0, _INT32))

    cb = r[R.CNTRL_BITS]
    if cb & c.REWINDBIT:
        r[R.REC_CNT] = 0
        cb &= ~c.REWINDBIT
    if cb & c.SYNCPOSMAN:
        if cb & c.SYNCPOSREL:
            r[R.P_IST] = wrap32(r[R.P_IST] + r[R.P_NEW])
            r[R.P_SOLL] = wrap32(r[R.P_SOLL] + r[R.P_NEW])
            s[L.S_PF16] += 16.0 * float(r[R.P_NEW])
        else:
            r[R.P_IST] = r[R.P_NEW]
            r[R.P_SOLL] = r[R.P_NEW]
            s[L.S_PF16] = 16.0 * float(r[R.P_NEW])
        cb &= ~c.SYNCPOSMAN
    r[R.CNTRL_BITS] = cb

    mode = int(r[R.MODE_REG])
    if mode == c.PASSIVE_MODE and (cb & c.SYNCPOSAUTO):
        r[R.P_SOLL] = r[R.P_IST]
        s[L.S_PF16] = 16.0 * float(r[R.P_IST])
    gv = 0.0
    if mode == c.GEAR_MODE or mode == c.ANALOG_VELOCITY_GEAR_MODE or mode == c.ANALOG_GEAR_MODE:
        gv = geared_velocity(r, s, A.gear_factor(r) if mode == c.ANALOG_GEAR_MODE else 1.0)
    else:
        r[R.GV_EXT] = 0
    if regulated(mode):
        emerg = s[L.S_EMERG] > 0.5
        f, t_lim = _profile(r, s, mode, gv)
        f, corr = main_filter(r, s, f, correcting(mode) and not emerg, t_lim)
        if corr != 0.0:
            s[L.S_V_OLD] = f
            s[L.S_PF16] += corr
            s[L.S_G_FNC] -= corr
            r[R.FNCERR] = int(clamp(r[R.FNCERR] + corr, -_INT32, _INT32))
        if following(mode) or mode >= c.TORQUE_ZERO_SEARCH and mode <= c.SENSOR2_ZERO_SEARCH:
            s[L.S_FLW16] += f - 16.0 * v
            r[R.FLWERR] = int(clamp(rnd(s[L.S_FLW16] / 16.0), -_INT32, _INT32))
        else:
            s[L.S_FLW16] = 0.0
            r[R.FLWERR] = 0
        if emerg:
            if s[L.S_V_OLD] == 0.0 and abs(v) < c.STOP_SPEED_COUNTS:
                go_passive(r, s)
        elif c.TORQUE_ZERO_SEARCH <= mode <= c.SENSOR2_ZERO_SEARCH and home_found(
                r, s, mode, counts_from_index(s[L.S_THETA], p[L.P_INDEX_POS])):
            _after_search(r, s)
    elif mode == c.ANALOG_TORQUE_MODE:
        r[R.VF_OUT] = int(A.analog_torque(r))
    else:  # passive: FLWERR and FNCERR 0, as in the MAC050–141's INIT_MODE
        r[R.VF_OUT] = 0
        r[R.FNC_OUT] = 0
        r[R.FLWERR] = 0
        r[R.FNCERR] = 0
    r[R.P_FUNC] = wrap32(int(rnd(s[L.S_PF16] / 16.0)))
    r[R.G_FNC] = int(clamp(rnd(s[L.S_G_FNC]), -_INT32, _INT32))

    loads(r, s, p)
    check_errors(r, s)
    mode = int(r[R.MODE_REG])
    in_position(r, s, mode, mode == c.POSITION_MODE or mode == c.ANALOG_POSITION_MODE)
    cb = r[R.CNTRL_BITS]
    if (cb & c.RECORDBIT) and not (cb & c.RECINNERBIT):
        record(r, buf, rec)


@njit(**KERNEL)
def derive_constants(p: np.ndarray) -> None:
    """The per-sample constants of a parameter row (``layout.P_CPA`` … ``P_KB6``)."""
    h = c.INNER_DT
    p[L.P_CPA] = 1.0 / p[L.P_AMPS_PER_COUNT]
    kc = coil_constants(p[L.P_R], p[L.P_L], p[L.P_LAMBDA], h)
    for k in range(4):
        p[L.P_KC0 + k] = kc[k]
    km = mech_constants(p[L.P_J_MOTOR] + p[L.P_J_LOAD], 0.0, p[L.P_VISCOUS], 0.0, 0.0, h)
    p[L.P_KM0] = km[0]
    p[L.P_KM1] = km[1]
    kb = bus_constants(p[L.P_C_BUS], p[L.P_R_SUPPLY], p[L.P_R_DUMP], h)
    for k in range(7):
        p[L.P_KB0 + k] = kb[k]
