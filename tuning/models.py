"""Plant and filter models of the current and speed loops of the tuned families (python-control).

Everything here is the *exact* discrete model the firmware and the simulator implement
(MAC050–141: docs/model.md §2, §3, §6, §7, manual 4.2, 4.3 and the filter registers
3.2.89–3.2.111; MAC800: the same loops on its registers, register overview §1.2 and
:mod:`tuning.sixth_order`). The family's numbers come from the family contract's
:class:`~jvl_gym.families.TuningSpec` (``motor.family``, or the ``family`` argument of the
filter functions), e.g. for the MAC050–141:

* inner (current) loop at ``TS_I`` (MAC050–141: 128 µs), outer (speed) loop at
  ``TS_O`` = 15·TS_I (1.92 ms);
* per phase, from the PWM value ``U`` [PWM counts] to the measured current ``I_IST`` [ADC counts]::

      I_IST(z)/U(z) = g (1 − a) / (z^d (z − a)),   a = exp(−R·TS_I/L),   g = k_u / (R·A_count)

  with ``k_u = U_supply/2/1023`` volts per PWM count and ``d`` the PWM delay (0 or 1);
* filter transfer functions exactly as printed in the manual, including the sign convention of
  the IF and VF denominators (3.2.93–3.2.100, 3.2.106–3.2.109); FF, VB and VF with the family's
  taps (MAC800: six FF, five VB, six VF numerator and denominator taps);
* the speed plant from VF_OUT to V_IST: the current loop closed at the inner rate, the rigid
  rotor ``J dω/dt = K_t·i − b·ω``, the encoder in counts, lifted exactly to the outer rate
  (VF_OUT held for 15 inner samples, the position sampled every 15th), and
  ``V_IST = (1 − z⁻¹)·P``. With an ideal current loop it reduces to
  ``(counts/rev/2π)·K_vf·TS_O²/(2J)·(z+1)/(z(z−1))``.

Register values are passed as plain ``dict[str, float]`` (register name → value in user units),
the same mapping a ``families/<family>/configs/setups/*.yaml`` file holds.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from typing import Any

import control as ct
import numpy as np
from scipy.linalg import expm

from jvl_gym.families import TuningSpec

from .family import setup_registers, tuned_family

__all__ = [
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
    "rigid_gain",
    "rigid_speed_plant",
    "speed_open_loop",
    "speed_closed_loop",
    "freqresp",
    "polymul",
]


@dataclass(frozen=True)
class MotorData:
    """Physical data of one motor, SI units, and its family's tuning facts (docs/model.md §15;
    representative values).

    Parameters
    ----------
    name : str
        Motor type (``"MAC140"``, ``"MAC800"``).
    J_m : float
        Rotor inertia [kg·m²]; KVOUT is relative to it (MAC050–141 manual 3.2.13; MAC800
        register 13).
    flux_linkage : float
        λ [V·s] (peak, per phase).
    R_phase, L_phase : float
        Phase resistance [Ω] and inductance [H].
    amps_per_count : float
        Current measurement scale [A per ADC count].
    pole_pairs : int
        p.
    supply_voltage : float
        Supply (DC bus) voltage [V] (MAC800: U_BUS, register 198).
    pwm_delay : int
        Inner samples between computing a PWM value and applying it (0 or 1).
    amplitude : float
        AMPLITUDE register: the phase current amplitude [ADC counts] at VF_OUT =
        ``family.amplitude_vf`` (MAC050–141 manual 3.2.127: per VF_OUT unit; MAC800 register
        174: at VF_OUT = 1023).
    family : TuningSpec
        The motor family's sample times, scales and filter taps (``Family.tuning`` of the
        family contract, :mod:`tuning.family`).
    """

    name: str
    J_m: float
    flux_linkage: float
    R_phase: float
    L_phase: float
    amps_per_count: float
    pole_pairs: int
    supply_voltage: float
    pwm_delay: int
    amplitude: float
    family: TuningSpec = field(repr=False)

    @classmethod
    def from_config(cls, motor: Any, amplitude: float | None = None) -> MotorData:
        """Build from a motor type name, a config path or a motor config of a tuned family
        (:func:`tuning.family.tuned_family`); AMPLITUDE from the type's default setup unless
        given, the register table's ROM default where the setup leaves it out.

        Raises
        ------
        ValueError
            The motor's family has no tuning procedure.
        """
        fam = tuned_family(motor)
        cfg = fam.load_motor(motor)
        if amplitude is None:
            amplitude = setup_registers(fam, cfg).get(
                "AMPLITUDE", float(fam.table.lookup("AMPLITUDE").default))
        return cls(name=cfg.name, J_m=cfg.rotor_inertia, flux_linkage=cfg.flux_linkage,
                   R_phase=cfg.phase_resistance, L_phase=cfg.phase_inductance,
                   amps_per_count=cfg.amps_per_count, pole_pairs=cfg.pole_pairs,
                   supply_voltage=cfg.supply_voltage, pwm_delay=cfg.pwm_delay_samples,
                   amplitude=amplitude, family=fam.tuning)

    def with_(self, **changes: Any) -> MotorData:
        """A copy with some fields changed (e.g. identified R and L)."""
        return replace(self, **changes)

    @property
    def volts_per_count(self) -> float:
        """k_u: phase-to-midpoint volts per PWM count [V] (±PWM_FULL ↔ ±U_supply/2)."""
        return self.supply_voltage / 2.0 / self.family.pwm_full

    @property
    def coil_pole(self) -> float:
        """a = exp(−R·TS_I/L) (dimensionless), TS_I the family's current-loop sample time."""
        return math.exp(-self.R_phase * self.family.inner_dt / self.L_phase)

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
        """K_vf = 1.5·p·λ·A_count·AMPLITUDE/amplitude_vf: torque per VF_OUT unit [N·m]
        (MAC050–141 manual 4.3; MAC800 register 174, amplitude_vf = 1023)."""
        k_t, amp = self.torque_constant, self.amplitude
        return k_t * self.amps_per_count * amp / self.family.amplitude_vf


