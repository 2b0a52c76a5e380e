"""The simulation kernel: one outer sample (1.92 ms) = firmware outer step + 15 inner samples.

Order within an outer sample (manual 1.2 sampled-system convention, docs/model.md §2):

1. read the encoder: ``V_IST = ΔP``, ``P_IST += V_IST``; read the world inputs (ANINP, V_EXT,
   U_SUPPLY); process REWINDBIT / re-synchronisation bits;
2. the active mode's function block → FNC_OUT; speed regulator → VF_OUT (with the function
   correction in the correcting modes); FLWERR / FNCERR;
3. monitoring (4.5), IN_POS, mode transitions; outer-rate recording;
4. 15 inner samples (:mod:`mac050_141.inner`), each: ELDEG_IST / V_ELDEG, current measurement,
   commutation and the three current loops (or the mode's fixed voltages), inner-rate
   recording, then the PWM voltage (after ``pwm_delay_samples``) drives the coil, mechanics and
   DC bus for 128 µs. VF_OUT computed in step 2 is used from the first of these inner samples on.

This module holds steps 1–3 (:func:`outer_firmware`) and the pure arithmetic the inner sample
calls (:func:`adc_count`, :func:`plant_sample`, :func:`sample_constants`). The drivers
(:mod:`mac050_141.lanes`) advance blocks of motors in lockstep, steps 1–3 one motor at a time
and step 4 for several motors in SIMD lanes where the motors allow; every motor's arithmetic is
independent of the others, so an N-motor array is bit-for-bit equal to N one-motor arrays.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ...engine.apart import apart
from ...engine.jit import KERNEL, LANE_KERNEL
from ...motor.noise import gauss
from ...physics.bus import bus_constants, bus_step_prepared
from ...physics.coil import coil_constants, coil_step_prepared, phase_to_vector
from ...physics.fixed import clamp, rnd, sat16, wrap32
from ...physics.mechanics import end_stop_torque, mech_constants, mech_step_prepared
from . import constants as c
from . import layout as L
from .firmware import regs as R
from .firmware.analog_blocks import (
    a2pos_update,
    apos_update,
    av_target,
    avz_target,
    vat_torque_limit,
)
from .firmware.blocks import position_block, stop_block, velocity_block
from .firmware.coil import coil_block
from .firmware.gear_blocks import (
    analog_gear_factor,
    avg_target,
    gear_factor,
    gear_follow_block,
    gear_position_block,
)
from .firmware.homing import home_block, home_check
from .firmware.mode_table import N_MODES
from .firmware.modes import (
    CORRECTING,
    FLWERR_MODES,
    REGULATED,
    enter_mode,
    fncerr_is_position,
    reset_speed_loop,
    stop_to,
)
from .firmware.monitor import check_errors, in_position, thermal, undervoltage
from .firmware.recorder import record
from .firmware.speed_loop import speed_regulator
from .plant.encoder import encoder_count

_H = c.INNER_DT
_HALF_PWM_PER_VOLT = 1.0 / (2.0 * c.PWM_FULL)  #: bus volts → phase volts per PWM count
_ANINP_PER_VOLT = c.ANINP_FULL / c.ANINP_VOLTS
_TESTTQ_HALF = c.REC_CNT_MAX // 2  #: TESTTQ: samples at +V_SOLL, then the same at −V_SOLL


@njit(cache=True, inline="always")
def _analog_volts(s: np.ndarray, p: np.ndarray, u: np.ndarray) -> float:
    """Analogue input voltage; a configured home sensor is wired to it (4.4.14: 10 V / 0 V)."""
    home = u[L.I_HOME]
    if home < 0.0 and math.isfinite(p[L.P_HOME_POS]):
        home = 1.0 if s[L.S_THETA] >= p[L.P_HOME_POS] else 0.0
    if home >= 0.0:
        return c.ANINP_VOLTS if home > 0.5 else 0.0
    return u[L.I_ANALOG_VOLTS]


@njit(**KERNEL)
def _profile(r: np.ndarray, s: np.ndarray, mode: int) -> tuple[float, float]:
    """Function block of a regulated mode (manual 4.1, 4.4): (FNC_OUT, torque limit)."""
    t_lim = float(r[R.T_SOLL])
    a = float(r[R.A_SOLL])
    if mode == c.V_MODE:
        f = velocity_block(r, s, float(r[R.V_SOLL]), a)
    elif mode == c.P_MODE or mode == c.A2POS_MODE or mode == c.APOS_MODE:
        if mode == c.A2POS_MODE:
            a2pos_update(r, s, False)
        elif mode == c.APOS_MODE:
            apos_update(r)
        f = position_block(r, s, 16.0 * r[R.P_SOLL] - r[R.P_FNC], float(r[R.V_SOLL]), a)
    elif mode == c.STOP_MODE:
        f = stop_block(r, s)
    elif mode == c.GP_MODE:
        f = gear_position_block(r, s, gear_factor(r))
    elif mode == c.AG_MODE:
        f = gear_position_block(r, s, gear_factor(r) * analog_gear_factor(r))
    elif mode == c.GF_MODE:
        f = gear_follow_block(r, s, gear_factor(r))
    elif mode == c.AVG_MODE:
        f = velocity_block(r, s, avg_target(r), a)
    elif mode == c.AV_MODE:
        f = velocity_block(r, s, av_target(r), a)
    elif mode == c.AVZ_MODE:
        f = velocity_block(r, s, avz_target(r), a)
    elif mode == c.VAT_MODE:
        f = velocity_block(r, s, float(r[R.V_SOLL]), a)
        t_lim = vat_torque_limit(r)
    elif mode == c.COIL_MODE:
        f = coil_block(r, s)
    elif mode == c.TESTTQ_MODE:
        sign = 1.0 if s[L.S_TEST_CNT] < _TESTTQ_HALF else -1.0
        f = velocity_block(r, s, sign * r[R.V_SOLL], a)
    else:  # HOME1..3
        f, t_lim = home_block(r, s, mode)
    return f, t_lim


@njit(**KERNEL)
def _finish_pending(r: np.ndarray, s: np.ndarray) -> None:
    pend = s[L.S_PENDING_MODE]
    enter_mode(r, s, int(pend) if pend >= 0.0 else c.INIT_MODE)


@apart
@njit(**KERNEL)
def outer_firmware(r: np.ndarray, s: np.ndarray, p: np.ndarray, u: np.ndarray, key: np.uint64,
                   buf: np.ndarray, rec: bool, fmt: np.ndarray) -> None:
    """Firmware work at one outer sample (steps 1–3 of the module docstring)."""
    enc = encoder_count(s[L.S_THETA])
    if p[L.P_POSITION_NOISE] > 0.0:
        enc += rnd(p[L.P_POSITION_NOISE] * gauss(key, s[L.S_TICK], 3))
    v = enc - s[L.S_ENC_PREV]
    s[L.S_ENC_PREV] = enc
    v = sat16(v)
    r[R.V_IST] = int(v)
    r[R.P_IST] = wrap32(r[R.P_IST] + int(v))
    r[R.ANINP] = int(clamp(rnd(_analog_volts(s, p, u) * _ANINP_PER_VOLT) + r[R.ANINP_OFFSET],
                           -1023.0, 1023.0))
    r[R.V_EXT] = int(sat16(u[L.I_PULSE_COUNTS]))
    r[R.U_SUPPLY] = int(clamp(rnd(s[L.S_UBUS] / c.U_SUPPLY_VOLTS_PER_UNIT), 0.0, 65535.0))

    cb = r[R.CNTRL_BITS]
    if cb & c.REWINDBIT:
        r[R.REC_CNT] = 0
        cb &= ~c.REWINDBIT
    if cb & c.MAN_RESYNC:  # 3.2.163
        if cb & c.REL_RESYNC:
            r[R.P_SOLL] = wrap32(r[R.P_SOLL] + r[R.P_NEW])
            r[R.P_IST] = wrap32(r[R.P_IST] + r[R.P_NEW])
            r[R.P_FNC] = wrap32(r[R.P_FNC] + 16 * r[R.P_NEW])
        else:
            r[R.P_SOLL] = r[R.P_NEW]
            r[R.P_IST] = r[R.P_NEW]
            r[R.P_FNC] = wrap32(16 * r[R.P_NEW])
        cb &= ~c.MAN_RESYNC
    r[R.CNTRL_BITS] = cb

    mode = int(r[R.MODE_REG])
    if mode == c.INIT_MODE and (cb & c.AUTO_RESYNC):
        r[R.P_FNC] = wrap32(16 * r[R.P_IST])

    if mode < N_MODES and REGULATED[mode]:
        f, t_lim = _profile(r, s, mode)
        f, corr = speed_regulator(r, s, f, CORRECTING[mode], t_lim)
        if corr != 0.0:
            s[L.S_V_OLD] = f
            r[R.P_FNC] = wrap32(r[R.P_FNC] + int(corr))
            s[L.S_G_FNC] += corr
            r[R.FNCERR] = int(clamp(r[R.FNCERR] + corr, -134217727.0, 134217727.0))
        if fncerr_is_position(mode):
            r[R.FNCERR] = int(clamp(rnd(s[L.S_G_FNC]), -134217727.0, 134217727.0))
        if FLWERR_MODES[mode]:
            s[L.S_FLW16] += f - 16.0 * v
            r[R.FLWERR] = int(clamp(rnd(s[L.S_FLW16] / 16.0), -67000000.0, 67000000.0))
        else:
            s[L.S_FLW16] = 0.0
            r[R.FLWERR] = 0
        if mode == c.STOP_MODE and abs(v) < c.STOP_SPEED_COUNTS:
            _finish_pending(r, s)
        elif c.HOME1_MODE <= mode <= c.HOME3_MODE and home_check(r, s, mode):
            # the zero (4.4.13–15): the function position is now the motor position
            # (set_home_position), so the follow error and the speed loop's history of the
            # search do not carry into STARTMODE (docs/model.md §9)
            s[L.S_FLW16] = 0.0
            r[R.FLWERR] = 0
            s[L.S_V_OLD] = 0.0
            reset_speed_loop(r, s)
            start = int(r[R.STARTMODE])
            if (0 < start < N_MODES and REGULATED[start]
                    and not c.HOME1_MODE <= start <= c.HOME3_MODE):
                enter_mode(r, s, start)
            else:
                stop_to(r, s, c.INIT_MODE, False)
        elif mode == c.TESTTQ_MODE:
            s[L.S_TEST_CNT] += 1.0
            if s[L.S_TEST_CNT] >= 2 * _TESTTQ_HALF:
                stop_to(r, s, c.INIT_MODE, False)
    elif mode == c.AT_MODE:  # torque function block, 4.1.4 / 4.4.5
        if s[L.S_AT_EXIT] > 0.5:
            r[R.VF_OUT] = 0
            if abs(v) < c.STOP_SPEED_COUNTS:
                _finish_pending(r, s)
        else:
            t_soll = float(r[R.T_SOLL])
            r[R.VF_OUT] = int(clamp(rnd(r[R.ANINP] * t_soll / 1023.0), -t_soll, t_soll))
    elif mode == c.TESTA_MODE:  # 4.4.10
        r[R.VF_OUT] = int(r[R.T_SOLL])
    elif mode == c.BREAK_MODE:  # 4.4.11: reversed torque until stopped
        d = s[L.S_BREAK_DIR]
        if d == 0.0 or v * d <= 0.0:
            r[R.VF_OUT] = 0
            _finish_pending(r, s)
        else:
            r[R.VF_OUT] = int(-d * r[R.T_SOLL])
    else:  # INIT, SAFE, MANI, TESTU: no function block, speed regulator passive
        r[R.VF_OUT] = 0
        if mode == c.INIT_MODE or mode == c.SAFE_MODE:
            s[L.S_V_OLD] = 0.0
            r[R.FLWERR] = 0
            r[R.FNCERR] = 0

    thermal(r, s, p)
    undervoltage(r, s)
    check_errors(r, s)
    in_position(r, s, int(r[R.MODE_REG]))

    cb = r[R.CNTRL_BITS]
    if (cb & c.RECORDBIT) and not (cb & c.RECINNERBIT):
        record(r, buf, fmt, rec)
        if int(r[R.MODE_REG]) == c.TESTA_MODE:
            s[L.S_TEST_CNT] += 1.0
            if s[L.S_TEST_CNT] >= s[L.S_REC_LEN]:
                r[R.CNTRL_BITS] &= ~c.RECORDBIT
                enter_mode(r, s, c.BREAK_MODE)
                s[L.S_PENDING_MODE] = c.INIT_MODE
    elif int(r[R.MODE_REG]) == c.TESTA_MODE:  # recording switched off by the user
        s[L.S_TEST_CNT] += 1.0
        if s[L.S_TEST_CNT] >= s[L.S_REC_LEN]:
            enter_mode(r, s, c.BREAK_MODE)
            s[L.S_PENDING_MODE] = c.INIT_MODE


@njit(**LANE_KERNEL, forceinline=True)
def adc_count(x: float) -> tuple[float, bool]:
    """A phase current reading of ``x`` ADC counts (before rounding): the stored IX_IST value,
    rounded and limited to ±1023, and whether the converter saturated (IX_ERR, 3.2.147).

    ``+ 0.0`` turns a rounded −0.0 into +0.0, the zero an integer register holds: the inner
    sample (``mac050_141.inner``) uses the value without reading it back from a register.
    """
    x = rnd(x)
    return clamp(x, -1023.0, 1023.0) + 0.0, x >= 1023.0 or x <= -1023.0


@njit(**LANE_KERNEL, forceinline=True)
def plant_sample(theta: float, omega: float, theta_l: float, omega_l: float, acc: float,
                 i_re: float, i_im: float, ubus: float, dump_on: float, ua: float, ub: float,
                 uc: float, theta_e: float, pp: float, r_phase: float, lam: float, j: float,
                 coulomb: float, stop_lo: float, stop_hi: float, stop_k: float, stop_d: float,
                 load: float, noise_torque: float, u_supply: float, u_dump: float,
                 k_coil: tuple, k_mech: tuple, k_bus: tuple, rigid: bool):
    """The plant over one inner sample (docs/model.md §5): PWM counts ``ua, ub, uc`` on the bus
    drive the coil, the torque the rotor (and the load behind an elastic coupling), the coil's
    power the DC bus.

    Returns ``(theta1, omega1, theta_l1, omega_l1, i_re1, i_im1, ubus1, dump_on1, p_el, p_cu,
    e_fric, e_load, e_dump, e_sup)``: the new state, the mean electrical and copper powers [W]
    and the energies of the step [J]. Pure arithmetic on scalars, so that the inner sample
    (:mod:`mac050_141.inner`) runs it in SIMD lanes. The load torque ``load``
    acts on the motor shaft when it is rigid and on the load behind the coupling otherwise.
    ``rigid`` (a constant at each call) leaves the coupling's terms out for a motor whose shaft
    is known to be rigid (``mech_step_prepared``): the same bits without their arithmetic.
    """
    kv = ubus * _HALF_PWM_PER_VOLT
    s_u = phase_to_vector(ua * kv, ub * kv, uc * kv)
    omega_mid = omega + 0.5 * _H * acc
    s1, torque, p_el, p_cu = coil_step_prepared(complex(i_re, i_im), s_u, theta_e,
                                                pp * omega_mid, r_phase, lam, pp, _H, k_coil)
    two = not rigid and k_mech[2] > 0.0
    load_l = load if two else 0.0
    drive = torque - (0.0 if two else load) + end_stop_torque(theta, omega, stop_lo, stop_hi,
                                                              stop_k, stop_d)
    if noise_torque != 0.0:
        drive += noise_torque
    theta1, omega1, theta_l1, omega_l1, e_fric = mech_step_prepared(
        theta, omega, theta_l, omega_l, drive, load_l, j, coulomb, _H, k_mech, rigid)
    e_load = load * ((theta_l1 - theta_l) if two else (theta1 - theta))
    ubus1, dump_on1, e_dump, e_sup = bus_step_prepared(ubus, p_el, u_supply, u_dump, dump_on,
                                                       _H, k_bus)
    return (theta1, omega1, theta_l1, omega_l1, s1.real, s1.imag, ubus1, dump_on1, p_el, p_cu,
            e_fric, e_load, e_dump, e_sup)


@njit(cache=True, inline="always")
def sample_constants(p: np.ndarray) -> tuple:
    """The parameter-only factors of the inner sample for a motor's parameter row ``p``:
    ``(counts_per_amp, k_coil, k_mech, k_bus)`` (ADC counts per ampere and the plant factors of
    ``coil_constants``, ``mech_constants``, ``bus_constants``)."""
    return (1.0 / p[L.P_AMPS_PER_COUNT], coil_constants(p[L.P_R], p[L.P_L], p[L.P_LAMBDA], _H),
            mech_constants(p[L.P_J_MOTOR], p[L.P_J_LOAD], p[L.P_VISCOUS], p[L.P_K_COUPLING],
                           p[L.P_D_COUPLING], _H),
            bus_constants(p[L.P_C_BUS], p[L.P_R_SUPPLY], p[L.P_R_DUMP], _H))
