"""The MAC800's current-loop samples and the plant, for a block of motors in SIMD lanes.

Fifteen current-loop samples (11550 Hz, 86.6 µs) follow each servo sample (OUTLOOPDIV,
register 157).
Each sample of a motor:

1. the encoder: ELDEG_IST (4096 per electrical turn) and V_ELDEG (counts over the sample);
2. the current measurement IA/IB/IC_IST = round(i·counts per ampere), limited to ±1023 (a
   reading at the limit counts for ERR_STAT bit 12 IPEAK_ERR);
3. commutation (the MAC050–141's, its manual 4.3.1, on the MAC800's registers):
   I_NOM = |VF_OUT|·AMPLITUDE/1023 [ADC counts], PHI_SOLL = ELDEG_IST ± 1024 (90°) +
   round(V_ELDEG·PHASE_COMP/256), IA/IB/IC_SOLL = I_NOM·sin(PHI_SOLL + k·120°);
4. per phase the current filter ``e = I_SOLL − IB(I_IST)``, ``IB(z) = KIB1 + KIB0 z⁻¹``
   (Fixed24), ``U = IF(e)``, ``IF(z) = (KIFX2 + KIFX1 z⁻¹)/(1 − KIFY1 z⁻¹ − KIFY0 z⁻²)``
   (Fixed16), rounded and limited to ±1023 PWM counts = ±U_BUS/2 (registers 144–149, 180–194);
5. the plant over the sample with the PWM voltage (applied one sample late with
   ``pwm_delay_samples``): the MAC050–141's PMSM coil, rigid rotor and DC bus kernels, the same
   physics with the MAC800's data (``mac050_141.plant``).

In passive mode the power stage is off: no voltage is applied, the winding current falls to zero
within the sample through the free-wheeling diodes (decision: a simplification of the diode
conduction, which lasts a fraction of a millisecond), the loops hold no history, no power
reaches the bus.

Every lane does the same arithmetic, with selects for the passive case, so the loop over lanes
runs in SIMD registers and a motor's result does not depend on its block: an N-motor array is
bit-for-bit equal to N one-motor arrays.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ...engine.apart import apart
from ...engine.jit import KERNEL, LANE_KERNEL, plain_arguments, widest_vectors
from ...physics.bus import bus_step_prepared
from ...physics.coil import coil_step_prepared, phase_to_vector, vector_to_phases
from ...physics.fixed import clamp, rnd
from ...physics.mechanics import end_stop_torque, mech_step_prepared
from ...physics.trig import fma, sincos
from . import constants as c
from . import layout as L
from .firmware import regs as R
from .firmware.modes import regulated
from .firmware.recorder import record
from .plant.encoder import eldeg, encoder_count

#: motors per block
LANES = 16
_H = c.INNER_DT
_HALF_PWM_PER_VOLT = 1.0 / (2.0 * c.PWM_FULL)
_RAD_PER_ELDEG = 2.0 * math.pi / c.ELDEG_PER_TURN
_PER_ELDEG_TURN = 1.0 / c.ELDEG_PER_TURN
_HALF_SQRT3 = 0.5 * math.sqrt(3.0)
_FX16 = 1.0 / 65536.0
_FX24 = 1.0 / 16777216.0
_QUARTER = c.ELDEG_PER_TURN / 4.0

#: the state columns a lane carries, gathered before the samples and scattered after them
LANE_STATE = (
    L.S_THETA, L.S_OMEGA, L.S_ACC, L.S_I_RE, L.S_I_IM, L.S_UBUS, L.S_DUMP_ON, L.S_ELDEG_PREV,
    L.S_IE1_A, L.S_IE1_B, L.S_IE1_C, L.S_IU1_A, L.S_IU1_B, L.S_IU1_C, L.S_IU2_A, L.S_IU2_B,
    L.S_IU2_C, L.S_IIST1_A, L.S_IIST1_B, L.S_IIST1_C, L.S_UPEND_A, L.S_UPEND_B, L.S_UPEND_C,
    L.S_E_ELEC, L.S_E_COPPER, L.S_E_FRICTION, L.S_E_LOAD, L.S_E_DUMP, L.S_E_SUPPLY,
    L.S_I2_SUM, L.S_PREG_SUM, L.S_PCU_SUM, L.S_IPEAK,
)
_NS = len(LANE_STATE)
_COLS = np.array(LANE_STATE, dtype=np.int64)
_LANE_OF = np.full(L.N_STATE, -1, dtype=np.int64)
_LANE_OF[_COLS] = np.arange(_NS)
#: the parameter columns a lane reads
LANE_PARAMS = (
    L.P_POLE_PAIRS, L.P_PWM_DELAY, L.P_R, L.P_LAMBDA, L.P_COULOMB, L.P_STOP_LO, L.P_STOP_HI,
    L.P_STOP_K, L.P_STOP_D, L.P_U_DUMP, L.P_CPA, L.P_KC0, L.P_KC1, L.P_KC2, L.P_KC3, L.P_KM0,
    L.P_KM1, L.P_KB0, L.P_KB1, L.P_KB2, L.P_KB3, L.P_KB4, L.P_KB5, L.P_KB6,
)
_NP = len(LANE_PARAMS)
_PCOLS = np.array(LANE_PARAMS, dtype=np.int64)
_PLANE_OF = np.full(L.N_PARAM, -1, dtype=np.int64)
_PLANE_OF[_PCOLS] = np.arange(_NS, _NS + _NP)
# the lane fields after the state and parameter columns, as int64 scalars: numba types a plain
# int global as a literal and would compile ``_get`` and ``_put`` once for each field
(
    F_J, F_LOAD, F_SUPPLY, F_ACTIVE, F_VF_OUT, F_AMPLITUDE, F_PHASE_COMP, F_KIB1, F_KIB0,
    F_KIFX2, F_KIFX1, F_KIFY1, F_KIFY0, F_MOTOR,
    # registers of the last sample
    F_ELDEG_IST, F_V_ELDEG, F_IA_IST, F_IB_IST, F_IC_IST, F_I_NOM, F_PHI_SOLL, F_IA_SOLL,
    F_IB_SOLL, F_IC_SOLL, F_UA_VAL, F_UB_VAL, F_UC_VAL, F_EMK_A, F_EMK_B, F_EMK_C,
    N_FIELDS,
) = np.arange(_NS + _NP, _NS + _NP + 31)
#: the register values of the last sample, in the order of their fields
_OUT_REGS = np.array([R.ELDEG_IST, R.V_ELDEG, R.IA_IST, R.IA_IST + 1, R.IA_IST + 2, R.I_NOM,
                      R.PHI_SOLL, R.IA_SOLL, R.IA_SOLL + 1, R.IA_SOLL + 2, R.UA_VAL,
                      R.UA_VAL + 1, R.UA_VAL + 2, R.EMK_A, R.EMK_A + 1, R.EMK_A + 2],
                     dtype=np.int64)


def lane_scratch(n_motors: int) -> np.ndarray:
    """Working memory of the blocks: one row of ``N_FIELDS·LANES`` float64 per block."""
    return np.zeros((-(-int(n_motors) // LANES), N_FIELDS * LANES))


# The lane accessors and the small stages of a sample (a phase's current filter, its PWM value,
# an ADC reading) are compiled once, as functions of their own, and LLVM inlines them into the
# lane loops (which it still vectorises); numba's IR inliner would copy each of them into each
# of their many call sites.
@njit(**KERNEL)
def _get(sc: np.ndarray, f: int, j: int) -> float:
    return sc[f * LANES + j]


@njit(**KERNEL)
def _put(sc: np.ndarray, f: int, j: int, x: float) -> None:
    sc[f * LANES + j] = x


@njit(**KERNEL)
def _sf(col: int) -> int:
    """Lane field of state column ``col``."""
    return _LANE_OF[col]


@njit(**KERNEL)
def _pf(col: int) -> int:
    """Lane field of parameter column ``col``."""
    return _PLANE_OF[col]


@njit(cache=True, inline="always")
def _gather(sc: np.ndarray, j: int, i: int, r: np.ndarray, s: np.ndarray, p: np.ndarray,
            u: np.ndarray) -> None:
    """Copy what motor ``i``'s samples read into lane ``j`` (the parameters only when the
    lane held another motor or the motor was reset since: they change only at a reset)."""
    for q in range(_NS):
        _put(sc, q, j, s[_COLS[q]])
    if _get(sc, F_MOTOR, j) != float(i) or s[L.S_PARAMS_NEW] > 0.5:
        for q in range(_NP):
            _put(sc, _NS + q, j, p[_PCOLS[q]])
        _put(sc, F_J, j, p[L.P_J_MOTOR] + p[L.P_J_LOAD])
        s[L.S_PARAMS_NEW] = 0.0
    _put(sc, F_LOAD, j, u[L.I_LOAD_TORQUE])
    _put(sc, F_SUPPLY, j, u[L.I_SUPPLY_VOLTS])
    mode = int(r[R.MODE_REG])
    _put(sc, F_ACTIVE, j, 1.0 if (regulated(mode) or mode == c.ANALOG_TORQUE_MODE) else 0.0)
    _put(sc, F_VF_OUT, j, float(r[R.VF_OUT]))
    _put(sc, F_AMPLITUDE, j, float(r[R.AMPLITUDE]))
    _put(sc, F_PHASE_COMP, j, float(r[R.PHASE_COMP]))
    _put(sc, F_KIB1, j, r[R.KIB1] * _FX24)
    _put(sc, F_KIB0, j, r[R.KIB0] * _FX24)
    _put(sc, F_KIFX2, j, r[R.KIFX2] * _FX16)
    _put(sc, F_KIFX1, j, r[R.KIFX1] * _FX16)
    _put(sc, F_KIFY1, j, r[R.KIFY1] * _FX16)
    _put(sc, F_KIFY0, j, r[R.KIFY0] * _FX16)
    _put(sc, F_MOTOR, j, float(i))


@njit(cache=True, inline="always")
def _store_regs(sc: np.ndarray, j: int, r: np.ndarray) -> None:
    """Store lane ``j``'s registers of the last sample."""
    for q in range(_OUT_REGS.shape[0]):
        r[_OUT_REGS[q]] = int(_get(sc, F_ELDEG_IST + q, j))


