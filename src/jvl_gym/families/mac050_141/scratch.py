"""The lane scratch of a block of :data:`LANES` motors: what the inner samples read and write.

A motor's inner samples (:mod:`mac050_141.inner`) run on a lane ``j`` of its block's scratch row:
field ``f`` of lane ``j`` is ``scratch[f * LANES + j]``. :func:`gather` copies the state the
samples carry (``layout.LANE_STATE``), the registers, parameters and inputs they read and the
parameter-only plant factors into the lane; :func:`scatter_state` and :func:`store_registers`
copy the results back. With the fields side by side, the loop over the lanes of a block runs
in SIMD registers (docs/model.md §17).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from . import constants as c
from . import layout as L
from .firmware import regs as R
from .firmware.fixed import fx4, fx8
from .kernel import sample_constants
from .plant.hall import hall_code
from .plant.mechanics import shaft_inertia

#: motors per block
LANES = 16

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


def lane_scratch(n_motors: int) -> np.ndarray:
    """Working memory of the blocks: one row of ``N_FIELDS * LANES`` float64 per block,
    shape ``(ceil(n_motors / LANES), N_FIELDS * LANES)``; row ``i // LANES`` is motor ``i``'s."""
    return np.zeros((-(-int(n_motors) // LANES), N_FIELDS * LANES))


@njit(cache=True, inline="always")
def get(sc: np.ndarray, f: int, j: int) -> float:
    """Field ``f`` of lane ``j``."""
    return sc[f * LANES + j]


@njit(cache=True, inline="always")
def put(sc: np.ndarray, f: int, j: int, x: float) -> None:
    """Set field ``f`` of lane ``j``."""
    sc[f * LANES + j] = x


@njit(cache=True, inline="always")
def sget(sc: np.ndarray, col: int, j: int) -> float:
    """Lane ``j``'s value of state column ``col`` (one of ``layout.LANE_STATE``)."""
    return sc[_LANE_OF[col] * LANES + j]


@njit(cache=True, inline="always")
def sput(sc: np.ndarray, col: int, j: int, x: float) -> None:
    """Set lane ``j``'s value of state column ``col`` (one of ``layout.LANE_STATE``)."""
    sc[_LANE_OF[col] * LANES + j] = x


@njit(cache=True, inline="always")
def gather(sc: np.ndarray, j: int, i: int, r: np.ndarray, s: np.ndarray, p: np.ndarray,
           u: np.ndarray) -> None:
    """Copy what the inner samples of motor ``i`` read into lane ``j``."""
    for q in range(N_LANE_STATE):
        put(sc, q, j, s[_LANE_COLS[q]])
    put(sc, F_IX_ERR, j, 0.0)
    put(sc, F_VF_OUT, j, float(r[R.VF_OUT]))
    put(sc, F_PHASE_COMP, j, float(r[R.PHASE_COMP]))
    put(sc, F_AMPLITUDE, j, float(r[R.AMPLITUDE]))
    put(sc, F_KIA, j, float(r[R.KIA]))
    put(sc, F_KIB, j, float(r[R.KIB]))
    put(sc, F_KIC, j, float(r[R.KIC]))
    put(sc, F_KIB1, j, fx8(r[R.KIB1]))
    put(sc, F_KIB0, j, fx8(r[R.KIB0]))
    put(sc, F_KIFX2, j, fx4(r[R.KIFX2]))
    put(sc, F_KIFX1, j, fx4(r[R.KIFX1]))
    put(sc, F_KIFY1, j, fx4(r[R.KIFY1]))
    put(sc, F_KIFY0, j, fx4(r[R.KIFY0]))
    put(sc, F_POLE_PAIRS, j, p[L.P_POLE_PAIRS])
    put(sc, F_THETA_E0, j, p[L.P_THETA_E0])
    put(sc, F_HALL_ANGLE, j, p[L.P_HALL_ANGLE])
    put(sc, F_PWM_DELAY, j, p[L.P_PWM_DELAY])
    put(sc, F_R, j, p[L.P_R])
    put(sc, F_LAMBDA, j, p[L.P_LAMBDA])
    put(sc, F_J, j, shaft_inertia(p[L.P_J_MOTOR], p[L.P_J_LOAD], p[L.P_K_COUPLING]))
    put(sc, F_COULOMB, j, p[L.P_COULOMB])
    put(sc, F_STOP_LO, j, p[L.P_STOP_LO])
    put(sc, F_STOP_HI, j, p[L.P_STOP_HI])
    put(sc, F_STOP_K, j, p[L.P_STOP_K])
    put(sc, F_STOP_D, j, p[L.P_STOP_D])
    put(sc, F_U_DUMP, j, p[L.P_U_DUMP])
    put(sc, F_LOAD, j, u[L.I_LOAD_TORQUE])
    put(sc, F_SUPPLY, j, u[L.I_SUPPLY_VOLTS])
    put(sc, F_MOTOR, j, float(i))
    _lane_constants(sc, j, p)


@njit(cache=True, inline="always")
def _lane_constants(sc: np.ndarray, j: int, p: np.ndarray) -> None:
    """Lane ``j``'s :func:`mac050_141.kernel.sample_constants` of the parameter row ``p``.

    They are a pure function of twelve parameters, which the lane keeps beside them: when the
    parameters are those of the last gather (the same motor, as a rule) the stored constants
    are reused, which saves an exponential and nine divisions per motor and outer sample.
    """
    if (get(sc, F_SRC_AMPS, j) == p[L.P_AMPS_PER_COUNT] and get(sc, F_SRC_R, j) == p[L.P_R]
            and get(sc, F_SRC_L, j) == p[L.P_L] and get(sc, F_SRC_LAMBDA, j) == p[L.P_LAMBDA]
            and get(sc, F_SRC_J_MOTOR, j) == p[L.P_J_MOTOR]
            and get(sc, F_SRC_J_LOAD, j) == p[L.P_J_LOAD]
            and get(sc, F_SRC_VISCOUS, j) == p[L.P_VISCOUS]
            and get(sc, F_SRC_C_BUS, j) == p[L.P_C_BUS]
            and get(sc, F_SRC_R_SUPPLY, j) == p[L.P_R_SUPPLY]
            and get(sc, F_SRC_R_DUMP, j) == p[L.P_R_DUMP]
            and get(sc, F_SRC_K_COUPLING, j) == p[L.P_K_COUPLING]
            and get(sc, F_SRC_D_COUPLING, j) == p[L.P_D_COUPLING]):
        return
    counts_per_amp, k_coil, k_mech, k_bus = sample_constants(p)
    put(sc, F_COUNTS_PER_AMP, j, counts_per_amp)
    for k in range(4):
        put(sc, F_KC0 + k, j, k_coil[k])
    for k in range(6):
        put(sc, F_KM0 + k, j, k_mech[k])
    for k in range(7):
        put(sc, F_KB0 + k, j, k_bus[k])
    put(sc, F_SRC_AMPS, j, p[L.P_AMPS_PER_COUNT])
    put(sc, F_SRC_R, j, p[L.P_R])
    put(sc, F_SRC_L, j, p[L.P_L])
    put(sc, F_SRC_LAMBDA, j, p[L.P_LAMBDA])
    put(sc, F_SRC_J_MOTOR, j, p[L.P_J_MOTOR])
    put(sc, F_SRC_J_LOAD, j, p[L.P_J_LOAD])
    put(sc, F_SRC_VISCOUS, j, p[L.P_VISCOUS])
    put(sc, F_SRC_C_BUS, j, p[L.P_C_BUS])
    put(sc, F_SRC_R_SUPPLY, j, p[L.P_R_SUPPLY])
    put(sc, F_SRC_R_DUMP, j, p[L.P_R_DUMP])
    put(sc, F_SRC_K_COUPLING, j, p[L.P_K_COUPLING])
    put(sc, F_SRC_D_COUPLING, j, p[L.P_D_COUPLING])


@njit(cache=True, inline="always")
def scatter_state(sc: np.ndarray, j: int, s: np.ndarray) -> None:
    """Store lane ``j``'s state back into its motor's state row, 15 inner samples on."""
    for q in range(N_LANE_STATE):
        s[_LANE_COLS[q]] = get(sc, q, j)
    s[L.S_TICK] += c.INNER_PER_OUTER


@njit(cache=True, inline="always")
def store_registers(sc: np.ndarray, j: int, r: np.ndarray) -> None:
    """Store lane ``j``'s registers of the last sample (``F_ELDEG_IST`` .. ``F_UC_VAL``, the
    hall status of CNTRL_BITS and IX_ERR of ERR_STAT) into its motor's register row."""
    r[R.ELDEG_IST] = int(get(sc, F_ELDEG_IST, j))
    r[R.V_ELDEG] = int(get(sc, F_V_ELDEG, j))
    r[R.IA_IST] = int(get(sc, F_IA_IST, j))
    r[R.IB_IST] = int(get(sc, F_IB_IST, j))
    r[R.IC_IST] = int(get(sc, F_IC_IST, j))
    r[R.I_NOM] = int(get(sc, F_I_NOM, j))
    r[R.PHI_SOLL] = int(get(sc, F_PHI_SOLL, j))
    r[R.IA_SOLL] = int(get(sc, F_IA_SOLL, j))
    r[R.IB_SOLL] = int(get(sc, F_IB_SOLL, j))
    r[R.IC_SOLL] = int(get(sc, F_IC_SOLL, j))
    r[R.UA_VAL] = int(get(sc, F_UA_VAL, j))
    r[R.UB_VAL] = int(get(sc, F_UB_VAL, j))
    r[R.UC_VAL] = int(get(sc, F_UC_VAL, j))
    hall = hall_code(sget(sc, L.S_HALL_SECTOR, j)) << c.HALL_STATUS_SHIFT
    r[R.CNTRL_BITS] = (r[R.CNTRL_BITS] & 0x1FFF) | hall
    if get(sc, F_IX_ERR, j) > 0.0:
        r[R.ERR_STAT] |= c.IX_ERR
