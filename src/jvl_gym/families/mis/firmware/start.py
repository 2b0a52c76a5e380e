"""The firmware's start of a motor at power-on or reset (MIS manual §5.4.2–5.4.3, §6.5.9,
§7.2.13, §7.2.16, §7.2.19, §8.2.33, §8.2.37, §8.2.68, §8.2.79–80, §8.2.93, §8.2.96; what
``MisMotorArray._start`` does per motor, on the rows of the motors it starts).

- Positions, counters, NOTSAVED (§8.2.96) and the error bits are cleared; EXT_ENCODER too unless
  SETUP_BITS bit 12 keeps it. P_IST = P_SOLL = ENCODER_POS = 0, or the position SETUP_BITS bits
  10/11 take from the encoder or the position back-up (:func:`power_up_position`); P_SOLL =
  P_IST, so a saved P_SOLL makes no move at power-on.
- The mode: HOMEMODE when it names a zero search, else STARTMODE (§8.2.33, §8.2.37; passive
  when STARTMODE is no start mode); a power-on zero search that times out goes on in
  STARTMODE (§6.5.9, §7.2.19).
- The hardware supervision (:mod:`.supervision`): CVI_VOLT, TEMP and TEMP_HIGHRES at the
  ambient temperature; the program starts at once when the control voltage is above
  ACCEPT_VOLTAGE, and otherwise waits until it has been measured there ACCEPT_COUNT times
  (§8.2.79–80); the brake holds; an encoder COM fault (H3/H4) and an external memory fault set
  ERR_BITS bits 10 and 13, which only the start sets (§7.2.13, §7.2.16). MAX_VOLTAGE and
  TEMP_LIMITS hold the factory values (§8.2.93: the registers a motor starts from carry them,
  ``MisMotorArray._memory_rows``).
- Every analogue input's filter takes the registers AFZUP_CONFMIN … AFZUP_FILTER (102–105)
  at power-up (:mod:`..filter_setup`, §8.2.50–55); EXTENCODER2 is zeroed unless SETUP_BITS bit
  13 keeps it (§8.2.68, :mod:`..ssi_port`).

Compiled, per motor: a reset of a few copies of an env costs a call, not a numpy operation per
rule; the call also takes the position back-up and stores the motors' rows.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ....engine.jit import KERNEL
from .. import constants as c
from .. import layout as L
from ..units import COUNTS_PER_REV, CVI_VOLTS_PER_UNIT, TEMP_CELSIUS_PER_UNIT
from . import regs as R
from .monitor import encoder_cpr, firmware_angle
from .ssi import SETUP_KEEP_SSI

__all__ = ["FILTER_SETTINGS", "start_rows", "power_up_position"]

#: the registers the start clears: positions, counters, NOTSAVED (§8.2.96), error bits
_CLEARED = np.array([
    R.P_IST, R.P_SOLL, R.V_IST, R.ENCODER_POS, R.FLWERR, R.ERR_BITS, R.WARN_BITS, R.STATUSBITS,
    R.TURNTAB_COUNT, R.COMMAND, R.S_CONTROL, R.ACTUAL_TORQUE, R.TICKS, R.MOTOR_REV,
    R.NOTSAVED], dtype=np.int64)
#: the ENCODER_TYPE codes of the H2 and H4, whose single-turn position a power-up can take
_SINGLE_TURN = np.array([k in (1, 3, 4) for k in range(len(c.ENCODER_CPR))], dtype=np.bool_)
#: the start modes (§8.2.33) among the MODE_REG values 0 … 15
_START_MODE = np.array([k in c.START_MODES for k in range(16)], dtype=np.bool_)
#: the registers 102–105 (AFZUP_CONFMIN, AFZUP_CONFMAX, AFZUP_MAXSLOPE, AFZUP_FILTER) in the
#: order of an input's filter settings in ``params`` (layout.AF_CONFMIN …; §8.2.50–55)
FILTER_SETTINGS = np.array([R.AFZUP_CONFMIN, R.AFZUP_CONFMAX, R.AFZUP_MAXSLOPE,
                             R.AFZUP_FILTER], dtype=np.int64)
_HALF_TURN = COUNTS_PER_REV // 2
_WRAP = 2**31  #: P_IST wraps at ±2³¹ (a 32-bit register)


@njit(cache=True, inline="always")
def power_up_position(setup: int, code: int, q: float, stored: int,
                      preset: float) -> float:  # pragma: no cover - compiled
    """P_IST after power-up by SETUP_BITS bits 10/11 and the encoder option (§5.4.3's table;
    bit 11 wins when both are set): 0 by default; bit 10 the single-turn position
    (0 … 409599) with an H2 or H4, 0 otherwise (H3: "not available"); bit 11 the H3's full
    multi-turn position, the stored position (the position back-up of §5.4.2) without an
    encoder, and with an H2 or H4 the stored position corrected by the single-turn encoder to
    within half a revolution. ``setup``: SETUP_BITS; ``code``: the ENCODER_TYPE code; ``q``:
    the quantised rotor angle in counts; ``stored``: the position back-up; ``preset``: the
    H3's preset offset (``P_H3_PRESET``). As a float, wrapped into 32 bits."""
    multi = (setup & c.SETUP_MULTI_TURN_AT_POWER_UP) != 0
    single = (setup & c.SETUP_SINGLE_TURN_AT_POWER_UP) != 0 and not multi
    pos = 0.0
    if single or multi:
        turn = int(q) % COUNTS_PER_REV
        single_turn_encoder = _SINGLE_TURN[code]
        if single and single_turn_encoder:
            pos = float(turn)
        if multi and code == 0:
            pos = float(stored)
        if multi and single_turn_encoder:
            pos = float(stored + (turn - stored + _HALF_TURN) % COUNTS_PER_REV - _HALF_TURN)
        if multi and code == c.ENCODER_H3:
            pos = q + preset
    return (pos + _WRAP) % (2 * _WRAP) - _WRAP


