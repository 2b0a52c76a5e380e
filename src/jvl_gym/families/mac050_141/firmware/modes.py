"""Operating modes: what each mode uses, entry actions, and the mode-change rules (manual 4.4).

Tables (index = MODE_REG value 0 … N_MODES − 1), derived from the mode table
(:mod:`mac050_141.firmware.mode_table`, the configuration lists of manual 4.4.1–4.4.25):

- ``REGULATED``: speed regulator active (the motor is assumed to be moving; a change to INIT goes
  through STOP_MODE, 4.4.2).
- ``CORRECTING``: "correction of function block: active" (P, GP, AG, COIL, A2POS, APOS, GF).
- ``FLWERR_MODES``: FLWERR is accumulated (3.2.20; HOME1–3 per 4.4.13–15); zero elsewhere.

Rules (4.4.1, 4.4.5, 4.4.16, 3.2.35), decided where the manual is silent (docs/model.md §9):
INIT → any implemented mode if no blocking error bit (0–3) is set; a regulated mode → INIT goes via
STOP_MODE; regulated → regulated switches directly (flying saw, 3.2.9); AT_MODE → anything sets
torque 0, waits for low speed and goes to INIT; TESTU/TESTA/MANI are entered from INIT only; BREAK
is entered only after TESTA; SAFE_MODE only through the MacTalk "go safe mode" command.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ....engine.jit import KERNEL, plain_arguments
from ....registers.fill import fill
from .. import constants as c
from .. import layout as L
from . import regs as R
from .analog_blocks import a2pos_update
from .coil import coil_entry
from .homing import home_entry
from .mode_table import N_MODES, flag_table

REGULATED = flag_table("regulated")
CORRECTING = flag_table("correcting")
FLWERR_MODES = flag_table("flwerr")
#: IN_POS = |P_SOLL − P_FNC/16 + FLWERR| < INPOSWIN
POSITION_INPOS = flag_table("in_pos", "position")
GEAR_INPOS = flag_table("in_pos", "gear")  #: IN_POS = |G_FNC|/16 < INPOSWIN (4.4.4, 4.4.25)
VELOCITY_INPOS = flag_table("in_pos", "velocity")  #: IN_POS per INPOSCNT rules of 4.1.1
PASSIVE = flag_table("passive")  #: current regulator passive (equal / test voltages)
GEAR_MODES = flag_table("gear")  #: modes that divide by GEARF2
#: current loops on commutated references: not passive, and not MANI_MODE, whose stator field
#: is set by hand (3.2.128)
COMMUTATED = ~PASSIVE & (np.arange(N_MODES) != c.MANI_MODE)


def member(x: np.ndarray, values: tuple[int, ...] | np.ndarray) -> np.ndarray:
    """Elementwise ``x ∈ values`` for a few values (np.isin's fixed overhead dominates on tiny
    arrays; this runs in every reset and mode write)."""
    out = np.zeros(np.shape(x), dtype=np.bool_)
    for v in values:
        out |= x == v
    return out


def in_table(x: np.ndarray, table: np.ndarray) -> np.ndarray:
    """Elementwise membership of mode numbers ``x`` in a mode table (False outside it).

    ``take(mode="clip")``, not ``np.clip``: the same indices at a fraction of the cost on the
    one- or two-element arrays of a reset."""
    x = np.asarray(x)
    return table.take(x, mode="clip") & (x >= 0) & (x < table.size)

# request outcome codes (mode_request); 0 = accepted
OK = 0
E_ERROR_BITS = 2
E_BREAK = 3
E_SAFE = 4
E_IN_SAFE = 5
E_NEEDS_INIT = 6
E_INVALID = 7
E_SPECIAL_OUTSIDE_SAFE = 8

REQUEST_MESSAGES = {
    E_ERROR_BITS: "cannot leave INIT_MODE while an error bit (ERR_STAT bits 0–3: I2T_ERR, FLW_ERR, "
    "FNC_ERR, UIT_ERR) is set; clear it by writing ERR_STAT first (manual 4.4.1)",
    E_BREAK: "BREAK_MODE (10) is entered automatically after TESTA_MODE (manual 4.4.11)",
    E_SAFE: "SAFE_MODE (15) cannot be entered by writing MODE_REG; use enter_safe_mode() "
    "(MacTalk 'go safe mode', manual 4.4.16)",
    E_IN_SAFE: "in SAFE_MODE only 256, 257, 258 may be written to MODE_REG; leave SAFE_MODE with "
    "exit_safe_mode() (manual 4.4.16)",
    E_NEEDS_INIT: "can only be entered from INIT_MODE (write 0 first and wait for INIT)",
    E_INVALID: "is not a mode: MODE_REG takes 0..24 or 256..258 (manual 3.2.2)",
    E_SPECIAL_OUTSIDE_SAFE: "256..258 are only accepted in SAFE_MODE (manual 4.4.16)",
}


@njit(**KERNEL)
def fncerr_is_position(mode: int) -> bool:
    """FNCERR is the gear position error in ``mode`` (GP, GF, AG; manual 3.2.24 "GP, GF_MODE"),
    not the sum of the profile corrections as in the other regulated modes."""
    return mode == c.GP_MODE or mode == c.GF_MODE or mode == c.AG_MODE


#: state a regulated mode's entry clears: the FF (F), speed error (E) and VF output (Y)
#: histories, the follow error's fraction and the IN_POS counter
_SPEED_LOOP_CLEARED = (L.S_F1, L.S_F2, L.S_F3, L.S_E1, L.S_E2, L.S_E3, L.S_Y1, L.S_Y2, L.S_Y3,
                       L.S_Y4, L.S_FLW16, L.S_INPOS_CNT)
_SPEED_HISTORY = (L.S_V1, L.S_V2, L.S_V3)  #: the VB filter's V_IST history
_ERRORS = (R.FNCERR, R.FLWERR)  #: the function and follow errors
#: registers INIT and SAFE clear: the errors and the speed loop's and function block's outputs
_PASSIVE_REGISTERS = _ERRORS + (R.VF_OUT, R.FNC_OUT)
#: state INIT and SAFE clear: the profile speed, the follow error's fraction, an emergency stop
#: and an AT_MODE exit under way
_PASSIVE_CLEARED = (L.S_V_OLD, L.S_FLW16, L.S_EMERG, L.S_AT_EXIT)


@njit(**KERNEL)
def reset_speed_loop(r: np.ndarray, s: np.ndarray) -> None:
    """Clear the FF/VB/VF histories and the profile memory (entry into a regulated mode); the
    speed history starts at V_IST."""
    fill(s, _SPEED_LOOP_CLEARED, 0.0)
    fill(s, _SPEED_HISTORY, float(r[R.V_IST]))
    fill(r, _ERRORS, 0)


@plain_arguments
@njit(**KERNEL)
def start_test_record(r: np.ndarray, s: np.ndarray, inner: bool) -> None:
    """Start a test mode's record into the sample buffer (4.4.9, 4.4.10): REC_CNT = 0,
    RECORDBIT set, RECINNERBIT set for a record at the current-loop rate (``inner``) and
    cleared for one at the servo rate, REWINDBIT cleared, the test's sample counter at 0."""
    r[R.REC_CNT] = 0
    if inner:
        r[R.CNTRL_BITS] = (r[R.CNTRL_BITS] | c.RECINNERBIT | c.RECORDBIT) & ~c.REWINDBIT
    else:
        r[R.CNTRL_BITS] = (r[R.CNTRL_BITS] | c.RECORDBIT) & ~(c.RECINNERBIT | c.REWINDBIT)
    s[L.S_TEST_CNT] = 0.0


