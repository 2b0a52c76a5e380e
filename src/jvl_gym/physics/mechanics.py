"""Rotor and load: viscous and Coulomb friction, load torque, end stops, and an optional elastic
coupling to the load (docs/model.md §5.2).

Rigid (coupling stiffness 0): ``(J_m + J_l) dω/dt = T_em − T_load − b ω − T_c sgn(ω) + T_stop``.

Two-mass (coupling stiffness ``k > 0``, damping ``d``): the load inertia sits behind the
coupling and carries the load torque; friction and end stops act on the motor shaft::

    J_m dω_m/dt = T_em − b ω_m − T_c sgn(ω_m) + T_stop − T_s
    J_l dω_l/dt = T_s − T_load,        T_s = k (θ_m − θ_l) + d (ω_m − ω_l)

The viscous term is integrated implicitly, Coulomb friction sticks the rotor when the driving
torque is below ``T_c`` (static friction = Coulomb friction) and stops it when the speed would
change sign within the step. Positions advance with the trapezoidal rule and the coupling
torque is taken at the mid-step twist and twist speed (the implicit midpoint rule, solved in
closed form), so the kinetic and coupling energies change by exactly the work of the torques
over the step: ``ΔE_kin + ΔE_spring = T·Δθ_m − T_load·Δθ_l − losses``. The implicit midpoint
rule is stable for any stiffness; it turns a coupling frequency ω into ``(2/h)·atan(ω h/2)``, so
:data:`MAX_COUPLING_OMEGA_H` bounds ``ω_n·h`` to keep that within 2 % (the motor parameters'
check, ``coupling_problem``).
"""

from __future__ import annotations

import math

from numba import njit

from ..engine.jit import KERNEL, LANE_KERNEL, plain_arguments

#: largest ``ω_n·h`` of the coupling (ω_n = √(k (1/J_m + 1/J_l)), h the inner step): the
#: implicit midpoint rule's frequency ``(2/h)·atan(ω_n h/2)`` is then within 2.1 % of ω_n
MAX_COUPLING_OMEGA_H = 0.5
#: largest ``h·d·(1/J_m + 1/J_l)/2`` of the coupling damping: beyond 1 the trapezoidal rule's
#: factor ``(1 − x)/(1 + x)`` of the twist speed turns negative (a numerical ringing)
MAX_COUPLING_DAMPING_H = 1.0


@njit(**LANE_KERNEL, forceinline=True)
def end_stop_torque(theta: float, omega: float, lo: float, hi: float, k: float, d: float) -> float:
    """Torque of stiff spring-damper end stops at ``lo`` and ``hi`` [rad]; none if ``lo >= hi``.

    Beyond ``hi`` the stop pushes back with ``min(−k·(θ − hi) − d·ω, 0)``, below ``lo`` with
    ``max(−k·(θ − lo) − d·ω, 0)``. Written as selects of one spring-damper term (the minimum
    and maximum in the form of the processor's instructions), not as branches: the SIMD
    lanes of ``jvl_gym.families.mac050_141.lanes`` compute every branch otherwise.

    Compiled once and inlined by LLVM into each caller, with numpy's error model
    (``engine.jit.LANE_KERNEL``; docs/architecture.md, "First use and numba's cache").
    """
    above = theta > hi
    t = -k * (theta - (hi if above else lo)) - d * omega
    pushed = (t if t < 0.0 else 0.0) if above else (t if t > 0.0 else 0.0)
    return pushed if (lo < hi and (above or theta < lo)) else 0.0


@njit(cache=True, inline="always")
def shaft_inertia(j_m: float, j_l: float, k: float) -> float:
    """Inertia on the motor shaft [kg·m²]: ``J_m + J_l`` when rigid (``k == 0``), else ``J_m``."""
    return j_m if k > 0.0 else j_m + j_l


