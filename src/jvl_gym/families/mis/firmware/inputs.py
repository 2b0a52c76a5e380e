"""The I/O inputs: digital input filter (MIS manual §2.2.6–2.2.7, §8.2.75–76) and the analogue
input filter (§2.3.5, §8.2.45–55).

Digital inputs: an input whose bit is set in INPUT_FILTER_MASK changes its state only after its
raw level has differed from the state for INPUT_FILTER_CNT ms; the others follow the raw level
at once (their 100 µs update is faster than the 1 ms outer sample). IOSETUP bits 0–7 set each
input's active level; the simulator reads a set bit as "active low" (decision: the manual does
not say which level a set bit selects).

Analogue filter, every 10 ms (§2.3.5): a raw sample outside AFZUP_CONFMIN … AFZUP_CONFMAX is
discarded; else it is limited to the last filtered value ± AFZUP_MAXSLOPE; the result is
``new·F/64 + old·(64 − F)/64`` with F = AFZUP_FILTER, kept with a fractional part inside and
rounded in the ANALOGUE_FILTERED registers. Each input filters with its own settings, the
firmware's copies of AFZUP_CONFMIN … AFZUP_FILTER that AFZUP_WRITEBITS hands it (§8.2.50;
``mis.filter_setup``), held in the motor's ``params`` row.

FILTERSTATUS (§8.2.56), each second of the motor's clock: bits 0–7 tell that more than half the
samples of the last second of IO1 … IO8 were discarded as outside the confidence limits, bits
8–15 that more than half were slope limited (the detail's order; the register overview swaps
the halves).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .. import layout as L
from ..units import ANALOGUE_FULL, ANALOGUE_VOLTS_PER_UNIT
from . import regs as R

#: outer samples (ms) between two analogue filter samples (§2.3.5: "fixed intervals of 10 mS")
AF_PERIOD = 10
#: analogue filter samples in the second FILTERSTATUS is taken over (§8.2.56)
AF_PER_SECOND = 1000 // AF_PERIOD


@njit(cache=True)
def analogue_filter_step(old: float, raw: float, conf_min: float, conf_max: float,
                         max_slope: float, filt: float) -> float:  # pragma: no cover
    """One 10 ms step of the analogue filter of §2.3.5 (values in 1.221 mV units).

    Parameters
    ----------
    old : float
        The last filtered value.
    raw : float
        The new raw sample.
    conf_min, conf_max : float
        Confidence limits; a sample outside them is discarded (the result is ``old``).
    max_slope : float
        Largest change of the sample against ``old``.
    filt : float
        AFZUP_FILTER: the new sample's weight in 64ths.
    """
    if raw < conf_min or raw > conf_max:
        return old
    limited = min(max(raw, old - max_slope), old + max_slope)
    return limited * (filt / 64.0) + old * ((64.0 - filt) / 64.0)


@njit(cache=True)
def update_inputs(regs, s, p, u) -> None:  # pragma: no cover - compiled
    """Digital inputs → INPUTS, analogue inputs → ANALOGUE_INPUT1..8 and (every 10 ms)
    ANALOGUE_FILTERED1..8. The home sensor model (``home_position``) drives the HOME_MASK
    inputs while the rotor is at or below its angle."""
    raw_bits = int(u[L.I_DIGITAL]) ^ (regs[R.IOSETUP] & 0xFF)
    if s[L.S_THETA] <= p[L.P_HOME_POS]:
        raw_bits |= regs[R.HOME_MASK] & 0xFF
    state = int(s[L.S_DIN_STATE])
    mask = regs[R.INPUT_FILTER_MASK]
    need = regs[R.INPUT_FILTER_CNT]
    for k in range(8):
        bit = 1 << k
        if not mask & bit:
            state = (state & ~bit) | (raw_bits & bit)
            s[L.S_DIN0 + k] = 0.0
        elif (raw_bits ^ state) & bit:
            s[L.S_DIN0 + k] += 1.0
            if s[L.S_DIN0 + k] >= need:
                state ^= bit
                s[L.S_DIN0 + k] = 0.0
        else:
            s[L.S_DIN0 + k] = 0.0
    s[L.S_DIN_STATE] = state
    regs[R.INPUTS] = state
    s[L.S_AF_MS] += 1.0
    sample = s[L.S_AF_MS] >= AF_PERIOD
    if sample:
        s[L.S_AF_MS] = 0.0
    for k in range(8):
        raw = min(max(np.floor(u[L.I_ANALOG0 + k] / ANALOGUE_VOLTS_PER_UNIT + 0.5), 0.0),
                  float(ANALOGUE_FULL))
        regs[R.ANALOGUE_INPUT1 + k] = int(raw)
        if sample:
            old = s[L.S_AF0 + k]
            af = L.P_AF0 + L.AF_SETTINGS * k
            conf_min, conf_max = p[af + L.AF_CONFMIN], p[af + L.AF_CONFMAX]
            max_slope = p[af + L.AF_MAXSLOPE]
            if raw < conf_min or raw > conf_max:
                s[L.S_AF_CONF0 + k] += 1.0
            elif abs(raw - old) > max_slope:
                s[L.S_AF_SLOPE0 + k] += 1.0
            s[L.S_AF0 + k] = analogue_filter_step(old, raw, conf_min, conf_max, max_slope,
                                                  p[af + L.AF_FILTER])
            regs[R.ANALOGUE_FILTERED1 + k] = int(math.floor(s[L.S_AF0 + k] + 0.5))
    if int(s[L.S_TICK]) % 1000 == 0:
        _filter_status(regs, s)


@njit(cache=True)
def _filter_status(regs, s) -> None:  # pragma: no cover - compiled
    """FILTERSTATUS of the last second (§8.2.56): bit k when more than half the analogue
    samples of IO(k+1) were outside the confidence limits, bit 8 + k when more than half were
    slope limited; the counts start again."""
    status = 0
    for k in range(8):
        if 2.0 * s[L.S_AF_CONF0 + k] > AF_PER_SECOND:
            status |= 1 << k
        if 2.0 * s[L.S_AF_SLOPE0 + k] > AF_PER_SECOND:
            status |= 1 << (8 + k)
        s[L.S_AF_CONF0 + k] = 0.0
        s[L.S_AF_SLOPE0 + k] = 0.0
    regs[R.FILTERSTATUS] = status
