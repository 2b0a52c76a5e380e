"""Web line process model: span strain, winder radius, tension and load cell.

Standard web-span model (Whitworth/Shelton, entering strain ``ε_in``, exit roll = winder)::

    L · dε/dt = v2 · (1 − ε) − v1 · (1 − ε_in)

with the master (entry) surface speed ``v1`` and the winder surface speed ``v2``. For speeds
held over a sample it is linear in ε and is integrated exactly:
``ε(t+h) = ε_ss + (ε − ε_ss)·exp(−v2·h/L)`` with the steady state ``ε_ss = 1 − v1(1 − ε_in)/v2``
(``= (v2 − v1)/v2`` for ``ε_in = 0``). Tension ``F = E·A·max(ε, 0)``; the web is slack for
``ε ≤ 0``. The winder radius grows with the wound length ℓ as ``r² = r0² + h·ℓ/π`` (web
thickness h). A load cell measures F through a first-order filter with additive noise.

The functions work on numpy arrays of copies; the ``*_s`` twins are the same formulas per
scalar for the compiled env step (``jvl_gym.envs.gear_sync``), tested equal to them.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..engine.jit import KERNEL

__all__ = ["span_step", "steady_strain", "tension", "winder_radius", "load_cell_step",
           "span_step_s", "tension_s", "winder_radius_s", "load_cell_s"]


def steady_strain(v1: np.ndarray, v2: np.ndarray, strain_in: float | np.ndarray = 0.0
                  ) -> np.ndarray:
    """Steady-state span strain for constant speeds: ``1 − v1·(1 − ε_in)/v2``."""
    return 1.0 - v1 * (1.0 - strain_in) / v2


def span_step(strain: np.ndarray, v1: np.ndarray, v2: np.ndarray, length: np.ndarray,
              dt: float, strain_in: float | np.ndarray = 0.0) -> np.ndarray:
    """Strain after ``dt`` with speeds ``v1``, ``v2`` [m/s] held, span ``length`` [m] (exact)."""
    b = v2 / length
    a = (v2 - v1 * (1.0 - strain_in)) / length
    bdt = b * dt
    small = np.abs(bdt) < 1e-9
    ss = a / np.where(small, 1.0, b)
    exact = ss + (strain - ss) * np.exp(-np.where(small, 0.0, bdt))
    return np.where(small, strain + dt * (a - b * strain), exact)


def tension(strain: np.ndarray, ea: np.ndarray) -> np.ndarray:
    """Web tension ``E·A·max(ε, 0)`` [N]."""
    return ea * np.maximum(strain, 0.0)


def winder_radius(r0: np.ndarray, thickness: np.ndarray, wound: np.ndarray) -> np.ndarray:
    """Winder radius ``sqrt(r0² + h·ℓ/π)`` [m] after winding ``wound`` metres."""
    return np.sqrt(r0 * r0 + thickness * np.maximum(wound, 0.0) / np.pi)


def load_cell_step(measured: np.ndarray, force: np.ndarray, dt: float, tau: float,
                   noise: np.ndarray | float = 0.0) -> np.ndarray:
    """Load-cell reading after ``dt``: first-order filter (time constant ``tau``) of
    ``force + noise``."""
    k = 1.0 - math.exp(-dt / tau) if tau > 0 else 1.0
    return measured + k * (force + noise - measured)


# --- the same model per scalar, for the compiled env step (tested equal to the above) -------
@njit(**KERNEL)
def span_step_s(strain: float, v1: float, v2: float, length: float,
                dt: float) -> float:  # pragma: no cover - compiled
    """:func:`span_step` for one copy with ``ε_in = 0``."""
    b = v2 / length
    a = (v2 - v1) / length
    bdt = b * dt
    if abs(bdt) < 1e-9:
        return strain + dt * (a - b * strain)
    ss = a / b
    return ss + (strain - ss) * math.exp(-bdt)


@njit(**KERNEL)
def tension_s(strain: float, ea: float) -> float:  # pragma: no cover - compiled
    """:func:`tension` for one copy."""
    return ea * max(strain, 0.0)


@njit(**KERNEL)
def winder_radius_s(r0: float, thickness: float, wound: float) -> float:  # pragma: no cover
    """:func:`winder_radius` for one copy."""
    return math.sqrt(r0 * r0 + thickness * max(wound, 0.0) / math.pi)


@njit(**KERNEL)
def load_cell_s(measured: float, force: float, k: float) -> float:  # pragma: no cover
    """One load-cell filter step with gain ``k = 1 − exp(−dt/τ)``."""
    return measured + k * (force - measured)
