"""Identify the coil (line-to-line R, L and the PWM delay) from TESTU records (manual 4.4.9).

Model (ZOH-exact, docs/model.md §5.1 and §6): the a–c line current, in ADC counts, obeys

    i(k+1) = a·i(k) + g(1 − a)·u(k − d),    IC_IST(k) = −i(k),    i(0) = i₀,

with u = UA_VAL = UMEAS [PWM counts], ``a = exp(−R·TS_I/L)``, ``g = k_u/(R·A_count)`` (ADC counts
per PWM count; R, L per phase: the line-to-line circuit has 2R, 2L and sees 2·u·k_u) and
``d`` ∈ {0, 1, 2} inner samples of PWM/computation delay.

Method: for each d, an ARX least-squares fit gives a start; an output-error fit
(``scipy.optimize.least_squares`` on the simulated output, parameters a, g, i₀) refines it.
The delay with the smallest output error wins (it is an integer: the record's first
non-zero sample fixes it). Confidence intervals (:mod:`tuning.intervals`): one or two records,
``s²·(1 + 2Σρ)·(JᵀJ)⁻¹`` at the optimum with Student-t quantiles, propagated to R and L (delta
method); three or more, the delete-one-record jackknife plus the quantisation floor. Fit
quality: NRMSE fit ``100·(1 − ‖y − ŷ‖/‖y − ȳ‖)`` %, and a Box–Pierce whiteness test of the
residuals.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import control as ct
import numpy as np
from scipy import optimize, stats

from .fit_report import FitReport
from .intervals import (
    LEVEL,
    QUANTISATION_VARIANCE,
    combined_halfwidth,
    jackknife,
    positive,
    student_halfwidth,
)
from .models import MotorData
from .records import Record, validated

__all__ = ["CoilEstimate", "identify_coil", "residual_check"]


@dataclass
class CoilEstimate(FitReport):
    """Identified coil, with its fit report (:class:`tuning.fit_report.FitReport`).

    Attributes
    ----------
    pole, gain : float
        a (dimensionless) and g [ADC counts per PWM count], the register-unit model.
    delay : int
        PWM delay d [inner samples].
    R_phase, L_phase : float
        Per-phase resistance [Ω] and inductance [H] (through k_u and A_count of the motor type).
    R_line, L_line : float
        Line-to-line values 2R [Ω], 2L [H].
    ts_i : float
        The records' sample time, the family's current-loop sample time [s].
    fitted : list of ndarray
        Model IC_IST [ADC counts] of each record, shape (n_r,).
    ci, nrmse_fit, residual, n_samples, detected
        The fit report: intervals of "pole", "gain", "R_phase", "L_phase", "R_line",
        "L_line" and "delay" (the plausible delays, inner samples); the residual's "sigma"
        in ADC counts; "R_phase", "L_phase" detected or not.
    """

    pole: float
    gain: float
    delay: int
    R_phase: float
    L_phase: float
    ts_i: float
    fitted: list[np.ndarray] = field(default_factory=list, repr=False)

    @property
    def R_line(self) -> float:
        """Line-to-line resistance 2R [Ω]."""
        return 2.0 * self.R_phase

    @property
    def L_line(self) -> float:
        """Line-to-line inductance 2L [H]."""
        return 2.0 * self.L_phase

    def model(self) -> ct.TransferFunction:
        """Per-phase U [PWM counts] → I_IST [ADC counts]: ``g(1−a)/(z^d (z−a))`` at
        :attr:`ts_i`."""
        den = np.polymul([1.0, -self.pole], np.r_[1.0, np.zeros(self.delay)])
        return ct.tf([self.gain * (1 - self.pole)], den, self.ts_i)

    def motor(self, base: MotorData) -> MotorData:
        """``base`` with the identified R, L and delay."""
        return base.with_(R_phase=self.R_phase, L_phase=self.L_phase, pwm_delay=self.delay)


def _simulate(a: float, g: float, i0: float, u: np.ndarray, d: int) -> np.ndarray:
    n = u.size
    i = np.empty(n)
    i[0] = i0
    b = g * (1.0 - a)
    for k in range(n - 1):
        i[k + 1] = a * i[k] + b * (u[k - d] if k - d >= 0 else 0.0)
    return -i


def _arx(recs: Sequence[Record], d: int) -> tuple[float, float]:
    rows, rhs = [], []
    for r in recs:
        y, u = r.output, r.input
        for k in range(max(1, d + 1), r.n):
            rows.append([y[k - 1], -u[k - 1 - d]])
            rhs.append(y[k])
    theta, *_ = np.linalg.lstsq(np.array(rows), np.array(rhs), rcond=None)
    a = float(np.clip(theta[0], 1e-3, 0.9999))
    g = float(theta[1] / (1 - a))
    return a, g


def correlation_inflation(res: np.ndarray, n_records: int = 1) -> float:
    """Variance inflation ``1 + 2·Σ ρ_k`` for autocorrelated residuals (effective sample size).

    Model errors (quantisation, unmodelled dynamics) make residuals correlated; the plain
    ``s²(JᵀJ)⁻¹`` then understates the uncertainty. The sum runs over lags until the first
    non-positive autocorrelation (at most n/4). Returns a factor ≥ 1.
    """
    res = np.asarray(res, dtype=float)
    parts = np.array_split(res, max(n_records, 1))
    num = 0.0
    for e in parts:
        e = e - e.mean()
        var = float(e @ e)
        if var == 0.0 or e.size < 8:
            continue
        acc = 0.0
        for k in range(1, e.size // 4):
            rho = float(e[:-k] @ e[k:]) / var
            if rho <= 0:
                break
            acc += rho
        num = max(num, acc)
    return 1.0 + 2.0 * num


def residual_check(res: np.ndarray, n_params: int, max_lag: int | None = None
                   ) -> dict[str, float]:
    """Box–Pierce whiteness test of residuals (``p > 0.05`` ⇒ no evidence against whiteness)."""
    res = np.asarray(res, dtype=float)
    n = res.size
    e = res - res.mean()
    var = float(e @ e) / max(n, 1)
    lags = max(1, min(max_lag or 10, n // 4))
    if var == 0.0:
        return {"sigma": 0.0, "box_pierce_p": 1.0, "max_autocorr": 0.0, "white": True}
    r = np.array([float(e[:-k] @ e[k:]) / (n * var) for k in range(1, lags + 1)])
    q = n * float(r @ r)
    dof = max(1, lags - 0)
    p = float(stats.chi2.sf(q, dof))
    return {"sigma": math.sqrt(float(res @ res) / max(n - n_params, 1)), "box_pierce_p": p,
            "max_autocorr": float(np.max(np.abs(r))), "white": bool(p > 0.05)}


def _fit(recs: Sequence[Record], d: int, scale: float) -> optimize.OptimizeResult:
    """Output-error fit of (a, g, i₀ per record) for PWM delay ``d`` (ARX start)."""
    a0, g0 = _arx(recs, d)
    if not (0.0 < a0 < 1.0) or g0 <= 0:
        a0, g0 = 0.9, scale / max(1.0, float(np.max(np.abs(recs[0].input))))

    def resid(x: np.ndarray) -> np.ndarray:
        a, g = x[0], x[1]
        return np.concatenate([_simulate(a, g, x[2 + j], r.input, d) - r.output
                               for j, r in enumerate(recs)])

    x0 = np.r_[a0, g0, [-r.output[0] for r in recs]]
    lo = np.r_[1e-6, 1e-9, [-np.inf] * len(recs)]
    hi = np.r_[1.0 - 1e-12, np.inf, [np.inf] * len(recs)]
    return optimize.least_squares(resid, np.clip(x0, lo + 1e-9, hi - 1e-9), bounds=(lo, hi),
                                  x_scale="jac", xtol=1e-14, ftol=1e-14, gtol=1e-14)


def _phys(a: float, g: float, md: MotorData) -> tuple[float, float]:
    """(R, L) per phase [Ω, H] from the register-unit model: ``R = k_u/(g·A_count)``,
    ``L = −R·TS_I/ln a`` with the family's TS_I (module docstring)."""
    R = md.volts_per_count / (g * md.amps_per_count)
    return R, -R * md.family.inner_dt / math.log(a)


