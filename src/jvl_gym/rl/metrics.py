"""A task's engineering metrics, computed from an episode's trace.

The envs report these in ``info`` at an episode's end, from their own state; a deployed policy
has only what it read over the link. :func:`engineering_metrics` computes the same figures from
a trace (name -> array, one row per control period), so a simulated episode, an episode over
the link model and one deployed against a twin or a motor are judged alike (docs/envs.md,
"Engineering metrics"):

- Positioning: ``settle_time`` [s], the time from the start to the last sample with the
  position error outside the in-position window (INPOSWIN, MAC050–141 manual register 33),
  after which it stays inside to the end (the whole trace when it ends outside);
  ``final_error`` [turns], |error| at the end; ``overshoot`` [turns], the largest excursion
  past the target; ``copper_loss`` [J], from a ``copper`` column (an energy account) where the
  trace has one, else NaN.
- GearSync: ``tension_error`` and ``tension_error_max`` [%], the mean and largest |tension
  error| (from a ``tension_error`` column in %); ``copper_loss`` as above.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

__all__ = ["engineering_metrics", "settle_time", "METRICS"]

#: the metrics of each env id (name -> what it is, with its unit), as its ``episode_stats``
METRICS: dict[str, dict[str, str]] = {
    "jvl_gym/Positioning-v0": {"settle_time": "settle time [s]",
                               "final_error": "final error (abs.) [turns]",
                               "overshoot": "overshoot [turns]",
                               "copper_loss": "copper loss [J]"},
    "jvl_gym/GearSync-v0": {"tension_error": "mean tension error (abs.) [%]",
                            "tension_error_max": "max tension error (abs.) [%]",
                            "copper_loss": "copper loss [J]"},
}


def settle_time(t: np.ndarray, error: np.ndarray, window: float) -> float:
    """Time [s] from ``t[0]`` (the episode's start) to the last sample with ``|error|``
    outside ``window``: after it the error stays inside to the end (0 when no sample is
    outside; the trace's length when the last one is), as the env counts it."""
    t = np.asarray(t, dtype=np.float64)
    outside = np.flatnonzero(np.abs(np.asarray(error, dtype=np.float64)) > window)
    if outside.size == 0:
        return 0.0
    return float(t[int(outside[-1])] - t[0])


def _copper(trace: Mapping[str, np.ndarray]) -> float:
    copper = trace.get("copper")
    if copper is None or len(copper) == 0:
        return float("nan")
    return float(np.asarray(copper)[-1] - np.asarray(copper)[0])


def engineering_metrics(env_id: str, trace: Mapping[str, np.ndarray],
                        window: float | None = None) -> dict[str, float]:
    """The metrics of ``env_id`` (:data:`METRICS`) of one episode's ``trace``.

    Parameters
    ----------
    env_id : str
        A key of :data:`METRICS`.
    trace : mapping of str to array
        Columns of one episode, a row per control period: ``t`` [s] and, for Positioning,
        ``error`` [turns] (target − position) and ``direction`` (+1/−1, the move's sign) or
        ``target`` [turns]; for GearSync ``tension_error`` [%]; optionally ``copper`` [J].
    window : float, optional
        Positioning's in-position window [turns].

    Raises
    ------
    KeyError
        An env without stated metrics, or a trace without a needed column (one line).
    """
    if env_id not in METRICS:
        raise KeyError(f"no engineering metrics stated for {env_id}; known: "
                       f"{', '.join(METRICS)}")
    if env_id == "jvl_gym/Positioning-v0":
        if window is None:
            raise KeyError("Positioning's metrics need the in-position window (window=)")
        error = np.asarray(trace["error"], dtype=np.float64)
        direction = (np.asarray(trace["direction"], dtype=np.float64) if "direction" in trace
                     else np.sign(np.asarray(trace["target"], dtype=np.float64)) + 0.0)
        direction = np.where(direction == 0, 1.0, direction)
        past = -direction * error  # > 0 past the target
        return {"settle_time": settle_time(trace["t"], error, window),
                "final_error": float(abs(error[-1])),
                "overshoot": float(max(0.0, past.max())),
                "copper_loss": _copper(trace)}
    tension = np.abs(np.asarray(trace["tension_error"], dtype=np.float64))
    return {"tension_error": float(tension.mean()), "tension_error_max": float(tension.max()),
            "copper_loss": _copper(trace)}
