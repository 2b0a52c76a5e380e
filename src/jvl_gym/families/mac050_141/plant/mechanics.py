"""Rigid rotor + load: viscous and Coulomb friction, load torque, end stops (docs/model.md §5.2).

``(J_m + J_l) dω/dt = T_em − T_load − b ω − T_c sgn(ω) + T_stop``. The viscous term is integrated
implicitly, Coulomb friction sticks the rotor when the driving torque is below ``T_c`` (static
friction = Coulomb friction) and stops it when the speed would change sign within the step. The
position advances with the trapezoidal rule, so the kinetic energy change equals the work of the
mean torque over the step exactly: ``J (ω1² − ω0²)/2 = (T − …)·Δθ``.
"""

from __future__ import annotations

from numba import njit

from ....jit import KERNEL


@njit(cache=True, inline="always")
def end_stop_torque(theta: float, omega: float, lo: float, hi: float, k: float, d: float) -> float:
    """Torque of stiff spring-damper end stops at ``lo`` and ``hi`` [rad]; none if ``lo >= hi``.

    Beyond ``hi`` the stop pushes back with ``min(−k·(θ − hi) − d·ω, 0)``, below ``lo`` with
    ``max(−k·(θ − lo) − d·ω, 0)``. Written as selects of one spring-damper term (the minimum
    and maximum in the form of the processor's instructions), not as branches: the SIMD
    lanes of ``jvl_gym.families.mac050_141.lanes`` compute every branch otherwise.
    """
    above = theta > hi
    t = -k * (theta - (hi if above else lo)) - d * omega
    pushed = (t if t < 0.0 else 0.0) if above else (t if t > 0.0 else 0.0)
    return pushed if (lo < hi and (above or theta < lo)) else 0.0


@njit(cache=True, inline="always")
def mech_constants(j: float, b: float, h: float) -> tuple[float, float]:
    """The rotor's parameter-only factors for steps of ``h`` [s]: ``(h/J, 1/(1 + h·b/J))``
    (computed once per kernel call for :func:`mech_step_prepared`, not every 128 µs)."""
    h_j = h / j
    return h_j, 1.0 / (1.0 + h_j * b)


@njit(**KERNEL)
def mech_step(theta: float, omega: float, drive: float, j: float, b: float, tc: float, h: float):
    """Advance the mechanics by ``h`` [s] under the net driving torque ``drive`` [N·m].

    ``drive`` is the electromagnetic torque minus the load torque plus the end-stop torque,
    before friction. Returns ``(theta1, omega1, friction_energy)``.
    """
    return mech_step_prepared(theta, omega, drive, j, tc, h, mech_constants(j, b, h))


@njit(cache=True, inline="always")
def mech_step_prepared(theta: float, omega: float, drive: float, j: float, tc: float, h: float,
                       k: tuple[float, float]):
    """:func:`mech_step` given ``k = mech_constants(j, b, h)``; same returns."""
    # the branches are selects (the SIMD lanes of mac050_141.lanes compute both sides anyway)
    stuck = omega == 0.0 and abs(drive) <= tc
    sgn = 1.0 if omega > 0.0 else (-1.0 if omega < 0.0 else (1.0 if drive > 0.0 else -1.0))
    h_j, inv_den = k
    omega1 = (omega + h_j * (drive - tc * sgn)) * inv_den
    omega1 = 0.0 if (omega1 * sgn < 0.0 and tc > 0.0) else omega1
    dtheta = 0.5 * h * (omega + omega1)
    # friction loss = work of the driving torque minus the kinetic energy gained; with the implicit
    # viscous term this equals (T_c sgn + b ω1)·Δθ, and it stays exact when the rotor is stopped.
    e_fric = drive * dtheta - 0.5 * j * (omega1 * omega1 - omega * omega)
    if stuck:
        return theta, 0.0, 0.0
    return theta + dtheta, omega1, e_fric
