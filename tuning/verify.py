"""Verification of designed loops: stability, margins, bandwidth, robustness, time simulation.

Stability is decided by the closed-loop pole radius (all roots of ``den(L) + num(L)`` inside
``POLE_RADIUS_MAX``), never by margins alone: python-control 0.10.2 reports positive margins for
some unstable type-2 discrete loops. Margins and bandwidths are computed on a dense logarithmic
frequency grid up to the Nyquist frequency: every gain crossover gives a phase margin (the
smallest is reported), every −180° phase crossing with ``|L| < 1`` a gain margin (the smallest is
reported) and every crossing with ``|L| > 1`` a gain-*reduction* margin.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field, replace

import control as ct
import numpy as np

from .models import (
    MotorData,
    current_open_loop,
    freqresp,
    speed_closed_loop,
    speed_open_loop,
    speed_plant,
)

__all__ = [
    "POLE_RADIUS_MAX",
    "LoopMetrics",
    "loop_metrics",
    "metrics_from_response",
    "with_pole_radius",
    "frequency_grid",
    "CurrentLoopReport",
    "SpeedLoopReport",
    "verify_current_loop",
    "verify_speed_loop",
]

POLE_RADIUS_MAX: float = 0.999  #: closed-loop poles must satisfy |z| < this


@dataclass
class LoopMetrics:
    """Stability margins and bandwidth of one loop.

    Attributes
    ----------
    pm_deg : float
        Smallest phase margin over all gain crossovers [deg] (inf if none).
    gm_db : float
        Smallest gain (increase) margin over the −180° crossings with ``|L| < 1`` [dB].
    gm_low_db : float
        Gain-reduction margin (−180° crossings with ``|L| > 1``) [dB, ≥ 0], inf if none.
    crossover_hz : float
        Lowest gain-crossover frequency [Hz].
    bandwidth_hz : float
        −3 dB bandwidth of ``L/(1+L)`` [Hz].
    pole_radius : float
        Largest closed-loop pole magnitude.
    stable : bool
        ``pole_radius < POLE_RADIUS_MAX``.
    """

    pm_deg: float
    gm_db: float
    gm_low_db: float
    crossover_hz: float
    bandwidth_hz: float
    pole_radius: float
    stable: bool

    def as_dict(self) -> dict[str, float]:
        """Plain dict (for tables and YAML)."""
        return asdict(self)


def frequency_grid(dt: float, n: int = 3000, lowest: float = 1e-4) -> np.ndarray:
    """Log-spaced angular frequencies from ``lowest``·ω_N to 0.9999·ω_N [rad/s], shape (n,)."""
    wn = math.pi / dt
    return np.logspace(math.log10(lowest * wn), math.log10(0.9999 * wn), n)


def _crossings(x: np.ndarray) -> np.ndarray:
    """Indices i with a sign change between x[i] and x[i+1]."""
    s = np.sign(x)
    return np.flatnonzero(s[:-1] * s[1:] < 0)


def _crossed_integers(f: np.ndarray, candidates: range) -> list[int]:
    """The integers j of ``candidates`` that ``f`` can cross (``min f < j < max f``): f − j
    changes sign only for those; all of them when ``f`` holds a NaN."""
    lo, hi = float(np.min(f)), float(np.max(f))
    if math.isnan(lo) or math.isnan(hi):
        return list(candidates)
    return [j for j in candidates if lo < j < hi]


def metrics_from_response(lw: np.ndarray, w: np.ndarray, char_poly: np.ndarray | None = None
                          ) -> LoopMetrics:
    """Margins and bandwidth from a sampled open-loop response.

    Parameters
    ----------
    lw : ndarray, shape (n,)
        ``L(e^{jωT})`` on the grid.
    w : ndarray, shape (n,)
        Angular frequencies [rad/s], increasing.
    char_poly : ndarray, optional
        Closed-loop characteristic polynomial (descending powers of z) for the pole radius.
    """
    mag = np.abs(lw)
    ph = np.unwrap(np.angle(lw))
    logm = np.log(np.maximum(mag, 1e-300))
    pm = math.inf
    wc = math.nan
    for i in _crossings(logm):
        t = logm[i] / (logm[i] - logm[i + 1])
        p = ph[i] + t * (ph[i + 1] - ph[i])
        marg = (math.degrees(p) + 180.0 + 180.0) % 360.0 - 180.0
        pm = min(pm, marg)
        if math.isnan(wc):
            wc = w[i] + t * (w[i + 1] - w[i])
    gm = math.inf
    gm_low = math.inf
    k = (ph / math.pi + 1.0) / 2.0  # integer when the phase is an odd multiple of 180°
    f = k - np.floor(k[0] + 0.5)
    for j in _crossed_integers(f, range(-3, 4)):
        for i in _crossings(f - j):
            t = (f[i] - j) / (f[i] - f[i + 1])
            lm = logm[i] + t * (logm[i + 1] - logm[i])
            db = -20.0 * lm / math.log(10.0)
            if lm < 0:
                gm = min(gm, db)
            else:
                gm_low = min(gm_low, -db)
    tw = lw / (1.0 + lw)
    t0 = abs(tw[0])
    below = np.flatnonzero(np.abs(tw) < t0 / math.sqrt(2.0))
    bw = w[below[0]] / (2 * math.pi) if below.size else w[-1] / (2 * math.pi)
    wc_hz = wc / (2 * math.pi) if not math.isnan(wc) else math.nan
    m = LoopMetrics(pm_deg=pm, gm_db=gm, gm_low_db=gm_low, crossover_hz=wc_hz,
                    bandwidth_hz=bw, pole_radius=math.nan, stable=False)
    return m if char_poly is None else with_pole_radius(m, char_poly)


def with_pole_radius(m: LoopMetrics, char_poly: np.ndarray) -> LoopMetrics:
    """``m`` with the pole radius and stability of the closed-loop characteristic polynomial
    ``char_poly`` (descending powers of z): what :func:`metrics_from_response` gives with it, so
    that a search can screen on the margins before it computes the roots."""
    roots = np.roots(np.trim_zeros(np.asarray(char_poly, dtype=float), "f"))
    radius = float(np.max(np.abs(roots))) if roots.size else 0.0
    return replace(m, pole_radius=radius,
                   stable=bool(radius < POLE_RADIUS_MAX) if not math.isnan(radius) else False)


def char_poly(loop: ct.TransferFunction) -> np.ndarray:
    """Closed-loop characteristic polynomial ``den + num`` of ``1 + L`` (descending z)."""
    num = np.asarray(loop.num[0][0], dtype=float)
    den = np.asarray(loop.den[0][0], dtype=float)
    return np.polyadd(den, num)


def loop_metrics(loop: ct.TransferFunction, n: int = 3000) -> LoopMetrics:
    """Margins, bandwidth and pole radius of a discrete SISO open loop ``L``."""
    w = frequency_grid(loop.dt, n)
    return metrics_from_response(freqresp(loop, w), w, char_poly(loop))


# ----------------------------------------------------------------------------- reports
class _Robustness:
    """The robustness set's summary of a loop report (``nominal``, ``robust``)."""

    nominal: LoopMetrics
    robust: dict[str, LoopMetrics]

    @property
    def worst_robust_pm(self) -> float:
        """Smallest phase margin over the robustness set [deg]."""
        return min((m.pm_deg for m in self.robust.values()), default=math.inf)

    @property
    def all_stable(self) -> bool:
        """Nominal and every robustness case have all poles inside POLE_RADIUS_MAX."""
        return self.nominal.stable and all(m.stable for m in self.robust.values())