def identify_coil(records: Record | Sequence[Record], motor: MotorData | str,
                  delays: Sequence[int] = (0, 1, 2)) -> CoilEstimate:
    """Estimate R, L and the PWM delay from one or more TESTU records.

    Parameters
    ----------
    records : Record or sequence of Record
        TESTU records (validated here). Several records share a, g, d; each has its own i₀.
    motor : MotorData or str
        Motor type (for k_u = U_supply/2/1023 and A_count, docs/model.md §3, §15).
    delays : sequence of int
        Candidate PWM delays [inner samples].

    Returns
    -------
    CoilEstimate
        Intervals (docs/tuning.md, "Intervals"): with one or two records the fit's
        ``s²·(1 + 2Σρ)·(JᵀJ)⁻¹`` (the residual includes the quantisation); with K ≥ 3 records
        the delete-one-record jackknife (t, K − 1 dof) plus the quantisation floor of one
        record (:mod:`tuning.intervals`). The delay's interval is the set of delays whose
        output error is not significantly larger than the best one's (likelihood ratio,
        χ²₁ at 95 %, residual variance × the correlation inflation).

    Raises
    ------
    RecordError
        A record is not a valid TESTU record (:func:`tuning.records.validate`).
    """
    md = motor if isinstance(motor, MotorData) else MotorData.from_config(motor)
    recs = validated(records, "TESTU", md, "identify_coil")
    ts_i = md.family.inner_dt
    y_all = np.concatenate([r.output for r in recs])
    scale = max(1.0, float(np.max(np.abs(y_all))))

    fits = {d: _fit(recs, d, scale) for d in delays}
    sses = {d: float(f.fun @ f.fun) for d, f in fits.items()}
    d = min(delays, key=lambda k: (sses[k] * (1 - 1e-9), k))
    sol = fits[d]
    sse = sses[d]
    n = y_all.size
    p = sol.x.size
    a, g = float(sol.x[0]), float(sol.x[1])
    dof = max(n - p, 1)
    s2 = sse / dof
    infl = correlation_inflation(sol.fun, len(recs))
    jac = sol.jac
    try:
        cov = s2 * infl * np.linalg.inv(jac.T @ jac)
    except np.linalg.LinAlgError:
        cov = np.full((p, p), np.inf)

    R, L = _phys(a, g, md)
    ln_a = math.log(a)
    # delta method: x = (a, g) → (R, L)
    jr = np.array([0.0, -R / g])
    jl = np.array([R * ts_i / (a * ln_a**2), (L / R) * (-R / g)])
    val = {"pole": a, "gain": g, "R_phase": R, "L_phase": L}
    grads = {"pole": np.array([1.0, 0.0]), "gain": np.array([0.0, 1.0]), "R_phase": jr,
             "L_phase": jl}
    if len(recs) >= 3:
        # whole-record jackknife around the joint fit + the quantisation floor of one record
        loo = []
        for i in range(len(recs)):
            x = _fit([r for j, r in enumerate(recs) if j != i], d, scale).x
            loo.append([x[0], x[1], *_phys(float(x[0]), float(x[1]), md)])
        var_j, kdof = jackknife(np.array([a, g, R, L]), np.array(loo))
        rows = slice(0, recs[0].n)
        j1 = jac[rows][:, [0, 1, 2]]
        try:
            cov_q = QUANTISATION_VARIANCE * infl * np.linalg.inv(j1.T @ j1)[:2, :2]
        except np.linalg.LinAlgError:
            cov_q = np.zeros((2, 2))
        hw = {}
        for k, name in enumerate(("pole", "gain", "R_phase", "L_phase")):
            gr = grads[name]
            hw[name] = combined_halfwidth(float(var_j[k]), kdof,
                                          max(float(gr @ cov_q @ gr), 0.0))
    else:
        c2 = cov[:2, :2]
        hw = {name: student_halfwidth(math.sqrt(max(float(gr @ c2 @ gr), 0.0)), dof)
              for name, gr in grads.items()}
    ci = {k: (val[k] - hw[k], val[k] + hw[k]) for k in val}
    detected = {}
    for k in ("R_phase", "L_phase"):
        b = positive(val[k], *ci[k])
        ci[k] = b.interval
        detected[k] = b.detected
    ci["R_line"] = (2 * ci["R_phase"][0], 2 * ci["R_phase"][1])
    ci["L_line"] = (2 * ci["L_phase"][0], 2 * ci["L_phase"][1])
    # delay: every candidate whose extra output error is within χ²₁(95 %) of the best
    crit = float(stats.chi2.ppf(LEVEL, 1)) * s2 * infl
    plausible = [k for k in delays if sses[k] - sse <= crit]
    ci["delay"] = (float(min(plausible)), float(max(plausible)))
    fitted = [_simulate(a, g, sol.x[2 + j], r.input, d) for j, r in enumerate(recs)]
    yhat = np.concatenate(fitted)
    den = float(np.linalg.norm(y_all - y_all.mean()))
    fit = 100.0 * (1.0 - float(np.linalg.norm(y_all - yhat)) / den) if den > 0 else math.nan
    return CoilEstimate(pole=a, gain=g, delay=int(d), R_phase=R, L_phase=L, ts_i=ts_i, ci=ci,
                        nrmse_fit=fit, residual=residual_check(y_all - yhat, p), n_samples=n,
                        fitted=fitted, detected=detected)
