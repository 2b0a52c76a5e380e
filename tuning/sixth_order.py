"""Models of the MAC800's loops: the coil and current loop at the current-loop rate, the speed
plant lifted to the servo rate, and the sixth-order main filter (python-control).

The MAC800 family's public data fix the numbers (:mod:`jvl_gym.families.mac800.constants`:
INNER_DT = 1/11550 s, OUTER_DT = 1/770 s, 15 current-loop samples per servo sample, 8000
counts/rev, PWM and ADC full scale ±1023, VF_OUT full scale T_SOLL_FULL = 1023 of peak torque;
register overview §1.2). The loops are those of the MAC050–141 (its manual 4.2, 4.3;
docs/model.md §2, §6, §7) on the MAC800's registers:

* per phase, ``U`` [PWM counts] → ``I_IST`` [ADC counts]: ``g(1 − a)/(z^d (z − a))`` with
  ``a = exp(−R·TS_I/L)``, ``g = k_u/(R·A_count)``, ``k_u = U_bus/2/1023`` V per PWM count;
* the current filter (registers 144–149): IF ``(KIFX2 z² + KIFX1 z)/(z² − KIFY1 z − KIFY0)``,
  IB ``(KIB1 z + KIB0)/z`` (:func:`tuning.models.if_tf`, :func:`tuning.models.ib_tf`);
* commutation: the phase current amplitude is ``|VF_OUT|·AMPLITUDE/1023`` ADC counts
  (AMPLITUDE, register 174: ADC counts at peak torque), so the torque per VF_OUT unit is
  ``K_vf = 1.5·p·λ·A_count·AMPLITUDE/1023``;
* the main filter (registers 121–143, 154, 156; ``firmware/main_filter.py`` of the family)::

      e = FF(FNC_OUT) − VB(16·V_IST),   VF_OUT = KVOUT·VF(e)/2^MODEL_POT
      FF(z) = KFF5 + KFF4 z⁻¹ + … + KFF0 z⁻⁵,   VB(z) = KVB4 + KVB3 z⁻¹ + … + KVB0 z⁻⁴
      VF(z) = (KVFX6 + KVFX5 z⁻¹ + … + KVFX1 z⁻⁵)/(1 − KVFY5 z⁻¹ − … − KVFY0 z⁻⁶)

  with S_ORDER = 6 (every tap in use);
* the speed plant VF_OUT → V_IST [counts/sample]: the closed current loop and the rigid rotor
  ``J dω/dt = K_t·i − b·ω`` at the current-loop rate, VF_OUT held for the 15 samples of a servo
  sample, the position read at the start of each servo sample, ``V_IST = (1 − z⁻¹)·P``
  (the MAC050–141's lift, :func:`tuning.models.speed_plant`, at the MAC800's rates).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Any

import control as ct
import numpy as np
import yaml
from scipy.linalg import expm

from jvl_gym.families.mac800 import constants as _c
from jvl_gym.families.mac800.config import Mac800Config, load_motor, setup_path
from jvl_gym.families.mac800.table import TABLE

from .models import ib_tf, if_tf

__all__ = ["TS_I", "TS_O", "INNER_PER_OUTER", "COUNTS_PER_RAD", "VF_FULL", "FF_KEYS", "VB_KEYS",
           "VFX_KEYS", "VFY_KEYS", "CURRENT_KEYS", "MAIN_KEYS", "Motor800", "ff_tf", "vb_tf",
           "vf_tf", "current_open_loop", "speed_plant", "speed_open_loop",
           "speed_closed_loop", "default_registers"]

TS_I: float = _c.INNER_DT  #: current-loop sample time [s]
TS_O: float = _c.OUTER_DT  #: servo sample time [s]
INNER_PER_OUTER: int = _c.INNER_PER_OUTER
COUNTS_PER_RAD: float = _c.COUNTS_PER_REV / (2.0 * math.pi)  #: encoder counts per radian
VF_FULL: int = _c.VF_FULL  #: VF_OUT at peak torque (register 7)
FF_KEYS = ("KFF5", "KFF4", "KFF3", "KFF2", "KFF1", "KFF0")  #: taps of delay 0 … 5
VB_KEYS = ("KVB4", "KVB3", "KVB2", "KVB1", "KVB0")  #: taps of delay 0 … 4
VFX_KEYS = ("KVFX6", "KVFX5", "KVFX4", "KVFX3", "KVFX2", "KVFX1")  #: delay 0 … 5
VFY_KEYS = ("KVFY5", "KVFY4", "KVFY3", "KVFY2", "KVFY1", "KVFY0")  #: delay 1 … 6
CURRENT_KEYS = ("KIFX2", "KIFX1", "KIFY1", "KIFY0", "KIB1", "KIB0")
#: the main filter's registers a design sets (with S_ORDER = 6)
MAIN_KEYS = (*FF_KEYS, *VB_KEYS, *VFX_KEYS, *VFY_KEYS, "KVOUT", "MODEL_POT", "S_ORDER")


@dataclass(frozen=True)
class Motor800:
    """Physical data of one MAC800-family motor, SI units.

    Parameters
    ----------
    name : str
        Motor type (``"MAC800"``).
    J_m : float
        Rotor inertia [kg·m²]; KVOUT is relative to it (register 13).
    flux_linkage : float
        λ [V·s] (peak, per phase).
    R_phase, L_phase : float
        Phase resistance [Ω] and inductance [H].
    amps_per_count : float
        Current measurement scale [A per ADC count].
    pole_pairs : int
        p.
    bus_voltage : float
        DC bus [V] (U_BUS, register 198).
    pwm_delay : int
        Current-loop samples between computing a PWM value and applying it (0 or 1).
    amplitude : float
        AMPLITUDE (register 174): phase current amplitude at VF_OUT = 1023 [ADC counts].
    """

    name: str
    J_m: float
    flux_linkage: float
    R_phase: float
    L_phase: float
    amps_per_count: float
    pole_pairs: int
    bus_voltage: float
    pwm_delay: int = 1
    amplitude: float = 776.0

    @classmethod
    def from_config(cls, motor: Any, amplitude: float | None = None) -> Motor800:
        """From a MAC800 motor type name, config path or :class:`Mac800Config`; AMPLITUDE from
        the type's default setup unless given."""
        cfg = motor if isinstance(motor, Mac800Config) else load_motor(motor)
        if amplitude is None:
            amplitude = float(default_registers(cfg.name).get("AMPLITUDE", 0.0))
        return cls(name=cfg.name, J_m=cfg.rotor_inertia, flux_linkage=cfg.flux_linkage,
                   R_phase=cfg.phase_resistance, L_phase=cfg.phase_inductance,
                   amps_per_count=cfg.amps_per_count, pole_pairs=cfg.pole_pairs,
                   bus_voltage=cfg.supply_voltage, pwm_delay=cfg.pwm_delay_samples,
                   amplitude=float(amplitude))

    def with_(self, **changes: Any) -> Motor800:
        """A copy with some fields changed (e.g. identified R and L)."""
        return replace(self, **changes)

    @property
    def volts_per_count(self) -> float:
        """k_u: phase volts per PWM count [V] (±1023 ↔ ±U_bus/2)."""
        return self.bus_voltage / 2.0 / _c.PWM_FULL

    @property
    def coil_pole(self) -> float:
        """a = exp(−R·TS_I/L)."""
        return math.exp(-self.R_phase * TS_I / self.L_phase)

    @property
    def coil_gain(self) -> float:
        """g = k_u/(R·A_count): steady-state ADC counts per PWM count."""
        return self.volts_per_count / (self.R_phase * self.amps_per_count)

    @property
    def torque_constant(self) -> float:
        """K_t = 1.5·p·λ [N·m/A]."""
        return 1.5 * self.pole_pairs * self.flux_linkage

    @property
    def torque_per_vf(self) -> float:
        """K_vf = K_t·A_count·AMPLITUDE/1023: torque per VF_OUT unit [N·m]."""
        return self.torque_constant * self.amps_per_count * self.amplitude / VF_FULL


