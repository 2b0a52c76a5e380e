"""Plant and filter models of the MAC50–141 current and speed loops (python-control).

Everything here is the *exact* discrete model the firmware and the simulator implement
(docs/model.md §2, §3, §6, §7; manual 4.2, 4.3 and the filter registers 3.2.89–3.2.111):

* inner (current) loop at ``TS_I`` = 128 µs, outer (speed) loop at ``TS_O`` = 15·TS_I = 1.92 ms;
* per phase, from the PWM value ``U`` [PWM counts] to the measured current ``I_IST`` [ADC counts]::

      I_IST(z)/U(z) = g (1 − a) / (z^d (z − a)),   a = exp(−R·TS_I/L),   g = k_u / (R·A_count)

  with ``k_u = U_supply/2/1023`` volts per PWM count and ``d`` the PWM delay (0 or 1);
* filter transfer functions exactly as printed in the manual, including the sign convention of
  the IF and VF denominators (3.2.93–3.2.100, 3.2.106–3.2.109);
* the speed plant from VF_OUT to V_IST: the current loop closed at the inner rate, the rigid
  rotor ``J dω/dt = K_t·i − b·ω``, the encoder in counts, lifted exactly to the outer rate
  (VF_OUT held for 15 inner samples, the position sampled every 15th), and
  ``V_IST = (1 − z⁻¹)·P``. With an ideal current loop it reduces to
  ``(4096/2π)·K_vf·TS_O²/(2J)·(z+1)/(z(z−1))``.

Register values are passed as plain ``dict[str, float]`` (register name → value in user units),
the same mapping a ``families/mac050_141/configs/setups/*.yaml`` file holds.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Any

import control as ct
import numpy as np
from scipy.linalg import expm

from jvl_gym.families.mac050_141 import constants as _c

__all__ = [
    "TS_I",
    "TS_O",
    "INNER_PER_OUTER",
    "PWM_FULL",
    "ADC_FULL",
    "COUNTS_PER_REV",
    "MotorData",
    "coil_tf",
    "if_tf",
    "ib_tf",
    "ff_tf",
    "vb_tf",
    "vf_tf",
    "current_open_loop",
    "current_closed_loop",
    "speed_plant",
    "inner_modes",
    "rigid_speed_plant",
    "speed_open_loop",
    "speed_closed_loop",
    "freqresp",
]

#: sample times and scales, one source: the family's constants
#: (:mod:`jvl_gym.families.mac050_141.constants`; manual 1.2, 3.2.12, 3.2.139; docs/model.md
#: §2). TS_I: inner (current-loop) sample time [s]; TS_O = INNER_PER_OUTER·TS_I: outer
#: (speed-loop) sample time [s]; PWM_FULL: UA_VAL full scale ↔ U_supply/2; ADC_FULL: IA_IST..
#: measurement range; COUNTS_PER_REV: encoder counts per revolution.
TS_I: float = _c.INNER_DT
INNER_PER_OUTER: int = _c.INNER_PER_OUTER
TS_O: float = _c.OUTER_DT
PWM_FULL: int = _c.PWM_FULL
ADC_FULL: int = _c.ADC_FULL
COUNTS_PER_REV: int = _c.COUNTS_PER_REV
COUNTS_PER_RAD: float = COUNTS_PER_REV / (2.0 * math.pi)  #: encoder counts per radian


@dataclass(frozen=True)
class MotorData:
    """Physical data of one motor, SI units (docs/model.md §15; representative values).

    Parameters
    ----------
    name : str
        Motor type (``"MAC140"``).
    J_m : float
        Rotor inertia [kg·m²]; KVOUT is relative to it (manual 3.2.13).
    flux_linkage : float
        λ [V·s] (peak, per phase).
    R_phase, L_phase : float
        Phase resistance [Ω] and inductance [H].
    amps_per_count : float
        Current measurement scale [A per ADC count].
    pole_pairs : int
        p.
    supply_voltage : float
        Bus voltage [V].
    pwm_delay : int
        Inner samples between computing a PWM value and applying it (0 or 1).
    amplitude : float
        AMPLITUDE register (3.2.127): phase current amplitude per VF_OUT unit [ADC counts].
    """

    name: str
    J_m: float
    flux_linkage: float
    R_phase: float
    L_phase: float
    amps_per_count: float
    pole_pairs: int = 2
    supply_voltage: float = 48.0
    pwm_delay: int = 1
    amplitude: float = 0.83

    @classmethod
    def from_config(cls, motor: Any, amplitude: float = 0.83) -> MotorData:
        """Build from a motor type name, a config path or a motor config
        (``jvl_gym.families.mac050_141.config.MotorConfig``)."""
        from jvl_gym.families.mac050_141.config import MotorConfig, load_motor

        cfg = motor if isinstance(motor, MotorConfig) else load_motor(motor)
        return cls(name=cfg.name, J_m=cfg.rotor_inertia, flux_linkage=cfg.flux_linkage,
                   R_phase=cfg.phase_resistance, L_phase=cfg.phase_inductance,
                   amps_per_count=cfg.amps_per_count, pole_pairs=cfg.pole_pairs,
                   supply_voltage=cfg.supply_voltage, pwm_delay=cfg.pwm_delay_samples,
                   amplitude=amplitude)

    def with_(self, **changes: Any) -> MotorData:
        """A copy with some fields changed (e.g. identified R and L)."""
        return replace(self, **changes)

    @property
    def volts_per_count(self) -> float:
        """k_u: phase-to-midpoint volts per PWM count [V]."""
        return self.supply_voltage / 2.0 / PWM_FULL

    @property
    def coil_pole(self) -> float:
        """a = exp(−R·TS_I/L) (dimensionless)."""
        return math.exp(-self.R_phase * TS_I / self.L_phase)

    @property
    def coil_gain(self) -> float:
        """g = k_u/(R·A_count): steady-state ADC counts per PWM count."""
        return self.volts_per_count / (self.R_phase * self.amps_per_count)

    @property
    def torque_constant(self) -> float:
        """K_t = 1.5·p·λ: torque per ampere of phase current amplitude [N·m/A]."""
        return 1.5 * self.pole_pairs * self.flux_linkage

    @property
    def torque_per_vf(self) -> float:
        """K_vf = 1.5·p·λ·A_count·AMPLITUDE: torque per VF_OUT unit [N·m] (manual 4.3)."""
        return self.torque_constant * self.amps_per_count * self.amplitude


# ----------------------------------------------------------------------------- filters
def _tf(num: list[float], den: list[float], dt: float) -> ct.TransferFunction:
    return ct.tf(np.asarray(num, dtype=float), np.asarray(den, dtype=float), dt)


def coil_tf(motor: MotorData) -> ct.TransferFunction:
    """Per-phase coil, ``U`` [PWM counts] → ``I_IST`` [ADC counts], ZOH-exact, at TS_I.

    ``g(1 − a)/(z^d (z − a))`` (docs/model.md §6, one-sample PWM delay for d = 1).
    """
    a, g, d = motor.coil_pole, motor.coil_gain, int(motor.pwm_delay)
    den = np.polymul([1.0, -a], [1.0] + [0.0] * d)
    return _tf([g * (1.0 - a)], list(den), TS_I)


def if_tf(regs: Mapping[str, float], dt: float = TS_I) -> ct.TransferFunction:
    """IF filter (3.2.106–3.2.109): ``(KIFX2 z² + KIFX1 z)/(z² − KIFY1 z − KIFY0)``.

    ``dt``: the family's current-loop sample time [s] (the MAC800's current filter has the
    same structure, register overview §1.2 registers 144–149).
    """
    return _tf([regs["KIFX2"], regs["KIFX1"], 0.0], [1.0, -regs["KIFY1"], -regs["KIFY0"]], dt)


def ib_tf(regs: Mapping[str, float], dt: float = TS_I) -> ct.TransferFunction:
    """IB filter (3.2.110–3.2.111): ``(KIB1 z + KIB0)/z`` (``dt`` as in :func:`if_tf`)."""
    return _tf([regs["KIB1"], regs["KIB0"]], [1.0, 0.0], dt)


def ff_tf(regs: Mapping[str, float]) -> ct.TransferFunction:
    """FF filter (3.2.89–3.2.92): ``(KFF3 z³ + KFF2 z² + KFF1 z + KFF0)/z³``."""
    return _tf([regs["KFF3"], regs["KFF2"], regs["KFF1"], regs["KFF0"]], [1.0, 0, 0, 0], TS_O)


def vb_tf(regs: Mapping[str, float]) -> ct.TransferFunction:
    """VB filter with GEARB (3.2.101–3.2.105): ``GEARB·(KVB3 z³ + … + KVB0)/z³``."""
    gb = regs["GEARB"]
    return _tf([gb * regs["KVB3"], gb * regs["KVB2"], gb * regs["KVB1"], gb * regs["KVB0"]],
               [1.0, 0, 0, 0], TS_O)


def vf_tf(regs: Mapping[str, float], with_kvout: bool = True) -> ct.TransferFunction:
    """VF filter (3.2.93–3.2.100), times KVOUT (3.2.13) unless ``with_kvout`` is False.

    ``(KVFX4 z⁴ + KVFX3 z³ + KVFX2 z² + KVFX1 z)/(z⁴ − KVFY3 z³ − KVFY2 z² − KVFY1 z − KVFY0)``
    (note the sign convention of the denominator).
    """
    k = regs["KVOUT"] if with_kvout else 1.0
    num = [k * regs["KVFX4"], k * regs["KVFX3"], k * regs["KVFX2"], k * regs["KVFX1"], 0.0]
    den = [1.0, -regs["KVFY3"], -regs["KVFY2"], -regs["KVFY1"], -regs["KVFY0"]]
    return _tf(num, den, TS_O)


# ----------------------------------------------------------------------------- current loop
def current_open_loop(motor: MotorData, regs: Mapping[str, float]) -> ct.TransferFunction:
    """Current loop broken at the PWM output: ``L = IF·coil·IB`` (per phase, at TS_I)."""
    return if_tf(regs) * coil_tf(motor) * ib_tf(regs)


def current_closed_loop(motor: MotorData, regs: Mapping[str, float]) -> ct.TransferFunction:
    """``I_SOLL`` → ``I_IST`` (per phase, ADC counts/ADC counts): ``IF·P/(1 + IF·P·IB)``."""
    fwd = if_tf(regs) * coil_tf(motor)
    return ct.feedback(fwd, ib_tf(regs))


def _inner_position_ss(motor: MotorData, regs: Mapping[str, float], J: float, b: float,
                       coupling: tuple[float, float, float] | None = None,
                       back_emf: bool = False) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Inner-rate state space, input I_SOLL [counts], output encoder position [counts].

    States: continuous plant (i [A], ω [rad/s], θ [counts], and with ``coupling = (J_l, k,
    d)`` the load speed ω_l [rad/s] and the twist θ − θ_l [rad] of the two-mass plant of
    docs/model.md §5.2, ``J`` then being the rotor's inertia) sampled at TS_I, the PWM delay
    line, IF and IB states. The back-EMF is left out (it is a disturbance the PI rejects).
    """
    k_u, R, L, A = motor.volts_per_count, motor.R_phase, motor.L_phase, motor.amps_per_count
    kt = motor.torque_constant
    ke = motor.pole_pairs * motor.flux_linkage if back_emf else 0.0
    ac = np.array([[-R / L, -ke / L, 0.0], [kt / J, -b / J, 0.0], [0.0, COUNTS_PER_RAD, 0.0]])
    if coupling is not None:
        j_l, k, d = coupling
        ac = np.pad(ac, ((0, 2), (0, 2)))
        ac[1, 1] -= d / J
        ac[1, 3] = d / J
        ac[1, 4] = -k / J
        ac[3, 1] = d / j_l
        ac[3, 3] = -d / j_l
        ac[3, 4] = k / j_l
        ac[4, 1] = 1.0
        ac[4, 3] = -1.0
    ns = ac.shape[0]
    bc = np.zeros((ns, 1))
    bc[0, 0] = k_u / L
    m = np.zeros((ns + 1, ns + 1))
    m[:ns, :ns] = ac * TS_I
    m[:ns, ns:] = bc * TS_I
    e = expm(m)
    ad, bd = e[:ns, :ns], e[:ns, ns:]
    cc = np.zeros((2, ns))
    cc[0, 0] = 1.0 / A
    cc[1, 2] = 1.0
    plant = ct.ss(ad, bd, cc, np.zeros((2, 1)), TS_I)
    d = int(motor.pwm_delay)
    delay = ct.tf([1.0], [1.0] + [0.0] * d, TS_I) if d else ct.tf([1.0], [1.0], TS_I)
    p_u = plant * ct.ss(delay)
    ifs = ct.ss(if_tf(regs))
    ibs = ct.ss(ib_tf(regs))
    p_u = ct.ss(p_u.A, p_u.B, p_u.C, p_u.D, TS_I, inputs="u", outputs=["iist", "pos"])
    ifs = ct.ss(ifs.A, ifs.B, ifs.C, ifs.D, TS_I, inputs="e", outputs="u")
    ibs = ct.ss(ibs.A, ibs.B, ibs.C, ibs.D, TS_I, inputs="iist", outputs="ibf")
    sumblk = ct.summing_junction(inputs=["isoll", "-ibf"], output="e", dt=TS_I)
    sys = ct.interconnect([p_u, ifs, ibs, sumblk], inputs="isoll", outputs="pos")
    return np.asarray(sys.A), np.asarray(sys.B), np.asarray(sys.C)