@njit(cache=True, inline="always")
def _scatter(sc: np.ndarray, j: int, r: np.ndarray, s: np.ndarray) -> None:
    """Store lane ``j``'s state and registers back into its motor's rows."""
    for q in range(_NS):
        s[_COLS[q]] = _get(sc, q, j)
    s[L.S_TICK] += c.INNER_PER_OUTER
    _store_regs(sc, j, r)


@njit(**LANE_KERNEL)
def _phase(sc: np.ndarray, j: int, k: int, i_soll: float, i_ist: float, on: bool) -> float:
    """Phase ``k``'s current filter in lane ``j``; passive (``on`` False): U = 0, no history."""
    e1 = _get(sc, _sf(L.S_IE1_A) + k, j)
    u1 = _get(sc, _sf(L.S_IU1_A) + k, j)
    u2 = _get(sc, _sf(L.S_IU2_A) + k, j)
    i1 = _get(sc, _sf(L.S_IIST1_A) + k, j)
    e = i_soll - fma(_get(sc, F_KIB1, j), i_ist, _get(sc, F_KIB0, j) * i1)
    u = fma(_get(sc, F_KIFX2, j), e, fma(_get(sc, F_KIFX1, j), e1,
                                         fma(_get(sc, F_KIFY1, j), u1,
                                             _get(sc, F_KIFY0, j) * u2)))
    u = clamp(rnd(u), -1023.0, 1023.0) + 0.0
    u = u if on else 0.0
    _put(sc, _sf(L.S_IE1_A) + k, j, e if on else 0.0)
    _put(sc, _sf(L.S_IU2_A) + k, j, u1 if on else 0.0)
    _put(sc, _sf(L.S_IU1_A) + k, j, u)
    _put(sc, _sf(L.S_IIST1_A) + k, j, i_ist)
    return u