@dataclass
class CurrentLoopReport(_Robustness):
    """Verification of a current-loop design (per phase, TS_I)."""

    nominal: LoopMetrics
    robust: dict[str, LoopMetrics] = field(default_factory=dict)


@dataclass
class SpeedLoopReport(_Robustness):
    """Verification of a speed-loop design (TS_O), including the closed current loop."""

    nominal: LoopMetrics
    reference_bandwidth_hz: float
    step_overshoot: float
    robust: dict[str, LoopMetrics] = field(default_factory=dict)


ROBUST_RL: tuple[float, ...] = (0.7, 1.3)  #: R and L factors of the robustness set (±30 %)
ROBUST_KVOUT: tuple[float, ...] = (0.5, 0.7, 1.4, 2.0)  #: KVOUT / (J_true/J_m) factors


def verify_current_loop(motor: MotorData, regs: Mapping[str, float],
                        robust: bool = True) -> CurrentLoopReport:
    """Margins of the current loop on ``motor``, and on R, L × {0.7, 1.3} (all 4 corners).

    Parameters
    ----------
    motor : MotorData
        Coil the loop runs on (the identified or the true one).
    regs : mapping
        KIFX2, KIFX1, KIFY1, KIFY0, KIB1, KIB0.
    """
    rep = CurrentLoopReport(nominal=loop_metrics(current_open_loop(motor, regs)))
    if robust:
        for fr in ROBUST_RL:
            for fl in ROBUST_RL:
                m = motor.with_(R_phase=motor.R_phase * fr, L_phase=motor.L_phase * fl)
                rep.robust[f"R x{fr:g}, L x{fl:g}"] = loop_metrics(current_open_loop(m, regs))
    return rep


def step_overshoot(sys: ct.TransferFunction, n: int = 400) -> float:
    """Relative overshoot of the unit-step response of a discrete system (0 = none)."""
    t, y = ct.step_response(sys, T=np.arange(n) * sys.dt)
    y = np.squeeze(y)
    final = y[-1]
    if final == 0:
        return math.nan
    return float(max(0.0, (np.max(y) - final) / abs(final)))


