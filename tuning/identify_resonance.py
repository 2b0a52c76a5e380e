"""Resonance of a load behind an elastic coupling, from torque-step records (docs/tuning.md,
"Two-mass loads").

The record. In AT_MODE (manual 4.4.5) the speed regulator is passive and the current loop
makes the torque ``VF_OUT = ANINP·T_SOLL/1023``; ANINP is the analogue input plus ANINP_OFFSET
(3.2.122/123), so writing ANINP_OFFSET = ±1023 with the input at 0 V is a torque step of
±T_SOLL that needs no signal source. The sample buffer (3.2.112–116, CNTRL_BITS RECORDBIT,
REWINDBIT, RECINNERBIT, 3.2.36) records ELDEG_IST (3.2.143, the encoder count modulo 2048) and
VF_OUT (3.2.121) at the current-loop rate, 7812.5 Hz, 895 samples (REC_CNT, 3.2.116: 114.6 ms).
The recording starts :data:`LEAD_OUTER` outer samples before the step, so the step is in the
record wherever it falls: VF_OUT marks it, and the end of the step (the brake) too. This needs no
timing between the host and the motor, so the same procedure runs over a serial link
(:class:`tuning.serial_source.SerialMotor`), where a frame's round trip is milliseconds of motor
time. Between steps the motor is braked by the reversed torque and rests.

The link. The brake is the one part that acts on what it reads: it reverses the torque while
V_IST has not crossed zero, so the speed overshoots zero by the step's acceleration times one
brake iteration (a read, a write, an outer sample, and the age of the read). Leaving AT_MODE
needs the speed below the stop speed (300 rpm, 4.4.5); above it the motor coasts in AT_MODE.
Over a port the link is measured before each record (:func:`tuning.link.measure_link`) and a
record whose overshoot would exceed half the stop speed is not taken: the short record is
skipped (its step's acceleration is 4.5 times the long one's; resonances above about 120 Hz are
then found in the long record only), and when the long one cannot be kept either the step is
refused (:class:`tuning.link.LinkTooSlow`) instead of reporting a record it could not make.

The model. With the current loop fast against the mechanics the torque is a step ``T`` and the
motor angle (torque-driven two-mass system, the load free) is::

    θ_m(t) = T t²/(2 J) + A (1 − e^{−σt} cos(ω_d t + φ)) + …,   ω_r = √(k (1/J_m + 1/J_l))

with ``J = J_m + J_l``: a parabola and a damped oscillation at the coupling's resonance. The fit
takes a polynomial (back-EMF and friction bend the parabola: order 3 over the short record,
5 over the long one, whose residual is white with it and strongly correlated with order 3)
plus ``e^{−σt}(a cos ω t + b sin ω t)``, from 2 ms after the step (the current rise); ω and σ
nonlinear (a grid over the frequency, then least squares), the rest linear. The interval of
the frequency is the fit's covariance with the residual variance inflated for its
autocorrelation (:func:`tuning.identify_coil.correlation_inflation`) and a Student t factor.

The current loop. The record shows the coupling *under the closed current loop*: the per-phase
PI loops do not reject the back-EMF of the oscillation completely, and the torque it costs acts
on the rotor like extra inertia and damping, which lowers the resonance by 1–5 % (more for large
load ratios) and raises its damping. :func:`coupling_resonance` undoes this with the model of
:func:`tuning.models.inner_modes` (current loop, coil with back-EMF, both masses; the current-loop
registers of the record): it finds the coupling's resonance and damping ratio whose modelled
mode is the fitted one. The model is quasi-static in the electrical angle; what it leaves out
(the per-phase loops see the oscillation beside the electrical frequency) is taken as up to
:data:`SHIFT_ERROR` of the modelled shift and added to both sides of the intervals.

The load ratio. ``J_l/J_m = J/J_m − 1`` from the identified total inertia
(:mod:`tuning.identify_mechanics`, TESTA) and the type's rotor inertia; the anti-resonance (the
load's own frequency on a held motor) is ``ω_a = ω_r/√(1 + J_l/J_m)``.

Two records: a short one (:data:`SHORT_S`, 24 ms) with a large torque for resonances above
about 120 Hz, whose oscillation in the angle is small (``∝ 1/ω²``), and a long one
(:data:`LONG_S`, 108 ms) with a small torque for low ones; each torque reaches 150 rad/s at the
step's planned end. The short record is kept when it holds at least three
periods and its oscillation stands out of the noise, else the long one.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy import optimize, stats

from jvl_gym.physics.coupling import coupling_for

from .identify_coil import correlation_inflation
from .intervals import LEVEL
from .link import LinkTiming, LinkTooSlow
from .models import MotorData, inner_modes
from .records import RecordError
from .testmode_facts import record_facts_of

__all__ = ["ResonanceEstimate", "ResonanceFit", "acquire_step_records", "fit_resonance",
           "identify_resonance", "step_record", "step_torques", "estimate_from_fits",
           "coupling_of", "apparent_resonance", "coupling_resonance", "CURRENT_LOOP_KEYS",
           "SHORT_S", "LONG_S", "SHIFT_ERROR"]

LEAD_OUTER: int = 2  #: outer samples recorded before the step
SHORT_S, LONG_S = 0.024, 0.108  #: torque-step lengths of the short and the long record [s]
MIN_RECORD_S: float = 0.012  #: least length of a usable record after the step [s]
#: polynomial order of the fit of the short and of the long record (module docstring)
FIT_ORDERS: tuple[int, int] = (3, 5)
ELDEG_TURN: int = 2048  #: ELDEG_IST counts per electrical turn (3.2.143)
ANINP_FULL: int = 1023  #: ANINP of ±10 V (3.2.122)
SKIP_S: float = 2e-3  #: time after the step left out of the fit (the current rise) [s]
F_MIN, F_MAX = 15.0, 480.0  #: frequency range searched [Hz]
#: the current-loop registers (3.2.106–3.2.111) the correction for the current loop needs
CURRENT_LOOP_KEYS = ("KIFX2", "KIFX1", "KIFY1", "KIFY0", "KIB1", "KIB0")
#: the model's error of the current loop's shift, as a share of the modelled shift (module
#: docstring); on the benchmark's 20 loads (docs/tuning.md) the corrected resonance missed by
#: at most 0.42 of the shift
SHIFT_ERROR: float = 0.75
ZETA_MIN: float = 0.002  #: smallest damping ratio an estimate or interval reports
END_SPEED: float = 150.0  #: speed each torque step reaches at its planned end [rad/s]
#: round trips of a brake iteration: the read, the write, and the read's age (module docstring)
BRAKE_ROUND_TRIPS: float = 3.0


@dataclass
class ResonanceFit:
    """The fit of one joined record.

    Attributes
    ----------
    f_hz, f_sd : float
        Damped oscillation frequency [Hz] and its standard error (inflated).
    sigma, sigma_sd : float
        Decay rate [1/s] and its standard error (inflated).
    amplitude : float
        Oscillation amplitude [counts] at the start of the fit.
    amplitude_sd : float
        Its standard error [counts].
    periods : float
        Oscillation periods within the fitted part of the record.
    rms : float
        Residual rms [counts].
    dof : int
        Degrees of freedom of the interval (effective samples − parameters).
    """

    f_hz: float
    f_sd: float
    sigma: float
    sigma_sd: float
    amplitude: float
    amplitude_sd: float
    periods: float
    rms: float
    dof: int


@dataclass
class ResonanceEstimate:
    """Identified resonance of a two-mass load.

    Attributes
    ----------
    f_res, f_anti : float
        Resonance (motor driven, load free) and anti-resonance frequency [Hz] of the coupling.
    load_ratio : float
        J_l/J_m.
    zeta : float
        Modal damping ratio of the coupling's resonance.
    f_seen, zeta_seen : float
        Resonance [Hz] and damping ratio as recorded, under the closed current loop
        (√(ω_d² + σ²)/2π and σ/√(ω_d² + σ²) of the fit).
    ci : dict
        95 % intervals (lo, hi) of "f_res", "f_anti", "load_ratio", "zeta".
    detected : bool
        An oscillation was found (amplitude above three standard errors with enough periods).
    fits : list of ResonanceFit
        The fits of the short and the long record; ``used`` indexes the one kept.
    used : int
        Index into ``fits``.
    """

    f_res: float
    f_anti: float
    load_ratio: float
    zeta: float
    f_seen: float
    zeta_seen: float
    ci: dict[str, tuple[float, float]]
    detected: bool
    fits: list[ResonanceFit] = field(default_factory=list)
    used: int = 0
    notes: list[str] = field(default_factory=list)


def _step_until(m: Any, done: Any, max_samples: int) -> None:
    for _ in range(max_samples):
        if done():
            return
        m.step(1)


def _brake_and_rest(m: Any, sign: np.ndarray, rest_s: float, ts_o: float) -> None:
    """Reverse the torque until every motor's V_IST has reached zero, leave AT_MODE (4.4.5:
    any mode request goes to INIT below 300 rpm) and rest ``rest_s`` [s] (servo sample time
    ``ts_o`` [s]). Over a serial link the motor may not have started when this begins: it
    first waits until every motor moves (at most 0.2 s)."""
    _step_until(m, lambda: bool(np.all(np.asarray(m.read("V_IST"), dtype=float) * sign > 0)),
                int(0.2 / ts_o))
    braking = np.ones(m.n, dtype=bool)
    for _ in range(int(1.0 / ts_o)):
        v = np.asarray(m.read("V_IST"), dtype=float)
        braking &= v * sign > 0
        if not braking.any():
            break
        m.write("ANINP_OFFSET", np.where(braking, -sign * ANINP_FULL, 0).astype(int))
        m.step(1)
    m.write("ANINP_OFFSET", 0)
    m.write("MODE_REG", 0)
    _step_until(m, lambda: bool(np.all(np.asarray(m.read("MODE_REG")) == 0)), 5000)
    mode = np.asarray(m.read("MODE_REG"))
    if np.any(mode != 0):  # still coasting in AT_MODE: the next record would start moving
        v = np.asarray(m.read("V_IST"))[mode != 0]
        raise RecordError(f"the motor did not leave AT_MODE after the brake (V_IST {v.tolist()}, "
                          "above the 300 rpm of manual 4.4.5): the brake overshot, e.g. over a "
                          "link that became slow during the record")
    m.step(int(rest_s / ts_o))


def acquire_step_records(m: Any, t_soll: np.ndarray | float, duration_s: float,
                         rest_s: float = 1.0) -> list[np.ndarray]:
    """Record the motor angle after an AT_MODE torque step of ``t_soll`` (VF_OUT units, per
    motor) held ``duration_s`` [s], on every motor of ``m`` (module docstring).

    The sample buffer records ELDEG_IST and VF_OUT at the inner rate from before the step; the
    step is where VF_OUT turns to the torque, the record ends where the brake reverses it or
    the buffer ends. Returns one angle record per motor [counts, unwrapped], 0 at the step.
    The motors end in INIT_MODE at rest; T_SOLL, ANINP_OFFSET, SAMPLE1/2 and CNTRL_BITS are
    restored.

    Raises
    ------
    RecordError
        A motor's record does not hold the step and :data:`MIN_RECORD_S` after it (over a slow
        serial link the mode change can arrive after the buffer is full), or a motor did not
        leave AT_MODE after the brake.
    """
    facts = record_facts_of(m)
    c = facts.constants  # AT_MODE and the sample buffer's control bits
    t = np.broadcast_to(np.abs(np.asarray(t_soll, dtype=float)), (m.n,)).round()
    saved = {k: np.asarray(m.read(k)).copy()
             for k in ("T_SOLL", "ANINP_OFFSET", "SAMPLE1", "SAMPLE2", "CNTRL_BITS")}
    sign = np.ones(m.n)
    m.write("T_SOLL", t)
    m.write("SAMPLE1", facts.table.lookup("ELDEG_IST").number)
    m.write("SAMPLE2", facts.table.lookup("VF_OUT").number)
    m.write("ANINP_OFFSET", (sign * ANINP_FULL).astype(int))
    rec_bits = c.RECORDBIT | c.REWINDBIT | c.RECINNERBIT
    cb = np.asarray(m.read("CNTRL_BITS")).astype(np.int64) & ~rec_bits
    m.write("CNTRL_BITS", cb | rec_bits)
    m.step(LEAD_OUTER)
    m.write("MODE_REG", c.AT_MODE)
    m.step(max(int(round(duration_s / facts.ts_o)), 1))
    _brake_and_rest(m, sign, rest_s, facts.ts_o)
    buf = m.sample_buffer()
    for k in ("T_SOLL", "ANINP_OFFSET", "SAMPLE1", "SAMPLE2", "CNTRL_BITS"):
        m.write(k, saved[k])
    return [step_record(buf["ELDEG_IST"][i], buf["VF_OUT"][i], facts.ts_i) for i in range(m.n)]


def step_record(eldeg: np.ndarray, vf_out: np.ndarray, dt: float) -> np.ndarray:
    """The motor angle [counts] from the torque step on, 0 at the step, from the recorded
    ELDEG_IST (modulo 2048, unwrapped here) and VF_OUT of one motor, sampled every ``dt`` [s]
    (the family's current-loop sample time): from the first sample with VF_OUT > 0 to the last
    before VF_OUT changes again (the brake) or the record ends.

    Raises
    ------
    RecordError
        Fewer than :data:`MIN_RECORD_S` of the step in the record.
    """
    vf = np.asarray(vf_out, dtype=float)
    on = np.flatnonzero(vf > 0)
    n_min = int(round(MIN_RECORD_S / dt))
    if on.size == 0:
        raise RecordError("the torque step is not in the sample buffer (VF_OUT never turned "
                          "on): the mode change came after the record ended; the link (or the "
                          "twin's clock: `jvl-gym serve --speed 25` advances the motor in steps "
                          "as long as the record) is too coarse, use --speed 5 or less")
    k0 = int(on[0])
    change = np.flatnonzero(vf[k0:] != vf[k0])
    k1 = k0 + int(change[0]) if change.size else vf.size
    if k1 - k0 < n_min:
        raise RecordError(f"only {(k1 - k0) * dt * 1e3:.1f} ms of the torque step are in the "
                          f"sample buffer, {MIN_RECORD_S * 1e3:.0f} ms needed: the mode change "
                          "came late in the record (slow link)")
    x = np.unwrap(np.asarray(eldeg, dtype=float)[k0:k1], period=ELDEG_TURN)
    return x - x[0]


def _basis(t: np.ndarray, w: float, sigma: float, order: int) -> np.ndarray:
    e = np.exp(-sigma * t)
    tt = t / t[-1]
    return np.column_stack([tt**q for q in range(order + 1)]
                           + [e * np.cos(w * t), e * np.sin(w * t)])


def fit_resonance(x: np.ndarray, dt: float, skip_s: float = SKIP_S,
                  order: int = 3) -> ResonanceFit:
    """Fit the polynomial-plus-damped-oscillation model (module docstring; polynomial of
    ``order``) to the angle record ``x`` [counts] sampled every ``dt`` [s] from the step on."""
    x = np.asarray(x, dtype=float)
    k0 = int(round(skip_s / dt))
    t = np.arange(x.size)[k0:] * dt
    y = x[k0:]
    t0 = t[0]
    ts = t - t0

    def rss(w: float, sigma: float) -> tuple[float, np.ndarray, np.ndarray]:
        a = _basis(ts, w, sigma, order)
        coef, *_ = np.linalg.lstsq(a, y, rcond=None)
        r = y - a @ coef
        return float(r @ r), coef, r

    f_hi = min(F_MAX, 0.45 / dt)
    f_lo = max(F_MIN, 1.2 / ts[-1])
    grid = np.geomspace(f_lo, f_hi, 600)
    scores = [rss(2 * math.pi * f, 0.0)[0] for f in grid]
    f0 = grid[int(np.argmin(scores))]

    def resid(p: np.ndarray) -> np.ndarray:
        return rss(p[0], p[1])[2]

    sol = optimize.least_squares(resid, [2 * math.pi * f0, 0.0],
                                 bounds=([2 * math.pi * f_lo * 0.8, -50.0],
                                         [2 * math.pi * f_hi * 1.2, 2e3]),
                                 x_scale=[2 * math.pi * f0 * 0.01, 10.0])
    w, sigma = float(sol.x[0]), float(sol.x[1])
    _, coef, r = rss(w, sigma)
    # covariance of all eight parameters from the full Jacobian
    a = _basis(ts, w, sigma, order)
    e = np.exp(-sigma * ts)
    ca, cb = coef[-2], coef[-1]
    d_w = e * ts * (-ca * np.sin(w * ts) + cb * np.cos(w * ts))
    d_s = -ts * e * (ca * np.cos(w * ts) + cb * np.sin(w * ts))
    jac = np.column_stack([a, d_w, d_s])
    n, npar = y.size, jac.shape[1]
    s2 = float(r @ r) / max(n - npar, 1)
    infl = correlation_inflation(r)
    cov = np.linalg.pinv(jac.T @ jac) * s2 * infl
    amp = math.hypot(ca, cb)
    g = np.array([ca, cb]) / amp if amp > 0 else np.zeros(2)
    amp_sd = math.sqrt(max(float(g @ cov[-4:-2, -4:-2] @ g), 0.0))
    dof = max(int(n / infl) - npar, 1)
    f_sd = math.sqrt(max(cov[-2, -2], 0.0)) / (2 * math.pi)
    return ResonanceFit(f_hz=w / (2 * math.pi), f_sd=f_sd, sigma=sigma,
                        sigma_sd=math.sqrt(max(cov[-1, -1], 0.0)), amplitude=amp,
                        amplitude_sd=amp_sd,
                        periods=w / (2 * math.pi) * ts[-1], rms=math.sqrt(float(r @ r) / n),
                        dof=dof)


def _usable(fit: ResonanceFit, min_periods: float) -> bool:
    return (fit.periods >= min_periods and fit.amplitude > 3.0 * fit.amplitude_sd
            and fit.amplitude > 0.5 and fit.f_sd < 0.05 * fit.f_hz)


def coupling_of(J_m: float, load_ratio: float, f_res: float, zeta: float
                ) -> tuple[float, float, float]:
    """``(J_l, k, d)`` of the two-mass plant with resonance ``f_res`` [Hz], load ratio J_l/J_m
    (> 0) and modal damping ratio ``zeta`` (:func:`jvl_gym.physics.coupling.coupling_for`)."""
    j_l = load_ratio * J_m
    k, d = coupling_for(J_m, j_l, f_res, zeta)
    return j_l, float(k), float(d)


def apparent_resonance(motor: MotorData, regs: Mapping[str, float], load_ratio: float,
                       f_res: float, zeta: float) -> tuple[float, float]:
    """Resonance [Hz] and damping ratio of the motor under its closed current loop (current-loop
    registers ``regs``, back-EMF included, :func:`tuning.models.inner_modes`) for a coupling
    with resonance ``f_res`` [Hz], damping ratio ``zeta`` and load ratio ``load_ratio`` (> 0)."""
    cp = coupling_of(motor.J_m, load_ratio, f_res, zeta)
    s = inner_modes(motor, regs, motor.J_m, 0.0, cp, back_emf=True)
    s = s[s.imag > 0]
    k = int(np.argmin(np.abs(np.abs(s) - 2 * math.pi * f_res)))
    return float(abs(s[k])) / (2 * math.pi), float(-s[k].real / abs(s[k]))


def coupling_resonance(motor: MotorData, regs: Mapping[str, float], load_ratio: float,
                       f_seen: float, zeta_seen: float) -> tuple[float, float]:
    """The coupling's resonance [Hz] and damping ratio whose mode under the closed current loop
    (:func:`apparent_resonance`) is ``f_seen`` [Hz], ``zeta_seen`` (fixed-point iteration; the
    map is close to a constant factor and offset)."""
    f, z = f_seen, max(zeta_seen, ZETA_MIN)
    for _ in range(8):
        fa, za = apparent_resonance(motor, regs, load_ratio, f, z)
        f *= f_seen / fa
        z = max(z + zeta_seen - za, ZETA_MIN)
    return f, z


def estimate_from_fits(fits: Sequence[ResonanceFit], J: float, J_ci: tuple[float, float],
                       motor: MotorData, regs: Mapping[str, float] | None = None
                       ) -> ResonanceEstimate:
    """The estimate from the short record's fit (kept when it holds ≥ 3 periods and a clear
    oscillation) or the long one's, with the load ratio from the identified total inertia
    ``J`` (interval ``J_ci``) [kg·m²] and the rotor inertia ``motor.J_m``. With the current-loop
    registers ``regs`` (:data:`CURRENT_LOOP_KEYS`) of the records the resonance and damping
    are the coupling's (:func:`coupling_resonance`), else the recorded ones."""
    used = 0 if _usable(fits[0], 3.0) else len(fits) - 1
    fit = fits[used]
    detected = _usable(fit, 1.5)
    tq = float(stats.t.ppf(0.5 + LEVEL / 2, fit.dof))
    # the oscillation's frequency is the damped one; the resonance is √(ω_d² + σ²)
    w_d = 2 * math.pi * fit.f_hz
    w_n = math.hypot(w_d, fit.sigma)
    f_seen = w_n / (2 * math.pi)
    zeta_seen = fit.sigma / w_n if w_n > 0 else 0.0
    ratio = max(J / motor.J_m - 1.0, 0.0)
    r_lo, r_hi = max(J_ci[0] / motor.J_m - 1.0, 0.0), max(J_ci[1] / motor.J_m - 1.0, 0.0)
    f_res, zeta = f_seen, max(zeta_seen, ZETA_MIN)
    if regs is not None and ratio > 0 and f_seen > 0:
        f_res, zeta = coupling_resonance(motor, regs, ratio, f_seen, zeta_seen)
    hw = tq * fit.f_sd * f_res / f_seen + SHIFT_ERROR * abs(f_res - f_seen) if f_seen else 0.0
    z_hw = tq * fit.sigma_sd / w_n + SHIFT_ERROR * abs(zeta - zeta_seen) if w_n else 0.0
    f_lo, f_hi = max(f_res - hw, 0.0), f_res + hw
    return ResonanceEstimate(
        f_res=f_res, f_anti=f_res / math.sqrt(1.0 + ratio), load_ratio=ratio, zeta=zeta,
        f_seen=f_seen, zeta_seen=zeta_seen,
        ci={"f_res": (f_lo, f_hi), "load_ratio": (r_lo, r_hi),
            "f_anti": (f_lo / math.sqrt(1.0 + r_hi), f_hi / math.sqrt(1.0 + r_lo)),
            "zeta": (max(zeta - z_hw, ZETA_MIN), zeta + z_hw)},
        detected=detected, fits=list(fits), used=used)


