"""Monitoring functions at 520.8 Hz (manual 4.5) and the IN_POS logic (3.2.33, 4.1.1, 4.4.3).

- I2T (3.2.16, 4.5.1): first-order thermal model of the coil, ``q ← q + (1 − e^{−T/τ})(ΣI² − q)``
  with ΣI² = Ia² + Ib² + Ic² averaged over the outer sample [ADC counts²]; I2T = 65535 ↔ the
  three-phase mean square at 1023·0.83 counts amplitude. The default I2TLIM 13107 (0.2 of full
  scale) lets rated current (1/3 of peak → 0.111) run forever and trips at peak after
  −τ·ln(0.8) = 2.2 s with τ = 10 s (decision, docs/model.md §10).
- UIT (3.2.18, 4.5.2): the same filter on the regenerative power ``max(0, −Σ I·U)`` [W];
  UIT = 65535 ↔ 100 W. Trips when UIT > UITLIM *and* the supply is above 52 V.
- FLWERR / FNCERR (4.5.4, 4.5.5), software limits (4.5.3). Any error goes to INIT_MODE through
  STOP_MODE (decelerating with ACC_EMERG when set); bits 0–3 must be cleared before leaving INIT.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ....engine.jit import KERNEL
from ....physics.fixed import clamp, rnd
from ....registers.uv_handle import UvHandle, uv_handle_reaction
from .. import constants as c
from .. import layout as L
from . import regs as R
from .mode_table import N_MODES
from .modes import GEAR_INPOS, POSITION_INPOS, VELOCITY_INPOS, stop_to

_I2T_FULL = 1.5 * (c.ADC_FULL * c.I2T_FULL_SCALE_AMPLITUDE) ** 2


def filter_gain(tau: float) -> float:
    """Gain per outer sample ``1 − exp(−T/τ)`` of the first-order I2T and UIT filters with
    time constant ``tau`` [s] (T = 1.92 ms); kept in the motor's parameters (P_K_THERMAL,
    P_K_REGEN), not computed every outer sample."""
    return 1.0 - math.exp(-c.OUTER_DT / tau)


@njit(**KERNEL)
def thermal(r: np.ndarray, s: np.ndarray, p: np.ndarray) -> None:
    """Update I2T and UIT from the sums collected over the last outer sample."""
    n = float(c.INNER_PER_OUTER)
    s[L.S_I2T_Q] += p[L.P_K_THERMAL] * (s[L.S_I2_SUM] / n - s[L.S_I2T_Q])
    s[L.S_UIT_Q] += p[L.P_K_REGEN] * (s[L.S_PREG_SUM] / n - s[L.S_UIT_Q])
    s[L.S_I2_SUM] = 0.0
    s[L.S_PREG_SUM] = 0.0
    r[R.I2T] = int(clamp(rnd(s[L.S_I2T_Q] / _I2T_FULL * 65535.0), 0.0, 65535.0))
    r[R.UIT] = int(clamp(rnd(s[L.S_UIT_Q] / c.UIT_FULL_SCALE_WATTS * 65535.0), 0.0, 65535.0))


@njit(**KERNEL)
def trip(r: np.ndarray, s: np.ndarray, bit: int) -> None:
    """Set an error bit and take the motor to INIT_MODE the protective way (4.5)."""
    r[R.ERR_STAT] |= bit
    mode = int(r[R.MODE_REG])
    if mode != c.INIT_MODE and mode != c.SAFE_MODE:
        stop_to(r, s, c.INIT_MODE, True)


@njit(**KERNEL)
def check_errors(r: np.ndarray, s: np.ndarray) -> None:
    """Compare the monitored quantities with their limits (4.5.1–4.5.5)."""
    if r[R.I2T] > r[R.I2TLIM]:
        trip(r, s, c.I2T_ERR)
    if r[R.UIT] > r[R.UITLIM] and s[L.S_UBUS] > c.UIT_SUPPLY_THRESHOLD:
        trip(r, s, c.UIT_ERR)
    if r[R.FLWERRMAX] > 0 and abs(r[R.FLWERR]) > r[R.FLWERRMAX]:
        trip(r, s, c.FLW_ERR)
    if r[R.FNCERRMAX] > 0 and abs(r[R.FNCERR]) > r[R.FNCERRMAX]:
        trip(r, s, c.FNC_ERR)
    if (r[R.MIN_P_IST] != 0 or r[R.MAX_P_IST] != 0) and (r[R.ERR_STAT] & c.DIS_P_LIM) == 0:
        if r[R.P_IST] < r[R.MIN_P_IST] or r[R.P_IST] > r[R.MAX_P_IST]:
            trip(r, s, c.PLIM_ERR)


@njit(**KERNEL)
def in_position(r: np.ndarray, s: np.ndarray, mode: int) -> None:
    """IN_POS bit of ERR_STAT for the mode (4.1.1, 4.4.3, 4.4.4, 3.2.33, 3.2.34).

    Position modes: ``|P_SOLL − P_FNC/16 + FLWERR| < INPOSWIN`` for INPOSCNT consecutive samples.
    Gear modes: ``|G_FNC|/16 < INPOSWIN`` (4.4.4 writes |P_FNC|, the absolute function position,
    which cannot be meant: the follow error G_FNC is; docs/model.md §10).
    Velocity mode: with INPOSCNT = 0, ``|V_IST| < INPOSWIN``
    (standstill); with INPOSCNT > 0, ``|V_SOLL − 16·V_IST| < INPOSWIN`` for INPOSCNT samples
    (the 4.1.1 formula; 4.4.2 states it with FLWERR, docs/model.md §10). Other modes: 0.
    """
    win = float(r[R.INPOSWIN])
    cnt = float(r[R.INPOSCNT])
    inside = False
    counted = True
    if mode < N_MODES and POSITION_INPOS[mode]:
        inside = abs(r[R.P_SOLL] - r[R.P_FNC] / 16.0 + r[R.FLWERR]) < win
    elif mode < N_MODES and GEAR_INPOS[mode]:  # "|P_FNC|" read as the gear follow error G_FNC
        inside = abs(s[L.S_G_FNC]) / 16.0 < win
    elif mode < N_MODES and VELOCITY_INPOS[mode]:
        if cnt == 0.0:
            inside = abs(float(r[R.V_IST])) < win
            counted = False
        else:
            inside = abs(r[R.V_SOLL] - 16.0 * r[R.V_IST]) < win
    if inside:
        s[L.S_INPOS_CNT] += 1.0
    else:
        s[L.S_INPOS_CNT] = 0.0
    ok = inside and (not counted or s[L.S_INPOS_CNT] >= cnt)
    if ok:
        r[R.ERR_STAT] |= c.IN_POS
    else:
        r[R.ERR_STAT] &= ~c.IN_POS


_UV_TIMER_SAMPLES = round(1.0 * c.OUTER_HZ)  #: 1 s undervoltage timer (4.5.6)
#: UV_HANDLE's bits (3.2.160)
_UV_HANDLE = UvHandle(handle=R.UV_HANDLE, err_stat=R.ERR_STAT, uv_err=c.UV_ERR, v_soll=R.V_SOLL,
                      set_uv_err=c.SET_UV_ERR, stop_profile=c.UV_SOLL0,
                      go_passive=c.UV_GO_PASSIVE)


@njit(**KERNEL)
def undervoltage(r: np.ndarray, s: np.ndarray) -> None:
    """Undervoltage detection (4.5.6, UV_HANDLE 3.2.160).

    Outside INIT: U_SUPPLY < U_MIN_SUP presets the 1 s timer, sets UV_DETECT, sets UV_ERR if
    SET_UV_ERR, stops the profile (V_SOLL = 0) if UV_SOLL0 and goes passive if UV_GO_PASSIVE
    (the manual's pseudo-code writes "IF UV_VSOLL0 = 0", an evident typo for "is set"). Above
    1.25·U_MIN_SUP with the timer run out, UV_DETECT clears. In INIT the 1.25·U_MIN_SUP threshold
    is used for detection. U_MIN_SUP = 0 disables the function.
    """
    umin = float(r[R.U_MIN_SUP])
    if umin <= 0.0:
        return
    if s[L.S_UV_TIMER] > 0.0:
        s[L.S_UV_TIMER] -= 1.0
    u = float(r[R.U_SUPPLY])
    mode = int(r[R.MODE_REG])
    if mode == c.INIT_MODE or mode == c.SAFE_MODE:
        if u < 1.25 * umin:
            s[L.S_UV_TIMER] = _UV_TIMER_SAMPLES
            r[R.ERR_STAT] |= c.UV_DETECT
        elif s[L.S_UV_TIMER] <= 0.0:
            r[R.ERR_STAT] &= ~c.UV_DETECT
        return
    if u < umin:
        s[L.S_UV_TIMER] = _UV_TIMER_SAMPLES
        r[R.ERR_STAT] |= c.UV_DETECT
        if uv_handle_reaction(r, _UV_HANDLE):
            stop_to(r, s, c.INIT_MODE, True)
    elif u > 1.25 * umin and s[L.S_UV_TIMER] <= 0.0:
        r[R.ERR_STAT] &= ~c.UV_DETECT