def verify_speed_loop(motor: MotorData, regs: Mapping[str, float], J_total: float,
                      robust: bool = True) -> SpeedLoopReport:
    """Margins of the speed loop for a load of total inertia ``J_total`` [kg·m²].

    The plant includes the closed current loop (``regs``' IF/IB on ``motor``'s coil). The
    robustness set: the true inertia differing from ``KVOUT·J_m`` by the factors
    ``ROBUST_KVOUT`` (KVOUT × 0.5–2), and the coil R, L ±30 % under the current loop.
    """
    plant = speed_plant(motor, regs, J=J_total)
    fam = motor.family
    loop = speed_open_loop(plant, regs, fam)
    nominal = loop_metrics(loop)
    cl = speed_closed_loop(plant, regs, fam)
    w = np.logspace(-1, math.log10(0.999 * math.pi / fam.outer_dt), 2000)
    tw = np.abs(freqresp(ct.minreal(cl, verbose=False), w))
    below = np.flatnonzero(tw < abs(tw[0]) / math.sqrt(2.0))
    ref_bw = w[below[0]] / (2 * math.pi) if below.size else w[-1] / (2 * math.pi)
    rep = SpeedLoopReport(nominal=nominal, reference_bandwidth_hz=ref_bw,
                          step_overshoot=step_overshoot(cl))
    if robust:
        for fk in ROBUST_KVOUT:
            p = speed_plant(motor, regs, J=J_total / fk)
            rep.robust[f"KVOUT x{fk:g}"] = loop_metrics(speed_open_loop(p, regs, fam))
        for fr in ROBUST_RL:
            for fl in ROBUST_RL:
                m = motor.with_(R_phase=motor.R_phase * fr, L_phase=motor.L_phase * fl)
                p = speed_plant(m, regs, J=J_total)
                rep.robust[f"R x{fr:g}, L x{fl:g}"] = loop_metrics(speed_open_loop(p, regs, fam))
    return rep


# ----------------------------------------------------------------------------- time simulation
@dataclass
class MoveResult:
    """A position move on the simulator (one entry per motor of the array).

    Attributes
    ----------
    settle_s : ndarray, shape (N,)
        Time from the start until |P_IST − P_SOLL| ≤ ``window`` for good [s] (inf if never).
    overshoot : ndarray, shape (N,)
        Largest travel past the target [counts].
    fncerr : ndarray, shape (N,)
        Largest |FNCERR| during the move [1/16 counts].
    errors : ndarray, shape (N,)
        ERR_STAT error bits (0..3) seen during the move.
    position : ndarray, shape (n_samples, N)
        P_IST [counts] per outer sample.
    """

    settle_s: np.ndarray
    overshoot: np.ndarray
    fncerr: np.ndarray
    errors: np.ndarray
    position: np.ndarray


def position_move(m, distance: int, v_soll: int, a_soll: int, seconds: float = 1.0,
                  window: int = 10, dt: float | None = None) -> MoveResult:
    """Run a P_MODE move of ``distance`` counts on every motor of ``m`` (a ``MotorArray``).

    ``dt`` is the family's servo sample time [s] (default ``1/m.OUTER_HZ``).

    The motors must be in INIT_MODE at rest; they are left in P_MODE at the target.
    """
    dt = 1.0 / m.OUTER_HZ if dt is None else dt
    n_steps = int(round(seconds / dt))
    start = np.asarray(m.read("P_IST")).astype(float)
    target = start + distance
    m.write("V_SOLL", v_soll)
    m.write("A_SOLL", a_soll)
    m.write("P_SOLL", target)
    m.write("MODE_REG", 2)
    pos = np.empty((n_steps, m.n))
    fnc = np.zeros(m.n)
    err = np.zeros(m.n, dtype=np.int64)
    for k in range(n_steps):
        m.step(1)
        pos[k] = m.read("P_IST")
        fnc = np.maximum(fnc, np.abs(np.asarray(m.read("FNCERR"), dtype=float)))
        err |= np.asarray(m.read("ERR_STAT")).astype(np.int64) & 0xF
    off = np.abs(pos - target) > window
    settle = np.full(m.n, math.inf)
    for i in range(m.n):
        bad = np.flatnonzero(off[:, i])
        if bad.size == 0:
            settle[i] = dt
        elif bad[-1] < n_steps - 1:
            settle[i] = (bad[-1] + 2) * dt
    over = np.max((pos - target) * np.sign(distance), axis=0).clip(min=0)
    return MoveResult(settle, over, fnc, err, pos)


def velocity_step(m, v_soll: int, a_soll: int = 10000, seconds: float = 0.3) -> np.ndarray:
    """V_MODE step to ``v_soll`` [1/16 count/sample]; returns V_IST, shape (n_samples, N)."""
    n_steps = int(round(seconds / (1.0 / m.OUTER_HZ)))
    m.write("A_SOLL", a_soll)
    m.write("V_SOLL", v_soll)
    m.write("MODE_REG", 1)
    out = np.empty((n_steps, m.n))
    for k in range(n_steps):
        m.step(1)
        out[k] = m.read("V_IST")
    return out
