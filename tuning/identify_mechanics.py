"""Identify inertia, KVOUT and friction from TESTA records (manual 4.4.10, 3.2.13).

Model: from rest, constant torque ``K_vf·T_SOLL`` (K_vf = 1.5·p·λ·A_count·AMPLITUDE, manual 4.3)
acting from ``t = δ`` (δ: the current loop's onset, in outer samples, shared by all records)::

    J dω/dt = K_vf·T_SOLL − b·ω − T_c      (ω > 0; TESTA torque is positive)

so the encoder position (the running sum of V_IST, which undoes the velocity quantisation
except for ±1 count) is, with β = b/J and α = (K_vf·T_SOLL − T_c)/J,

    P(t) = C + (4096/2π)·α/β·(t' − (1 − e^{−βt'})/β),   t' = max(t − δ, 0).

One torque level cannot separate J from T_c (only α is observable): the *two-level procedure*
records TESTA at T₁ and T₂ ≈ T₁/2 and fits J, T_c, b, δ and one offset C per record jointly
(``scipy.optimize.least_squares``). With ``coulomb=False`` (friction known to be negligible) a
single record suffices.

Intervals (:mod:`tuning.intervals`, docs/tuning.md "Intervals"): the residuals are dominated by
model error the electrical model leaves out (current and commutation quantisation, which the
current noise dithers), strongly correlated within a record, so ``s²(JᵀJ)⁻¹`` is far too
narrow. The recommended procedure repeats the two levels K times; each set is fitted alone and
the interval comes from the spread between the sets (batch means, Student t with K − 1 degrees
of freedom) plus the encoder quantisation floor of one set (which repetitions without noise do
not average out). Friction whose interval reaches 0 is reported as not detected, value 0.
"""

from __future__ import annotations

import cmath
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np
from scipy import optimize

from jvl_gym.families import TuningSpec

from .fit_report import FitReport
from .identify_coil import correlation_inflation, residual_check
from .intervals import (
    QUANTISATION_VARIANCE,
    batch_means,
    combined_halfwidth,
    positive,
    student_halfwidth,
)
from .models import MotorData
from .records import Record, RecordError, record_registers, validated

__all__ = ["MechanicsEstimate", "identify_mechanics", "position_model", "two_level_torques",
           "electrical_position", "refine_electrical", "repeat_sets", "coil_uncertainty",
           "combine_sets"]


_CURRENT_KEYS = ("KIFX2", "KIFX1", "KIFY1", "KIFY0", "KIB1", "KIB0")


@dataclass
class MechanicsEstimate(FitReport):
    """Identified mechanics, with its fit report (:class:`tuning.fit_report.FitReport`).

    Attributes
    ----------
    J : float
        Total inertia [kg·m²].
    kvout : float
        KVOUT = J/J_m (manual 3.2.13).
    viscous : float
        b [N·m·s/rad].
    coulomb : float
        T_c [N·m].
    delay : float
        Torque onset δ [outer samples].
    ci, nrmse_fit, residual, n_samples, detected
        The fit report: intervals of "J", "kvout", "viscous", "coulomb"; the fit of V_IST
        over all records (the fitted position differenced); the position fit's residual
        check; "J", "coulomb", "viscous" detected or not (one not detected is reported as 0
        with the interval [0, hi]).
    fitted_velocity : list of ndarray
        Model V_IST [counts/sample] of each record.
    repeats : int
        K, the number of repeated sets the estimate averages (1: one fit).
    J_repeats : list of float
        J [kg·m²] of each repeated set (K > 1).
    raw : dict
        "J", "coulomb", "viscous" before the detection rule (may be negative) [SI].
    quantisation_var : dict
        Variance of "J", "coulomb", "viscous" [SI²] from the encoder's 1-count quantisation
        (1/12 count² per sample) for this fit (the quantisation floor of
        :mod:`tuning.intervals`).
    coil_var : dict
        Variance of "J", "coulomb", "viscous" [SI²] caused by the coil identification's
        uncertainty (``coil_sd`` of :func:`identify_mechanics`), shared by all sets.
    """

    J: float
    kvout: float
    viscous: float
    coulomb: float
    delay: float
    fitted_velocity: list[np.ndarray] = field(default_factory=list, repr=False)
    repeats: int = 1
    J_repeats: list[float] = field(default_factory=list)
    raw: dict[str, float] = field(default_factory=dict)
    quantisation_var: dict[str, float] = field(default_factory=dict, repr=False)
    coil_var: dict[str, float] = field(default_factory=dict, repr=False)