@njit(**LANE_KERNEL)
def _pwm(sc: np.ndarray, j: int, k: int, u: float) -> float:
    """PWM value applied in phase ``k``: ``u``, or the last sample's with a PWM delay."""
    pending = _get(sc, _sf(L.S_UPEND_A) + k, j)
    _put(sc, _sf(L.S_UPEND_A) + k, j, u)
    return pending if _get(sc, _pf(L.P_PWM_DELAY), j) > 0.5 else u


@njit(**LANE_KERNEL)
def _adc(x: float) -> float:
    return clamp(rnd(x), -1023.0, 1023.0) + 0.0


@plain_arguments
@njit(**LANE_KERNEL, forceinline=True)
def _sample(sc: np.ndarray, j: int, last: bool) -> None:
    """One current-loop sample of lane ``j`` (module docstring); ``last`` (a constant at each
    call) also keeps the sample's registers.

    Compiled once, for a plain bool ``last`` (``engine.jit.plain_arguments``), as a function of
    its own that LLVM inlines into each lane loop (``forceinline``), folds ``last`` there and
    vectorises; numba's IR inliner would type and lower the whole sample once per call."""
    theta = _get(sc, _sf(L.S_THETA), j)
    omega = _get(sc, _sf(L.S_OMEGA), j)
    pp = _get(sc, _pf(L.P_POLE_PAIRS), j)
    on = _get(sc, F_ACTIVE, j) > 0.5
    theta_e = pp * theta
    enc = encoder_count(theta)
    el = eldeg(theta_e)
    dv = enc - _get(sc, _sf(L.S_ELDEG_PREV), j)
    _put(sc, _sf(L.S_ELDEG_PREV), j, enc)
    i_re = _get(sc, _sf(L.S_I_RE), j)
    i_im = _get(sc, _sf(L.S_I_IM), j)
    ia, ib, ic = vector_to_phases(complex(i_re, i_im))
    cpa = _get(sc, _pf(L.P_CPA), j)
    xa = _adc(ia * cpa)
    xb = _adc(ib * cpa)
    xc = _adc(ic * cpa)
    over = abs(xa) >= 1023.0 or abs(xb) >= 1023.0 or abs(xc) >= 1023.0
    vf = _get(sc, F_VF_OUT, j)
    amp = abs(vf) * _get(sc, F_AMPLITUDE, j) * (1.0 / 1023.0)
    phi = el + (_QUARTER if vf >= 0.0 else -_QUARTER) + rnd(
        dv * _get(sc, F_PHASE_COMP, j) * (1.0 / 256.0))
    phi -= c.ELDEG_PER_TURN * np.floor(phi * _PER_ELDEG_TURN)
    sa, ca = sincos(phi * _RAD_PER_ELDEG)
    isa = clamp(rnd(amp * sa), -1023.0, 1023.0) + 0.0
    isb = clamp(rnd(amp * (-0.5 * sa + _HALF_SQRT3 * ca)), -1023.0, 1023.0) + 0.0
    isc = clamp(rnd(amp * (-0.5 * sa - _HALF_SQRT3 * ca)), -1023.0, 1023.0) + 0.0
    ua = _phase(sc, j, 0, isa, xa, on)
    ub = _phase(sc, j, 1, isb, xb, on)
    uc = _phase(sc, j, 2, isc, xc, on)
    ubus = _get(sc, _sf(L.S_UBUS), j)
    kv = ubus * _HALF_PWM_PER_VOLT
    s_u = phase_to_vector(_pwm(sc, j, 0, ua) * kv, _pwm(sc, j, 1, ub) * kv,
                          _pwm(sc, j, 2, uc) * kv)
    omega_mid = omega + 0.5 * _H * _get(sc, _sf(L.S_ACC), j)
    lam = _get(sc, _pf(L.P_LAMBDA), j)
    k_coil = (_get(sc, _pf(L.P_KC0), j), _get(sc, _pf(L.P_KC1), j),
              _get(sc, _pf(L.P_KC2), j), _get(sc, _pf(L.P_KC3), j))
    s1, torque, p_el, p_cu = coil_step_prepared(complex(i_re, i_im), s_u, theta_e,
                                                pp * omega_mid, _get(sc, _pf(L.P_R), j), lam,
                                                pp, _H, k_coil)
    i_re1 = s1.real if on else 0.0
    i_im1 = s1.imag if on else 0.0
    torque = torque if on else 0.0
    p_el = p_el if on else 0.0
    p_cu = p_cu if on else 0.0
    load = _get(sc, F_LOAD, j)
    drive = torque - load + end_stop_torque(
        theta, omega, _get(sc, _pf(L.P_STOP_LO), j), _get(sc, _pf(L.P_STOP_HI), j),
        _get(sc, _pf(L.P_STOP_K), j), _get(sc, _pf(L.P_STOP_D), j))
    # a rigid shaft: the load follows the rotor, its torque is part of ``drive``
    theta1, omega1, _theta_l, _omega_l, e_fric = mech_step_prepared(
        theta, omega, theta, omega, drive, 0.0, _get(sc, F_J, j),
        _get(sc, _pf(L.P_COULOMB), j), _H,
        (_get(sc, _pf(L.P_KM0), j), _get(sc, _pf(L.P_KM1), j), 0.0, 0.0, 0.0, 0.0))
    ubus1, dump_on, e_dump, e_sup = bus_step_prepared(
        ubus, p_el, _get(sc, F_SUPPLY, j), _get(sc, _pf(L.P_U_DUMP), j),
        _get(sc, _sf(L.S_DUMP_ON), j), _H,
        (_get(sc, _pf(L.P_KB0), j), _get(sc, _pf(L.P_KB1), j), _get(sc, _pf(L.P_KB2), j),
         _get(sc, _pf(L.P_KB3), j), _get(sc, _pf(L.P_KB4), j), _get(sc, _pf(L.P_KB5), j),
         _get(sc, _pf(L.P_KB6), j)))
    if last:
        _put(sc, F_ELDEG_IST, j, el)
        _put(sc, F_V_ELDEG, j, dv)
        _put(sc, F_IA_IST, j, xa)
        _put(sc, F_IB_IST, j, xb)
        _put(sc, F_IC_IST, j, xc)
        _put(sc, F_I_NOM, j, rnd(amp) if on else 0.0)
        _put(sc, F_PHI_SOLL, j, phi)
        _put(sc, F_IA_SOLL, j, isa if on else 0.0)
        _put(sc, F_IB_SOLL, j, isb if on else 0.0)
        _put(sc, F_IC_SOLL, j, isc if on else 0.0)
        _put(sc, F_UA_VAL, j, ua)
        _put(sc, F_UB_VAL, j, ub)
        _put(sc, F_UC_VAL, j, uc)
        se, ce = sincos(theta_e)
        w = lam * pp * omega
        _put(sc, F_EMK_A, j, rnd(w * ce) + 0.0)
        _put(sc, F_EMK_B, j, rnd(w * (-0.5 * ce - _HALF_SQRT3 * se)) + 0.0)
        _put(sc, F_EMK_C, j, rnd(w * (-0.5 * ce + _HALF_SQRT3 * se)) + 0.0)
    _put(sc, _sf(L.S_THETA), j, theta1)
    _put(sc, _sf(L.S_OMEGA), j, omega1)
    _put(sc, _sf(L.S_ACC), j, (omega1 - omega) * c.INNER_HZ)
    _put(sc, _sf(L.S_I_RE), j, i_re1)
    _put(sc, _sf(L.S_I_IM), j, i_im1)
    _put(sc, _sf(L.S_UBUS), j, ubus1)
    _put(sc, _sf(L.S_DUMP_ON), j, dump_on)
    _put(sc, _sf(L.S_E_ELEC), j, _get(sc, _sf(L.S_E_ELEC), j) + p_el * _H)
    _put(sc, _sf(L.S_E_COPPER), j, _get(sc, _sf(L.S_E_COPPER), j) + p_cu * _H)
    _put(sc, _sf(L.S_E_FRICTION), j, _get(sc, _sf(L.S_E_FRICTION), j) + e_fric)
    _put(sc, _sf(L.S_E_LOAD), j, _get(sc, _sf(L.S_E_LOAD), j) + load * (theta1 - theta))
    _put(sc, _sf(L.S_E_DUMP), j, _get(sc, _sf(L.S_E_DUMP), j) + e_dump)
    _put(sc, _sf(L.S_E_SUPPLY), j, _get(sc, _sf(L.S_E_SUPPLY), j) + e_sup)
    _put(sc, _sf(L.S_I2_SUM), j, _get(sc, _sf(L.S_I2_SUM), j) + (i_re * i_re + i_im * i_im))
    _put(sc, _sf(L.S_PREG_SUM), j, _get(sc, _sf(L.S_PREG_SUM), j) + max(-p_el, 0.0))
    _put(sc, _sf(L.S_PCU_SUM), j, _get(sc, _sf(L.S_PCU_SUM), j) + p_cu)
    _put(sc, _sf(L.S_IPEAK), j, _get(sc, _sf(L.S_IPEAK), j) + (1.0 if over else 0.0))