@njit(**KERNEL)
def enter_mode(r: np.ndarray, s: np.ndarray, new: int) -> None:
    """Set MODE_REG and perform the entry actions of ``new`` (manual 4.4)."""
    old = int(r[R.MODE_REG])
    r[R.MODE_REG] = new
    if new == c.INIT_MODE or new == c.SAFE_MODE:
        fill(s, _PASSIVE_CLEARED, 0.0)
        s[L.S_PENDING_MODE] = -1.0
        fill(r, _PASSIVE_REGISTERS, 0)
        r[R.ERR_STAT] &= ~(c.IN_POS | c.ACC_FLAG | c.DEC_FLAG)
        return
    old_regulated = old < N_MODES and REGULATED[old]
    if new < N_MODES and REGULATED[new] and not old_regulated:
        reset_speed_loop(r, s)
        s[L.S_V_OLD] = 0.0
    if new == c.TESTU_MODE:
        r[R.SAMPLE1] = R.UA_VAL
        r[R.SAMPLE2] = R.IC_IST
        start_test_record(r, s, True)
    elif new == c.TESTA_MODE:
        r[R.SAMPLE1] = R.T_SOLL
        r[R.SAMPLE2] = R.V_IST
        start_test_record(r, s, False)
    elif new == c.BREAK_MODE:
        d = s[L.S_OMEGA]
        s[L.S_BREAK_DIR] = 1.0 if d > 0.0 else (-1.0 if d < 0.0 else 0.0)
    elif new == c.TESTKI_MODE:  # documented measurement: phase currents of a UA/UB step
        r[R.SAMPLE1] = R.IA_IST
        r[R.SAMPLE2] = R.IB_IST
        r[R.SAMPLE3] = R.IC_IST
        start_test_record(r, s, True)
    elif new == c.TESTTQ_MODE:  # documented measurement: torque at +V_SOLL then -V_SOLL
        r[R.SAMPLE1] = R.VF_OUT
        r[R.SAMPLE2] = R.V_IST
        start_test_record(r, s, False)
    elif new == c.COIL_MODE:
        coil_entry(r, s)
    elif new == c.HOME1_MODE or new == c.HOME2_MODE or new == c.HOME3_MODE:
        home_entry(r, s)
    elif new == c.A2POS_MODE:
        a2pos_update(r, s, True)
    if fncerr_is_position(new):
        s[L.S_G_FNC] = 0.0
    elif fncerr_is_position(old):
        # FNCERR changes meaning from a position error to a correction sum (3.2.24)
        r[R.FNCERR] = 0