@njit(cache=True, inline="always")
def mech_constants(j_m: float, j_l: float, b: float, k: float, d: float, h: float) -> tuple:
    """Parameter-only factors for steps of ``h`` [s] (computed once per kernel call for
    :func:`mech_step_prepared`, not every 128 µs).

    Returns ``(h/J, 1/(1 + h·b/J + h·c·J_l'/(J·(J_l' + h·c))), k', c, 1/(J_l' + h·c), J_l')``
    with ``J`` = :func:`shaft_inertia`, ``c = k·h/4 + d/2`` (the coupling torque's factor of
    the twist speeds at both ends of the step), and for a rigid shaft ``k' = c = J_l' = 0``
    and the fifth factor 0: the two-mass terms then vanish exactly.
    """
    two = k > 0.0
    h_j = h / shaft_inertia(j_m, j_l, k)
    c = (0.25 * k * h + 0.5 * d) if two else 0.0
    jl = j_l if two else 0.0
    gl = (1.0 / (j_l + h * c)) if two else 0.0
    return h_j, 1.0 / (1.0 + h_j * b + h_j * c * jl * gl), (k if two else 0.0), c, gl, jl


@njit(**KERNEL)
def mech_step(theta: float, omega: float, drive: float, j: float, b: float, tc: float, h: float):
    """Advance a rigid shaft of inertia ``j`` [kg·m²] by ``h`` [s] under the net driving torque
    ``drive`` [N·m].

    ``drive`` is the electromagnetic torque minus the load torque plus the end-stop torque,
    before friction. Returns ``(theta1, omega1, friction_energy)``.
    """
    theta1, omega1, _tl, _wl, e_fric = mech_step_prepared(
        theta, omega, theta, omega, drive, 0.0, j, tc, h, mech_constants(j, 0.0, b, 0.0, 0.0, h))
    return theta1, omega1, e_fric


@njit(**KERNEL)
def two_mass_step(theta: float, omega: float, theta_l: float, omega_l: float, drive: float,
                  load: float, j_m: float, j_l: float, b: float, tc: float, k: float, d: float,
                  h: float):
    """Advance the motor and a load behind the coupling (``k`` [N·m/rad], ``d`` [N·m·s/rad])
    by ``h`` [s]: ``drive`` [N·m] acts on the motor, ``load`` [N·m] opposes the load.

    Returns ``(theta1, omega1, theta_l1, omega_l1, loss)``; ``loss`` [J] is the friction and
    coupling-damping energy of the step.
    """
    return mech_step_prepared(theta, omega, theta_l, omega_l, drive, load,
                              shaft_inertia(j_m, j_l, k), tc, h,
                              mech_constants(j_m, j_l, b, k, d, h))