@njit(cache=True, inline="always")
def _records_inner(r: np.ndarray) -> bool:
    cb = r[R.CNTRL_BITS]
    return (cb & c.RECORDBIT) != 0 and (cb & c.RECINNERBIT) != 0


@apart
@widest_vectors
@njit(**LANE_KERNEL)
def inner_samples(regs, state, params, inputs, buf, rec, i0, n, scratch):
    """The current-loop samples of one servo sample of motors ``i0 … i0 + n − 1`` (one
    block, ``n ≤ LANES``); ``scratch`` is the block's row of :func:`lane_scratch`.

    The sample runs in two lane loops, one that keeps no registers and one that keeps them (the
    last sample, or every sample while a motor of the block records at the current-loop rate):
    LLVM inlines the one compiled sample into each, with ``last`` folded, and vectorises it.
    (:func:`_phase` and :func:`_pwm` keep numba's specialisation on their literal phase index:
    with a plain index LLVM no longer vectorised these loops.)"""
    inner_rec = False
    for j in range(n):
        i = i0 + j
        _gather(scratch, j, i, regs[i], state[i], params[i], inputs[i])
        inner_rec = inner_rec or _records_inner(regs[i])
    for k in range(c.INNER_PER_OUTER):
        if inner_rec or k == c.INNER_PER_OUTER - 1:
            for j in range(n):
                _sample(scratch, j, True)
        else:
            for j in range(n):
                _sample(scratch, j, False)
        if inner_rec:  # the sample buffer at the current-loop rate: registers every sample
            for j in range(n):
                r = regs[i0 + j]
                if _records_inner(r):
                    _store_regs(scratch, j, r)
                    record(r, buf[i0 + j] if rec else buf[0], rec)
    for j in range(n):
        _scatter(scratch, j, regs[i0 + j], state[i0 + j])
