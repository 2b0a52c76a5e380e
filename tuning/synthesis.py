"""Synthesis of the current-loop (IF, IB) and speed-loop (FF, VB, VF, KVOUT) filters.

Current loop (manual 4.3, 3.2.106–3.2.111). A PI ``IF(z) = Kp + Ki·z/(z − 1)`` (KIFX2 = Kp + Ki,
KIFX1 = −Kp, KIFY1 = 1, KIFY0 = 0), IB = 1 (KIB1 = 1, KIB0 = 0). The normalised gains
``Kp·g(1−a)``, ``Ki·g(1−a)`` are chosen on a grid: the largest integral gain (best rejection of
the back-EMF, which the per-phase loops see as a sinusoidal disturbance at speed; a pole-
cancelling PI rejects it poorly and loses several % of torque at a few hundred rpm) that meets
the margins on the nominal coil and on R, L ±30 %, or the target bandwidth.

Speed loop (manual 4.2, 3.2.89–3.2.105, 3.2.13). The plant from VF_OUT to V_IST is the exact
lifted model of :func:`tuning.models.speed_plant` (closed current loop + rigid rotor, J = J_m),
and KVOUT = J_total/J_m makes the loop gain load-invariant (3.2.13). The controller is a PI on
the velocity error in 1/16 units, ``16·(kp + ki·z/(z − 1))``, in one of two structures with the
*same* loop transfer function:

* ``"pi"``: all in VF (KVFX4 = kp + ki, KVFX3 = −kp, KVFY3 = 1), FF = 1, VB = 1;
* ``"ip"`` (default): integral in VF (KVFX4 = ki, KVFY3 = 1) and the proportional part in the
  feedback filter VB = 1 + (kp/ki)(1 − z⁻¹) (KVB3 = 1 + kp/ki, KVB2 = −kp/ki). The reference
  path has no zero, so a velocity step has (almost) no overshoot, and the direct gain
  ``KVOUT·KVFX4·KFF3 = KVOUT·ki ≠ 0`` keeps the function correction working (docs/model.md §8).
  ``setpoint_weight`` β puts β·kp back into FF (FF = 1 + β(kp/ki)(1 − z⁻¹)), between I-P (β=0)
  and PI (β=1).

(kp, ki) are chosen on a grid in normalised units (``kp_n = 16·Kpl·kp`` with
``Kpl = (4096/2π)·K_vf·TS_O²/(2·J_m)``) for the target loop bandwidth, subject to: nominal PM and
GM, pole radius, and PM under KVOUT × 0.5 and × 2 and under coil R, L ±30 %.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .models import (
    MotorData,
    freqresp,
    polymul,
    rigid_gain,
    speed_plant,
)
from .verify import LoopMetrics, frequency_grid, metrics_from_response, with_pole_radius

__all__ = [
    "CurrentDesign",
    "SpeedDesign",
    "design_current_loop",
    "design_speed_loop",
    "current_registers",
    "speed_registers",
    "torque_guidance",
    "friction_dead_band",
]


@dataclass
class CurrentDesign:
    """Result of :func:`design_current_loop`.

    Attributes
    ----------
    registers : dict
        KIFX2, KIFX1, KIFY1, KIFY0, KIB1, KIB0 (unquantised).
    loop_gain : float
        Normalised proportional gain ``Kp·g(1 − a)`` (dimensionless).
    metrics : LoopMetrics
        Nominal metrics of the (unquantised) design.
    robust_pm_deg : float
        Worst PM over R, L ±30 %.
    notes : list of str
        What the designer had to compromise.
    """

    registers: dict[str, float]
    loop_gain: float
    metrics: LoopMetrics
    robust_pm_deg: float
    notes: list[str] = field(default_factory=list)
    ki_norm: float = 0.0


@dataclass
class SpeedDesign:
    """Result of :func:`design_speed_loop` (registers unquantised; kp, ki in VF units)."""

    registers: dict[str, float]
    kp: float
    ki: float
    kp_norm: float
    ki_norm: float
    metrics: LoopMetrics
    robust_pm_deg: float
    structure: str
    notes: list[str] = field(default_factory=list)
    kii: float = 0.0


# ----------------------------------------------------------------------------- current loop
def current_registers(motor: MotorData, kp_norm: float, ki_norm: float | None = None
                      ) -> dict[str, float]:
    """IF/IB registers of a PI with normalised gains (``kp_norm = Kp·g(1−a)``, same for ki).

    ``IF = Kp + Ki·z/(z − 1)``: KIFX2 = Kp + Ki, KIFX1 = −Kp, KIFY1 = 1, KIFY0 = 0; IB = 1.
    With ``ki_norm`` None the zero cancels the coil pole (Ki = Kp(1 − a)/a).
    """
    a, g = motor.coil_pole, motor.coil_gain
    b = g * (1.0 - a)
    kp = kp_norm / b
    if ki_norm is None:  # zero at a: (Kp+Ki) z − Kp  ∝  z − a
        kp_total = kp
        return {"KIFX2": kp_total, "KIFX1": -kp_total * a, "KIFY1": 1.0, "KIFY0": 0.0,
                "KIB1": 1.0, "KIB0": 0.0}
    ki = ki_norm / b
    return {"KIFX2": kp + ki, "KIFX1": -kp, "KIFY1": 1.0, "KIFY0": 0.0, "KIB1": 1.0,
            "KIB0": 0.0}


def _current_loop_poly(motor: MotorData, regs: Mapping[str, float]
                       ) -> tuple[np.ndarray, np.ndarray]:
    """Numerator and denominator (descending powers of z) of the current open loop."""
    return _current_loop_num(motor, regs), _current_loop_den(motor, regs)


def _current_loop_num(motor: MotorData, regs: Mapping[str, float]) -> np.ndarray:
    a, g = motor.coil_pole, motor.coil_gain
    num = polymul([regs["KIFX2"], regs["KIFX1"], 0.0], [g * (1 - a)])
    return polymul(num, [regs["KIB1"], regs["KIB0"]])


def _current_loop_den(motor: MotorData, regs: Mapping[str, float]) -> np.ndarray:
    """The denominator: the coil, its PWM delay and IF's denominator (KIFY1, KIFY0)."""
    a, d = motor.coil_pole, int(motor.pwm_delay)
    den = polymul([1.0, -regs["KIFY1"], -regs["KIFY0"]], [1.0, -a])
    den = polymul(den, np.r_[1.0, np.zeros(d)])
    return polymul(den, [1.0, 0.0])


