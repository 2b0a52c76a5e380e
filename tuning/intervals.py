"""Confidence intervals of identified quantities that hold under model error and quantisation.

The residuals of a TESTU or TESTA fit are not independent: quantisation of IC_IST and of the
encoder, and what the model leaves out, make them a smooth, correlated sequence within a
record (docs/tuning.md, "Intervals"). The toolkit therefore takes its intervals from the
*spread between whole records*, which are independent of each other:

* **repeated sets** (batch means): K sets of records, each fitted on its own; the interval of
  the mean is ``t₀.₉₇₅(K−1)·sd/√K`` (:func:`batch_means`);
* **delete-one-record jackknife** around a joint fit of K records: ``var = (K−1)/K·Σ(θ₍ᵢ₎ − θ̄)²``
  with Student t on K − 1 degrees of freedom (:func:`jackknife`);
* a **quantisation floor**: records taken under identical conditions share their quantisation
  pattern unless noise dithers it (the digital twin without noise repeats a record exactly), so
  the between-record spread can be zero while the quantisation error is not. The variance of one
  set's fit under white quantisation noise of 1/12 LSB² (× the correlation inflation of
  :func:`tuning.identify_coil.correlation_inflation`) is added to the spread's variance and is
  not divided by K (:func:`combined_halfwidth`).

A quantity that must be positive (R, L, J, friction) whose interval reaches zero or below is
*not detected*: :func:`positive` reports it as 0 with the interval ``[0, hi]`` (the truth is
≥ 0, so clipping the interval loses no coverage) and ``detected = False``. Friction is never
reported negative.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy import stats

__all__ = ["LEVEL", "QUANTISATION_VARIANCE", "Bounded", "batch_means", "jackknife",
           "combined_halfwidth", "positive", "student_halfwidth"]

LEVEL: float = 0.95  #: confidence level of every interval the toolkit reports
QUANTISATION_VARIANCE: float = 1.0 / 12.0  #: variance of rounding to 1 LSB [LSB²]


@dataclass(frozen=True)
class Bounded:
    """An estimate of a quantity that must be positive, after the detection rule.

    Attributes
    ----------
    value : float
        The estimate, 0 when not detected (never negative).
    interval : (float, float)
        95 % interval, its lower end clipped at 0.
    detected : bool
        The unclipped interval lies above 0.
    raw : float
        The estimate before the rule (may be negative), for diagnostics.
    """

    value: float
    interval: tuple[float, float]
    detected: bool
    raw: float


def student_halfwidth(sd: float, dof: float, level: float = LEVEL) -> float:
    """Half-width ``t_{(1+level)/2}(dof)·sd`` of a two-sided interval (``dof = inf``: normal)."""
    q = (1.0 + level) / 2.0
    tq = float(stats.norm.ppf(q)) if not math.isfinite(dof) else float(stats.t.ppf(q, dof))
    return tq * sd


def batch_means(values: Sequence[float] | np.ndarray) -> tuple[float, float, int]:
    """Mean, variance of the mean and degrees of freedom of K repeated-set estimates.

    Parameters
    ----------
    values : array_like, shape (K,)
        One estimate per independent set of records.

    Returns
    -------
    mean : float
    var_mean : float
        ``sd²/K`` (sample variance, ddof = 1).
    dof : int
        K − 1.
    """
    v = np.asarray(values, dtype=float)
    k = v.size
    if k < 2:
        raise ValueError("batch means need at least two sets")
    return float(v.mean()), float(v.var(ddof=1)) / k, k - 1


def jackknife(full: np.ndarray, leave_one_out: np.ndarray) -> tuple[np.ndarray, int]:
    """Delete-one-group jackknife variance of a joint fit (Efron & Stein; Quenouille).

    Parameters
    ----------
    full : ndarray, shape (p,)
        The estimate from all K groups (records).
    leave_one_out : ndarray, shape (K, p)
        The estimate without group i, row i.

    Returns
    -------
    var : ndarray, shape (p,)
        ``(K−1)/K·Σᵢ(θ₍ᵢ₎ − θ̄)²``.
    dof : int
        K − 1.
    """
    loo = np.atleast_2d(np.asarray(leave_one_out, dtype=float))
    k = loo.shape[0]
    if k < 2:
        raise ValueError("the jackknife needs at least two groups")
    dev = loo - loo.mean(axis=0)
    assert np.asarray(full).shape[-1] == loo.shape[1]
    return (k - 1) / k * np.sum(dev**2, axis=0), k - 1


def combined_halfwidth(var_spread: float, dof: int, var_floor: float,
                       level: float = LEVEL) -> float:
    """Half-width of spread + quantisation floor: ``√((t_ν·sd_s)² + (z·sd_f)²)``.

    The spread's variance ``var_spread`` has ``dof`` degrees of freedom (Student t), the floor
    ``var_floor`` is known (normal quantile z). Never narrower than either part alone.
    """
    hs = student_halfwidth(math.sqrt(max(var_spread, 0.0)), dof, level)
    hf = student_halfwidth(math.sqrt(max(var_floor, 0.0)), math.inf, level)
    return math.hypot(hs, hf)


def positive(value: float, lo: float, hi: float) -> Bounded:
    """Apply the detection rule to a quantity that must be positive (module docstring)."""
    detected = bool(lo > 0.0 and value > 0.0)
    if detected:
        return Bounded(float(value), (float(lo), float(hi)), True, float(value))
    return Bounded(0.0, (0.0, max(float(hi), 0.0)), False, float(value))