def position_model(t: np.ndarray, alpha: float, beta: float, delay: float, *,
                   spec: TuningSpec) -> np.ndarray:
    """Position [counts] at times ``t`` [s] from rest: module docstring (without C); ``delay``
    in servo samples and the counts of the family's ``spec``."""
    tp = np.maximum(np.asarray(t, dtype=float) - delay * spec.outer_dt, 0.0)
    if abs(beta) * float(np.max(tp, initial=0.0)) < 1e-6:
        term = 0.5 * tp**2 - beta * tp**3 / 6.0
    else:
        term = (tp + np.expm1(-beta * tp) / beta) / beta
    return spec.counts_per_rad * alpha * term


class CurrentLoopModel(NamedTuple):
    """The coefficients of the current loop, coil and rotor model that
    :func:`electrical_position` steps (and the rounded loop of
    :mod:`tuning.loop_quantisation`), from the motor data and the current filter registers."""

    h: float  #: inner (current-loop) sample time [s]
    per_outer: int  #: inner samples per outer sample
    R: float  #: phase resistance [ohm]
    decay: float  #: the coil's decay per inner sample, exp(−R·h/L)
    k_u: float  #: phase volts per PWM count [V]
    amps: float  #: phase amperes per current count [A]
    pp: int  #: pole pairs
    lam: float  #: flux linkage [V·s/rad]
    kt: float  #: torque constant [N·m/A]
    x2: float  #: KIFX2
    x1: float  #: KIFX1
    y1: float  #: KIFY1
    y0: float  #: KIFY0
    b1: float  #: KIB1
    b0: float  #: KIB0


def current_loop_model(motor: MotorData, current_regs: Mapping[str, float]) -> CurrentLoopModel:
    """The :class:`CurrentLoopModel` of ``motor`` (its family's sample times) with the current
    filter registers ``current_regs`` (KIFX2, KIFX1, KIFY1, KIFY0, KIB1, KIB0)."""
    fam = motor.family
    h = fam.inner_dt
    R, L = motor.R_phase, motor.L_phase
    return CurrentLoopModel(
        h, int(round(fam.outer_dt / h)), R, math.exp(-R * h / L), motor.volts_per_count,
        motor.amps_per_count, motor.pole_pairs, motor.flux_linkage, motor.torque_constant,
        *(float(current_regs[k]) for k in ("KIFX2", "KIFX1", "KIFY1", "KIFY0", "KIB1", "KIB0")))


def _numpy(x: Any) -> bool:
    """Whether ``x`` is a NumPy scalar or array (its arithmetic is NumPy's)."""
    return isinstance(x, (np.generic, np.ndarray))