@njit(cache=True, inline="always")
def start(regs, s, p, u, stored: int) -> None:  # pragma: no cover - compiled
    """The start of one motor from its registers ``regs`` (flash or ROM), state ``s`` (at a
    reset 0 but for the plant's), parameters ``p`` and world inputs ``u``; ``stored``: its
    position back-up (module docstring)."""
    for num in _CLEARED:
        regs[num] = 0
    setup = regs[R.SETUP_BITS]
    # SETUP_BITS bit 12 KeepExtEncoder: "Do not zero the external encoder count on startup"
    if not setup & c.SETUP_KEEP_EXT_ENCODER:
        regs[R.EXT_ENCODER] = 0
    s[L.S_CUR_SCALE] = 2047.0
    code = int(p[L.P_ENCODER])
    regs[R.ENCODER_TYPE] = code
    cpr = encoder_cpr(p)
    per = COUNTS_PER_REV // cpr if cpr > 0 else 1
    # the rotor angle in the firmware's direction, quantised to the encoder's counts
    q = np.floor(firmware_angle(regs, s) * COUNTS_PER_REV / (2 * math.pi) / per) * per
    pos = power_up_position(setup, code, q, stored, p[L.P_H3_PRESET])
    regs[R.P_IST] = regs[R.P_SOLL] = int(pos)
    s[L.S_SEEN_PSOLL] = pos
    regs[R.ENCODER_POS] = int(pos) if cpr > 0 else 0
    s[L.S_ENC_OFFSET] = pos - q if cpr > 0 else 0.0
    s[L.S_ENC_PREV] = regs[R.ENCODER_POS]
    s[L.S_CMD] = s[L.S_CMD_PREV] = 0.0
    home = regs[R.HOMEMODE]
    mode = regs[R.STARTMODE]
    if not (0 <= mode < _START_MODE.size and _START_MODE[mode]):
        mode = c.PASSIVE
    regs[R.MODE_REG] = home if home == c.ZERO_SEARCH_1 or home == c.ZERO_SEARCH_2 else mode
    # a power-on zero search that times out goes on in STARTMODE (§6.5.9, §7.2.19)
    s[L.S_HOME_PREV] = mode
    # the hardware supervision at the start (.supervision)
    cvi = min(max(np.floor(u[L.I_CONTROL_VOLTS] / CVI_VOLTS_PER_UNIT + 0.5), 0.0), 4095.0)
    regs[R.CVI_VOLT] = int(cvi)
    waits = regs[R.CVI_VOLT] <= regs[R.ACCEPT_VOLTAGE] and regs[R.ACCEPT_COUNT] > 0
    s[L.S_CVI_WAIT] = 1.0 if waits else 0.0
    s[L.S_CVI_N] = 0.0
    celsius = u[L.I_AMBIENT] + s[L.S_TEMP_RISE]
    regs[R.TEMP_HIGHRES] = int(np.floor(celsius * 1000.0 + 0.5))
    regs[R.TEMP] = int(min(max(np.floor(celsius / TEMP_CELSIUS_PER_UNIT + 0.5), 0.0), 127.0))
    s[L.S_BRAKE_HELD] = s[L.S_BRAKE_CMD] = 1.0
    s[L.S_BRAKE_MS] = 0.0
    s[L.S_BRAKE_EXT] = 1.0 if regs[R.BRAKE] & 0xFF else 0.0
    if p[L.P_BRAKE_TORQUE] > 0.0 or s[L.S_BRAKE_EXT] != 0.0:
        regs[R.STATUSBITS] |= c.ST_BRAKE_ACTIVE
    found = int(u[L.I_FAULTS]) & c.FAULTS_AT_START
    if found != 0:
        regs[R.ERR_BITS] |= found | c.ERR_GENERAL
    # every input's filter takes the registers 102-105 at power-up (§8.2.50-55, ..filter_setup)
    for k in range(8):
        for col in range(L.AF_SETTINGS):
            p[L.P_AF0 + L.AF_SETTINGS * k + col] = regs[FILTER_SETTINGS[col]]
    # SETUP_BITS bit 13: "do not zero the SSI data register at start-up" (§8.2.68)
    if not setup & SETUP_KEEP_SSI:
        regs[R.EXTENCODER2] = 0


