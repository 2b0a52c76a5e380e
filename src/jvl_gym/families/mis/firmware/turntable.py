"""Turn-table modes 1–5 (MIS manual §5.12): the working range, the wrap of P_IST and the travel
to the target.

The range is MIN_P_IST … MAX_P_IST (swapped if MIN > MAX, §5.12.3), ``size = MAX − MIN + 1``.
P_IST is kept inside it: leaving it at MAX continues at MIN and counts TURNTAB_COUNT up, leaving
it at MIN continues at MAX and counts down (§5.12.1, §5.12.5). The encoder position (ENCODER_POS)
wraps with it, so that it stays in P_IST's frame: the follow error P_IST − ENCODER_POS
(§8.2.18) and auto-correction's window around P_SOLL (§5.2.1, §8.2.15) compare positions of one
turn, while ABSENCODER stays "not corrected for the turntable" (§5.12.5).

The travel to P_SOLL is always positive (modes 1, 4: CW), always negative (2, 5: CCW) or the
shorter way round (3). A multiturn move (modes 4, 5) written beyond the range keeps its full
length in ``S_TT_TRAVEL`` (set where P_SOLL is written, ``motors.py``).
"""

from __future__ import annotations

from numba import njit

from ....physics.fixed import wrap32
from .. import constants as c
from .. import layout as L
from . import regs as R


@njit(cache=True, inline="always")
def tt_range(regs) -> tuple[int, int]:  # pragma: no cover - compiled
    """(MIN, MAX) of the working range, ordered."""
    lo, hi = regs[R.MIN_P_IST], regs[R.MAX_P_IST]
    return (lo, hi) if lo <= hi else (hi, lo)


@njit(cache=True, inline="always")
def tt_active(regs) -> bool:  # pragma: no cover - compiled
    """A turn-table mode 1–5 with a range of at least two positions."""
    lo, hi = tt_range(regs)
    return c.TT_CW <= regs[R.TURNTABLE_MODE] <= c.TT_MULTI_CCW and hi > lo


@njit(cache=True)
def tt_distance(regs, s) -> float:  # pragma: no cover - compiled
    """Signed counts from P_IST to P_SOLL by the turn-table mode's way round (§5.12.1)."""
    lo, hi = tt_range(regs)
    size = hi - lo + 1
    mode = regs[R.TURNTABLE_MODE]
    if s[L.S_TT_TRAVEL] != 0.0:
        return s[L.S_TT_TRAVEL]
    d = (regs[R.P_SOLL] - regs[R.P_IST]) % size  # Python modulo: 0 … size − 1
    if mode == c.TT_CW or mode == c.TT_MULTI_CW:
        return float(d)
    if mode == c.TT_CCW or mode == c.TT_MULTI_CCW:
        return float(d - size) if d != 0 else 0.0
    return float(d - size) if d > size // 2 else float(d)


@njit(cache=True)
def tt_wrap(regs, s) -> None:  # pragma: no cover - compiled
    """Keep P_IST inside the range, counting wrap-arounds in TURNTAB_COUNT (§5.12.5), and move
    the encoder position by the same whole turns (module docstring)."""
    lo, hi = tt_range(regs)
    size = hi - lo + 1
    p = regs[R.P_IST]
    turns = (p - lo) // size
    if turns != 0:
        shift = turns * size
        regs[R.P_IST] = p - shift
        regs[R.TURNTAB_COUNT] += turns
        s[L.S_ENC_OFFSET] -= shift
        s[L.S_ENC_PREV] = wrap32(int(s[L.S_ENC_PREV]) - shift)
        if regs[R.ENCODER_TYPE] != 0:
            regs[R.ENCODER_POS] = wrap32(regs[R.ENCODER_POS] - shift)
            regs[R.FLWERR] = wrap32(regs[R.P_IST] - regs[R.ENCODER_POS])