@plain_arguments
@njit(**KERNEL)
def stop_to(r: np.ndarray, s: np.ndarray, final: int, emergency: bool) -> None:
    """Bring a motor to ``final`` (INIT or SAFE) the protective way of manual 4.4.1/4.4.5/4.4.12."""
    mode = int(r[R.MODE_REG])
    if mode < N_MODES and REGULATED[mode]:
        if mode != c.STOP_MODE:
            enter_mode(r, s, c.STOP_MODE)
        s[L.S_PENDING_MODE] = final
        if emergency:
            s[L.S_EMERG] = 1.0
    elif mode == c.AT_MODE:
        s[L.S_AT_EXIT] = 1.0
        s[L.S_PENDING_MODE] = final
    elif mode == c.TESTA_MODE or mode == c.BREAK_MODE:
        if mode == c.TESTA_MODE:
            enter_mode(r, s, c.BREAK_MODE)
        s[L.S_PENDING_MODE] = final
    elif mode != final:
        enter_mode(r, s, final)


@njit(**KERNEL)
def check_request(r: np.ndarray, s: np.ndarray, req: int) -> int:
    """Outcome code of writing ``req`` to MODE_REG now (no change is made)."""
    mode = int(r[R.MODE_REG])
    if req < 0 or (N_MODES <= req < c.SAFE_LOAD_DEFAULTS_SAVE) or req > c.SAFE_LOAD_FLASH:
        return E_INVALID
    if mode == c.SAFE_MODE:
        return OK if req >= 256 else E_IN_SAFE
    if req >= 256:
        return E_SPECIAL_OUTSIDE_SAFE
    if req == c.SAFE_MODE:
        return E_SAFE
    if req == c.BREAK_MODE:
        return E_BREAK
    if req == c.INIT_MODE or req == c.STOP_MODE or req == mode:
        return OK
    if mode == c.AT_MODE:
        return OK  # any request leaves AT_MODE towards INIT (4.4.5)
    if (r[R.ERR_STAT] & c.BLOCKING_ERRORS) != 0:
        return E_ERROR_BITS
    if mode == c.INIT_MODE:
        return OK
    if REGULATED[mode] and REGULATED[req] and req != c.TESTTQ_MODE and mode != c.TESTTQ_MODE:
        return OK
    return E_NEEDS_INIT


@njit(**KERNEL)
def apply_request(r: np.ndarray, s: np.ndarray, req: int) -> None:
    """Carry out an accepted MODE_REG write (``check_request`` returned OK)."""
    mode = int(r[R.MODE_REG])
    if req == mode:
        return
    if req == c.INIT_MODE or req == c.STOP_MODE or mode == c.AT_MODE:
        stop_to(r, s, c.INIT_MODE, False)
        return
    enter_mode(r, s, req)


@njit(cache=True)  # allocates its result: NRT
def check_requests(regs: np.ndarray, state: np.ndarray, idx: np.ndarray, req: np.ndarray):
    """Outcome codes for a batch of requests (one per index)."""
    out = np.zeros(idx.shape[0], dtype=np.int64)
    for k in range(idx.shape[0]):
        out[k] = check_request(regs[idx[k]], state[idx[k]], int(req[k]))
    return out


@njit(**KERNEL)
def apply_requests(regs: np.ndarray, state: np.ndarray, idx: np.ndarray, req: np.ndarray) -> None:
    """Carry out a batch of accepted requests."""
    for k in range(idx.shape[0]):
        apply_request(regs[idx[k]], state[idx[k]], int(req[k]))


@njit(**KERNEL)
def go_safe(regs: np.ndarray, state: np.ndarray, idx: np.ndarray) -> None:
    """MacTalk 'go safe mode' (5.1, 4.4.16): via STOP/INIT as needed, then SAFE_MODE."""
    for k in range(idx.shape[0]):
        r = regs[idx[k]]
        s = state[idx[k]]
        mode = int(r[R.MODE_REG])
        if mode == c.INIT_MODE or not (REGULATED[mode] or mode == c.AT_MODE
                                       or mode == c.TESTA_MODE or mode == c.BREAK_MODE):
            enter_mode(r, s, c.SAFE_MODE)
        else:
            stop_to(r, s, c.SAFE_MODE, False)


@njit(**KERNEL)
def go_init(regs: np.ndarray, state: np.ndarray, idx: np.ndarray) -> None:
    """MacTalk 'go init mode' (5.1) and leaving SAFE_MODE: the protective path to INIT."""
    for k in range(idx.shape[0]):
        r = regs[idx[k]]
        s = state[idx[k]]
        if int(r[R.MODE_REG]) == c.SAFE_MODE:
            enter_mode(r, s, c.INIT_MODE)
        else:
            stop_to(r, s, c.INIT_MODE, False)