def brake_overshoot(link: LinkTiming, duration_s: float, ts_o: float) -> float:
    """Speed [rad/s] by which the brake may overshoot zero after a step of ``duration_s`` [s]
    to :data:`END_SPEED` over ``link`` (servo sample time ``ts_o`` [s]; module docstring)."""
    return END_SPEED / duration_s * (BRAKE_ROUND_TRIPS * link.motor_s + ts_o)


def stop_speed(m: Any) -> float:
    """The speed [rad/s] below which AT_MODE is left (4.4.5: 300 rpm), of ``m``'s family."""
    facts = record_facts_of(m)
    return float(facts.constants.STOP_SPEED_COUNTS) / facts.ts_o / facts.counts_per_rad


def link_refusal(m: Any, duration_s: float) -> str | None:
    """Why the link of ``m`` cannot keep a step of ``duration_s`` [s] (None: it can, or ``m``
    is a simulator, which has no link)."""
    measure = getattr(m, "measure_link", None)
    if measure is None:
        return None
    link = measure()
    facts = record_facts_of(m)
    over, limit = brake_overshoot(link, duration_s, facts.ts_o), 0.5 * stop_speed(m)
    if over <= limit:
        return None
    return (f"{link.describe()}, so the brake after the {1e3 * duration_s:.0f} ms torque step "
            f"may overshoot by {over:.0f} rad/s, more than the {limit:.0f} rad/s that lets the "
            "motor leave AT_MODE (half the 300 rpm stop speed, manual 4.4.5)")