# ----------------------------------------------------------------------------- filters
def _tf(num: list[float], den: list[float], dt: float) -> ct.TransferFunction:
    return ct.tf(np.asarray(num, dtype=float), np.asarray(den, dtype=float), dt)


def coil_tf(motor: MotorData) -> ct.TransferFunction:
    """Per-phase coil, ``U`` [PWM counts] → ``I_IST`` [ADC counts], ZOH-exact, at TS_I.

    ``g(1 − a)/(z^d (z − a))`` (docs/model.md §6, one-sample PWM delay for d = 1).
    """
    a, g, d = motor.coil_pole, motor.coil_gain, int(motor.pwm_delay)
    den = np.polymul([1.0, -a], [1.0] + [0.0] * d)
    return _tf([g * (1.0 - a)], list(den), motor.family.inner_dt)


def if_tf(regs: Mapping[str, float], dt: float) -> ct.TransferFunction:
    """IF filter (3.2.106–3.2.109): ``(KIFX2 z² + KIFX1 z)/(z² − KIFY1 z − KIFY0)``.

    ``dt``: the family's current-loop sample time [s] (the MAC800's current filter has the
    same structure, register overview §1.2 registers 144–149).
    """
    return _tf([regs["KIFX2"], regs["KIFX1"], 0.0], [1.0, -regs["KIFY1"], -regs["KIFY0"]], dt)


def ib_tf(regs: Mapping[str, float], dt: float) -> ct.TransferFunction:
    """IB filter (3.2.110–3.2.111): ``(KIB1 z + KIB0)/z`` (``dt`` as in :func:`if_tf`)."""
    return _tf([regs["KIB1"], regs["KIB0"]], [1.0, 0.0], dt)


def _fir(taps: list[float], dt: float) -> ct.TransferFunction:
    """``Σ taps[d]·z⁻ᵈ`` (taps of delay 0, 1, …) as a TF in z at ``dt``."""
    return _tf(taps, [1.0] + [0.0] * (len(taps) - 1), dt)


