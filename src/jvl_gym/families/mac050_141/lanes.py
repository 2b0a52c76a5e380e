"""The inner samples of a block of :data:`LANES` motors in SIMD lanes (docs/model.md §2, §17).

The engine's driver (``jvl_gym.engine.driver``) advances motors in blocks: the firmware's
outer step of every motor of the block, one motor at a time, then the block's 15 inner samples
in one call of :func:`inner_samples`, which steps the motors it can in SIMD lanes and the
others one at a time; both give the same bits, so an N-motor array is still bit-for-bit equal
to N one-motor arrays.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ...jit import LANE_KERNEL
from . import constants as c
from . import layout as L
from .firmware import regs as R
from .firmware.current_loop import phase_step, references
from .firmware.fixed import fx4, fx8
from .firmware.mode_table import N_MODES
from .firmware.modes import COMMUTATED
from .kernel import adc_count, inner_samples_one, plant_sample, sample_constants
from .plant.coil import vector_to_phases
from .plant.encoder import eldeg, encoder_count
from .plant.hall import hall_code, sector_index
from .plant.mechanics import shaft_inertia

#: motors per block
LANES = 16

# --- lane scratch: field f of lane j is scratch[f * LANES + j] -------------------------------
#: lane field of each state column the lanes carry (``layout.LANE_STATE``, fields
#: 0 … N_LANE_STATE − 1 in that order), −1 for the others
N_LANE_STATE = len(L.LANE_STATE)
_LANE_OF = np.full(L.N_STATE, -1, dtype=np.int64)
_LANE_OF[list(L.LANE_STATE)] = np.arange(N_LANE_STATE)
_LANE_COLS = np.array(L.LANE_STATE, dtype=np.int64)
#: the other fields, after the state
(
    F_IX_ERR,
    # register values of the last sample
    F_ELDEG_IST, F_V_ELDEG, F_IA_IST, F_IB_IST, F_IC_IST, F_I_NOM, F_PHI_SOLL, F_IA_SOLL,
    F_IB_SOLL, F_IC_SOLL, F_UA_VAL, F_UB_VAL, F_UC_VAL,
    # registers, parameters and inputs, constant over the 15 samples
    F_VF_OUT, F_PHASE_COMP, F_AMPLITUDE, F_KIA, F_KIB, F_KIC, F_KIB1, F_KIB0, F_KIFX2, F_KIFX1,
    F_KIFY1, F_KIFY0, F_POLE_PAIRS, F_THETA_E0, F_HALL_ANGLE, F_PWM_DELAY, F_R, F_LAMBDA, F_J,
    F_COULOMB, F_STOP_LO, F_STOP_HI, F_STOP_K, F_STOP_D, F_U_DUMP, F_LOAD, F_SUPPLY,
    F_COUNTS_PER_AMP, F_KC0, F_KC1, F_KC2, F_KC3, F_KM0, F_KM1, F_KM2, F_KM3, F_KM4, F_KM5,
    F_KB0, F_KB1, F_KB2, F_KB3, F_KB4, F_KB5, F_KB6, F_MOTOR,
    # the parameters F_COUNTS_PER_AMP .. F_KB6 were computed from (see _lane_constants)
    F_SRC_AMPS, F_SRC_R, F_SRC_L, F_SRC_LAMBDA, F_SRC_J_MOTOR, F_SRC_J_LOAD, F_SRC_VISCOUS,
    F_SRC_C_BUS, F_SRC_R_SUPPLY, F_SRC_R_DUMP, F_SRC_K_COUPLING, F_SRC_D_COUPLING,
    N_FIELDS,
) = range(N_LANE_STATE, N_LANE_STATE + 73)

_H = c.INNER_DT


def lane_scratch(n_motors: int) -> np.ndarray:
    """Working memory of the blocks: one row of ``N_FIELDS * LANES`` float64 per block,
    shape ``(ceil(n_motors / LANES), N_FIELDS * LANES)``; row ``i // LANES`` is motor ``i``'s."""
    return np.zeros((-(-int(n_motors) // LANES), N_FIELDS * LANES))


@njit(cache=True, inline="always")
def _get(sc: np.ndarray, f: int, j: int) -> float:
    return sc[f * LANES + j]


@njit(cache=True, inline="always")
def _put(sc: np.ndarray, f: int, j: int, x: float) -> None:
    sc[f * LANES + j] = x


@njit(cache=True, inline="always")
def _sget(sc: np.ndarray, col: int, j: int) -> float:
    """Lane ``j``'s value of state column ``col`` (one of ``layout.LANE_STATE``)."""
    return sc[_LANE_OF[col] * LANES + j]


@njit(cache=True, inline="always")
def _sput(sc: np.ndarray, col: int, j: int, x: float) -> None:
    sc[_LANE_OF[col] * LANES + j] = x


@njit(cache=True, inline="always")
def in_lanes(r: np.ndarray, p: np.ndarray) -> bool:
    """True when a motor's next inner samples take none of :func:`mac050_141.kernel.inner_sample`'s
    per-motor branches: a mode with commutation and current loops (not INIT, SAFE, TESTU,
    TESTKI, MANI), commutation aligned (no hall synchronisation), no current or torque noise,
    no inner-rate recording. Such a motor can run in a SIMD lane."""
    mode = r[R.MODE_REG]
    cb = r[R.CNTRL_BITS]
    return (0 <= mode < N_MODES and COMMUTATED[mode] and p[L.P_HALL_START] < 0.5
            and not p[L.P_CURRENT_NOISE] > 0.0 and not p[L.P_TORQUE_NOISE] > 0.0
            and not ((cb & c.RECORDBIT) and (cb & c.RECINNERBIT)))


@njit(cache=True, inline="always")
def _gather(sc: np.ndarray, j: int, i: int, r: np.ndarray, s: np.ndarray, p: np.ndarray,
            u: np.ndarray) -> None:
    """Copy what the inner samples of motor ``i`` read into lane ``j``."""
    for q in range(N_LANE_STATE):
        _put(sc, q, j, s[_LANE_COLS[q]])
    _put(sc, F_IX_ERR, j, 0.0)
    _put(sc, F_VF_OUT, j, float(r[R.VF_OUT]))
    _put(sc, F_PHASE_COMP, j, float(r[R.PHASE_COMP]))
    _put(sc, F_AMPLITUDE, j, float(r[R.AMPLITUDE]))
    _put(sc, F_KIA, j, float(r[R.KIA]))
    _put(sc, F_KIB, j, float(r[R.KIB]))
    _put(sc, F_KIC, j, float(r[R.KIC]))
    _put(sc, F_KIB1, j, fx8(r[R.KIB1]))
    _put(sc, F_KIB0, j, fx8(r[R.KIB0]))
    _put(sc, F_KIFX2, j, fx4(r[R.KIFX2]))
    _put(sc, F_KIFX1, j, fx4(r[R.KIFX1]))
    _put(sc, F_KIFY1, j, fx4(r[R.KIFY1]))
    _put(sc, F_KIFY0, j, fx4(r[R.KIFY0]))
    _put(sc, F_POLE_PAIRS, j, p[L.P_POLE_PAIRS])
    _put(sc, F_THETA_E0, j, p[L.P_THETA_E0])
    _put(sc, F_HALL_ANGLE, j, p[L.P_HALL_ANGLE])
    _put(sc, F_PWM_DELAY, j, p[L.P_PWM_DELAY])
    _put(sc, F_R, j, p[L.P_R])
    _put(sc, F_LAMBDA, j, p[L.P_LAMBDA])
    _put(sc, F_J, j, shaft_inertia(p[L.P_J_MOTOR], p[L.P_J_LOAD], p[L.P_K_COUPLING]))
    _put(sc, F_COULOMB, j, p[L.P_COULOMB])
    _put(sc, F_STOP_LO, j, p[L.P_STOP_LO])
    _put(sc, F_STOP_HI, j, p[L.P_STOP_HI])
    _put(sc, F_STOP_K, j, p[L.P_STOP_K])
    _put(sc, F_STOP_D, j, p[L.P_STOP_D])
    _put(sc, F_U_DUMP, j, p[L.P_U_DUMP])
    _put(sc, F_LOAD, j, u[L.I_LOAD_TORQUE])
    _put(sc, F_SUPPLY, j, u[L.I_SUPPLY_VOLTS])
    _put(sc, F_MOTOR, j, float(i))
    _lane_constants(sc, j, p)


@njit(cache=True, inline="always")
def _lane_constants(sc: np.ndarray, j: int, p: np.ndarray) -> None:
    """Lane ``j``'s :func:`mac050_141.kernel.sample_constants` of the parameter row ``p``.

    They are a pure function of twelve parameters, which the lane keeps beside them: when the
    parameters are those of the last gather (the same motor, as a rule) the stored constants
    are reused, which saves an exponential and nine divisions per motor and outer sample.
    """
    if (_get(sc, F_SRC_AMPS, j) == p[L.P_AMPS_PER_COUNT] and _get(sc, F_SRC_R, j) == p[L.P_R]
            and _get(sc, F_SRC_L, j) == p[L.P_L] and _get(sc, F_SRC_LAMBDA, j) == p[L.P_LAMBDA]
            and _get(sc, F_SRC_J_MOTOR, j) == p[L.P_J_MOTOR]
            and _get(sc, F_SRC_J_LOAD, j) == p[L.P_J_LOAD]
            and _get(sc, F_SRC_VISCOUS, j) == p[L.P_VISCOUS]
            and _get(sc, F_SRC_C_BUS, j) == p[L.P_C_BUS]
            and _get(sc, F_SRC_R_SUPPLY, j) == p[L.P_R_SUPPLY]
            and _get(sc, F_SRC_R_DUMP, j) == p[L.P_R_DUMP]
            and _get(sc, F_SRC_K_COUPLING, j) == p[L.P_K_COUPLING]
            and _get(sc, F_SRC_D_COUPLING, j) == p[L.P_D_COUPLING]):
        return
    counts_per_amp, k_coil, k_mech, k_bus = sample_constants(p)
    _put(sc, F_COUNTS_PER_AMP, j, counts_per_amp)
    for k in range(4):
        _put(sc, F_KC0 + k, j, k_coil[k])
    for k in range(6):
        _put(sc, F_KM0 + k, j, k_mech[k])
    for k in range(7):
        _put(sc, F_KB0 + k, j, k_bus[k])
    _put(sc, F_SRC_AMPS, j, p[L.P_AMPS_PER_COUNT])
    _put(sc, F_SRC_R, j, p[L.P_R])
    _put(sc, F_SRC_L, j, p[L.P_L])
    _put(sc, F_SRC_LAMBDA, j, p[L.P_LAMBDA])
    _put(sc, F_SRC_J_MOTOR, j, p[L.P_J_MOTOR])
    _put(sc, F_SRC_J_LOAD, j, p[L.P_J_LOAD])
    _put(sc, F_SRC_VISCOUS, j, p[L.P_VISCOUS])
    _put(sc, F_SRC_C_BUS, j, p[L.P_C_BUS])
    _put(sc, F_SRC_R_SUPPLY, j, p[L.P_R_SUPPLY])
    _put(sc, F_SRC_R_DUMP, j, p[L.P_R_DUMP])
    _put(sc, F_SRC_K_COUPLING, j, p[L.P_K_COUPLING])
    _put(sc, F_SRC_D_COUPLING, j, p[L.P_D_COUPLING])


@njit(cache=True, inline="always")
def _scatter(sc: np.ndarray, j: int, r: np.ndarray, s: np.ndarray) -> None:
    """Store lane ``j``'s state and last-sample registers back into its motor's rows."""
    for q in range(N_LANE_STATE):
        s[_LANE_COLS[q]] = _get(sc, q, j)
    s[L.S_TICK] += c.INNER_PER_OUTER
    r[R.ELDEG_IST] = int(_get(sc, F_ELDEG_IST, j))
    r[R.V_ELDEG] = int(_get(sc, F_V_ELDEG, j))
    r[R.IA_IST] = int(_get(sc, F_IA_IST, j))
    r[R.IB_IST] = int(_get(sc, F_IB_IST, j))
    r[R.IC_IST] = int(_get(sc, F_IC_IST, j))
    r[R.I_NOM] = int(_get(sc, F_I_NOM, j))
    r[R.PHI_SOLL] = int(_get(sc, F_PHI_SOLL, j))
    r[R.IA_SOLL] = int(_get(sc, F_IA_SOLL, j))
    r[R.IB_SOLL] = int(_get(sc, F_IB_SOLL, j))
    r[R.IC_SOLL] = int(_get(sc, F_IC_SOLL, j))
    r[R.UA_VAL] = int(_get(sc, F_UA_VAL, j))
    r[R.UB_VAL] = int(_get(sc, F_UB_VAL, j))
    r[R.UC_VAL] = int(_get(sc, F_UC_VAL, j))
    hall = hall_code(_sget(sc, L.S_HALL_SECTOR, j)) << c.HALL_STATUS_SHIFT
    r[R.CNTRL_BITS] = (r[R.CNTRL_BITS] & 0x1FFF) | hall
    if _get(sc, F_IX_ERR, j) > 0.0:
        r[R.ERR_STAT] |= c.IX_ERR


@njit(cache=True, inline="always")
def _phase_lane(sc: np.ndarray, j: int, k: int, i_soll: float, i_ist: float) -> float:
    """One phase's current loop in lane ``j`` (:func:`mac050_141.firmware.current_loop._phase`)."""
    u1 = _sget(sc, L.S_IU1_A + k, j)
    u, e = phase_step(i_soll, i_ist, _sget(sc, L.S_IE1_A + k, j), u1, _sget(sc, L.S_IU2_A + k, j),
                      _sget(sc, L.S_IIST1_A + k, j), _get(sc, F_KIB1, j), _get(sc, F_KIB0, j),
                      _get(sc, F_KIFX2, j), _get(sc, F_KIFX1, j), _get(sc, F_KIFY1, j),
                      _get(sc, F_KIFY0, j))
    _sput(sc, L.S_IE1_A + k, j, e)
    _sput(sc, L.S_IU2_A + k, j, u1)
    _sput(sc, L.S_IU1_A + k, j, u)
    _sput(sc, L.S_IIST1_A + k, j, i_ist)
    return u


@njit(cache=True, inline="always")
def _pwm_lane(sc: np.ndarray, j: int, k: int, u: float) -> float:
    """PWM value applied in phase ``k`` of lane ``j``: ``u`` itself, or the value computed one
    sample earlier when the motor has a PWM delay (``inner_sample``). ``u`` is kept either
    way: a store that depends on the delay became a masked store, slow on AMD cores."""
    pending = _sget(sc, L.S_UPEND_A + k, j)
    _sput(sc, L.S_UPEND_A + k, j, u)
    return pending if _get(sc, F_PWM_DELAY, j) > 0.5 else u


@njit(cache=True, inline="always")
def _lane_sample(sc: np.ndarray, j: int, last: bool) -> None:
    """One inner sample of lane ``j``: the operations of :func:`mac050_141.kernel.inner_sample`
    for a motor that :func:`in_lanes` admits, in the same order on the same values (so the
    result is bit-for-bit the same), written without a branch the compiler cannot turn into
    a select, so that the loop over lanes runs in SIMD registers.

    The registers an inner sample writes (ELDEG_IST .. UC_VAL, the hall sector) are
    overwritten by the next sample: only the ``last`` of the 15 stores them (a constant at
    each call, so the other samples' loop has no such stores).
    """
    theta = _sget(sc, L.S_THETA, j)
    omega = _sget(sc, L.S_OMEGA, j)
    pp = _get(sc, F_POLE_PAIRS, j)
    theta_e = pp * theta + _get(sc, F_THETA_E0, j)
    if last:
        _sput(sc, L.S_HALL_SECTOR, j, sector_index(theta_e, _get(sc, F_HALL_ANGLE, j)))
    enc_abs = encoder_count(theta)
    el = eldeg(theta_e)
    dv = enc_abs - _sget(sc, L.S_ELDEG_PREV, j)
    _sput(sc, L.S_ELDEG_PREV, j, enc_abs)
    i_re = _sget(sc, L.S_I_RE, j)
    i_im = _sget(sc, L.S_I_IM, j)
    ia, ib, ic = vector_to_phases(complex(i_re, i_im))
    cpa = _get(sc, F_COUNTS_PER_AMP, j)
    xa, over_a = adc_count(ia * cpa * _get(sc, F_KIA, j) / 256.0)
    xb, over_b = adc_count(ib * cpa * _get(sc, F_KIB, j) / 256.0)
    xc, over_c = adc_count(ic * cpa * _get(sc, F_KIC, j) / 256.0)
    # F_IX_ERR counts the samples with a saturated converter (a select between the stored
    # flag and 1 became a masked, conditional store: slow on AMD cores)
    _put(sc, F_IX_ERR, j, _get(sc, F_IX_ERR, j) + (1.0 if (over_a or over_b or over_c) else 0.0))
    i_nom, phi, isa, isb, isc = references(_get(sc, F_VF_OUT, j), el, dv,
                                           _get(sc, F_PHASE_COMP, j), _get(sc, F_AMPLITUDE, j))
    ua = _phase_lane(sc, j, 0, isa, xa)
    ub = _phase_lane(sc, j, 1, isb, xb)
    uc = _phase_lane(sc, j, 2, isc, xc)
    if last:
        _put(sc, F_ELDEG_IST, j, el)
        _put(sc, F_V_ELDEG, j, dv)
        _put(sc, F_IA_IST, j, xa)
        _put(sc, F_IB_IST, j, xb)
        _put(sc, F_IC_IST, j, xc)
        _put(sc, F_I_NOM, j, i_nom)
        _put(sc, F_PHI_SOLL, j, phi)
        _put(sc, F_IA_SOLL, j, isa)
        _put(sc, F_IB_SOLL, j, isb)
        _put(sc, F_IC_SOLL, j, isc)
        _put(sc, F_UA_VAL, j, ua)
        _put(sc, F_UB_VAL, j, ub)
        _put(sc, F_UC_VAL, j, uc)
    load = _get(sc, F_LOAD, j)
    (theta1, omega1, theta_l1, omega_l1, i_re1, i_im1, ubus, dump_on, p_el, p_cu, e_fric,
     e_load, e_dump, e_sup) = plant_sample(
        theta, omega, _sget(sc, L.S_LOAD_THETA, j), _sget(sc, L.S_LOAD_OMEGA, j),
        _sget(sc, L.S_ACC, j), i_re, i_im, _sget(sc, L.S_UBUS, j),
        _sget(sc, L.S_DUMP_ON, j), _pwm_lane(sc, j, 0, ua), _pwm_lane(sc, j, 1, ub),
        _pwm_lane(sc, j, 2, uc), theta_e, pp, _get(sc, F_R, j), _get(sc, F_LAMBDA, j),
        _get(sc, F_J, j), _get(sc, F_COULOMB, j), _get(sc, F_STOP_LO, j),
        _get(sc, F_STOP_HI, j), _get(sc, F_STOP_K, j), _get(sc, F_STOP_D, j), load, 0.0,
        _get(sc, F_SUPPLY, j), _get(sc, F_U_DUMP, j),
        (_get(sc, F_KC0, j), _get(sc, F_KC1, j), _get(sc, F_KC2, j), _get(sc, F_KC3, j)),
        (_get(sc, F_KM0, j), _get(sc, F_KM1, j), _get(sc, F_KM2, j), _get(sc, F_KM3, j),
         _get(sc, F_KM4, j), _get(sc, F_KM5, j)),
        (_get(sc, F_KB0, j), _get(sc, F_KB1, j), _get(sc, F_KB2, j), _get(sc, F_KB3, j),
         _get(sc, F_KB4, j), _get(sc, F_KB5, j), _get(sc, F_KB6, j)))
    _sput(sc, L.S_THETA, j, theta1)
    _sput(sc, L.S_OMEGA, j, omega1)
    _sput(sc, L.S_LOAD_THETA, j, theta_l1)
    _sput(sc, L.S_LOAD_OMEGA, j, omega_l1)
    _sput(sc, L.S_ACC, j, (omega1 - omega) * c.INNER_HZ)
    _sput(sc, L.S_I_RE, j, i_re1)
    _sput(sc, L.S_I_IM, j, i_im1)
    _sput(sc, L.S_E_ELEC, j, _sget(sc, L.S_E_ELEC, j) + p_el * _H)
    _sput(sc, L.S_E_COPPER, j, _sget(sc, L.S_E_COPPER, j) + p_cu * _H)
    _sput(sc, L.S_E_FRICTION, j, _sget(sc, L.S_E_FRICTION, j) + e_fric)
    _sput(sc, L.S_E_LOAD, j, _sget(sc, L.S_E_LOAD, j) + e_load)
    _sput(sc, L.S_UBUS, j, ubus)
    _sput(sc, L.S_DUMP_ON, j, dump_on)
    _sput(sc, L.S_E_DUMP, j, _sget(sc, L.S_E_DUMP, j) + e_dump)
    _sput(sc, L.S_E_SUPPLY, j, _sget(sc, L.S_E_SUPPLY, j) + e_sup)
    _sput(sc, L.S_I2_SUM, j, _sget(sc, L.S_I2_SUM, j) + (xa * xa + xb * xb + xc * xc))
    _sput(sc, L.S_PREG_SUM, j, _sget(sc, L.S_PREG_SUM, j) + max(-p_el, 0.0))


@njit(**LANE_KERNEL)
def inner_samples(regs, state, params, inputs, keys, buf, rec, fmt, i0, n, scratch):
    """The 15 inner samples (step 4, ``mac050_141.kernel``) of motors ``i0 .. i0 + n - 1``
    (``n <= LANES``, one block); ``scratch`` is the block's row of :func:`lane_scratch`.

    The motors that :func:`in_lanes` admits are copied into SIMD lanes, stepped together
    (:func:`_lane_sample`) and copied back; the others run
    :func:`mac050_141.kernel.inner_samples_one` one at a time. Both give the same bits
    (tests/test_lanes.py).
    """
    m = 0
    for i in range(i0, i0 + n):
        r = regs[i]
        s = state[i]
        p = params[i]
        if in_lanes(r, p):
            _gather(scratch, m, i, r, s, p, inputs[i])
            m += 1
            continue
        inner_samples_one(r, s, p, inputs[i], keys[i], buf[i] if rec else buf[0], rec, fmt)
    for _k in range(c.INNER_PER_OUTER - 1):
        for j in range(m):
            _lane_sample(scratch, j, False)
    for j in range(m):
        _lane_sample(scratch, j, True)
    for j in range(m):
        i = int(_get(scratch, F_MOTOR, j))
        _scatter(scratch, j, regs[i], state[i])
