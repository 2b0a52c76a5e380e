"""A load behind an elastic coupling (two-mass plant, docs/model.md §5.2) from its modal figures.

The coupling of stiffness k [N·m/rad] and damping d [N·m·s/rad] between a rotor J_m and a load
J_l [kg·m²] has the natural frequency ``ω_n = √(k (1/J_m + 1/J_l))`` (the resonance the motor
shaft sees, with the anti-resonance ``ω_n / √(1 + J_l/J_m)`` below it) and the modal damping
ratio ``ζ = d (1/J_m + 1/J_l) / (2 ω_n)``. :func:`coupling_for` inverts these, so a load can be
stated the way it is measured: resonance, damping ratio, inertia.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["coupling_for"]


def coupling_for(rotor_inertia: ArrayLike, load_inertia: ArrayLike, resonance_hz: ArrayLike,
                 damping_ratio: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Stiffness and damping of the coupling with the given resonance and damping ratio.

    Parameters
    ----------
    rotor_inertia, load_inertia : array_like
        J_m > 0 and J_l [kg·m²]; broadcast together with the other arguments.
    resonance_hz : array_like
        Natural frequency of the coupled pair ω_n / 2π [Hz] (0: rigid shaft).
    damping_ratio : array_like
        Modal damping ratio ζ (≥ 0).

    Returns
    -------
    stiffness, damping : ndarray
        k [N·m/rad] and d [N·m·s/rad], the broadcast shape; 0 where the resonance or the load
        inertia is 0 (the rigid shaft: no load behind a coupling).
    """
    j_m, j_l, f, zeta = np.broadcast_arrays(*(np.asarray(x, dtype=np.float64) for x in
                                                 (rotor_inertia, load_inertia, resonance_hz,
                                                  damping_ratio)))
    w = 2.0 * math.pi * f
    coupled = (f > 0.0) & (j_l > 0.0)
    j_lc = np.where(coupled, j_l, 1.0)
    k = w * w / (1.0 / j_m + 1.0 / j_lc)
    d = 2.0 * zeta * w * j_m * j_lc / (j_m + j_lc)
    return np.where(coupled, k, 0.0), np.where(coupled, d, 0.0)
