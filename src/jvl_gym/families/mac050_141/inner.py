"""The inner sample: one 128 µs current-loop sample and the plant over it (docs/model.md §2).

Each inner sample (step 4 of ``mac050_141.kernel``): ELDEG_IST and V_ELDEG from the rotor angle
(3.2.143, 3.2.144; with the hall synchronisation of 3.2.124/125 until its first zero
transition when the motor starts from its hall sector); the three phase currents measured
(IA/IB/IC_IST, quantised and limited to ±1023, IX_ERR 3.2.147); commutation and the three
current loops (4.3.1), or the mode's fixed voltages (INIT, SAFE: 4.4.1; TESTU 4.4.9; TESTKI),
or MANI's stator field (3.2.128); inner-rate recording (3.2.112–3.2.116); then the PWM voltage
(after ``pwm_delay_samples``) drives the coil, the mechanics and the DC bus for 128 µs
(docs/model.md §5) and the energy accounts.

:func:`inner_sample` is the one implementation, compiled once as a function of its own that
LLVM inlines into each caller (``forceinline``). It works on a lane of the block's scratch
(:mod:`mac050_141.scratch`) and takes a flag ``full``, a constant at each call: numba compiles
the sample once for plain bools (``engine.jit.plain_arguments``), and LLVM, having inlined it,
folds the branches on the caller's constant, so one source gives two specialisations:

- ``full`` False: the sample of a motor that :func:`mac050_141.lanes.in_lanes` admits, with no
  branch the compiler cannot turn into a select, so that the loop over the lanes of a block
  (:func:`mac050_141.lanes.inner_samples`) runs in SIMD registers; the registers of the sample
  are kept for the last of the 15 only;
- ``full`` True: every per-motor feature besides (hall synchronisation, current and torque
  noise, the passive and test modes and MANI, inner-rate recording, IX_ERR at once, the
  registers of every sample), one motor at a time (:func:`inner_samples_one`). These features
  are compiled functions of their own (:func:`_angle`, :func:`_measure`, :func:`_regulate`,
  :func:`_record_inner`, :func:`_torque_noise`), one call each from a single ``if full``
  block, which the lanes' code does not contain once LLVM has folded it.

Both specialisations do the same arithmetic in the same order on the same values, so a motor
gives the same bits on either path and an N-motor array is bit-for-bit equal to N one-motor
arrays (tests/test_lanes.py).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ...engine.apart import apart
from ...engine.jit import KERNEL, LANE_KERNEL, plain_arguments
from ...motor.noise import gauss
from ...physics.coil import vector_to_phases
from . import constants as c
from . import layout as L
from .firmware import regs as R
from .firmware.current_loop import manual_references, phase_step, references, store_references
from .firmware.modes import enter_mode
from .firmware.recorder import record
from .kernel import adc_count, plant_sample
from .plant.encoder import eldeg, encoder_count
from .plant.hall import SECTOR, hall_code, sector_index, zero_crossing
from .scratch import (
    F_AMPLITUDE,
    F_COULOMB,
    F_COUNTS_PER_AMP,
    F_ELDEG_IST,
    F_HALL_ANGLE,
    F_I_NOM,
    F_IA_IST,
    F_IA_SOLL,
    F_IB_IST,
    F_IB_SOLL,
    F_IC_IST,
    F_IC_SOLL,
    F_IX_ERR,
    F_J,
    F_KB0,
    F_KB1,
    F_KB2,
    F_KB3,
    F_KB4,
    F_KB5,
    F_KB6,
    F_KC0,
    F_KC1,
    F_KC2,
    F_KC3,
    F_KIA,
    F_KIB,
    F_KIB0,
    F_KIB1,
    F_KIC,
    F_KIFX1,
    F_KIFX2,
    F_KIFY0,
    F_KIFY1,
    F_KM0,
    F_KM1,
    F_KM2,
    F_KM3,
    F_KM4,
    F_KM5,
    F_LAMBDA,
    F_LOAD,
    F_PHASE_COMP,
    F_PHI_SOLL,
    F_POLE_PAIRS,
    F_PWM_DELAY,
    F_R,
    F_STOP_D,
    F_STOP_HI,
    F_STOP_K,
    F_STOP_LO,
    F_SUPPLY,
    F_THETA_E0,
    F_U_DUMP,
    F_UA_VAL,
    F_UB_VAL,
    F_UC_VAL,
    F_V_ELDEG,
    F_VF_OUT,
    LANE_BASE,
    LANES,
    gather,
    scatter_state,
)

_H = c.INNER_DT


# The stages of a sample below, and the commutation, ADC, plant, encoder and hall functions
# they and inner_sample call, are compiled once, as functions of their own, with forceinline:
# LLVM inlines them into each caller (into the lane loops too, which it still vectorises);
# numba's IR inliner would type and lower a copy of each at every call. Those called with a
# constant (a phase 0, 1, 2) take plain arguments: one compiled body, not one per constant.
@plain_arguments
@njit(**LANE_KERNEL, forceinline=True)
def _phase(sc: np.ndarray, j: int, k: int, i_soll: float, i_ist: float) -> float:
    """Phase ``k``'s current loop in lane ``j`` (4.3.1, :func:`current_loop.phase_step`):
    U, and the histories e(k−1), U(k−1), U(k−2), I_IST(k−1) moved on."""
    u1 = sc[LANE_BASE[L.S_IU1_A + k] + j]
    u, e = phase_step(i_soll, i_ist, sc[LANE_BASE[L.S_IE1_A + k] + j], u1,
                      sc[LANE_BASE[L.S_IU2_A + k] + j], sc[LANE_BASE[L.S_IIST1_A + k] + j],
                      sc[F_KIB1 * LANES + j], sc[F_KIB0 * LANES + j],
                      sc[F_KIFX2 * LANES + j], sc[F_KIFX1 * LANES + j], sc[F_KIFY1 * LANES + j],
                      sc[F_KIFY0 * LANES + j])
    sc[LANE_BASE[L.S_IE1_A + k] + j] = e
    sc[LANE_BASE[L.S_IU2_A + k] + j] = u1
    sc[LANE_BASE[L.S_IU1_A + k] + j] = u
    sc[LANE_BASE[L.S_IIST1_A + k] + j] = i_ist
    return u


@plain_arguments
@njit(**LANE_KERNEL, forceinline=True)
def _at_rest(sc: np.ndarray, j: int, k: int, i_ist: float) -> None:
    """Phase ``k``'s loop held at rest while the current regulator is passive (4.4.1, 4.4.9):
    no history but the measured current."""
    sc[LANE_BASE[L.S_IE1_A + k] + j] = 0.0
    sc[LANE_BASE[L.S_IU1_A + k] + j] = 0.0
    sc[LANE_BASE[L.S_IU2_A + k] + j] = 0.0
    sc[LANE_BASE[L.S_IIST1_A + k] + j] = i_ist


@plain_arguments
@njit(**LANE_KERNEL, forceinline=True)
def _pwm(sc: np.ndarray, j: int, k: int, u: float) -> float:
    """PWM value applied in phase ``k`` of lane ``j``: ``u`` itself, or the value computed one
    sample earlier when the motor has a PWM delay (docs/model.md §2). ``u`` is kept either
    way (so switching the delay on applies the previous sample's value): a store that depends
    on the delay became a masked store, slow on AMD cores."""
    pending = sc[LANE_BASE[L.S_UPEND_A + k] + j]
    sc[LANE_BASE[L.S_UPEND_A + k] + j] = u
    return pending if sc[F_PWM_DELAY * LANES + j] > 0.5 else u


@njit(**LANE_KERNEL, forceinline=True)
def _commutation(sc: np.ndarray, j: int, el: float, dv: float
                 ) -> tuple[float, float, float, float, float]:
    """Commutation of lane ``j`` (4.3.1): (I_NOM, PHI_SOLL, IA_SOLL, IB_SOLL, IC_SOLL)."""
    return references(sc[F_VF_OUT * LANES + j], el, dv, sc[F_PHASE_COMP * LANES + j],
                      sc[F_AMPLITUDE * LANES + j])


@njit(**LANE_KERNEL, forceinline=True)
def _loops(sc: np.ndarray, j: int, isa: float, isb: float, isc: float, xa: float, xb: float,
           xc: float) -> tuple[float, float, float]:
    """The three current loops of lane ``j`` (4.3.1): (UA, UB, UC)."""
    return (_phase(sc, j, 0, isa, xa), _phase(sc, j, 1, isb, xb), _phase(sc, j, 2, isc, xc))


@njit(**KERNEL)
def _angle(sc: np.ndarray, j: int, r: np.ndarray, s: np.ndarray, p: np.ndarray,
           theta_e: float, enc_abs: float) -> float:
    """ELDEG_IST of the motor in lane ``j``, one motor at a time; the hall sector and the hall
    status of CNTRL_BITS (bits 15..13) at every sample.

    Commutation aligned from power-on: the electrical angle. A motor that started from its
    hall sector (3.2.124/125): the encoder count plus the offset latched at the last hall zero
    transition that counted (the first after power-on, later ones with CNTRL_BITS HALL_INT),
    mod 2048.
    """
    sec = sector_index(theta_e, sc[F_HALL_ANGLE * LANES + j])
    cross = zero_crossing(sc[LANE_BASE[L.S_HALL_SECTOR] + j], sec)
    sc[LANE_BASE[L.S_HALL_SECTOR] + j] = sec
    if p[L.P_HALL_START] < 0.5:
        el = eldeg(theta_e)
    else:
        if cross != 0 and (s[L.S_HALL_SYNCED] < 0.5 or (r[R.CNTRL_BITS] & c.HALL_INT)):
            # the firmware latches the count at the edge
            edge_e = p[L.P_HALL_ANGLE] + (sec if cross > 0 else sec + 1.0) * SECTOR
            enc_edge = encoder_count((edge_e - p[L.P_THETA_E0]) / p[L.P_POLE_PAIRS])
            target = r[R.ELDEGP_OFFSET] if cross > 0 else r[R.ELDEGN_OFFSET]
            s[L.S_ELDEG_OFS] = target - enc_edge
            s[L.S_HALL_SYNCED] = 1.0
        el = float(int(enc_abs + s[L.S_ELDEG_OFS]) % c.ELDEG_PER_TURN)
    r[R.CNTRL_BITS] = (r[R.CNTRL_BITS] & 0x1FFF) | (hall_code(sec) << c.HALL_STATUS_SHIFT)
    return el


@njit(**KERNEL)
def _measure(r: np.ndarray, p: np.ndarray, key: np.uint64, tick: float, el: float, dv: float,
             xa: float, xb: float, xc: float) -> tuple[float, float, float]:
    """The phase current readings of ``xa, xb, xc`` ADC counts (before rounding) with the
    current sensing noise (noise channels 0–2), one motor at a time: stored with ELDEG_IST
    ``el`` and V_ELDEG ``dv``; a saturated converter sets IX_ERR (3.2.147) at once."""
    if p[L.P_CURRENT_NOISE] > 0.0:
        xa += p[L.P_CURRENT_NOISE] * gauss(key, tick, 0)
        xb += p[L.P_CURRENT_NOISE] * gauss(key, tick, 1)
        xc += p[L.P_CURRENT_NOISE] * gauss(key, tick, 2)
    xa, over_a = adc_count(xa)
    xb, over_b = adc_count(xb)
    xc, over_c = adc_count(xc)
    if over_a or over_b or over_c:
        r[R.ERR_STAT] |= c.IX_ERR
    r[R.ELDEG_IST] = int(el)
    r[R.V_ELDEG] = int(dv)
    r[R.IA_IST] = int(xa)
    r[R.IB_IST] = int(xb)
    r[R.IC_IST] = int(xc)
    return xa, xb, xc


@njit(**KERNEL)
def _regulate(sc: np.ndarray, j: int, r: np.ndarray, mode: int, el: float, dv: float,
              xa: float, xb: float, xc: float) -> tuple[float, float, float]:
    """The current regulator in mode ``mode``, one motor at a time, with its registers:
    (UA, UB, UC) = UA/UB/UC_VAL.

    Passive (INIT, SAFE 4.4.1; TESTU 4.4.9: UA = UMEAS, UC = −UMEAS; TESTKI, the documented
    measurement: UA = UMEAS, UB = −UMEAS): the fixed voltages, the loops of lane ``j`` at rest
    and no references. Otherwise the references of commutation (4.3.1) or of MANI_MODE's
    stator field (3.2.128), then the three current loops (the lanes' :func:`_commutation` and
    :func:`_loops`).
    """
    if (mode == c.INIT_MODE or mode == c.SAFE_MODE or mode == c.TESTU_MODE
            or mode == c.TESTKI_MODE):
        um = float(r[R.UMEAS]) if mode == c.TESTU_MODE or mode == c.TESTKI_MODE else 0.0
        ua = um
        # + 0.0: −UMEAS of a zero UMEAS is the +0.0 the register holds
        ub = -um + 0.0 if mode == c.TESTKI_MODE else 0.0
        uc = -um + 0.0 if mode == c.TESTU_MODE else 0.0
        _at_rest(sc, j, 0, xa)
        _at_rest(sc, j, 1, xb)
        _at_rest(sc, j, 2, xc)
        r[R.I_NOM] = 0
        r[R.IA_SOLL] = 0
        r[R.IB_SOLL] = 0
        r[R.IC_SOLL] = 0
    else:
        if mode == c.MANI_MODE:
            isa, isb, isc = manual_references(float(r[R.MAN_I_NOM]), int(r[R.MAN_ALPHA]),
                                              r[R.AMPLITUDE])
            r[R.IA_SOLL] = int(isa)
            r[R.IB_SOLL] = int(isb)
            r[R.IC_SOLL] = int(isc)
        else:
            i_nom, phi, isa, isb, isc = _commutation(sc, j, el, dv)
            store_references(r, i_nom, phi, isa, isb, isc)
        ua, ub, uc = _loops(sc, j, isa, isb, isc, xa, xb, xc)
    r[R.UA_VAL] = int(ua)
    r[R.UB_VAL] = int(ub)
    r[R.UC_VAL] = int(uc)
    return ua, ub, uc


@njit(**KERNEL)
def _record_inner(r: np.ndarray, s: np.ndarray, buf: np.ndarray, rec: bool, fmt: np.ndarray,
                  mode: int) -> None:
    """Inner-rate recording (3.2.112–3.2.116, RECINNERBIT) and the end of a TESTU / TESTKI
    record (4.4.9): after its samples the motor enters INIT_MODE."""
    cb = r[R.CNTRL_BITS]
    if mode == c.TESTU_MODE or mode == c.TESTKI_MODE:
        if (cb & c.RECORDBIT) and (cb & c.RECINNERBIT):
            record(r, buf, fmt, rec)
        s[L.S_TEST_CNT] += 1.0
        if s[L.S_TEST_CNT] >= s[L.S_REC_LEN]:
            r[R.CNTRL_BITS] &= ~c.RECORDBIT
            enter_mode(r, s, c.INIT_MODE)
    elif (cb & c.RECORDBIT) and (cb & c.RECINNERBIT):
        record(r, buf, fmt, rec)


@njit(**KERNEL)
def _torque_noise(p: np.ndarray, key: np.uint64, tick: float) -> float:
    """The process torque noise of the sample [N·m] (noise channel 4)."""
    return p[L.P_TORQUE_NOISE] * gauss(key, tick, 4) if p[L.P_TORQUE_NOISE] > 0.0 else 0.0


@plain_arguments
@njit(**LANE_KERNEL, forceinline=True)
def inner_sample(sc: np.ndarray, j: int, k: int, last: bool, full: bool, rigid: bool,
                 r: np.ndarray, s: np.ndarray, p: np.ndarray, u: np.ndarray, key: np.uint64,
                 buf: np.ndarray, rec: bool, fmt: np.ndarray) -> None:
    """Inner sample ``k`` (0 … 14) of an outer sample for the motor in lane ``j`` of the
    scratch row ``sc`` (module docstring).

    ``last``, ``full`` and ``rigid`` are constants at each call, which LLVM folds once it has
    inlined the sample (module docstring). ``last``: the sample stores its
    registers into the lane's fields (``full`` False; the earlier samples' registers would be
    overwritten unread). ``full``: the per-motor features, with the motor's rows ``r``, ``s``,
    ``p``, ``u``, its noise ``key`` and the sample buffer ``buf``, ``rec``, ``fmt``; the
    registers go to ``r`` at once. Without ``full`` those arguments are not read (any rows of
    the right types will do). ``rigid``: the motor's shaft is rigid (no elastic coupling), so
    the plant leaves the coupling's terms out (``plant_sample``; the same bits).
    """
    theta = sc[LANE_BASE[L.S_THETA] + j]
    omega = sc[LANE_BASE[L.S_OMEGA] + j]
    pp = sc[F_POLE_PAIRS * LANES + j]
    theta_e = pp * theta + sc[F_THETA_E0 * LANES + j]
    enc_abs = encoder_count(theta)
    if full:
        el = _angle(sc, j, r, s, p, theta_e, enc_abs)
    else:
        if last:
            sc[LANE_BASE[L.S_HALL_SECTOR] + j] = sector_index(theta_e, sc[F_HALL_ANGLE * LANES + j])
        el = eldeg(theta_e)
    # V_ELDEG: encoder counts per inner sample (3.2.144)
    dv = enc_abs - sc[LANE_BASE[L.S_ELDEG_PREV] + j]
    sc[LANE_BASE[L.S_ELDEG_PREV] + j] = enc_abs

    i_re = sc[LANE_BASE[L.S_I_RE] + j]
    i_im = sc[LANE_BASE[L.S_I_IM] + j]
    ia, ib, ic = vector_to_phases(complex(i_re, i_im))
    cpa = sc[F_COUNTS_PER_AMP * LANES + j]
    xa = ia * cpa * sc[F_KIA * LANES + j] / 256.0
    xb = ib * cpa * sc[F_KIB * LANES + j] / 256.0
    xc = ic * cpa * sc[F_KIC * LANES + j] / 256.0
    noise_torque = 0.0
    if full:
        tick = s[L.S_TICK] + k  # the noise streams' counter
        xa, xb, xc = _measure(r, p, key, tick, el, dv, xa, xb, xc)
        mode = int(r[R.MODE_REG])
        ua, ub, uc = _regulate(sc, j, r, mode, el, dv, xa, xb, xc)
        _record_inner(r, s, buf, rec, fmt, mode)
        noise_torque = _torque_noise(p, key, tick)
    else:
        xa, over_a = adc_count(xa)
        xb, over_b = adc_count(xb)
        xc, over_c = adc_count(xc)
        # F_IX_ERR counts the samples with a saturated converter (a select between the stored
        # flag and 1 became a masked, conditional store: slow on AMD cores)
        sc[F_IX_ERR * LANES + j] = sc[F_IX_ERR * LANES + j] + (1.0 if (over_a or over_b or over_c)
                                                      else 0.0)
        i_nom, phi, isa, isb, isc = _commutation(sc, j, el, dv)
        ua, ub, uc = _loops(sc, j, isa, isb, isc, xa, xb, xc)
        if last:
            sc[F_ELDEG_IST * LANES + j] = el
            sc[F_V_ELDEG * LANES + j] = dv
            sc[F_IA_IST * LANES + j] = xa
            sc[F_IB_IST * LANES + j] = xb
            sc[F_IC_IST * LANES + j] = xc
            sc[F_I_NOM * LANES + j] = i_nom
            sc[F_PHI_SOLL * LANES + j] = phi
            sc[F_IA_SOLL * LANES + j] = isa
            sc[F_IB_SOLL * LANES + j] = isb
            sc[F_IC_SOLL * LANES + j] = isc
            sc[F_UA_VAL * LANES + j] = ua
            sc[F_UB_VAL * LANES + j] = ub
            sc[F_UC_VAL * LANES + j] = uc
    load = sc[F_LOAD * LANES + j]
    (theta1, omega1, theta_l1, omega_l1, i_re1, i_im1, ubus, dump_on, p_el, p_cu, e_fric,
     e_load, e_dump, e_sup) = plant_sample(
        theta, omega, sc[LANE_BASE[L.S_LOAD_THETA] + j], sc[LANE_BASE[L.S_LOAD_OMEGA] + j],
        sc[LANE_BASE[L.S_ACC] + j], i_re, i_im, sc[LANE_BASE[L.S_UBUS] + j],
        sc[LANE_BASE[L.S_DUMP_ON] + j], _pwm(sc, j, 0, ua), _pwm(sc, j, 1, ub),
        _pwm(sc, j, 2, uc), theta_e, pp, sc[F_R * LANES + j], sc[F_LAMBDA * LANES + j],
        sc[F_J * LANES + j], sc[F_COULOMB * LANES + j], sc[F_STOP_LO * LANES + j],
        sc[F_STOP_HI * LANES + j], sc[F_STOP_K * LANES + j], sc[F_STOP_D * LANES + j], load,
        noise_torque,
        sc[F_SUPPLY * LANES + j], sc[F_U_DUMP * LANES + j],
        (sc[F_KC0 * LANES + j], sc[F_KC1 * LANES + j], sc[F_KC2 * LANES + j],
         sc[F_KC3 * LANES + j]),
        (sc[F_KM0 * LANES + j], sc[F_KM1 * LANES + j], sc[F_KM2 * LANES + j], sc[F_KM3 * LANES + j],
         sc[F_KM4 * LANES + j], sc[F_KM5 * LANES + j]),
        (sc[F_KB0 * LANES + j], sc[F_KB1 * LANES + j], sc[F_KB2 * LANES + j], sc[F_KB3 * LANES + j],
         sc[F_KB4 * LANES + j], sc[F_KB5 * LANES + j], sc[F_KB6 * LANES + j]), rigid)
    sc[LANE_BASE[L.S_THETA] + j] = theta1
    sc[LANE_BASE[L.S_OMEGA] + j] = omega1
    if not rigid:  # a rigid shaft's load follows the motor: set after the samples
        sc[LANE_BASE[L.S_LOAD_THETA] + j] = theta_l1
        sc[LANE_BASE[L.S_LOAD_OMEGA] + j] = omega_l1
    sc[LANE_BASE[L.S_ACC] + j] = (omega1 - omega) * c.INNER_HZ
    sc[LANE_BASE[L.S_I_RE] + j] = i_re1
    sc[LANE_BASE[L.S_I_IM] + j] = i_im1
    sc[LANE_BASE[L.S_E_ELEC] + j] = sc[LANE_BASE[L.S_E_ELEC] + j] + p_el * _H
    sc[LANE_BASE[L.S_E_COPPER] + j] = sc[LANE_BASE[L.S_E_COPPER] + j] + p_cu * _H
    sc[LANE_BASE[L.S_E_FRICTION] + j] = sc[LANE_BASE[L.S_E_FRICTION] + j] + e_fric
    sc[LANE_BASE[L.S_E_LOAD] + j] = sc[LANE_BASE[L.S_E_LOAD] + j] + e_load
    sc[LANE_BASE[L.S_UBUS] + j] = ubus
    sc[LANE_BASE[L.S_DUMP_ON] + j] = dump_on
    sc[LANE_BASE[L.S_E_DUMP] + j] = sc[LANE_BASE[L.S_E_DUMP] + j] + e_dump
    sc[LANE_BASE[L.S_E_SUPPLY] + j] = sc[LANE_BASE[L.S_E_SUPPLY] + j] + e_sup
    sc[LANE_BASE[L.S_I2_SUM] + j] = sc[LANE_BASE[L.S_I2_SUM] + j] + (xa * xa + xb * xb + xc * xc)
    # the regenerated power; no branch on its sign
    sc[LANE_BASE[L.S_PREG_SUM] + j] = sc[LANE_BASE[L.S_PREG_SUM] + j] + max(-p_el, 0.0)


@apart
@njit(**LANE_KERNEL)
def inner_samples_one(r: np.ndarray, s: np.ndarray, p: np.ndarray, u: np.ndarray,
                      key: np.uint64, buf: np.ndarray, rec: bool, fmt: np.ndarray,
                      sc: np.ndarray, j: int) -> None:
    """The 15 inner samples of one outer sample of one motor, with every per-motor feature
    (:func:`inner_sample` with ``full``), in lane ``j`` of the scratch row ``sc``: the path of
    the motors :func:`mac050_141.lanes.inner_samples` cannot put into SIMD lanes.

    A function of its own, compiled apart and called from ``inner_samples``, so that its loop
    is not optimised again inside every caller. The call costs one argument transfer per motor
    and outer sample, on this path only.
    """
    gather(sc, j, 0, r, s, p, u)
    for k in range(c.INNER_PER_OUTER):
        inner_sample(sc, j, k, True, True, False, r, s, p, u, key, buf, rec, fmt)
    scatter_state(sc, j, s)