def default_registers(motor_type: str) -> dict[str, float]:
    """The registers of the motor type's default setup (the family's ``configs/setups``), the
    filter registers it leaves out at their ROM defaults (the family's register table)."""
    cfg = load_motor(motor_type)
    data = yaml.safe_load(setup_path(cfg.setup).read_text())
    regs = {k: TABLE.lookup(k).default for k in (*CURRENT_KEYS, *MAIN_KEYS)}
    regs.update({k: float(v) for k, v in (data.get("registers") or {}).items()})
    return regs


# ----------------------------------------------------------------------------- filters
def _fir(regs: Mapping[str, float], keys: tuple[str, ...]) -> ct.TransferFunction:
    """``Σ k_d z⁻ᵈ`` over ``keys`` (taps of delay 0, 1, …) as a TF in z at TS_O."""
    num = [float(regs.get(k, 0.0)) for k in keys]
    return ct.tf(num, [1.0] + [0.0] * (len(keys) - 1), TS_O)


def ff_tf(regs: Mapping[str, float]) -> ct.TransferFunction:
    """FF (registers 121–126): ``KFF5 + KFF4 z⁻¹ + … + KFF0 z⁻⁵``."""
    return _fir(regs, FF_KEYS)


def vb_tf(regs: Mapping[str, float]) -> ct.TransferFunction:
    """VB (registers 139–143): ``KVB4 + KVB3 z⁻¹ + … + KVB0 z⁻⁴``."""
    return _fir(regs, VB_KEYS)


def vf_tf(regs: Mapping[str, float], with_gain: bool = True) -> ct.TransferFunction:
    """VF (registers 127–138) times KVOUT/2^MODEL_POT (registers 13, 154) unless
    ``with_gain`` is False: ``(KVFX6 + … + KVFX1 z⁻⁵)/(1 − KVFY5 z⁻¹ − … − KVFY0 z⁻⁶)``."""
    k = regs.get("KVOUT", 1.0) * 2.0 ** -regs.get("MODEL_POT", 0.0) if with_gain else 1.0
    num = [k * float(regs.get(x, 0.0)) for x in VFX_KEYS] + [0.0]
    den = [1.0] + [-float(regs.get(y, 0.0)) for y in VFY_KEYS]
    return ct.tf(num, den, TS_O)