@njit(**KERNEL)
def start_rows(idx: np.ndarray, regs: np.ndarray, s: np.ndarray, p: np.ndarray,
               all_regs: np.ndarray, all_state: np.ndarray, all_params: np.ndarray,
               inputs: np.ndarray, backup: np.ndarray,
               take_backup: bool) -> None:  # pragma: no cover - compiled
    """:func:`start` of motors ``idx`` (M,) (distinct) whose registers, state and parameters
    before it are the rows of the (M, ·) blocks ``regs``, ``s`` and ``p`` (changed in place),
    with their world inputs (rows ``idx`` of ``inputs``) and position back-up (``backup``
    (N,)); then the blocks are stored in rows ``idx`` of ``all_regs``, ``all_state`` and
    ``all_params``. ``take_backup``: first set ``backup`` to the motors' P_IST in
    ``all_regs`` (the position a reset or power-down leaves, §5.4.2)."""
    for j in range(idx.size):
        i = idx[j]
        if take_backup:
            backup[i] = all_regs[i, R.P_IST]
        start(regs[j], s[j], p[j], inputs[i], backup[i])
    for j in range(idx.size):
        i = idx[j]
        for k in range(regs.shape[1]):
            all_regs[i, k] = regs[j, k]
        for k in range(s.shape[1]):
            all_state[i, k] = s[j, k]
        for k in range(p.shape[1]):
            all_params[i, k] = p[j, k]
