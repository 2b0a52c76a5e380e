"""The lane scratch of a block of :data:`LANES` motors: what the inner samples read and write.

A motor's inner samples (:mod:`mac050_141.inner`) run on a lane ``j`` of its block's scratch row:
field ``f`` of lane ``j`` is ``scratch[f * LANES + j]``, state column ``col`` (one of
``layout.LANE_STATE``) is ``scratch[LANE_BASE[col] + j]``; they are written out as such
expressions, not as calls of accessor functions, each of which numba's inliner would copy
into the caller's scope at a cost in compile time. :func:`gather` copies the state the
samples carry (``layout.LANE_STATE``), the registers, parameters and inputs they read and the
parameter-only plant factors into the lane; :func:`scatter_state` and :func:`store_registers`
copy the results back. With the fields side by side, the loop over the lanes of a block runs
in SIMD registers (docs/model.md §17).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ...engine.jit import LANE_KERNEL, plain_arguments
from ...physics.fixed import fx4, fx8
from ...physics.mechanics import shaft_inertia
from . import constants as c
from . import layout as L
from .firmware import regs as R
from .kernel import sample_constants
from .plant.hall import hall_code

#: motors per block
LANES = 16

#: lane field of each state column the lanes carry (``layout.LANE_STATE``, fields
#: 0 … N_LANE_STATE − 1 in that order), −1 for the others
N_LANE_STATE = len(L.LANE_STATE)
_LANE_OF = np.full(L.N_STATE, -1, dtype=np.int64)
_LANE_OF[list(L.LANE_STATE)] = np.arange(N_LANE_STATE)
#: index of lane 0's value of each state column the lanes carry: lane ``j``'s value of column
#: ``col`` is ``scratch[LANE_BASE[col] + j]`` (negative for the columns the lanes do not carry)
LANE_BASE = _LANE_OF * LANES
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


@plain_arguments
@njit(**LANE_KERNEL, forceinline=True)
def gather(sc: np.ndarray, j: int, i: int, r: np.ndarray, s: np.ndarray, p: np.ndarray,
           u: np.ndarray) -> None:
    """Copy what the inner samples of motor ``i`` read into lane ``j``.

    Compiled once (the lanes' loop and the one-motor path both call it, the latter with lane
    0), and inlined by LLVM into each caller (``forceinline``)."""
    for q in range(N_LANE_STATE):
        sc[q * LANES + j] = s[_LANE_COLS[q]]
    sc[F_IX_ERR * LANES + j] = 0.0
    sc[F_VF_OUT * LANES + j] = float(r[R.VF_OUT])
    sc[F_PHASE_COMP * LANES + j] = float(r[R.PHASE_COMP])
    sc[F_AMPLITUDE * LANES + j] = float(r[R.AMPLITUDE])
    sc[F_KIA * LANES + j] = float(r[R.KIA])
    sc[F_KIB * LANES + j] = float(r[R.KIB])
    sc[F_KIC * LANES + j] = float(r[R.KIC])
    sc[F_KIB1 * LANES + j] = fx8(r[R.KIB1])
    sc[F_KIB0 * LANES + j] = fx8(r[R.KIB0])
    sc[F_KIFX2 * LANES + j] = fx4(r[R.KIFX2])
    sc[F_KIFX1 * LANES + j] = fx4(r[R.KIFX1])
    sc[F_KIFY1 * LANES + j] = fx4(r[R.KIFY1])
    sc[F_KIFY0 * LANES + j] = fx4(r[R.KIFY0])
    sc[F_POLE_PAIRS * LANES + j] = p[L.P_POLE_PAIRS]
    sc[F_THETA_E0 * LANES + j] = p[L.P_THETA_E0]
    sc[F_HALL_ANGLE * LANES + j] = p[L.P_HALL_ANGLE]
    sc[F_PWM_DELAY * LANES + j] = p[L.P_PWM_DELAY]
    sc[F_R * LANES + j] = p[L.P_R]
    sc[F_LAMBDA * LANES + j] = p[L.P_LAMBDA]
    sc[F_J * LANES + j] = shaft_inertia(p[L.P_J_MOTOR], p[L.P_J_LOAD], p[L.P_K_COUPLING])
    sc[F_COULOMB * LANES + j] = p[L.P_COULOMB]
    sc[F_STOP_LO * LANES + j] = p[L.P_STOP_LO]
    sc[F_STOP_HI * LANES + j] = p[L.P_STOP_HI]
    sc[F_STOP_K * LANES + j] = p[L.P_STOP_K]
    sc[F_STOP_D * LANES + j] = p[L.P_STOP_D]
    sc[F_U_DUMP * LANES + j] = p[L.P_U_DUMP]
    sc[F_LOAD * LANES + j] = u[L.I_LOAD_TORQUE]
    sc[F_SUPPLY * LANES + j] = u[L.I_SUPPLY_VOLTS]
    sc[F_MOTOR * LANES + j] = float(i)
    _lane_constants(sc, j, p)


@njit(cache=True, inline="always")
def _lane_constants(sc: np.ndarray, j: int, p: np.ndarray) -> None:
    """Lane ``j``'s :func:`mac050_141.kernel.sample_constants` of the parameter row ``p``.

    They are a pure function of twelve parameters, which the lane keeps beside them: when the
    parameters are those of the last gather (the same motor, as a rule) the stored constants
    are reused, which saves an exponential and nine divisions per motor and outer sample.
    """
    if (sc[F_SRC_AMPS * LANES + j] == p[L.P_AMPS_PER_COUNT] and sc[F_SRC_R * LANES + j] == p[L.P_R]
            and sc[F_SRC_L * LANES + j] == p[L.P_L]
            and sc[F_SRC_LAMBDA * LANES + j] == p[L.P_LAMBDA]
            and sc[F_SRC_J_MOTOR * LANES + j] == p[L.P_J_MOTOR]
            and sc[F_SRC_J_LOAD * LANES + j] == p[L.P_J_LOAD]
            and sc[F_SRC_VISCOUS * LANES + j] == p[L.P_VISCOUS]
            and sc[F_SRC_C_BUS * LANES + j] == p[L.P_C_BUS]
            and sc[F_SRC_R_SUPPLY * LANES + j] == p[L.P_R_SUPPLY]
            and sc[F_SRC_R_DUMP * LANES + j] == p[L.P_R_DUMP]
            and sc[F_SRC_K_COUPLING * LANES + j] == p[L.P_K_COUPLING]
            and sc[F_SRC_D_COUPLING * LANES + j] == p[L.P_D_COUPLING]):
        return
    counts_per_amp, k_coil, k_mech, k_bus = sample_constants(p)
    sc[F_COUNTS_PER_AMP * LANES + j] = counts_per_amp
    for k in range(4):
        sc[(F_KC0 + k) * LANES + j] = k_coil[k]
    for k in range(6):
        sc[(F_KM0 + k) * LANES + j] = k_mech[k]
    for k in range(7):
        sc[(F_KB0 + k) * LANES + j] = k_bus[k]
    sc[F_SRC_AMPS * LANES + j] = p[L.P_AMPS_PER_COUNT]
    sc[F_SRC_R * LANES + j] = p[L.P_R]
    sc[F_SRC_L * LANES + j] = p[L.P_L]
    sc[F_SRC_LAMBDA * LANES + j] = p[L.P_LAMBDA]
    sc[F_SRC_J_MOTOR * LANES + j] = p[L.P_J_MOTOR]
    sc[F_SRC_J_LOAD * LANES + j] = p[L.P_J_LOAD]
    sc[F_SRC_VISCOUS * LANES + j] = p[L.P_VISCOUS]
    sc[F_SRC_C_BUS * LANES + j] = p[L.P_C_BUS]
    sc[F_SRC_R_SUPPLY * LANES + j] = p[L.P_R_SUPPLY]
    sc[F_SRC_R_DUMP * LANES + j] = p[L.P_R_DUMP]
    sc[F_SRC_K_COUPLING * LANES + j] = p[L.P_K_COUPLING]
    sc[F_SRC_D_COUPLING * LANES + j] = p[L.P_D_COUPLING]


@plain_arguments
@njit(**LANE_KERNEL, forceinline=True)
def scatter_state(sc: np.ndarray, j: int, s: np.ndarray) -> None:
    """Store lane ``j``'s state back into its motor's state row, 15 inner samples on."""
    for q in range(N_LANE_STATE):
        s[_LANE_COLS[q]] = sc[q * LANES + j]
    s[L.S_TICK] += c.INNER_PER_OUTER


@njit(cache=True, inline="always")
def store_registers(sc: np.ndarray, j: int, r: np.ndarray) -> None:
    """Store lane ``j``'s registers of the last sample (``F_ELDEG_IST`` .. ``F_UC_VAL``, the
    hall status of CNTRL_BITS and IX_ERR of ERR_STAT) into its motor's register row."""
    r[R.ELDEG_IST] = int(sc[F_ELDEG_IST * LANES + j])
    r[R.V_ELDEG] = int(sc[F_V_ELDEG * LANES + j])
    r[R.IA_IST] = int(sc[F_IA_IST * LANES + j])
    r[R.IB_IST] = int(sc[F_IB_IST * LANES + j])
    r[R.IC_IST] = int(sc[F_IC_IST * LANES + j])
    r[R.I_NOM] = int(sc[F_I_NOM * LANES + j])
    r[R.PHI_SOLL] = int(sc[F_PHI_SOLL * LANES + j])
    r[R.IA_SOLL] = int(sc[F_IA_SOLL * LANES + j])
    r[R.IB_SOLL] = int(sc[F_IB_SOLL * LANES + j])
    r[R.IC_SOLL] = int(sc[F_IC_SOLL * LANES + j])
    r[R.UA_VAL] = int(sc[F_UA_VAL * LANES + j])
    r[R.UB_VAL] = int(sc[F_UB_VAL * LANES + j])
    r[R.UC_VAL] = int(sc[F_UC_VAL * LANES + j])
    hall = hall_code(sc[LANE_BASE[L.S_HALL_SECTOR] + j]) << c.HALL_STATUS_SHIFT
    r[R.CNTRL_BITS] = (r[R.CNTRL_BITS] & 0x1FFF) | hall
    if sc[F_IX_ERR * LANES + j] > 0.0:
        r[R.ERR_STAT] |= c.IX_ERR