def electrical_position(n: int, t_soll: float, J: float, b: float, tc: float,
                        motor: MotorData, current_regs: Mapping[str, float],
                        phase_comp: float = 0.0) -> np.ndarray:
    """Position [counts] of a torque step from rest with the current loop and the back-EMF
    modelled (a TESTA run, or a MAC800-family step of VF_OUT in analogue torque mode).

    The three per-phase loops are real LTI filters, so they act on the current space vector
    directly (stationary frame): reference ``AMPLITUDE·T_SOLL/amplitude_vf·e^{jθ_e}`` advanced
    by ``pp·h·PHASE_COMP·ω`` [rad] (manual 4.3, 3.2.126; the MAC800's register 173 advances by
    ``V_ELDEG·PHASE_COMP/256`` electrical units, the same with ``phase_comp`` = PHASE_COMP/256),
    IB and IF as in the firmware (no rounding; both families' current filters have this
    structure, MAC800 registers 144–149), the PWM delay, the coil
    ``L ds/dt = k_u s_u − R s − ω_e λ e^{jθ_e}`` (exact exponential with the back-EMF at
    mid-step), torque ``1.5pλ·Re(s e^{−jθ_e})``, the rotor with b and T_c. The sample times,
    the encoder scale and ``amplitude_vf`` are the motor family's (``motor.family``).
    Returns P(k) − P(0) at the n outer samples, shape (n,).
    """
    fam = motor.family
    counts_per_rad = fam.counts_per_rad
    (h, per_outer, R, a, k_u, amps, pp, lam, kt,
     x2, x1, y1, y0, b1, b0) = current_loop_model(motor, current_regs)
    d = int(motor.pwm_delay)
    amp = motor.amplitude * t_soll / fam.amplitude_vf
    adv_per_rad_s = pp * h * phase_comp  # electrical advance [rad] per rad/s of shaft speed
    coil_in = (1.0 - a) / R
    # The loop runs on Python numbers, with the numbers of the same loop run on the argument
    # types: NumPy scalars among them (the optimiser's J, b, T_c, an identified R) make the
    # quantities they reach NumPy scalars, and NumPy divides a complex number by a real one
    # by multiplying with the reciprocal. The n_* flags say which quantities those are; where
    # the coil current is one, meas = s/amps is divided as NumPy divides.
    n_ref, n_coil, n_emf, n_kt, n_acc, n_tc = (
        _numpy(amp), _numpy(a) or _numpy(coil_in) or _numpy(k_u), _numpy(pp) or _numpy(lam),
        _numpy(kt), _numpy(b) or _numpy(J) or _numpy(h), _numpy(tc))
    amp, a, coil_in, k_u, lam, kt, amps, h = (float(v) for v in (amp, a, coil_in, k_u, lam,
                                                                    kt, amps, h))
    J, b, tc, adv_per_rad_s = float(J), float(b), float(tc), float(adv_per_rad_s)
    rat = 0.0 / amps  # NumPy's division by amps + 0j: (re + im·rat)·scl, (im − re·rat)·scl
    scl = 1.0 / (amps + 0.0 * rat)
    half_pp = 0.5 * pp
    exp = cmath.exp
    s = 0j
    m_prev = 0j
    e1 = 0j
    u1 = u2 = 0j
    # the PWM values computed d samples earlier (d = 0: the present one), with their flags
    pend = [(0j, False)] * d
    n_s = n_m_prev = n_e1 = n_u1 = n_u2 = n_omega = False
    theta = omega = 0.0
    out = np.empty(n)
    for k in range(n):
        out[k] = theta * counts_per_rad
        for _ in range(per_outer):
            th_e = pp * theta
            if n_s:
                meas = complex((s.real + s.imag * rat) * scl, (s.imag - s.real * rat) * scl)
            else:
                meas = s / amps
            ref = amp * exp(1j * (th_e + adv_per_rad_s * omega))
            e = ref - (b1 * meas + b0 * m_prev)
            n_e = n_ref or n_s or n_m_prev
            u = x2 * e + x1 * e1 + y1 * u1 + y0 * u2
            n_u = n_e or n_e1 or n_u1 or n_u2
            e1, u2, u1, m_prev = e, u1, u, meas
            n_e1, n_u2, n_u1, n_m_prev = n_e, n_u1, n_u, n_s
            if d:
                pend.append((u, n_u))
                ua, n_ua = pend.pop(0)
            else:
                ua, n_ua = u, n_u
            th_mid = th_e + half_pp * omega * h
            emf = pp * omega * lam * exp(1j * th_mid)
            s_new = a * s + coil_in * (k_u * ua - emf)
            n_s = n_s or n_coil or n_ua or n_emf or n_omega
            torque = kt * ((0.5 * (s + s_new)) * exp(-1j * th_mid)).real
            n_torque = n_kt or n_s
            s = s_new
            if omega > 0 or torque > tc:
                friction, n_friction = tc, n_tc
            else:
                friction, n_friction = torque, n_torque
            acc = (torque - b * omega - friction) / J
            n_omega = n_omega or n_acc or n_torque or n_friction
            omega_new = omega + acc * h
            if 0.0 > omega_new:  # the rotor does not turn backwards
                omega_new, n_omega = 0.0, False
            theta += 0.5 * (omega + omega_new) * h
            omega = omega_new
    return out - out[0]