def _margins_poly(num: np.ndarray, den: np.ndarray, w: np.ndarray, z: np.ndarray,
                  den_z: np.ndarray | None = None) -> LoopMetrics:
    """Margins and bandwidth of the loop ``num/den`` on the grid ``w`` [rad/s], ``z =
    exp(jωT)``, without the pole radius (:func:`_metrics_poly`); ``den_z``: ``den`` on ``z``,
    when already computed."""
    dz = np.polyval(den, z) if den_z is None else den_z
    return metrics_from_response(np.polyval(num, z) / dz, w)


def _metrics_poly(num: np.ndarray, den: np.ndarray, w: np.ndarray, z: np.ndarray,
                  margins: LoopMetrics | None = None) -> LoopMetrics:
    """Metrics of the loop ``num/den`` with the pole radius of ``den + num``; ``margins``: its
    :func:`_margins_poly`, when already computed."""
    m = _margins_poly(num, den, w, z) if margins is None else margins
    return with_pole_radius(m, np.polyadd(den, num))


def design_current_loop(motor: MotorData, bandwidth_hz: float | None = None,
                        pm_min: float = 50.0, gm_min: float = 8.0,
                        robust_pm_min: float = 35.0,
                        gains: tuple[float, float] | None = None,
                        dt: float | None = None) -> CurrentDesign:
    """Design IF and IB for a target closed-loop bandwidth.

    Parameters
    ----------
    motor : MotorData
        The (identified) coil: R_phase [Ω], L_phase [H], amps_per_count, pwm_delay.
    bandwidth_hz : float, optional
        Target −3 dB bandwidth of the current loop [Hz] (among the designs within 10 % of it, the
        largest integral gain); default: the largest integral gain that meets the constraints.
    pm_min, gm_min : float
        Nominal phase [deg] and gain [dB] margins required (acceptance: 45°, 6 dB; the defaults
        leave room for quantisation).
    robust_pm_min : float
        PM required on every R, L ±30 % corner [deg].
    gains : (float, float), optional
        Fixed normalised (kp, ki) instead of the search (e.g. the default setups' design point).
    dt : float, optional
        The current-loop sample time [s] (default ``motor.family.inner_dt``, for which the
        coil pole and gain are): the loop is the same polynomial in z, ``dt`` sets the
        frequencies.

    Returns
    -------
    CurrentDesign
    """
    dt = motor.family.inner_dt if dt is None else dt
    w = frequency_grid(dt, 1500)
    z = np.exp(1j * w * dt)
    if gains is not None:
        regs = current_registers(motor, *gains)
        m = _metrics_poly(*_current_loop_poly(motor, regs), w, z)
        rpm = min(_margins_poly(*_current_loop_poly(
            motor.with_(R_phase=motor.R_phase * fr, L_phase=motor.L_phase * fl), regs), w,
            z).pm_deg for fr in (0.7, 1.3) for fl in (0.7, 1.3))
        return CurrentDesign(regs, gains[0], m, rpm, [], gains[1])
    # the nominal coil, then R, L x {0.7, 1.3}
    coils = [motor] + [motor.with_(R_phase=motor.R_phase * fr, L_phase=motor.L_phase * fl)
                       for fr in (0.7, 1.3) for fl in (0.7, 1.3)]
    dens: dict[tuple[int, str, str], tuple[np.ndarray, np.ndarray]] = {}

    def loop(i: int, regs: Mapping[str, float]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Numerator, denominator and the denominator on ``z`` of the loop on ``coils[i]``;
        the denominator (the coil's and KIFY1, KIFY0's) is computed once per coil."""
        key = (i, float(regs["KIFY1"]).hex(), float(regs["KIFY0"]).hex())
        if key not in dens:
            den = _current_loop_den(coils[i], regs)
            dens[key] = (den, np.polyval(den, z))
        return (_current_loop_num(coils[i], regs), *dens[key])

    def candidate(kpn: float, kin: float) -> tuple[Any, ...] | None:
        regs = current_registers(motor, float(kpn), float(kin))
        num, den, den_z = loop(0, regs)
        m = _margins_poly(num, den, w, z, den_z)
        if not (m.pm_deg >= pm_min and m.gm_db >= gm_min):
            return None
        m = _metrics_poly(num, den, w, z, m)
        if not m.stable:
            return None
        polys = [loop(i, regs) for i in range(1, len(coils))]
        rm = [_margins_poly(*p[:2], w, z, p[2]) for p in polys]
        rpm = min([math.inf] + [r.pm_deg for r in rm])
        if rpm >= robust_pm_min and all(_metrics_poly(*p[:2], w, z, r).stable
                                        for p, r in zip(polys, rm)):
            return (float(kpn), float(kin), m, rpm)
        return None

    # without a bandwidth only the largest feasible integral gain counts
    feasible = _feasible(np.linspace(0.05, 0.8, 31), np.geomspace(0.005, 0.25, 31), candidate,
                         1.0 if bandwidth_hz is None else None)
    if not feasible:
        raise ValueError("no current-loop gains meet the margin constraints; relax them")
    notes: list[str] = []
    if bandwidth_hz is None:
        best = max(feasible, key=lambda f: f[1])
    else:
        best = _at_bandwidth(feasible, 2, bandwidth_hz, "current-loop", 0, notes)
    kpn, kin, m, rpm = best
    return CurrentDesign(current_registers(motor, kpn, kin), kpn, m, rpm, notes, kin)


def _feasible(grid_p: Any, grid_i: Any, candidate: Any, within: float | None
              ) -> list[tuple[Any, ...]]:
    """The feasible designs ``candidate(kpn, kin)`` (None: not feasible) of the grid
    ``grid_p`` × ``grid_i`` of normalised proportional and integral gains, in the grid's order
    (``grid_p`` outer, ``grid_i`` inner).

    With ``within`` None every point is tried. Otherwise only those a choice among the
    largest integral gains needs: the integral gains are tried from the largest down, and
    the search stops at the first one below ``within`` times the largest feasible one."""
    if within is None:
        return [f for kpn in grid_p for kin in grid_i if (f := candidate(kpn, kin)) is not None]
    found: list[tuple[int, int, tuple[Any, ...]]] = []
    top = None
    for j in sorted(range(len(grid_i)), key=lambda j: -grid_i[j]):
        if top is not None and not grid_i[j] >= within * top:
            break
        for i in range(len(grid_p)):
            f = candidate(grid_p[i], grid_i[j])
            if f is not None:
                found.append((i, j, f))
                top = grid_i[j] if top is None else top
    return [f for _, _, f in sorted(found, key=lambda t: (t[0], t[1]))]


def _at_bandwidth(feasible: list[tuple[Any, ...]], metrics: int, bandwidth_hz: float, loop: str,
                  digits: int, notes: list[str]) -> tuple[Any, ...]:
    """The feasible design (a tuple: integral gain at index 1, the loop's metrics at index
    ``metrics``) with the largest integral gain among those whose bandwidth is within 10 % of
    ``bandwidth_hz`` [Hz]; if there is none, the one nearest to it on a log scale, with a note
    (``digits`` decimals) appended to ``notes``."""
    near = [f for f in feasible if abs(f[metrics].bandwidth_hz / bandwidth_hz - 1) <= 0.1]
    if near:
        return max(near, key=lambda f: f[1])
    best = min(feasible, key=lambda f: abs(math.log(f[metrics].bandwidth_hz / bandwidth_hz)))
    notes.append(f"{loop} bandwidth target {bandwidth_hz:.{digits}f} Hz not reachable within "
                 f"the margins; got {best[metrics].bandwidth_hz:.{digits}f} Hz")
    return best


# ----------------------------------------------------------------------------- speed loop
def speed_registers(kp: float, ki: float, kvout: float, structure: str = "ip",
                    setpoint_weight: float = 0.0, kii: float = 0.0) -> dict[str, float]:
    """FF, VB (with GEARB = 16), VF and KVOUT registers of a PI / I-P speed loop.

    Parameters
    ----------
    kp, ki : float
        Proportional and integral gains in VF units (VF_OUT/KVOUT per 1/16 count/sample).
    kvout : float
        KVOUT = J_total/J_m (manual 3.2.13).
    structure : {"ip", "pi"}
        Where the proportional part acts (module docstring).
    setpoint_weight : float
        β of the I-P structure: FF = 1 + β·(kp/ki)(1 − z⁻¹).
    kii : float
        Position-integral gain (``"pi"`` only): VF = kp + ki/(1 − z⁻¹) + kii/(1 − z⁻¹)²
        (KVFX4 = kp + ki + kii, KVFX3 = −2kp − ki, KVFX2 = kp, KVFY3 = 2, KVFY2 = −1).
    """
    regs = {"KFF3": 1.0, "KFF2": 0.0, "KFF1": 0.0, "KFF0": 0.0, "GEARB": 16.0,
            "KVB3": 1.0, "KVB2": 0.0, "KVB1": 0.0, "KVB0": 0.0,
            "KVFX4": kp + ki, "KVFX3": -kp, "KVFX2": 0.0, "KVFX1": 0.0,
            "KVFY3": 1.0, "KVFY2": 0.0, "KVFY1": 0.0, "KVFY0": 0.0, "KVOUT": kvout}
    if structure == "ip":
        c = kp / ki
        regs.update({"KVFX4": ki, "KVFX3": 0.0, "KVB3": 1.0 + c, "KVB2": -c,
                     "KFF3": 1.0 + setpoint_weight * c, "KFF2": -setpoint_weight * c})
    elif structure != "pi":
        raise ValueError(f"structure must be 'ip' or 'pi', got {structure!r}")
    elif kii > 0.0:
        regs.update({"KVFX4": kp + ki + kii, "KVFX3": -2.0 * kp - ki, "KVFX2": kp,
                     "KVFY3": 2.0, "KVFY2": -1.0})
    return regs


def _speed_candidates(motor: MotorData, current_regs: Mapping[str, float], w: np.ndarray
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[np.ndarray]]:
    plant = speed_plant(motor, current_regs)
    pn = np.asarray(plant.num[0][0], dtype=float)
    pd = np.asarray(plant.den[0][0], dtype=float)
    pw = freqresp(plant, w)
    rl = []
    for fr in (0.7, 1.3):
        for fl in (0.7, 1.3):
            mm = motor.with_(R_phase=motor.R_phase * fr, L_phase=motor.L_phase * fl)
            rl.append(freqresp(speed_plant(mm, current_regs), w))
    return pn, pd, pw, rl


def design_speed_loop(motor: MotorData, current_regs: Mapping[str, float], J_total: float,
                      bandwidth_hz: float | None = None, structure: str = "ip",
                      setpoint_weight: float = 0.0, pm_min: float = 50.0, gm_min: float = 10.0,
                      robust_pm_min: float = 35.0,
                      robust_gains: tuple[float, ...] = (0.5, 2.0),
                      gains: tuple[float, float] | None = None, coulomb: float = 0.0,
                      position_window: int = 10,
                      position_integral: bool | None = None) -> SpeedDesign:
    """Design FF, VB, VF and KVOUT for a target loop bandwidth.

    Parameters
    ----------
    motor : MotorData
        Motor data; ``J_m`` is the reference inertia of KVOUT.
    current_regs : mapping
        The current-loop registers (the speed plant includes the closed current loop).
    J_total : float
        Identified total inertia [kg·m²]; KVOUT = J_total/J_m.
    bandwidth_hz : float, optional
        Target −3 dB bandwidth of ``L/(1+L)`` [Hz]; default: the design with the largest
        integral gain that meets the constraints.
    structure, setpoint_weight
        See :func:`speed_registers`.
    pm_min, gm_min, robust_pm_min
        Nominal PM [deg], GM [dB], and PM on the robustness set (KVOUT × 0.5, × 2; R, L ±30 %).
    robust_gains : tuple of float
        Loop-gain factors of the robustness set (KVOUT/(J_true/J_m)); the default setups use
        (1/11, 2) so that KVOUT = 1 stays usable for any load up to 10·J_m.
    gains : (float, float), optional
        Fixed normalised (kp, ki) instead of the search.
    coulomb : float
        Identified Coulomb friction [N·m]. When the PI loop's friction dead band
        (:func:`friction_dead_band`) exceeds half of ``position_window``, a position integral
        is added (``"pi"`` structure): the largest that keeps the acceptance margins.
    position_window : int
        In-position window the moves must settle in [counts] (INPOSWIN, 3.2.33).
    position_integral : bool, optional
        ``"pi"`` only: force the position integral on (True) or off (False); default (None)
        the dead-band rule above. The acceptance step (:mod:`tuning.strategies.testu_pi`)
        tries both.

    Returns
    -------
    SpeedDesign
    """
    ts_o = motor.family.outer_dt
    w = frequency_grid(ts_o, 1200, lowest=1e-3)
    z = np.exp(1j * w * ts_o)
    pn, pd, pw, rl = _speed_candidates(motor, current_regs, w)
    kpl16 = 16.0 * rigid_gain(motor)
    integrated = polymul([1.0, -1.0], pd)
    grid_p = [gains[0]] if gains else np.geomspace(0.03, 1.2, 64)
    grid_i = [gains[1]] if gains else np.geomspace(0.002, 0.3, 64)

    def candidate(kpn: float, kin: float) -> tuple[Any, ...] | None:
        kp, ki = kpn / kpl16, kin / kpl16
        cw = 16.0 * (kp + ki * z / (z - 1.0))
        lw = cw * pw
        cnum = 16.0 * np.array([kp + ki, -kp])
        m = metrics_from_response(lw, w)
        if not (m.pm_deg >= pm_min and m.gm_db >= gm_min):
            return None
        ctrl = polymul(cnum, pn)
        # L = 16(kp + ki z/(z-1)) P = 16((kp+ki) z - kp)/(z-1) · pn/pd
        m = with_pole_radius(m, np.polyadd(integrated, ctrl))
        if not m.stable:
            return None
        rpm = math.inf
        for scale in robust_gains:
            rpm = min(rpm, metrics_from_response(lw * scale, w).pm_deg)
        if rpm < robust_pm_min:
            return None
        for prl in rl:
            rpm = min(rpm, metrics_from_response(cw * prl, w).pm_deg)
        if rpm < robust_pm_min:
            return None
        # the doubled-gain case must be stable too
        char2 = np.polyadd(integrated, max(robust_gains) * ctrl)
        if np.max(np.abs(np.roots(char2))) >= 0.999:
            return None
        return (kpn, kin, kp, ki, m, rpm)

    # without a bandwidth only the integral gains within 2 % of the largest feasible one count
    feasible = _feasible(grid_p, grid_i, candidate, 0.98 if bandwidth_hz is None else None)
    if not feasible:
        raise ValueError("no speed-loop gains meet the margin constraints; relax them")
    notes: list[str] = []
    if bandwidth_hz is None:
        # the largest integral gain; among designs within 2 % of it, the most damping (kp)
        top = max(f[1] for f in feasible)
        best = max((f for f in feasible if f[1] >= 0.98 * top), key=lambda f: f[0])
    else:
        best = _at_bandwidth(feasible, 4, bandwidth_hz, "speed-loop", 1, notes)
    kpn, kin, kp, ki, m, rpm = best
    kvout = J_total / motor.J_m
    kii = 0.0
    if structure == "pi" and position_integral is not False:
        band = friction_dead_band(motor, coulomb, kvout, ki) if coulomb > 0.0 else 0.0
        if position_integral or band > 0.5 * position_window:
            kii, m, rpm = _position_integral(pn, pd, pw, rl, z, w, kp, ki, kpl16, robust_gains,
                                             m, rpm)
            why = ("requested" if position_integral else
                   f"friction dead band {band:.0f} counts > half the {position_window}-count "
                   "window")
            notes.append(f"{why}: position integral KVFX sum {kii:.5f}" if kii > 0 else
                         f"{why}; no position integral meets the margins")
    if not 1.0 <= kvout <= 10.0:
        notes.append(f"KVOUT = {kvout:.2f} is outside the manual's recommended 1..10 (3.2.13)")
    regs = speed_registers(kp, ki, kvout, structure, setpoint_weight, kii)
    return SpeedDesign(regs, kp, ki, float(kpn), float(kin), m, rpm, structure, notes, kii)


def friction_dead_band(motor: MotorData, coulomb: float, kvout: float, ki: float) -> float:
    """Half-width [counts] of the positions where a PI speed loop holds a motor with Coulomb
    friction ``coulomb`` [N·m] at rest: VF_OUT = KVOUT·16·ki·(P_SOLL − P_IST) (the VF integral
    of the velocity error is the position error) must exceed T_c/K_vf to move it."""
    stiff = kvout * 16.0 * ki * motor.torque_per_vf  # N·m per count of position error
    return coulomb / stiff if stiff > 0 else math.inf


def _position_integral(pn: np.ndarray, pd: np.ndarray, pw: np.ndarray, rl: list[np.ndarray],
                       z: np.ndarray, w: np.ndarray, kp: float, ki: float, kpl16: float,
                       robust_gains: tuple[float, ...], m0: LoopMetrics, rpm0: float,
                       pm_min: float = 45.0, gm_min: float = 10.0, robust_pm_min: float = 30.0
                       ) -> tuple[float, LoopMetrics, float]:
    """The largest position-integral gain kii (VF = kp + ki/(1−z⁻¹) + kii/(1−z⁻¹)²) that keeps
    the acceptance margins (PM ≥ 45°, GM ≥ 10 dB, robust PM ≥ 30°, stable at the largest
    robust gain); (0, m0, rpm0) if none does. The integral removes the friction dead band of
    the PD position loop; with static = Coulomb friction PID positioning converges (no
    hunting limit cycle, Bisoffi et al., IEEE TAC 2018)."""
    best = (0.0, m0, rpm0)
    for frac in np.geomspace(1e-3, 0.2, 24):
        kii = float(frac * ki)
        cw = 16.0 * (kp + ki * z / (z - 1.0) + kii * z**2 / (z - 1.0) ** 2)
        lw = cw * pw
        cnum = 16.0 * np.array([kp + ki + kii, -2.0 * kp - ki, kp])
        dd = polymul([1.0, -2.0, 1.0], pd)
        ctrl = polymul(cnum, pn)
        m = metrics_from_response(lw, w)
        if not (m.pm_deg >= pm_min and m.gm_db >= gm_min):
            break
        m = with_pole_radius(m, np.polyadd(dd, ctrl))
        if not m.stable:
            break
        rpm = min(metrics_from_response(lw * g, w).pm_deg for g in robust_gains)
        rpm = min([rpm] + [metrics_from_response(cw * prl, w).pm_deg for prl in rl])
        char2 = np.polyadd(dd, max(robust_gains) * ctrl)
        if rpm < robust_pm_min or np.max(np.abs(np.roots(char2))) >= 0.999:
            break
        best = (kii, m, rpm)
    return best


# ----------------------------------------------------------------------------- T_SOLL
def torque_guidance(motor: MotorData, J_total: float, coulomb: float = 0.0,
                    t_soll: int = 1023, reserve: float = 0.5) -> dict[str, float]:
    """How much torque a profile may use: T_SOLL and the A_SOLL it supports.

    Parameters
    ----------
    motor : MotorData
        Torque per VF_OUT unit K_vf [N·m].
    J_total : float
        Total inertia [kg·m²].
    coulomb : float
        Coulomb friction [N·m] (consumes torque).
    t_soll : int
        Torque limit T_SOLL (0..1023 of peak, manual 3.2.7).
    reserve : float
        Fraction of T_SOLL kept for the regulator (disturbances, tracking): the profile may
        use ``(1 − reserve)·T_SOLL``. With the function correction (docs/model.md §8) a profile that
        needs more than T_SOLL is slowed down and FNCERR grows.

    Returns
    -------
    dict
        ``T_SOLL``; ``torque_Nm`` at T_SOLL; ``A_SOLL_max`` (1/16 count/sample², the profile
        acceleration using ``1 − reserve`` of T_SOLL); ``accel_rad_s2`` at A_SOLL_max.
    """
    torque = motor.torque_per_vf * t_soll
    usable = max(0.0, (1.0 - reserve) * torque - coulomb)
    alpha = usable / J_total
    fam = motor.family
    a_soll = alpha * fam.counts_per_rad * fam.speed_units * fam.outer_dt**2
    return {"T_SOLL": float(t_soll), "torque_Nm": torque, "A_SOLL_max": float(math.floor(a_soll)),
            "accel_rad_s2": alpha}