def inner_modes(motor: MotorData, regs: Mapping[str, float], J: float, b: float = 0.0,
                coupling: tuple[float, float, float] | None = None,
                back_emf: bool = False) -> np.ndarray:
    """Modes of the plant under its closed current loop at a constant I_SOLL (AT_MODE, manual
    4.4.5): the inner-rate closed-loop poles z ≠ 0 as ``s = ln(z)/TS_I`` [1/s]; arguments as
    :func:`_inner_position_ss`."""
    z = np.linalg.eigvals(_inner_position_ss(motor, regs, J, b, coupling, back_emf)[0])
    z = z[np.abs(z) > 1e-12].astype(complex)
    return np.log(z) / TS_I


def speed_plant(motor: MotorData, regs: Mapping[str, float], J: float | None = None,
                b: float = 0.0, coupling: tuple[float, float, float] | None = None,
                back_emf: bool = False) -> ct.TransferFunction:
    """VF_OUT → V_IST [counts/sample] at TS_O, including the closed current loop.

    Parameters
    ----------
    motor : MotorData
        Coil, torque constant and AMPLITUDE.
    regs : mapping
        Current-loop registers KIFX2..KIFY0, KIB1, KIB0.
    J : float, optional
        Total inertia [kg·m²]; default ``motor.J_m``.
    b : float
        Viscous friction [N·m·s/rad].
    coupling : (float, float, float), optional
        ``(J_l, k, d)``: a load of inertia J_l [kg·m²] behind an elastic coupling of stiffness
        k [N·m/rad] and damping d [N·m·s/rad] (docs/model.md §5.2); ``J`` is then the rotor's
        inertia alone.
    back_emf : bool
        Include the back-EMF in the coil (:func:`_inner_position_ss`).

    Returns
    -------
    TransferFunction
        Exact lift to the outer rate: VF_OUT is held for 15 inner samples (I_SOLL =
        AMPLITUDE·VF_OUT from inner sample 15m on), the encoder is read at the start of each
        outer sample, V_IST = (1 − z⁻¹)·P.
    """
    J = motor.J_m if J is None else J
    a, bb, c = _inner_position_ss(motor, regs, J, b, coupling, back_emf)
    n = INNER_PER_OUTER
    a_o = np.linalg.matrix_power(a, n)
    acc = np.zeros_like(a)
    pw = np.eye(a.shape[0])
    for _ in range(n):
        acc += pw
        pw = pw @ a
    b_o = acc @ bb * motor.amplitude
    # V_IST(m) = θ(m) − θ(m−1): θ feeds nothing back, so drop its state and output the increment
    k = int(np.argmax(np.abs(c[0])))
    keep = [i for i in range(a_o.shape[0]) if i != k]
    inc_c = (c[0] @ (a_o - np.eye(a_o.shape[0])))[keep][None, :]
    inc = ct.ss(a_o[np.ix_(keep, keep)], b_o[keep], inc_c, (c[0] @ b_o)[None, :], TS_O)
    delay = ct.tf([1.0], [1.0, 0.0], TS_O)
    return ct.minreal(ct.tf(inc) * delay, tol=1e-10, verbose=False)


