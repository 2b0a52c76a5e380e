"""What every identification estimate of the toolkit reports about its own fit: the intervals
of its quantities, the fit of the model to the records, the residual check, the samples used
and which quantities are detected.
"""

from __future__ import annotations

from dataclasses import dataclass, field

__all__ = ["FitReport"]


@dataclass(kw_only=True)
class FitReport:
    """The fit quality an estimate carries beside its values (keyword fields, after the
    estimate's own).

    Attributes
    ----------
    ci : dict
        95 % confidence intervals (lo, hi) of the estimate's quantities.
    nrmse_fit : float
        NRMSE fit [%] (100 = perfect) of the model over all records.
    residual : dict
        Residual check (:func:`tuning.identify_coil.residual_check`): "sigma",
        "box_pierce_p", "max_autocorr", "white" (bool).
    n_samples : int
        Samples used.
    detected : dict
        Quantity → whether its interval lies above 0 (:func:`tuning.intervals.positive`); a
        quantity not detected is reported as 0.
    """

    ci: dict[str, tuple[float, float]]
    nrmse_fit: float
    residual: dict[str, float]
    n_samples: int
    detected: dict[str, bool] = field(default_factory=dict)