# ----------------------------------------------------------------------------- loops
def current_open_loop(motor: Motor800, regs: Mapping[str, float]) -> ct.TransferFunction:
    """Current loop broken at the PWM output, per phase, at TS_I: ``IF·coil·IB``."""
    a, g, d = motor.coil_pole, motor.coil_gain, int(motor.pwm_delay)
    coil = ct.tf([g * (1.0 - a)], list(np.polymul([1.0, -a], [1.0] + [0.0] * d)), TS_I)
    return if_tf(regs, TS_I) * coil * ib_tf(regs, TS_I)


def _inner_position_ss(motor: Motor800, regs: Mapping[str, float], J: float, b: float
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Current-loop-rate state space, I_SOLL [ADC counts] → encoder position [counts]."""
    k_u, R, L, A = motor.volts_per_count, motor.R_phase, motor.L_phase, motor.amps_per_count
    ac = np.array([[-R / L, 0.0, 0.0], [motor.torque_constant / J, -b / J, 0.0],
                   [0.0, COUNTS_PER_RAD, 0.0]])
    bc = np.array([[k_u / L], [0.0], [0.0]])
    m = np.zeros((4, 4))
    m[:3, :3] = ac * TS_I
    m[:3, 3:] = bc * TS_I
    e = expm(m)
    cc = np.array([[1.0 / A, 0.0, 0.0], [0.0, 0.0, 1.0]])
    plant = ct.ss(e[:3, :3], e[:3, 3:], cc, np.zeros((2, 1)), TS_I)
    d = int(motor.pwm_delay)
    delay = ct.tf([1.0], [1.0] + [0.0] * d, TS_I)
    p_u = plant * ct.ss(delay)
    p_u = ct.ss(p_u.A, p_u.B, p_u.C, p_u.D, TS_I, inputs="u", outputs=["iist", "pos"])
    ifs, ibs = ct.ss(if_tf(regs, TS_I)), ct.ss(ib_tf(regs, TS_I))
    ifs = ct.ss(ifs.A, ifs.B, ifs.C, ifs.D, TS_I, inputs="e", outputs="u")
    ibs = ct.ss(ibs.A, ibs.B, ibs.C, ibs.D, TS_I, inputs="iist", outputs="ibf")
    sumblk = ct.summing_junction(inputs=["isoll", "-ibf"], output="e", dt=TS_I)
    sys = ct.interconnect([p_u, ifs, ibs, sumblk], inputs="isoll", outputs="pos")
    return np.asarray(sys.A), np.asarray(sys.B), np.asarray(sys.C)


def speed_plant(motor: Motor800, regs: Mapping[str, float], J: float | None = None,
                b: float = 0.0) -> ct.TransferFunction:
    """VF_OUT → V_IST [counts/sample] at TS_O, the closed current loop included.

    Parameters
    ----------
    motor : Motor800
        Coil, torque constant, AMPLITUDE.
    regs : mapping
        The current filter KIFX2 … KIB0.
    J : float, optional
        Total inertia [kg·m²]; default ``motor.J_m``.
    b : float
        Viscous friction [N·m·s/rad].
    """
    J = motor.J_m if J is None else J
    a, bb, c = _inner_position_ss(motor, regs, J, b)
    n = INNER_PER_OUTER
    a_o = np.linalg.matrix_power(a, n)
    acc = np.zeros_like(a)
    pw = np.eye(a.shape[0])
    for _ in range(n):
        acc += pw
        pw = pw @ a
    b_o = acc @ bb * motor.amplitude / VF_FULL
    k = int(np.argmax(np.abs(c[0])))
    keep = [i for i in range(a_o.shape[0]) if i != k]
    inc_c = (c[0] @ (a_o - np.eye(a_o.shape[0])))[keep][None, :]
    inc = ct.ss(a_o[np.ix_(keep, keep)], b_o[keep], inc_c, (c[0] @ b_o)[None, :], TS_O)
    return ct.minreal(ct.tf(inc) * ct.tf([1.0], [1.0, 0.0], TS_O), tol=1e-10, verbose=False)


def speed_open_loop(plant: ct.TransferFunction, regs: Mapping[str, float]
                    ) -> ct.TransferFunction:
    """The speed loop broken at VF_OUT: ``L = KVOUT·VF/2^MODEL_POT·VB·16·P``."""
    return vf_tf(regs) * vb_tf(regs) * plant * 16.0


def speed_closed_loop(plant: ct.TransferFunction, regs: Mapping[str, float]
                      ) -> ct.TransferFunction:
    """FNC_OUT [1/16 count/sample] → 16·V_IST: ``16·FF·KVOUT·VF·P/(1 + L)``."""
    fwd = vf_tf(regs) * plant
    return ff_tf(regs) * ct.feedback(fwd, vb_tf(regs) * 16.0) * 16.0