def two_level_torques(J_guess: float, motor: MotorData, n_samples: int,
                      final_speed_counts: float = 60.0, ratio: float = 0.5) -> tuple[int, int]:
    """T_SOLL levels (T₁, T₂ = ratio·T₁) reaching ``final_speed_counts`` [counts/sample] at the
    end of the record for inertia ``J_guess`` (e.g. from a short pilot record)."""
    ts_o = motor.family.outer_dt
    alpha = final_speed_counts / motor.family.counts_per_rad / ts_o / (n_samples * ts_o)
    t1 = alpha * J_guess / motor.torque_per_vf
    t1 = int(np.clip(round(t1), 4, 1023))
    return t1, int(max(2, round(ratio * t1)))


def identify_mechanics(records: Record | Sequence[Record], motor: MotorData | str,
                       coulomb: bool = True, viscous: bool = True,
                       current_regs: Mapping[str, float] | None = None,
                       phase_comp: float | None = None,
                       coil_sd: Mapping[str, float] | None = None) -> MechanicsEstimate:
    """Estimate J, KVOUT, viscous and Coulomb friction from TESTA records.

    Parameters
    ----------
    records : Record or sequence of Record
        TESTA records from rest. With ``coulomb=True`` at least two different T_SOLL levels
        are required (the two-level procedure). When every level was recorded K ≥ 2 times
        (the recommended procedure, :func:`repeat_sets`), each of the K sets is fitted on its
        own and the result is their mean with the 95 % interval ``t(K−1)·sd/√K`` from the
        spread between the sets (batch means). With one record per level the interval is the
        single fit's ``s²(JᵀJ)⁻¹`` × a correlation inflation, which is too narrow on
        records whose residuals are dominated by model error (docs/tuning.md).
    motor : MotorData or str
        Motor type: K_vf and J_m (KVOUT = J/J_m).
    coulomb, viscous : bool
        Estimate T_c / b (otherwise fixed at 0).
    current_regs : mapping, optional
        The current-loop registers (KIFX2..KIB0) the records were taken with. When given, the
        rigid-model estimate is refined with :func:`electrical_position`, which models the
        current loop's response to the back-EMF: at speed the per-phase loops lag and the torque
        falls below K_vf·T_SOLL (by 5–20 % at a few hundred rpm for an unloaded motor), which
        the rigid model would read as a larger inertia. ``motor`` must then carry the
        (identified) R, L, delay and the AMPLITUDE in use. Default: the registers the records
        carry (``meta["registers"]``, written by :func:`tuning.records.acquire_testa` and kept
        by the CSV files, :func:`tuning.records.record_registers`); the records' AMPLITUDE then
        replaces ``motor.amplitude``. Records without them get the rigid model.
    phase_comp : float, optional
        PHASE_COMP register (3.2.126) in use, for the electrical model; default: the records'
        PHASE_COMP, else 0.
    coil_sd : mapping, optional
        Relative standard deviations of "R_phase" and "L_phase" of ``motor`` (from the TESTU
        intervals, :func:`coil_uncertainty`). The electrical model's torque at speed depends
        on them, the same way in every repeated set, so their effect (first order) is added
        to the interval as a shared term (docs/tuning.md, "Intervals").

    Returns
    -------
    MechanicsEstimate

    Raises
    ------
    RecordError
        Invalid records, or one torque level with ``coulomb=True``.
    """
    md = motor if isinstance(motor, MotorData) else MotorData.from_config(motor)
    recs = validated(records, "TESTA", md, "identify_mechanics")
    carried = record_registers(recs) or {}
    if current_regs is None and all(k in carried for k in _CURRENT_KEYS):
        current_regs = {k: carried[k] for k in _CURRENT_KEYS}
        if "AMPLITUDE" in carried:
            md = md.with_(amplitude=carried["AMPLITUDE"])
    if phase_comp is None:
        phase_comp = carried.get("PHASE_COMP", 0.0)
    sets = repeat_sets(recs)
    if len(sets) < 2:
        return _detect(_identify_set(recs, md, coulomb, viscous, current_regs, phase_comp,
                                     coil_sd), md)
    ests = [_identify_set([recs[i] for i in idx], md, coulomb, viscous, current_regs,
                          phase_comp, coil_sd) for idx in sets]
    return combine_sets(ests, sets, len(recs), md)


def coil_uncertainty(coil: Any) -> dict[str, float]:
    """Relative standard deviations of R_phase and L_phase from a
    :class:`tuning.identify_coil.CoilEstimate`'s 95 % intervals (half-width / 1.96)."""
    out = {}
    for key in ("R_phase", "L_phase"):
        lo, hi = coil.ci[key]
        val = getattr(coil, key)
        out[key] = (hi - lo) / 2.0 / 1.959964 / val if val > 0 else 0.0
    return out


