"""Rules the firmware applies to register writes (Python side, vectorised over motors).

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

from .. import constants as c
from . import regs as R
from .modes import GEAR_MODES, in_table, member

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


def coil_violation(p: np.ndarray) -> str | None:
    """Message for the first motor whose P1..P6 (columns of ``p``) break the COIL rules."""
    p1, p2, p3, p4, p5, p6 = (p[:, k] for k in range(6))
    bad = ~((p1 <= p2) & (p2 <= p3) & (p3 <= p4) & (p1 <= p5) & (p5 <= p4) & (np.abs(p6) == 1))
    if not np.any(bad):
        return None
    k = int(np.flatnonzero(bad)[0])
    vals = ", ".join(f"P{j + 1}={int(p[k, j])}" for j in range(6))
    return (f"COIL_MODE rules P1 ≤ P2 ≤ P3 ≤ P4, P1 ≤ P5 ≤ P4, P6 = ±1 (manual 4.4.20) are "
            f"violated ({vals})")


def check_mode_request(regs: np.ndarray, idx: np.ndarray, req: np.ndarray) -> str | None:
    """Refuse gear modes with GEARF2 = 0 and COIL_MODE with broken P1..P6 rules."""
    gear = in_table(req, GEAR_MODES) & (regs[idx, R.GEARF2] == 0)
    if np.any(gear):
        return "GEARF2 = 0 is not a usable gear denominator (manual 3.2.15)"
    coil = req == c.COIL_MODE
    if np.any(coil):
        return coil_violation(regs[np.ix_(idx[coil], COIL_REGS)])
    return None


def check_write(regs: np.ndarray, idx: np.ndarray, num: int, raw: np.ndarray) -> str | None:
    """Message if writing ``raw`` to register ``num`` of motors ``idx`` must be refused."""
    modes = regs[idx, R.MODE_REG]
    if num == R.GEARF2 and np.any((raw == 0) & in_table(modes, GEAR_MODES)):
        return "GEARF2 = 0 is not a usable gear denominator in a gear mode (manual 3.2.15)"
    if num in COIL_REGS and np.any(modes == c.COIL_MODE):
        sel = modes == c.COIL_MODE
        p = regs[np.ix_(idx[sel], COIL_REGS)].copy()
        p[:, COIL_REGS.index(num)] = raw[sel]
        return coil_violation(p)
    if num == R.HOME_MODE:
        lo, hi = raw & 0xFF, raw >> 8
        if not (np.all(member(lo, _LEGAL_HOME)) and np.all(member(hi, _LEGAL_HOME))):
            return "HOME_MODE bytes must be 0, 12, 13 or 14 (manual 3.2.42)"
    if num == R.P_REG_P:
        sel = raw > 0
        rows = idx[sel]
        src = regs[rows, R.P1 + 2 * (raw[sel] - 1)]
        rel = (regs[rows, R.ERR_STAT] & (c.RELPOSPSOLL | c.RELPOSPFNC)) == c.RELPOSPSOLL
        if np.any(np.abs(regs[rows[rel], R.P_SOLL] + src[rel]) > _P_SOLL_MAX):
            return "the relative move would take P_SOLL outside ±67E6 (manual 3.2.3, 4.1.2)"
    return None


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
