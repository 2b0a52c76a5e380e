"""Power-on of motor rows after their registers were loaded from flash or ROM, compiled.

:meth:`jvl_gym.MotorArray.reset` and :meth:`~jvl_gym.MotorArray.software_reset` load each
motor's register image and then call :func:`power_on_rows`: per motor a few dozen scalar
operations, which in numpy over a handful of rows cost more in per-call overhead than the work
(an env resets one or two copies at a time).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from . import constants as c
from . import layout as L
from .firmware import regs as R
from .firmware.modes import OK, apply_request, check_request
from .jit import KERNEL
from .plant.encoder import eldeg, encoder_count
from .plant.hall import SECTOR, sector_index

__all__ = ["power_on_rows"]

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
        start = home if home == 12 or home == 13 or home == 14 else regs[i, R.STARTMODE]
        if 0 < start < 25 and check_request(regs[i], state[i], start) == OK:
            apply_request(regs[i], state[i], start)