def repeat_sets(recs: Sequence[Record]) -> list[list[int]]:
    """Indices of the repeated sets in ``recs``: the k-th record of every T_SOLL level.

    K = the smallest number of records at any level; records beyond K at a level are left out.
    One set (all records) when some level has a single record.
    """
    by_level: dict[float, list[int]] = {}
    for i, r in enumerate(recs):
        by_level.setdefault(float(np.median(r.input)), []).append(i)
    k = min(len(v) for v in by_level.values())
    if k < 2:
        return [list(range(len(recs)))]
    return [sorted(v[j] for v in by_level.values()) for j in range(k)]


def combine_sets(ests: list[MechanicsEstimate], sets: list[list[int]], n_recs: int,
                 md: MotorData) -> MechanicsEstimate:
    """Batch means over K repeated sets: value = mean, 95 % interval from the spread between
    the sets (t, K − 1 dof) and one set's quantisation floor and coil-uncertainty term
    (:mod:`tuning.intervals`); the detection rule applied.

    ``ests``: the K sets' estimates; ``sets``: the indices of each set's records among the
    ``n_recs`` records (for the fitted velocities); ``md``: J_m (KVOUT).
    """
    k = len(ests)
    vals = {nm: np.array([getattr(e, nm) for e in ests]) for nm in ("J", "viscous", "coulomb")}
    vals["delay"] = np.array([e.delay for e in ests])
    mean = {nm: float(v.mean()) for nm, v in vals.items()}
    ci = {}
    for nm in ("J", "viscous", "coulomb"):
        _, var_mean, dof = batch_means(vals[nm])
        floor = float(np.mean([e.quantisation_var.get(nm, 0.0) + e.coil_var.get(nm, 0.0)
                               for e in ests]))
        h = combined_halfwidth(var_mean, dof, floor)
        ci[nm] = (mean[nm] - h, mean[nm] + h)
    fitted: list[np.ndarray] = [np.zeros(0)] * n_recs
    for e, idx in zip(ests, sets):
        for i, fv in zip(idx, e.fitted_velocity):
            fitted[i] = fv
    out = MechanicsEstimate(J=mean["J"], kvout=mean["J"] / md.J_m, viscous=mean["viscous"],
                            coulomb=mean["coulomb"], delay=mean["delay"], ci=ci,
                            nrmse_fit=float(np.mean([e.nrmse_fit for e in ests])),
                            residual=ests[0].residual,
                            n_samples=sum(e.n_samples for e in ests), fitted_velocity=fitted,
                            repeats=k, J_repeats=[float(x) for x in vals["J"]],
                            quantisation_var={nm: float(np.mean(
                                [e.quantisation_var.get(nm, 0.0) for e in ests]))
                                for nm in ("J", "viscous", "coulomb")},
                            coil_var={nm: float(np.mean([e.coil_var.get(nm, 0.0) for e in ests]))
                                      for nm in ("J", "viscous", "coulomb")})
    return _detect(out, md)


def _detect(est: MechanicsEstimate, md: MotorData) -> MechanicsEstimate:
    """Apply the detection rule to J, T_c and b (:func:`tuning.intervals.positive`). A J that
    is not detected (inconsistent records) is reported as 0, which :mod:`tuning.credibility`
    names ("J = 0 is not positive") and synthesis refuses (KVOUT must be positive)."""
    for nm in ("J", "coulomb", "viscous"):
        raw = est.raw.get(nm, getattr(est, nm))
        lo, hi = est.ci[nm]
        if lo == hi == 0.0 and raw == 0.0:  # not estimated (coulomb=False / viscous=False)
            est.detected[nm] = False
            est.raw[nm] = 0.0
            continue
        b = positive(raw, lo, hi)
        setattr(est, nm, b.value)
        est.ci[nm] = b.interval
        est.detected[nm] = b.detected
        est.raw[nm] = b.raw
    est.kvout = est.J / md.J_m
    est.ci["kvout"] = (est.ci["J"][0] / md.J_m, est.ci["J"][1] / md.J_m)
    return est