def ff_tf(regs: Mapping[str, float], family: TuningSpec) -> ct.TransferFunction:
    """FF filter on the family's taps, at its TS_O: MAC050–141 (3.2.89–3.2.92)
    ``(KFF3 z³ + KFF2 z² + KFF1 z + KFF0)/z³``; MAC800 (registers 121–126)
    ``KFF5 + KFF4 z⁻¹ + … + KFF0 z⁻⁵``."""
    return _fir([regs[k] for k in family.ff_keys], family.outer_dt)


def vb_tf(regs: Mapping[str, float], family: TuningSpec) -> ct.TransferFunction:
    """VB filter on the family's taps, at its TS_O, from V_IST [counts/sample] to the speed
    error's unit [1/16 count/sample]: MAC050–141 with GEARB (3.2.101–3.2.105)
    ``GEARB·(KVB3 z³ + … + KVB0)/z³``; MAC800 (registers 139–143, the firmware's 16·V_IST)
    ``16·(KVB4 + KVB3 z⁻¹ + … + KVB0 z⁻⁴)``."""
    reg = family.vb_gain_register
    gain = regs[reg] if reg is not None else family.speed_units
    return _fir([gain * regs[k] for k in family.vb_keys], family.outer_dt)


def vf_tf(regs: Mapping[str, float], family: TuningSpec,
          with_gain: bool = True) -> ct.TransferFunction:
    """VF filter on the family's taps, at its TS_O, times its gain KVOUT·2^−MODEL_POT unless
    ``with_gain`` is False (KVOUT: MAC050–141 3.2.13, MAC800 register 13; MODEL_POT: MAC800
    register 154, 0 where ``regs`` has none).

    MAC050–141 (3.2.93–3.2.100):
    ``(KVFX4 z⁴ + KVFX3 z³ + KVFX2 z² + KVFX1 z)/(z⁴ − KVFY3 z³ − KVFY2 z² − KVFY1 z − KVFY0)``;
    MAC800 (registers 127–138): ``(KVFX6 + … + KVFX1 z⁻⁵)/(1 − KVFY5 z⁻¹ − … − KVFY0 z⁻⁶)``
    (note the sign convention of the denominator).
    """
    k = regs["KVOUT"] * 2.0 ** -regs.get("MODEL_POT", 0.0) if with_gain else 1.0
    num = [k * regs[x] for x in family.vfx_keys] + [0.0]
    den = [1.0] + [-regs[y] for y in family.vfy_keys]
    return _tf(num, den, family.outer_dt)


# ----------------------------------------------------------------------------- current loop
def current_open_loop(motor: MotorData, regs: Mapping[str, float]) -> ct.TransferFunction:
    """Current loop broken at the PWM output: ``L = IF·coil·IB`` (per phase, at TS_I)."""
    dt = motor.family.inner_dt
    return if_tf(regs, dt) * coil_tf(motor) * ib_tf(regs, dt)


def current_closed_loop(motor: MotorData, regs: Mapping[str, float]) -> ct.TransferFunction:
    """``I_SOLL`` → ``I_IST`` (per phase, ADC counts/ADC counts): ``IF·P/(1 + IF·P·IB)``."""
    dt = motor.family.inner_dt
    fwd = if_tf(regs, dt) * coil_tf(motor)
    return ct.feedback(fwd, ib_tf(regs, dt))


