"""Power-on of motor rows, compiled.

:meth:`jvl_gym.MotorArray.software_reset` loads each motor's register image and powers on
(:func:`power_on_from_memory`); :meth:`jvl_gym.MotorArray.reset` first sets the motors' parameters,
world inputs and state (:func:`reset_rows`). Per motor these are a few dozen scalar operations,
which in numpy over a handful of rows cost more in per-call overhead than the work (an env
resets one or two copies at a time).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ...engine.jit import KERNEL
from . import constants as c
from . import layout as L
from .firmware import regs as R
from .firmware.mode_table import N_MODES
from .firmware.modes import OK, apply_request, check_request
from .plant.encoder import eldeg, encoder_count
from .plant.hall import SECTOR, sector_index

__all__ = ["power_on_rows", "power_on_from_memory", "reset_rows", "start_loaded_rows"]

#: registers cleared at power-on (counters, measurements, loop outputs)
CLEARED = (R.P_IST, R.V_IST, R.P_FNC, R.FLWERR, R.FNCERR, R.I2T, R.UIT, R.REC_CNT, R.FNC_OUT,
           R.FF_OUT, R.VB_OUT, R.VF_OUT, R.V_EXT, R.I_NOM, R.PHI_SOLL, R.IA_SOLL, R.IB_SOLL,
           R.IC_SOLL, R.IA_IST, R.IB_IST, R.IC_IST, R.UA_VAL, R.UB_VAL, R.UC_VAL, R.V_ELDEG)
_ERR_KEPT = c.RELPOSPSOLL | c.RELPOSPFNC | c.DIS_P_LIM  #: ERR_STAT bits that survive a reset
_CNTRL_CLEARED = c.RECORDBIT | c.REWINDBIT | c.MAN_RESYNC


@njit(**KERNEL)
def power_on_rows(regs: np.ndarray, state: np.ndarray, params: np.ndarray, latched: np.ndarray,
                  idx: np.ndarray) -> None:  # pragma: no cover - compiled
    """Power on motors ``idx`` whose registers hold their flash/ROM image (manual 3.2.37).

    Clears the counters and measurements, keeps the ERR_STAT positioning bits, enters INIT_MODE,
    sets the encoder reference (P_IST = 0 at the rotor angle ``state[:, S_THETA]``) and the
    commutation (aligned, or the hall sector estimate when ``P_HALL_START`` is set), U_SUPPLY
    from the bus voltage, latches CNTRL_BITS into ``latched`` and finally requests the start
    mode: HOME_MODE's low byte if it is a power-on search (12, 13, 14), else STARTMODE.
    """
    for i in idx:
        r = regs[i]
        s = state[i]
        p = params[i]
        for num in CLEARED:
            r[num] = 0
        r[R.ERR_STAT] &= _ERR_KEPT
        r[R.CNTRL_BITS] &= ~_CNTRL_CLEARED
        r[R.MODE_REG] = c.INIT_MODE
        theta = s[L.S_THETA]
        enc = encoder_count(theta)
        s[L.S_ENC0] = enc
        s[L.S_ENC_PREV] = enc
        theta_e = p[L.P_POLE_PAIRS] * theta + p[L.P_THETA_E0]
        sec = sector_index(theta_e, p[L.P_HALL_ANGLE])
        s[L.S_HALL_SECTOR] = sec
        if p[L.P_HALL_START] > 0.5:  # only the hall sector is known: start at its centre
            centre = p[L.P_HALL_ANGLE] + (sec + 0.5) * SECTOR
            el = int(math.floor(centre * c.ELDEG_PER_TURN / (2 * math.pi))) % 2048
            s[L.S_ELDEG_OFS] = el - enc
            s[L.S_HALL_SYNCED] = 0.0
        else:
            el = int(eldeg(theta_e))
            s[L.S_HALL_SYNCED] = 1.0
        s[L.S_ELDEG_PREV] = enc
        r[R.ELDEG_IST] = el
        s[L.S_PENDING_MODE] = -1.0
        r[R.U_SUPPLY] = np.rint(s[L.S_UBUS] / c.U_SUPPLY_VOLTS_PER_UNIT)
        latched[i] = r[R.CNTRL_BITS]
    for i in idx:
        home = regs[i, R.HOME_MODE] & 0xFF
        start = (home if c.HOME1_MODE <= home <= c.HOME3_MODE
                 else regs[i, R.STARTMODE])
        if 0 < start < N_MODES and check_request(regs[i], state[i], start) == OK:
            apply_request(regs[i], state[i], start)


@njit(**KERNEL)
def _copy_row(dst: np.ndarray, src: np.ndarray) -> None:  # pragma: no cover - compiled
    """``dst[:] = src`` for two 1-D arrays of one length (a slice copy would need numba's NRT)."""
    for k in range(dst.shape[0]):
        dst[k] = src[k]


@njit(**KERNEL)
def reset_rows(regs: np.ndarray, state: np.ndarray, params: np.ndarray, inputs: np.ndarray,
               latched: np.ndarray, idx: np.ndarray, types: np.ndarray, rom: np.ndarray,
               type_params: np.ndarray, type_inputs: np.ndarray, flash: np.ndarray,
               has_flash: np.ndarray, cols: np.ndarray, to_state: np.ndarray,
               values: np.ndarray) -> None:  # pragma: no cover - compiled
    """Power-on reset of motors ``idx`` (:meth:`jvl_gym.MotorArray.reset`).

    Per motor: the parameters and world inputs at rest of its type, then the given parameters;
    the state cleared but for the record length (default TEST_RECORD_SAMPLES, manual 4.4.9),
    then the given state (rotor angle and speed, the load's the same: an elastic coupling starts
    untwisted), the bus at the supply voltage; registers from
    flash if written, else the type's ROM image; then :func:`power_on_rows`. The values are
    checked (:func:`first_bad_value`).

    Parameters
    ----------
    regs, state, params, inputs : numpy.ndarray
        The motors' arrays (``jvl_gym.families.mac050_141.layout``), (N, ·).
    latched : numpy.ndarray
        CNTRL_BITS latched at power-on, (N,) int64.
    idx, types : numpy.ndarray
        Motors to reset and their type codes, (M,) int64.
    rom, type_params, type_inputs : numpy.ndarray
        Per type: ROM register image (T, N_REGS) int64, parameters (T, N_PARAM) and inputs at
        rest (T, N_INPUT) float64.
    flash, has_flash : numpy.ndarray
        Flash images (N, N_REGS) int64 (any array when no motor has one) and (N,) bool.
    cols, to_state, values : numpy.ndarray
        Columns (P,) int64 of the given values in ``params``, or in ``state`` where
        ``to_state`` (P,) bool; the values (P, M) float64 (SI units), set in order.
    """
    for j in range(idx.shape[0]):
        i = idx[j]
        t = types[j]
        _copy_row(params[i], type_params[t])
        _copy_row(inputs[i], type_inputs[t])
        for q in range(cols.shape[0]):
            if not to_state[q]:
                params[i, cols[q]] = values[q, j]
        rec_len = state[i, L.S_REC_LEN]
        state[i].fill(0.0)
        state[i, L.S_REC_LEN] = rec_len if rec_len > 0 else c.TEST_RECORD_SAMPLES
        for q in range(cols.shape[0]):
            if to_state[q]:
                state[i, cols[q]] = values[q, j]
        state[i, L.S_LOAD_THETA] = state[i, L.S_THETA]  # the coupling starts untwisted
        state[i, L.S_LOAD_OMEGA] = state[i, L.S_OMEGA]
        state[i, L.S_UBUS] = inputs[i, L.I_SUPPLY_VOLTS]
    power_on_from_memory(regs, state, params, latched, idx, types, rom, flash, has_flash)


@njit(**KERNEL)
def power_on_from_memory(regs: np.ndarray, state: np.ndarray, params: np.ndarray,
                         latched: np.ndarray, idx: np.ndarray, types: np.ndarray,
                         rom: np.ndarray, flash: np.ndarray,
                         has_flash: np.ndarray) -> None:  # pragma: no cover - compiled
    """Registers of motors ``idx`` from flash if written, else their type's ROM image
    (3.2.37), then :func:`power_on_rows` (arguments as for :func:`reset_rows`)."""
    for j in range(idx.shape[0]):
        i = idx[j]
        _copy_row(regs[i], flash[i] if has_flash[i] else rom[types[j]])
    power_on_rows(regs, state, params, latched, idx)


@njit(**KERNEL)
def start_loaded_rows(regs: np.ndarray, state: np.ndarray, inputs: np.ndarray, idx: np.ndarray,
                      torque: np.ndarray, peak: np.ndarray) -> None:  # pragma: no cover
    """Motors ``idx`` (M,) under a standing load ``torque`` (M,) [N·m]: the load torque input
    and the speed regulator's integrator holding it (VF_OUT = torque / peak · 1023 through
    KVOUT, manual 3.2.7 and 4.2; ``peak`` (M,) the types' peak torques [N·m])."""
    for j in range(idx.shape[0]):
        i = idx[j]
        inputs[i, L.I_LOAD_TORQUE] = torque[j]
        state[i, L.S_Y1] = torque[j] / peak[j] * c.VF_FULL / (regs[i, R.KVOUT] / 256.0)