def _identify_set(recs: list[Record], md: MotorData, coulomb: bool, viscous: bool,
                  current_regs: Mapping[str, float] | None, phase_comp: float,
                  coil_sd: Mapping[str, float] | None = None) -> MechanicsEstimate:
    """One least-squares fit of J, T_c, b over ``recs`` (rigid start, electrical refinement)."""
    levels = sorted({float(np.median(r.input)) for r in recs})
    if coulomb and len(levels) < 2:
        raise RecordError(
            "one torque level cannot separate the inertia J from Coulomb friction (only "
            "(K·T − T_c)/J is observable): record TESTA at two T_SOLL levels (e.g. T and T/2, "
            "see two_level_torques) or pass coulomb=False if friction is negligible")
    k = md.torque_per_vf
    spec = md.family
    ts_o = spec.outer_dt
    pos = [np.cumsum(r.output) for r in recs]
    times = [np.arange(r.n) * ts_o for r in recs]
    torques = [k * float(np.median(r.input)) for r in recs]

    # start: parabola per record → α_r, δ; then J, T_c from α_r = (K T_r − T_c)/J
    alphas, delays = [], []
    for p, t in zip(pos, times):
        sel = slice(2, None)
        c = np.polyfit(t[sel], p[sel], 2)
        a = 2 * c[0] / spec.counts_per_rad
        alphas.append(a)
        delays.append(float(np.clip(-c[1] / (2 * c[0]) / ts_o, 0.0, 3.0)) if c[0] > 0 else 0.5)
    if coulomb:
        A = np.array([[tq, -1.0] for tq in torques])
        inv_j, tcj = np.linalg.lstsq(A, np.array(alphas), rcond=None)[0]
        j0 = 1.0 / inv_j if inv_j > 0 else md.J_m
        tc0 = max(tcj * j0, 0.0)
    else:
        j0 = float(np.mean([tq / a for tq, a in zip(torques, alphas) if a > 0] or [md.J_m]))
        tc0 = 0.0
    jscale = md.J_m
    names = ["J", "delay"] + (["coulomb"] if coulomb else []) + (["viscous"] if viscous else [])
    x0 = [j0 / jscale, float(np.median(delays))]
    lo, hi = [1e-3, -1.0], [1e4, 5.0]
    if coulomb:
        x0.append(tc0 / k)
        lo.append(-np.inf)
        hi.append(np.inf)
    if viscous:
        x0.append(0.0)
        lo.append(-np.inf)
        hi.append(np.inf)
    nr = len(recs)
    x0 += [float(p[0]) for p in pos]
    lo += [-np.inf] * nr
    hi += [np.inf] * nr

    def unpack(x: np.ndarray) -> tuple[float, float, float, float]:
        J = x[0] * jscale
        i = 2
        tc = 0.0
        b = 0.0
        if coulomb:
            tc = x[i] * k
            i += 1
        if viscous:
            b = x[i] * jscale / ts_o
        return J, float(x[1]), tc, b

    def predict(x: np.ndarray) -> list[np.ndarray]:
        J, dl, tc, b = unpack(x)
        off = len(names)
        return [x[off + j] + position_model(t, (tq - tc) / J, b / J, dl, spec=spec)
                for j, (t, tq) in enumerate(zip(times, torques))]

    def resid(x: np.ndarray) -> np.ndarray:
        return np.concatenate([ph - p for ph, p in zip(predict(x), pos)])

    x0a = np.clip(np.array(x0, dtype=float), np.array(lo) + 1e-9, np.array(hi) - 1e-9)
    sol = optimize.least_squares(resid, x0a, bounds=(lo, hi), x_scale="jac",
                                 xtol=1e-15, ftol=1e-15, gtol=1e-15, max_nfev=2000)
    J, dl, tc, b = unpack(sol.x)
    n = sum(r.n for r in recs)
    if current_regs is not None:
        return refine_electrical([float(np.median(r.input)) for r in recs], pos,
                                 md, current_regs, phase_comp, J, tc, b, coulomb, viscous,
                                 coil_sd)
    p = sol.x.size
    dof = max(n - p, 1)
    s2 = float(sol.fun @ sol.fun) / dof
    try:
        cov = s2 * correlation_inflation(sol.fun, len(recs)) * np.linalg.pinv(sol.jac.T @ sol.jac)
    except np.linalg.LinAlgError:
        cov = np.full((p, p), np.inf)
    sd = np.sqrt(np.maximum(np.diag(cov), 0.0))
    ci: dict[str, tuple[float, float]] = {}
    scale = {"J": jscale, "coulomb": k, "viscous": jscale / ts_o, "delay": 1.0}
    vals = {"J": J, "coulomb": tc, "viscous": b, "delay": dl}
    for i, nm in enumerate(names):
        h = student_halfwidth(sd[i] * scale[nm], dof)
        ci[nm] = (vals[nm] - h, vals[nm] + h)
    qv = _quantisation_var(sol.jac, names, scale)
    if not coulomb:
        ci["coulomb"] = (0.0, 0.0)
    if not viscous:
        ci["viscous"] = (0.0, 0.0)
    ci["kvout"] = (ci["J"][0] / md.J_m, ci["J"][1] / md.J_m)
    fitted_v = [np.diff(np.r_[0.0, ph - ph[0]]) for ph in predict(sol.x)]
    v_all = np.concatenate([r.output for r in recs])
    vh = np.concatenate(fitted_v)
    den = float(np.linalg.norm(v_all - v_all.mean()))
    fit = 100.0 * (1 - float(np.linalg.norm(v_all - vh)) / den) if den > 0 else math.nan
    return MechanicsEstimate(J=J, kvout=J / md.J_m, viscous=b, coulomb=tc, delay=dl, ci=ci,
                             nrmse_fit=fit, residual=residual_check(sol.fun, p), n_samples=n,
                             fitted_velocity=fitted_v, quantisation_var=qv)


