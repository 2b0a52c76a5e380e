"""The torque step's position error that the MAC800's integer current loop adds to the smooth
electrical model (:func:`tuning.identify_mechanics.electrical_position`).

The firmware's current loop works on integer registers (MAC800 register overview §1.2): the
phase current readings IA/IB/IC_IST (ADC counts), the setpoints IA/IB/IC_SOLL = I_NOM·sin(PHI_SOLL
+ k·120°) with PHI_SOLL from the 12-bit electrical angle ELDEG_IST (and V_ELDEG·PHASE_COMP/256,
register 173), and the PWM values UA/UB/UC_VAL, which the current filter (registers 144–149)
also keeps as its output history. The rounding is a deterministic function of the current
amplitude and the loop gains: averaged over the rotor's electrical angle at the step it does
not vanish but changes the torque by a few 1e-4 N·m, differently at each VF_OUT level. The
two-level fit reads a torque error that is constant in VF_OUT as Coulomb friction and one that
changes with the level as inertia, so the identification subtracts this average from the
records before its electrical fit (:func:`tuning.identify_buffer.identify_torque_steps`).

:func:`quantised_position` runs the per-phase loop (the smooth model's coil, back-EMF and rotor,
the same sample times and scales) for a batch of start angles at once, with the rounding
(round half away from zero, ELDEG_IST = floor of the angle) or without it (then it is the
smooth model); :func:`quantisation_error` is the mean over start angles of the difference.
The register overview gives the registers as integers but not how the firmware rounds: the
rounding mode, the 12-bit angle and the ±1023 ranges are the MAC800 family's decisions (its
``constants``), taken here from the family.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from .identify_mechanics import current_loop_model, electrical_position
from .models import MotorData
from .sixth_order import CONSTANTS as _c

__all__ = ["quantised_position", "quantisation_error", "START_ANGLES"]

START_ANGLES: int = 16  #: start angles over one electrical turn the error is averaged over
_SQRT3 = math.sqrt(3.0)


def _rnd(x: np.ndarray) -> np.ndarray:
    """Round half away from zero (the firmware's integer registers)."""
    return np.copysign(np.floor(np.abs(x) + 0.5), x)


def quantised_position(n: int, vf: float, J: float, motor: MotorData,
                       current_regs: Mapping[str, float], phase_comp: float,
                       start_eldeg: np.ndarray, rounding: bool = True) -> np.ndarray:
    """Position [counts] of a torque step of VF_OUT ``vf`` from rest with the per-phase
    integer current loop (module docstring), one row per start angle.

    Parameters
    ----------
    n : int
        Servo samples.
    vf : float
        VF_OUT of the step.
    J : float
        Inertia [kg·m²] (no friction: the rounding's effect, not the motion, is wanted).
    motor : MotorData
        Coil, PWM delay, bus voltage, AMPLITUDE, pole pairs, λ.
    current_regs : mapping
        KIFX2, KIFX1, KIFY1, KIFY0, KIB1, KIB0.
    phase_comp : float
        PHASE_COMP (register 173) as the register holds it.
    start_eldeg : ndarray
        The rotor's electrical angle at the step [ELDEG units], shape (K,).
    rounding : bool
        Round the readings, setpoints, PWM values and the angle as the firmware does; without
        it the same loop in real numbers.

    Returns
    -------
    ndarray
        P(k) − P(0), shape (K, n).
    """
    fam = motor.family
    turn = float(_c.ELDEG_PER_TURN)
    adc, pwm = float(_c.ADC_FULL), float(_c.PWM_FULL)
    q = _rnd if rounding else (lambda x: x)
    (h, per_outer, R, a, k_u, amps, pp, lam, kt,
     x2, x1, y1, y0, b1, b0) = current_loop_model(motor, current_regs)
    delay = int(motor.pwm_delay) > 0
    amp = abs(vf) * motor.amplitude / fam.amplitude_vf
    quarter = (turn / 4.0) if vf >= 0 else -(turn / 4.0)
    shifts = np.array([0.0, 2.0 * math.pi / 3.0, -2.0 * math.pi / 3.0])[:, None]
    rad_per_eldeg = 2.0 * math.pi / turn
    counts_per_rad = fam.counts_per_rad
    k = np.asarray(start_eldeg, dtype=float).size
    theta = (np.asarray(start_eldeg, dtype=float) + 0.5) * rad_per_eldeg / pp
    omega = np.zeros(k)
    s = np.zeros(k, dtype=complex)
    e1 = np.zeros((3, k))
    u1 = np.zeros((3, k))
    u2 = np.zeros((3, k))
    m_prev = np.zeros((3, k))
    pend = np.zeros((3, k))
    enc_prev = np.floor(theta * counts_per_rad)
    theta0 = theta.copy()
    out = np.empty((k, n))
    for j in range(n):
        out[:, j] = (theta - theta0) * counts_per_rad
        for _ in range(per_outer):
            th_e = pp * theta
            el = np.floor(th_e / rad_per_eldeg) if rounding else th_e / rad_per_eldeg
            enc = np.floor(theta * counts_per_rad)
            dv = enc - enc_prev if rounding else omega * h * counts_per_rad
            enc_prev = enc
            # the phase readings Re(s·e^{j·k·120°}), the setpoints I_NOM·sin(PHI + k·120°)
            meas = np.clip(q((s[None, :] * np.exp(1j * shifts)).real / amps), -adc, adc)
            phi = (el + quarter + q(dv * phase_comp / 256.0)) * rad_per_eldeg
            ref = np.clip(q(amp * np.sin(phi[None, :] + shifts)), -adc, adc)
            e = ref - (b1 * meas + b0 * m_prev)
            u = np.clip(q(x2 * e + x1 * e1 + y1 * u1 + y0 * u2), -pwm, pwm)
            e1, u2, u1, m_prev = e, u1, u, meas
            applied = pend if delay else u
            pend = u
            s_u = (2.0 * applied[0] - applied[1] - applied[2]) / 3.0 \
                + 1j * (applied[2] - applied[1]) / _SQRT3
            th_mid = th_e + 0.5 * pp * omega * h
            rot = np.exp(1j * th_mid)
            s_new = a * s + (1.0 - a) / R * (k_u * s_u - pp * omega * lam * rot)
            torque = kt * (0.5 * (s + s_new) * np.conj(rot)).real
            s = s_new
            omega_new = omega + torque / J * h
            theta = theta + 0.5 * (omega + omega_new) * h
            omega = omega_new
    return out


def quantisation_error(n: int, vf: float, J: float, motor: MotorData,
                       current_regs: Mapping[str, float], phase_comp: float = 0.0,
                       angles: int = START_ANGLES) -> np.ndarray:
    """Mean position error [counts] the rounding adds to a torque step of VF_OUT ``vf`` from
    rest over ``angles`` start angles spread evenly over one electrical turn, shape (n,): the
    mean of :func:`quantised_position` less the smooth model
    (:func:`tuning.identify_mechanics.electrical_position`, the same loop without rounding,
    which does not depend on the start angle)."""
    start = np.floor((np.arange(angles) + 0.5) * (_c.ELDEG_PER_TURN / angles))
    with_r = quantised_position(n, vf, J, motor, current_regs, phase_comp, start, True)
    smooth = electrical_position(n, vf, J, 0.0, 0.0, motor, current_regs, phase_comp / 256.0)
    return with_r.mean(axis=0) - smooth
