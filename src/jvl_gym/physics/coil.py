"""Three-phase star-connected coil, floating neutral, sinusoidal back-EMF (docs/model.md §5.1).

Per phase k ∈ {a, b, c}: ``L di_k/dt = u_k − u_n − R i_k − e_k`` with the neutral ``u_n`` floating
(Σ i_k = 0) and the magnet flux ``ψ_k = λ sin(θ_e + k·120°)``, so ``e_k = λ ω_e cos(θ_e + k·120°)``.
With the space vector ``s_x = (2/3) Σ x_k e^{−jk·120°}``
(phase values ``x_k = Re(s_x e^{jk·120°})``,
zero sequence removed, which is what the floating neutral does) the coil is

    L ds_i/dt = s_u − R s_i − ω_e λ e^{jθ_e},       T = 1.5 p λ Re(s_i e^{−jθ_e}).

Over one inner sample the PWM voltage is constant and the speed is taken constant (the mid-step
prediction), so the step is integrated *exactly* (closed form of the exponential convolution with
a rotating vector): the result does not depend on the step size (tests/test_plant.py shows it).
Torque and powers are averaged over the step with Simpson's rule on the exact trajectory.
"""

from __future__ import annotations

import math

from numba import njit

from ..engine.jit import KERNEL, LANE_KERNEL
from .trig import fma, sincos

SQRT3 = math.sqrt(3.0)
# Divisions are the slowest arithmetic of the inner sample (long latency, one divider per core):
# constant divisors are multiplications by these reciprocals.
_THIRD = 1.0 / 3.0
_INV_SQRT3 = 1.0 / SQRT3
_SIXTH = 1.0 / 6.0


@njit(cache=True, inline="always")
def phase_to_vector(xa: float, xb: float, xc: float) -> complex:
    """Space vector of three phase quantities (zero sequence removed)."""
    return complex((2.0 * xa - xb - xc) * _THIRD, (xc - xb) * _INV_SQRT3)


@njit(cache=True, inline="always")
def vector_to_phases(s: complex) -> tuple[float, float, float]:
    """Phase values ``Re(s e^{jk·120°})`` of a space vector, k = 0, 1, 2."""
    re = s.real
    im = s.imag
    return re, -0.5 * re - 0.5 * SQRT3 * im, -0.5 * re + 0.5 * SQRT3 * im


@njit(cache=True, inline="always")
def _dot(a: complex, b: complex) -> float:
    """``Re(a·conj(b))``, the scalar product of two space vectors."""
    return fma(a.real, b.real, a.imag * b.imag)


@njit(cache=True, inline="always")
def _simpson(x0: float, xm: float, x1: float) -> float:
    """Mean over a step by Simpson's rule from the start, middle and end values."""
    return (fma(4.0, xm, x0) + x1) * _SIXTH


@njit(cache=True, inline="always")
def _current_at(s0: complex, s_u: complex, k_emf_over_c: complex, inv_r: float, a_t: float,
                rot: complex) -> complex:
    return a_t * s0 + (1.0 - a_t) * inv_r * s_u - k_emf_over_c * (rot - a_t)


@njit(cache=True, inline="always")
def expi(x: float) -> complex:
    """``e^{jx}`` (:func:`jvl_gym.physics.trig.sincos`)."""
    s, co = sincos(x)
    return complex(co, s)


@njit(cache=True, inline="always")
def coil_constants(r: float, ell: float, lam: float, h: float) -> tuple[float, float, float, float]:
    """The coil's parameter-only factors for steps of ``h`` [s]: ``(e^{−h/(2τ)}, 1/R, 1/τ, λ/L)``
    with ``τ = L/R``.

    The kernel computes them once per call for :func:`coil_step_prepared` instead of four
    divisions and an exponential every 128 µs.
    """
    inv_tau = r / ell
    return math.exp(-0.5 * h * inv_tau), 1.0 / r, inv_tau, lam / ell


@njit(**KERNEL)
def coil_step(s0: complex, s_u: complex, theta_e: float, omega_e: float, r: float, ell: float,
              lam: float, pole_pairs: float, h: float):
    """Advance the coil current by one step of length ``h`` [s].

    Parameters
    ----------
    s0 : complex
        Current space vector at the start of the step [A].
    s_u : complex
        Applied phase voltage space vector, constant over the step [V].
    theta_e, omega_e : float
        Electrical angle at the start [rad] and electrical speed over the step [rad/s].
    r, ell, lam : float
        Phase resistance [Ω], phase inductance [H], flux linkage [V·s].
    pole_pairs : float
        Number of pole pairs p.
    h : float
        Step length [s].

    Returns
    -------
    s1 : complex
        Current space vector at the end of the step [A].
    torque : float
        Mean electromagnetic torque over the step [N·m].
    p_elec : float
        Mean electrical power delivered to the windings [W].
    p_copper : float
        Mean copper loss [W].
    """
    return coil_step_prepared(s0, s_u, theta_e, omega_e, r, lam, pole_pairs, h,
                              coil_constants(r, ell, lam, h))


@njit(**LANE_KERNEL, forceinline=True)
def coil_step_prepared(s0: complex, s_u: complex, theta_e: float, omega_e: float, r: float,
                       lam: float, pole_pairs: float, h: float,
                       k: tuple[float, float, float, float]):
    """:func:`coil_step` given ``k = coil_constants(r, ell, lam, h)``; same returns.

    Compiled once and inlined by LLVM into each caller, with numpy's error model
    (``engine.jit.LANE_KERNEL``; docs/architecture.md, "First use and numba's cache").
    """
    a_h, inv_r, inv_tau, lam_over_l = k
    sin_e, cos_e = sincos(theta_e)
    e0 = complex(cos_e, sin_e)
    # back-EMF term ω λ/L · e^{jθe} / (1/τ + jω), the division written out (1/τ > 0)
    g = omega_e * lam_over_l / fma(inv_tau, inv_tau, omega_e * omega_e)
    k_emf_over_c = complex(g * fma(cos_e, inv_tau, sin_e * omega_e),
                           g * fma(sin_e, inv_tau, -(cos_e * omega_e)))
    rot_h = expi(omega_e * 0.5 * h)
    rot_1 = rot_h * rot_h
    s_m = _current_at(s0, s_u, k_emf_over_c, inv_r, a_h, rot_h)
    s1 = _current_at(s0, s_u, k_emf_over_c, inv_r, a_h * a_h, rot_1)
    e_m = e0 * rot_h
    e_1 = e0 * rot_1
    # Re(a·conj(b)) sums and Simpson's weights with fused multiply-adds (one rounding each)
    t0 = _dot(s0, e0)  # Re(s e^{−jθ}) at the start, middle and end
    tm = _dot(s_m, e_m)
    t1 = _dot(s1, e_1)
    torque = 1.5 * pole_pairs * lam * _simpson(t0, tm, t1)
    p_elec = 1.5 * _simpson(_dot(s_u, s0), _dot(s_u, s_m), _dot(s_u, s1))
    p_copper = 1.5 * r * _simpson(_dot(s0, s0), _dot(s_m, s_m), _dot(s1, s1))
    return s1, torque, p_elec, p_copper