def step_torques(J: np.ndarray, torque_per_vf: np.ndarray, duration_s: float,
                 end_speed: float = END_SPEED) -> np.ndarray:
    """T_SOLL [VF_OUT units] that brings total inertias ``J`` [kg·m²] to ``end_speed`` [rad/s]
    in ``duration_s`` [s], within 5..1023."""
    t = np.asarray(J) * end_speed / duration_s / np.asarray(torque_per_vf)
    return np.clip(np.round(t), 5, 1023)


def identify_resonance(m: Any, idents: Sequence[Any], short_s: float = SHORT_S,
                       long_s: float = LONG_S) -> list[ResonanceEstimate]:
    """Record the short and the long torque step (module docstring) on every motor of ``m``
    (a ``MotorArray`` or :class:`tuning.serial_source.SerialMotor`) and identify the
    resonance; ``idents`` are the motors' :class:`tuning.autotune.Identification` (their total
    inertia J and its interval, rotor inertia J_m, K_vf).

    Returns one :class:`ResonanceEstimate` per motor, corrected for the current loop with the
    current-loop registers ``m`` has; its ``notes`` name a record the link could not keep.

    Raises
    ------
    LinkTooSlow
        Over a port, the link cannot keep the long record's timing either (module docstring).
    """
    regs = [{k: float(np.asarray(m.read(k))[i]) for k in CURRENT_LOOP_KEYS}
            for i in range(len(idents))]
    J = np.array([i.mechanics.J for i in idents])
    kvf = np.array([i.motor.torque_per_vf for i in idents])
    fits: list[list[ResonanceFit]] = [[] for _ in idents]
    ts_i = record_facts_of(m).ts_i
    notes: list[str] = []
    for dur, order in zip((short_s, long_s), FIT_ORDERS):
        why = link_refusal(m, dur)
        if why is not None:
            notes.append(f"the {1e3 * dur:.0f} ms record was not taken: {why}")
            continue
        for i, x in enumerate(acquire_step_records(m, step_torques(J, kvf, dur), dur)):
            fits[i].append(fit_resonance(x, ts_i, order=order))
    if not fits[0]:
        raise LinkTooSlow(f"the resonance step is refused: {notes[-1]}; use a faster link "
                          "(a higher baud rate) or a slower twin (--speed)")
    out = [estimate_from_fits(f, idn.mechanics.J, idn.mechanics.ci["J"], idn.motor, r)
           for f, idn, r in zip(fits, idents, regs)]
    for est in out:
        est.notes.extend(notes)
    return out