def rigid_speed_plant(motor: MotorData, J: float | None = None) -> ct.TransferFunction:
    """Ideal current loop: ``(4096/2π)·K_vf·TS_O²/(2J)·(z+1)/(z(z−1))`` (VF_OUT → V_IST)."""
    J = motor.J_m if J is None else J
    k = COUNTS_PER_RAD * motor.torque_per_vf * TS_O**2 / (2.0 * J)
    return _tf([k, k], [1.0, -1.0, 0.0], TS_O)


def speed_open_loop(plant: ct.TransferFunction, regs: Mapping[str, float]
                    ) -> ct.TransferFunction:
    """Speed loop broken at VF_OUT: ``L = KVOUT·VF·GEARB·VB·P`` (manual 4.2)."""
    return vf_tf(regs) * vb_tf(regs) * plant


def speed_closed_loop(plant: ct.TransferFunction, regs: Mapping[str, float]
                      ) -> ct.TransferFunction:
    """FNC_OUT [1/16 count/sample] → 16·V_IST [1/16 count/sample]: ``16·FF·KVOUT·VF·P/(1+L)``."""
    fwd = vf_tf(regs) * plant
    return ff_tf(regs) * ct.feedback(fwd, vb_tf(regs)) * 16.0


def freqresp(sys: ct.TransferFunction, w: np.ndarray) -> np.ndarray:
    """Complex frequency response of a discrete SISO transfer function at ``w`` [rad/s].

    Evaluated directly from the numerator and denominator polynomials (fast, no warnings).
    """
    num = np.asarray(sys.num[0][0], dtype=float)
    den = np.asarray(sys.den[0][0], dtype=float)
    z = np.exp(1j * np.asarray(w) * sys.dt)
    return np.polyval(num, z) / np.polyval(den, z)