def _inner_position_ss(motor: MotorData, regs: Mapping[str, float], J: float, b: float,
                       coupling: tuple[float, float, float] | None = None,
                       back_emf: bool = False) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Inner-rate state space, input I_SOLL [counts], output encoder position [counts].

    States: continuous plant (i [A], ω [rad/s], θ [counts], and with ``coupling = (J_l, k,
    d)`` the load speed ω_l [rad/s] and the twist θ − θ_l [rad] of the two-mass plant of
    docs/model.md §5.2, ``J`` then being the rotor's inertia) sampled at the family's TS_I, the
    PWM delay line, IF and IB states. The back-EMF is left out unless ``back_emf`` (it is a
    disturbance the PI rejects).
    """
    ts_i = motor.family.inner_dt
    k_u, R, L, A = motor.volts_per_count, motor.R_phase, motor.L_phase, motor.amps_per_count
    kt = motor.torque_constant
    ke = motor.pole_pairs * motor.flux_linkage if back_emf else 0.0
    ac = np.array([[-R / L, -ke / L, 0.0], [kt / J, -b / J, 0.0],
                   [0.0, motor.family.counts_per_rad, 0.0]])
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
    m[:ns, :ns] = ac * ts_i
    m[:ns, ns:] = bc * ts_i
    e = expm(m)
    ad, bd = e[:ns, :ns], e[:ns, ns:]
    cc = np.zeros((2, ns))
    cc[0, 0] = 1.0 / A
    cc[1, 2] = 1.0
    plant = ct.ss(ad, bd, cc, np.zeros((2, 1)), ts_i)
    d = int(motor.pwm_delay)
    delay = ct.tf([1.0], [1.0] + [0.0] * d, ts_i)
    p_u = plant * ct.ss(delay)
    ifs = ct.ss(if_tf(regs, ts_i))
    ibs = ct.ss(ib_tf(regs, ts_i))
    p_u = ct.ss(p_u.A, p_u.B, p_u.C, p_u.D, ts_i, inputs="u", outputs=["iist", "pos"])
    ifs = ct.ss(ifs.A, ifs.B, ifs.C, ifs.D, ts_i, inputs="e", outputs="u")
    ibs = ct.ss(ibs.A, ibs.B, ibs.C, ibs.D, ts_i, inputs="iist", outputs="ibf")
    sumblk = ct.summing_junction(inputs=["isoll", "-ibf"], output="e", dt=ts_i)
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
    return np.log(z) / motor.family.inner_dt


def speed_plant(motor: MotorData, regs: Mapping[str, float], J: float | None = None,
                b: float = 0.0, coupling: tuple[float, float, float] | None = None,
                back_emf: bool = False) -> ct.TransferFunction:
    """VF_OUT → V_IST [counts/sample] at the family's TS_O, including the closed current loop.

    Parameters
    ----------
    motor : MotorData
        Coil, torque constant, AMPLITUDE and the family's rates.
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
        AMPLITUDE·VF_OUT/amplitude_vf from inner sample 15m on), the encoder is read at the
        start of each outer sample, V_IST = (1 − z⁻¹)·P. The same arguments give the same
        object (the last :data:`PLANT_CACHE_SIZE` plants are kept): do not modify it.
    """
    J = motor.J_m if J is None else J
    key = _plant_key(motor, regs, J, b, coupling, back_emf)
    plant = _PLANTS.get(key)
    if plant is None:
        plant = _lifted_speed_plant(motor, regs, J, b, coupling, back_emf)
        if len(_PLANTS) >= PLANT_CACHE_SIZE:
            _PLANTS.pop(next(iter(_PLANTS)))
        _PLANTS[key] = plant
    return plant


PLANT_CACHE_SIZE: int = 256  #: speed plants :func:`speed_plant` keeps (oldest dropped first)
_PLANTS: dict[tuple[Any, ...], ct.TransferFunction] = {}
_CURRENT_LOOP_KEYS = ("KIFX2", "KIFX1", "KIFY1", "KIFY0", "KIB1", "KIB0")


def _plant_key(motor: MotorData, regs: Mapping[str, float], J: float, b: float,
               coupling: tuple[float, float, float] | None, back_emf: bool) -> tuple[Any, ...]:
    """What :func:`speed_plant` depends on, every number as its exact bits (``float.hex``, so
    that −0.0 and 0.0 are different keys): the motor's data and family, the current-loop
    registers, J, b, the coupling and ``back_emf``."""
    data = tuple(float(getattr(motor, f)).hex() for f in
                 ("J_m", "flux_linkage", "R_phase", "L_phase", "amps_per_count", "pole_pairs",
                  "supply_voltage", "pwm_delay", "amplitude"))
    return (motor.name, motor.family, data,
            tuple(float(regs[k]).hex() for k in _CURRENT_LOOP_KEYS), float(J).hex(),
            float(b).hex(), None if coupling is None else tuple(float(x).hex() for x in coupling),
            bool(back_emf))


def _lifted_speed_plant(motor: MotorData, regs: Mapping[str, float], J: float, b: float,
                        coupling: tuple[float, float, float] | None,
                        back_emf: bool) -> ct.TransferFunction:
    """:func:`speed_plant` computed (the exact lift of :func:`_inner_position_ss`)."""
    fam = motor.family
    a, bb, c = _inner_position_ss(motor, regs, J, b, coupling, back_emf)
    n = fam.inner_per_outer
    a_o = np.linalg.matrix_power(a, n)
    acc = np.zeros_like(a)
    pw = np.eye(a.shape[0])
    for _ in range(n):
        acc += pw
        pw = pw @ a
    b_o = acc @ bb * motor.amplitude / fam.amplitude_vf
    # V_IST(m) = θ(m) − θ(m−1): θ feeds nothing back, so drop its state and output the increment
    k = int(np.argmax(np.abs(c[0])))
    keep = [i for i in range(a_o.shape[0]) if i != k]
    inc_c = (c[0] @ (a_o - np.eye(a_o.shape[0])))[keep][None, :]
    ts_o = fam.outer_dt
    inc = ct.ss(a_o[np.ix_(keep, keep)], b_o[keep], inc_c, (c[0] @ b_o)[None, :], ts_o)
    delay = ct.tf([1.0], [1.0, 0.0], ts_o)
    return ct.minreal(ct.tf(inc) * delay, tol=1e-10, verbose=False)


def rigid_gain(motor: MotorData, J: float | None = None) -> float:
    """Kpl = (counts/rev/2π)·K_vf·TS_O²/(2·J): the rigid rotor's V_IST per VF_OUT [counts/sample
    per VF_OUT unit] at KVOUT = 1, TS_O the family's servo sample time; ``J`` default J_m."""
    J = motor.J_m if J is None else J
    return motor.family.counts_per_rad * motor.torque_per_vf * motor.family.outer_dt**2 / (2.0 * J)