def refine_electrical(levels: Sequence[float], pos: Sequence[np.ndarray], md: MotorData,
                      current_regs: Mapping[str, float], phase_comp: float, J0: float,
                      tc0: float, b0: float, coulomb: bool = True, viscous: bool = True,
                      coil_sd: Mapping[str, float] | None = None, free_terms: int = 1
                      ) -> MechanicsEstimate:
    """Output-error fit of J (and T_c, b) with :func:`electrical_position`; offsets projected.

    Parameters
    ----------
    levels : sequence of float
        The torque level of each record (T_SOLL of TESTA, VF_OUT of a MAC800-family step).
    pos : sequence of ndarray
        The position of each record [counts], from the sample the torque is applied in,
        shape (n_r,) each.
    md : MotorData
        The motor with the (identified) coil, PWM delay and AMPLITUDE in use.
    current_regs : mapping
        The current-loop registers KIFX2..KIB0 the records were taken with.
    phase_comp : float
        PHASE_COMP in :func:`electrical_position`'s unit.
    J0, tc0, b0 : float
        Start values [kg·m², N·m, N·m·s/rad] (the rigid fit's).
    coulomb, viscous : bool
        Estimate T_c / b (otherwise fixed at 0).
    coil_sd : mapping, optional
        Relative standard deviations of "R_phase" and "L_phase" (the coil identification's);
        their effect on the estimate is returned in ``coil_var``.
    free_terms : int
        Per record, the polynomial terms in time the residual is made orthogonal to: 1 the
        position offset, 2 also a speed offset (which takes up an onset between two samples).
    """
    k = md.torque_per_vf
    jscale = md.J_m
    bscale = jscale / md.family.outer_dt
    names = ["J"] + (["coulomb"] if coulomb else []) + (["viscous"] if viscous else [])
    levels = [float(v) for v in levels]
    sizes = [int(np.size(p)) for p in pos]

    def unpack(x: np.ndarray) -> tuple[float, float, float]:
        i = 1
        tc = b = 0.0
        if coulomb:
            tc = x[i] * k
            i += 1
        if viscous:
            b = x[i] * bscale
        return x[0] * jscale, tc, b

    def predict(x: np.ndarray, mdx: MotorData = md) -> list[np.ndarray]:
        J, tc, b = unpack(x)
        return [electrical_position(n, t, J, b, tc, mdx, current_regs, phase_comp)
                for n, t in zip(sizes, levels)]

    # per record, an orthonormal basis of the free terms (offset, speed offset)
    bases = [np.linalg.qr(np.vander(np.arange(n, dtype=float), free_terms, increasing=True))[0]
             for n in sizes]

    def resid(x: np.ndarray, mdx: MotorData = md) -> np.ndarray:
        out = []
        for ph, p, q in zip(predict(x, mdx), pos, bases):
            r = ph - p
            out.append(r - q @ (q.T @ r))
        return np.concatenate(out)

    x0 = [J0 / jscale] + ([tc0 / k] if coulomb else []) + ([b0 / bscale] if viscous else [])
    lo = [1e-3] + [-np.inf] * (len(x0) - 1)
    sol = optimize.least_squares(resid, np.maximum(np.array(x0), 2e-3), bounds=(lo, np.inf),
                                 x_scale="jac", diff_step=1e-6, xtol=1e-12, ftol=1e-12)
    J, tc, b = unpack(sol.x)
    n = sum(sizes)
    p = sol.x.size + free_terms * len(sizes)
    dof = max(n - p, 1)
    s2 = float(sol.fun @ sol.fun) / dof
    cov = s2 * correlation_inflation(sol.fun, len(sizes)) * np.linalg.pinv(sol.jac.T @ sol.jac)
    sd = np.sqrt(np.maximum(np.diag(cov), 0.0))
    scale = {"J": jscale, "coulomb": k, "viscous": bscale}
    vals = {"J": J, "coulomb": tc, "viscous": b}
    ci = {}
    for i, nm in enumerate(names):
        h = student_halfwidth(sd[i] * scale[nm], dof)
        ci[nm] = (vals[nm] - h, vals[nm] + h)
    qv = _quantisation_var(sol.jac, names, scale)
    # the coil's uncertainty moves the model's torque deficit the same way in every set:
    # first-order sensitivity of the estimate to R and L, δθ = −J⁺·∂r/∂R·δR (Gauss–Newton)
    cv = dict.fromkeys(names, 0.0)
    if coil_sd:
        base = sol.fun
        jp = np.linalg.pinv(sol.jac)[: len(names)]
        for key, rel in coil_sd.items():
            if not rel > 0.0:
                continue
            h = 1e-3
            dr = (resid(sol.x, md.with_(**{key: getattr(md, key) * (1.0 + h)})) - base) / h
            dth = -(jp @ dr) * rel
            for i, nm in enumerate(names):
                cv[nm] += float(dth[i] * scale[nm]) ** 2
    for nm in names:
        h2 = student_halfwidth(math.sqrt(cv[nm]), math.inf)
        c0, w0 = vals[nm], ci[nm][1] - vals[nm]
        ci[nm] = (c0 - math.hypot(w0, h2), c0 + math.hypot(w0, h2))
    ci.setdefault("coulomb", (0.0, 0.0))
    ci.setdefault("viscous", (0.0, 0.0))
    ci["kvout"] = (ci["J"][0] / md.J_m, ci["J"][1] / md.J_m)
    fitted_v = [np.diff(np.r_[0.0, ph]) for ph in predict(sol.x)]
    v_all = np.concatenate([np.diff(np.r_[p[0], p]) for p in pos])
    vh = np.concatenate(fitted_v)
    den = float(np.linalg.norm(v_all - v_all.mean()))
    fit = 100.0 * (1 - float(np.linalg.norm(v_all - vh)) / den) if den > 0 else math.nan
    return MechanicsEstimate(J=J, kvout=J / md.J_m, viscous=b, coulomb=tc, delay=0.0, ci=ci,
                             nrmse_fit=fit, residual=residual_check(sol.fun, p), n_samples=n,
                             fitted_velocity=fitted_v, quantisation_var=qv, coil_var=cv)


def _quantisation_var(jac: np.ndarray, names: list[str], scale: Mapping[str, float]
                      ) -> dict[str, float]:
    """Variance [SI²] of the fitted parameters under white encoder quantisation noise,
    ``(1/12)·(JᵀJ)⁻¹`` (position residuals in counts; ``jac`` w.r.t. the scaled parameters,
    shape (n, ≥ len(names)), ``names`` its first columns)."""
    try:
        cov = QUANTISATION_VARIANCE * np.linalg.pinv(jac.T @ jac)
    except np.linalg.LinAlgError:
        return {}
    return {nm: float(max(cov[i, i], 0.0)) * scale[nm] ** 2 for i, nm in enumerate(names)}