@plain_arguments
@njit(**LANE_KERNEL, forceinline=True)
def mech_step_prepared(theta: float, omega: float, theta_l: float, omega_l: float, drive: float,
                       load_l: float, j: float, tc: float, h: float, k: tuple,
                       rigid: bool = False):
    """One step given ``k = mech_constants(...)`` and ``j = shaft_inertia(...)``.

    ``drive`` [N·m] acts on the motor shaft, ``load_l`` [N·m] on the load behind the coupling
    (0 for a rigid shaft, whose load torque is part of ``drive``). Returns ``(theta1, omega1,
    theta_l1, omega_l1, loss)``; for a rigid shaft the load follows the motor
    (``theta_l1 = theta1``, ``omega_l1 = omega1``).

    ``rigid`` (a constant at the call, which the compiler folds) says that the shaft is rigid
    (``k`` of a rigid shaft, ``theta_l, omega_l = theta, omega``, ``load_l = 0``): the coupling
    terms, exact zeros then, are left out, with the same results but for the sign of a zero
    loss (which the energy accounts sum to the same value). ``rigid`` is typed as a plain bool
    (``plain_arguments``): one compiled body, whose branch LLVM folds once it has inlined it.

    Compiled once and inlined by LLVM into each caller, with numpy's error model
    (``engine.jit.LANE_KERNEL``; docs/architecture.md, "First use and numba's cache").
    """
    # the branches are selects (the SIMD lanes of mac050_141.lanes compute both sides anyway)
    h_j, inv_den, kk, cc, gl, jl = k
    s0 = omega - omega_l
    tw0 = theta - theta_l
    # coupling torque = spring = kk·tw0 + cc·(s0 + s1) with s1 the twist speed at the step's
    # end; the load's equation gives ω_l1 = gl·(r_l + h·cc·ω1), which puts the part of s1 that
    # depends on ω1 into inv_den and the rest into the motor's effective driving torque
    spring = kk * tw0 + cc * s0
    r_l = jl * omega_l + h * (spring - load_l)
    drive_eff = drive if rigid else drive - spring + cc * gl * r_l
    stuck = omega == 0.0 and abs(drive_eff) <= tc
    sgn = 1.0 if omega > 0.0 else (-1.0 if omega < 0.0 else (1.0 if drive_eff > 0.0 else -1.0))
    omega1 = (omega + h_j * (drive_eff - tc * sgn)) * inv_den
    omega1 = 0.0 if ((omega1 * sgn < 0.0 and tc > 0.0) or stuck) else omega1
    dtheta = 0.5 * h * (omega + omega1)
    if rigid:
        theta1 = theta + dtheta
        return (theta1, omega1, theta1, omega1,
                drive * dtheta - 0.5 * j * (omega1 * omega1 - omega * omega))
    omega_l1 = gl * (r_l + h * cc * omega1)
    dtheta_l = 0.5 * h * (omega_l + omega_l1)
    tw1 = tw0 + (dtheta - dtheta_l)
    # losses = work of the external torques minus the kinetic and coupling energy gained; with
    # the implicit viscous term this equals (T_c sgn + b ω1)·Δθ_m plus the coupling damping
    # d·s_mid²·h, and it stays exact when the rotor is stopped
    e_fric = (drive * dtheta - load_l * dtheta_l - 0.5 * j * (omega1 * omega1 - omega * omega)
              - 0.5 * jl * (omega_l1 * omega_l1 - omega_l * omega_l)
              - 0.5 * kk * (tw1 * tw1 - tw0 * tw0))
    theta1 = theta + dtheta
    two = kk > 0.0
    return (theta1, omega1, (theta_l + dtheta_l) if two else theta1,
            omega_l1 if two else omega1, e_fric)


def coupling_problem(j_m: float, j_l: float, k: float, d: float, h: float) -> str | None:
    """Why the inner step of ``h`` [s] cannot carry this coupling, or None.

    A coupling (``k`` > 0) needs a load inertia ``j_l`` > 0, a natural frequency
    ``ω_n = √(k (1/J_m + 1/J_l))`` with ``ω_n·h`` ≤ :data:`MAX_COUPLING_OMEGA_H` and a damping
    with ``h·d·(1/J_m + 1/J_l)/2`` ≤ :data:`MAX_COUPLING_DAMPING_H`. The message names the
    motor parameter to change.
    """
    if not k > 0.0:
        return None
    if not j_l > 0.0:
        return ("load_inertia must be > 0 with an elastic coupling (coupling_stiffness > 0): "
                "the load sits behind the coupling")
    inv = 1.0 / j_m + 1.0 / j_l
    wn = math.sqrt(k * inv)
    if wn * h > MAX_COUPLING_OMEGA_H:
        f_max = MAX_COUPLING_OMEGA_H / h / (2.0 * math.pi)
        return (f"coupling_stiffness {k:.6g} N·m/rad gives a coupling natural frequency of "
                f"{wn / (2.0 * math.pi):.1f} Hz; the {h * 1e6:.0f} µs inner step carries up to "
                f"{f_max:.0f} Hz (ω_n·h ≤ {MAX_COUPLING_OMEGA_H})")
    if 0.5 * h * d * inv > MAX_COUPLING_DAMPING_H:
        d_max = 2.0 * MAX_COUPLING_DAMPING_H / (h * inv)
        return (f"coupling_damping {d:.6g} N·m·s/rad is above {d_max:.6g}, the most the "
                f"{h * 1e6:.0f} µs inner step integrates without a numerical ringing of the twist")
    return None
