"""The MAC800's monitors at 770 Hz: ERR_STAT bits 0–17 (register 35), each with its condition
(register overview §1.2 "Error Handling"; the levels and models the overview leaves open are
decisions, stated here and in ``docs/families/mac800.md``):

====  ============  =========================================================================
bit   name          condition (reaction: S = stop with ACC_EMERG then passive, P = passive)
====  ============  =========================================================================
0     I2T_ERR       I2T ≥ I2TLIM; I2T = 65536·q/î_rated², q the mean square current amplitude
                    through a first-order filter (thermal time constant): 100 % = the rated
                    (nominal) torque's current for ever (S)
1     FLW_ERR       FLWERRMAX > 0 and |FLWERR| > FLWERRMAX (S)
2     FNC_ERR       FNCERRMAX > 0 and |FNCERR| > FNCERRMAX (S)
3     UIT_ERR       UIT > UITLIM; UIT = 65536·filtered regenerated power / regen_power (S)
4     IN_POS        position modes: |P_SOLL − P_IST| < INPOSWIN with the profile at P_SOLL;
                    velocity modes: |V_SOLL/16 − V_IST| < INPOSWIN; for INPOSCNT samples
5, 6  ACC/DEC_FLAG  the profile's speed magnitude rises / falls (function blocks)
7     PLIM_ERR      MIN_P_IST or MAX_P_IST ≠ 0, DIS_P_LIM clear, and P_IST outside them (S)
8     DEGC_ERR      DEGC > DEGCMAX; DEGC from a first-order winding temperature model:
                    copper loss · thermal resistance above 25 °C ambient (S)
9     UV_ERR        bus below 195 V in a regulated mode with UV_HANDLE bit 0 (SET_UV_ERR)
10    UV_DETECT     bus below 195 V (status; clears when the bus is back)
11    OV_ERR        bus above 450 V (P)
12    IPEAK_ERR     a phase current reading at the ADC limit ±1023 (15 A on the MAC800) (P)
13    SPEED_ERR     |V_IST| above 3600 RPM (S)
14    DIS_P_LIM     set by the user: software position limits off (no condition)
15    INDEX_ERR     the count between two index pulses is not a whole turn (±8000) (P)
16    OLD_FILT_ERR  a regulated mode with a main-filter setting that is not valid (P)
17    U24V_ERR      24 V control supply below 18 V (P)
====  ============  =========================================================================

UV_HANDLE (register 23) on an under-voltage in a regulated mode: bit 0 sets UV_ERR, bit 1
goes passive, bit 2 sets V_SOLL = 0. Error bits stay set until written to 0 in ERR_STAT.
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
from .modes import go_passive, regulated, trip

_PER_N = 1.0 / c.INNER_PER_OUTER  #: the mean of a servo sample's current-loop samples
_DEGC_PER_CELSIUS = 1.0 / c.DEGC_CELSIUS
_OV_UNITS = c.OVERVOLTAGE / c.U_BUS_VOLTS
_UV_UNITS = c.UV_BUS_VOLTS / c.U_BUS_VOLTS
_U24_UNITS = c.U24V_MIN_VOLTS / c.U_24V_VOLTS
#: UV_HANDLE's bits (register 23)
_UV_HANDLE = UvHandle(handle=R.UV_HANDLE, err_stat=R.ERR_STAT, uv_err=c.UV_ERR, v_soll=R.V_SOLL,
                      set_uv_err=c.SET_UV_ERR, stop_profile=c.UV_VSOLL0,
                      go_passive=c.UV_GO_PASSIVE)


def filter_gain(tau: float) -> float:
    """Gain per servo sample ``1 − exp(−T/τ)`` of a first-order filter with time constant
    ``tau`` [s] (kept in the motor's parameters)."""
    return 1.0 - math.exp(-c.OUTER_DT / tau)


@njit(**KERNEL)
def loads(r: np.ndarray, s: np.ndarray, p: np.ndarray) -> None:
    """I2T, UIT and DEGC from the sums of the last servo sample's current-loop samples."""
    s[L.S_I2T_Q] += p[L.P_K_I2T] * (s[L.S_I2_SUM] * _PER_N - s[L.S_I2T_Q])
    s[L.S_UIT_Q] += p[L.P_K_UIT] * (s[L.S_PREG_SUM] * _PER_N - s[L.S_UIT_Q])
    target = c.AMBIENT_CELSIUS + p[L.P_R_TH] * s[L.S_PCU_SUM] * _PER_N
    s[L.S_TEMP] += p[L.P_K_TEMP] * (target - s[L.S_TEMP])
    s[L.S_I2_SUM] = 0.0
    s[L.S_PREG_SUM] = 0.0
    s[L.S_PCU_SUM] = 0.0
    r[R.I2T] = int(clamp(rnd(s[L.S_I2T_Q] * p[L.P_I2T_SCALE]), 0.0, 2147483647.0))
    r[R.UIT] = int(clamp(rnd(s[L.S_UIT_Q] * p[L.P_UIT_SCALE]), 0.0, 2147483647.0))
    r[R.DEGC] = int(rnd(s[L.S_TEMP] * _DEGC_PER_CELSIUS))


@njit(**KERNEL)
def check_errors(r: np.ndarray, s: np.ndarray) -> None:
    """Compare the monitored quantities with their limits and react (module docstring)."""
    mode = int(r[R.MODE_REG])
    if r[R.U_24V] < _U24_UNITS:
        trip(r, s, c.U24V_ERR)
    if r[R.U_BUS] > _OV_UNITS:
        trip(r, s, c.OV_ERR)
    if s[L.S_IPEAK] > 0.0:
        trip(r, s, c.IPEAK_ERR)
    s[L.S_IPEAK] = 0.0
    if regulated(mode) and s[L.S_FILT_BAD] > 0.5:
        trip(r, s, c.OLD_FILT_ERR)
    if r[R.U_BUS] < _UV_UNITS:
        r[R.ERR_STAT] |= c.UV_DETECT
        if (regulated(mode) or mode == c.ANALOG_TORQUE_MODE) and uv_handle_reaction(
                r, _UV_HANDLE):
            go_passive(r, s)
    else:
        r[R.ERR_STAT] &= ~c.UV_DETECT
    if r[R.I2T] >= r[R.I2TLIM]:
        trip(r, s, c.I2T_ERR)
    if r[R.UIT] > r[R.UITLIM]:
        trip(r, s, c.UIT_ERR)
    if r[R.FLWERRMAX] > 0 and abs(r[R.FLWERR]) > r[R.FLWERRMAX]:
        trip(r, s, c.FLW_ERR)
    if r[R.FNCERRMAX] > 0 and abs(r[R.FNCERR]) > r[R.FNCERRMAX]:
        trip(r, s, c.FNC_ERR)
    if ((r[R.MIN_P_IST] != 0 or r[R.MAX_P_IST] != 0) and (r[R.ERR_STAT] & c.DIS_P_LIM) == 0
            and (r[R.P_IST] < r[R.MIN_P_IST] or r[R.P_IST] > r[R.MAX_P_IST])):
        trip(r, s, c.PLIM_ERR)
    if r[R.DEGC] > r[R.DEGCMAX]:
        trip(r, s, c.DEGC_ERR)
    if abs(float(r[R.V_IST])) > c.OVERSPEED_COUNTS:
        trip(r, s, c.SPEED_ERR)


@njit(**KERNEL)
def in_position(r: np.ndarray, s: np.ndarray, mode: int, position: bool) -> None:
    """ERR_STAT bit 4 IN_POS (registers 33, 34): inside INPOSWIN for INPOSCNT samples."""
    win = float(r[R.INPOSWIN])
    if not regulated(mode) or s[L.S_EMERG] > 0.5:
        inside = False
    elif position:
        inside = (abs(float(r[R.P_SOLL] - r[R.P_IST])) < win
                  and s[L.S_PF16] == 16.0 * float(r[R.P_SOLL]))
    else:
        inside = abs(r[R.V_SOLL] / 16.0 - float(r[R.V_IST])) < win
    s[L.S_INPOS_CNT] = s[L.S_INPOS_CNT] + 1.0 if inside else 0.0
    if inside and s[L.S_INPOS_CNT] >= float(r[R.INPOSCNT]):
        r[R.ERR_STAT] |= c.IN_POS
    else:
        r[R.ERR_STAT] &= ~c.IN_POS