def rigid_speed_plant(motor: MotorData, J: float | None = None) -> ct.TransferFunction:
    """Ideal current loop: ``Kpl·(z+1)/(z(z−1))`` (VF_OUT → V_IST, :func:`rigid_gain`)."""
    k = rigid_gain(motor, J)
    return _tf([k, k], [1.0, -1.0, 0.0], motor.family.outer_dt)


def speed_open_loop(plant: ct.TransferFunction, regs: Mapping[str, float],
                    family: TuningSpec) -> ct.TransferFunction:
    """Speed loop broken at VF_OUT: ``L = KVOUT·VF·VB·P`` with VB's gain (MAC050–141 manual 4.2:
    GEARB; MAC800: 16, :func:`vb_tf`)."""
    return vf_tf(regs, family) * vb_tf(regs, family) * plant


def speed_closed_loop(plant: ct.TransferFunction, regs: Mapping[str, float],
                      family: TuningSpec) -> ct.TransferFunction:
    """FNC_OUT [1/16 count/sample] → 16·V_IST [1/16 count/sample]: ``16·FF·KVOUT·VF·P/(1+L)``."""
    fwd = vf_tf(regs, family) * plant
    return ff_tf(regs, family) * ct.feedback(fwd, vb_tf(regs, family)) * family.speed_units


def polymul(a: Any, b: Any) -> np.ndarray:
    """``np.polymul`` of two coefficient sequences (descending powers) as a plain array: the
    same leading-zero trimming and convolution, the same numbers, without ``np.poly1d``."""
    return np.convolve(_trimmed(a), _trimmed(b))


def _trimmed(p: Any) -> np.ndarray:
    """Coefficients without leading zeros (``[0]`` when all are zero), as ``np.poly1d``
    keeps them."""
    p = np.atleast_1d(np.asarray(p))
    nz = np.flatnonzero(p)
    return p[nz[0]:] if nz.size else np.array([0], dtype=p.dtype)


def freqresp(sys: ct.TransferFunction, w: np.ndarray) -> np.ndarray:
    """Complex frequency response of a discrete SISO transfer function at ``w`` [rad/s].

    Evaluated directly from the numerator and denominator polynomials (fast, no warnings).
    """
    num = np.asarray(sys.num[0][0], dtype=float)
    den = np.asarray(sys.den[0][0], dtype=float)
    z = np.exp(1j * np.asarray(w) * sys.dt)
    return np.polyval(num, z) / np.polyval(den, z)
