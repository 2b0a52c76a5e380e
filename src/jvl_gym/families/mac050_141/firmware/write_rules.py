"""Rules the firmware applies to register writes.

The rules are compiled per motor (:func:`write_refusal`, :func:`mode_refusal`: a refusal code)
for the compiled register stores (``jvl_gym.families.mac050_141.store``); :func:`check_write` and
:func:`check_mode_request` apply them to a batch of motors and word the refusal.

- Register mode (manual 3.2.43–3.2.48): writing k to P_REG_P, V_REG_P, A_REG_P, T_REG_P, L_REG_P,
  Z_REG_P copies Pk/Vk/Ak/Tk/Lk/Zk to P_SOLL/V_SOLL/A_SOLL/T_SOLL/KVOUT/INPOSWIN and resets the
  pointer to 0. For P_REG_P the ERR_STAT bits select absolute (P_SOLL = Pk), RELPOSPSOLL
  (P_SOLL += Pk) or RELPOSPFNC (P_FNC −= 16·Pk) positioning (3.2.35); IN_POS is cleared (5.2.1.4).
- Combinations the firmware cannot run are refused with a clear message and change nothing:
  GEARF2 = 0 in a gear mode (3.2.15), the COIL rules P1 ≤ P2 ≤ P3 ≤ P4, P1 ≤ P5 ≤ P4, P6 = ±1
  (4.4.20), HOME_MODE bytes other than 0, 12, 13, 14 (3.2.42).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from ....engine.jit import KERNEL, plain_arguments
from .. import constants as c
from . import regs as R
from .modes import GEAR_MODES

POINTERS = {
    R.P_REG_P: (R.P1, 2, R.P_SOLL),
    R.V_REG_P: (R.V1, 1, R.V_SOLL),
    R.A_REG_P: (R.A1, 1, R.A_SOLL),
    R.T_REG_P: (R.T1, 1, R.T_SOLL),
    R.L_REG_P: (R.L1, 1, R.KVOUT),
    R.Z_REG_P: (R.Z1, 1, R.INPOSWIN),
}
COIL_REGS = (R.P1, R.P2, R.P3, R.P4, R.P5, R.P6)
_LEGAL_HOME = (0, 12, 13, 14)
_P_SOLL_MAX = 67_000_000


#: refusal codes of :func:`write_refusal` and :func:`mode_refusal` (0: accepted)
OK = 0
GEARF2_ZERO = 1
COIL_RULES = 2
HOME_BYTES = 3
P_SOLL_RANGE = 4
REFUSAL_MESSAGES = {
    HOME_BYTES: "HOME_MODE bytes must be 0, 12, 13 or 14 (manual 3.2.42)",
    P_SOLL_RANGE: "the relative move would take P_SOLL outside ±67E6 (manual 3.2.3, 4.1.2)",
}


@njit(**KERNEL)
def _gear_mode(mode: int) -> bool:  # pragma: no cover - compiled
    """``mode`` divides by GEARF2 (:data:`~mac050_141.firmware.modes.GEAR_MODES`)."""
    return 0 <= mode < GEAR_MODES.size and GEAR_MODES[mode]


@plain_arguments
@njit(**KERNEL)
def coil_rules_hold(r: np.ndarray, num: int, raw: int) -> bool:  # pragma: no cover - compiled
    """P1 ≤ P2 ≤ P3 ≤ P4, P1 ≤ P5 ≤ P4, P6 = ±1 (manual 4.4.20) for the P1..P6 of register row
    ``r`` with register ``num`` replaced by ``raw`` (``num`` = 0: as stored)."""
    p1 = raw if num == R.P1 else r[R.P1]
    p2 = raw if num == R.P2 else r[R.P2]
    p3 = raw if num == R.P3 else r[R.P3]
    p4 = raw if num == R.P4 else r[R.P4]
    p5 = raw if num == R.P5 else r[R.P5]
    p6 = raw if num == R.P6 else r[R.P6]
    return p1 <= p2 <= p3 <= p4 and p1 <= p5 <= p4 and abs(p6) == 1


@njit(**KERNEL)
def write_refusal(r: np.ndarray, num: int, raw: int) -> int:  # pragma: no cover - compiled
    """Refusal code of storing ``raw`` in register ``num`` of one motor (register row ``r``).

    Parameters
    ----------
    r : numpy.ndarray
        The motor's registers, (N_REGS,) int64 (stored integers).
    num : int
        Register number (not MODE_REG: see :func:`mode_refusal`).
    raw : int
        Stored integer to write, already range-checked (``jvl_gym.registers.formats``).

    Returns
    -------
    int
        :data:`OK`, :data:`GEARF2_ZERO` (3.2.15), :data:`COIL_RULES` (4.4.20, in COIL_MODE),
        :data:`HOME_BYTES` (3.2.42) or :data:`P_SOLL_RANGE` (3.2.3, a relative P_REG_P move).
    """
    mode = int(r[R.MODE_REG])
    if num == R.GEARF2:
        return GEARF2_ZERO if raw == 0 and _gear_mode(mode) else OK
    if num in COIL_REGS:
        return OK if mode != c.COIL_MODE or coil_rules_hold(r, num, raw) else COIL_RULES
    if num == R.HOME_MODE:
        legal = (raw & 0xFF) in _LEGAL_HOME and (raw >> 8) in _LEGAL_HOME
        return OK if legal else HOME_BYTES
    if num == R.P_REG_P and raw > 0:
        relative = (r[R.ERR_STAT] & (c.RELPOSPSOLL | c.RELPOSPFNC)) == c.RELPOSPSOLL
        if relative and abs(r[R.P_SOLL] + r[R.P1 + 2 * (raw - 1)]) > _P_SOLL_MAX:
            return P_SOLL_RANGE
    return OK


@njit(**KERNEL)
def mode_refusal(r: np.ndarray, req: int) -> int:  # pragma: no cover - compiled
    """Refusal code of the MODE_REG request ``req`` of one motor by the register rules:
    :data:`GEARF2_ZERO` for a gear mode with GEARF2 = 0 (3.2.15), :data:`COIL_RULES` for
    COIL_MODE with P1..P6 breaking the rules (4.4.20), else :data:`OK`. (The mode-change rules
    of manual 4.4 are :func:`jvl_gym.families.mac050_141.firmware.modes.check_request`.)"""
    if _gear_mode(req) and r[R.GEARF2] == 0:
        return GEARF2_ZERO
    if req == c.COIL_MODE and not coil_rules_hold(r, 0, 0):
        return COIL_RULES
    return OK


@njit(**KERNEL)
def first_write_refusal(regs: np.ndarray, idx: np.ndarray, num: int,
                        raw: np.ndarray) -> int:  # pragma: no cover - compiled
    """Position in ``idx`` of the first motor whose write of ``raw`` (one per motor of ``idx``)
    to register ``num`` :func:`write_refusal` refuses, or −1."""
    for k in range(idx.shape[0]):
        if write_refusal(regs[idx[k]], num, raw[k]) != OK:
            return k
    return -1


@njit(**KERNEL)
def first_mode_refusal(regs: np.ndarray, idx: np.ndarray,
                       req: np.ndarray) -> int:  # pragma: no cover - compiled
    """Position in ``idx`` of the motor whose MODE_REG request (one per motor) is reported:
    the first refused for GEARF2 = 0, else the first refused for the COIL rules, else −1."""
    for code in (GEARF2_ZERO, COIL_RULES):
        for k in range(idx.shape[0]):
            if mode_refusal(regs[idx[k]], req[k]) == code:
                return k
    return -1


def _refusal_message(r: np.ndarray, code: int, num: int = 0, raw: int = 0) -> str:
    """Message of refusal ``code`` for the motor with register row ``r`` (P1..P6 with ``num``
    replaced by ``raw`` in the COIL message)."""
    if code == GEARF2_ZERO:
        where = " in a gear mode" if num == R.GEARF2 else ""
        return f"GEARF2 = 0 is not a usable gear denominator{where} (manual 3.2.15)"
    if code == COIL_RULES:
        p = [raw if num == reg else int(r[reg]) for reg in COIL_REGS]
        vals = ", ".join(f"P{j + 1}={v}" for j, v in enumerate(p))
        return (f"COIL_MODE rules P1 ≤ P2 ≤ P3 ≤ P4, P1 ≤ P5 ≤ P4, P6 = ±1 (manual 4.4.20) are "
                f"violated ({vals})")
    return REFUSAL_MESSAGES[code]


def check_mode_request(regs: np.ndarray, idx: np.ndarray, req: np.ndarray) -> str | None:
    """Refuse gear modes with GEARF2 = 0 and COIL_MODE with broken P1..P6 rules."""
    req = np.asarray(req, dtype=np.int64)
    k = first_mode_refusal(regs, idx, req)
    if k < 0:
        return None
    r = regs[idx[k]]
    return _refusal_message(r, mode_refusal(r, req[k]))


def check_write(regs: np.ndarray, idx: np.ndarray, num: int, raw: np.ndarray) -> str | None:
    """Message if writing ``raw`` to register ``num`` of motors ``idx`` must be refused."""
    raw = np.asarray(raw, dtype=np.int64)
    k = first_write_refusal(regs, idx, num, raw)
    if k < 0:
        return None
    r = regs[idx[k]]
    return _refusal_message(r, write_refusal(r, num, raw[k]), num, int(raw[k]))


def apply_pointer(regs: np.ndarray, idx: np.ndarray, num: int, raw: np.ndarray) -> None:
    """Carry out a register-mode pointer write, then reset the pointer to 0."""
    first, stride, target = POINTERS[num]
    regs[idx, num] = 0
    sel = raw > 0
    rows = idx[sel]
    if rows.size == 0:
        return
    src = regs[rows, first + stride * (raw[sel] - 1)]
    if num != R.P_REG_P:
        regs[rows, target] = src
        return
    st = regs[rows, R.ERR_STAT]
    rel_fnc = (st & c.RELPOSPFNC) != 0
    rel_soll = ((st & c.RELPOSPSOLL) != 0) & ~rel_fnc
    absolute = ~(rel_fnc | rel_soll)
    regs[rows[absolute], R.P_SOLL] = src[absolute]
    regs[rows[rel_soll], R.P_SOLL] += src[rel_soll]
    p_fnc = regs[rows[rel_fnc], R.P_FNC] - 16 * src[rel_fnc]
    regs[rows[rel_fnc], R.P_FNC] = ((p_fnc + 2**31) % 2**32) - 2**31
    regs[rows, R.ERR_STAT] &= ~c.IN_POS
