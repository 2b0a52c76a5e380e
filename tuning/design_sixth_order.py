"""Synthesis, quantisation and verification of the MAC800's current filter and sixth-order main
filter (register overview §1.2 "Filters"; the loop models of :mod:`tuning.sixth_order`).

*Current loop*: the MAC050–141 design (:func:`tuning.synthesis.design_current_loop`: a PI in IF,
IB = 1, the largest integral gain that meets the margins on the coil and on R, L ±30 %) at the
MAC800's current-loop rate, quantised to Fixed16 (KIFX, KIFY) and Fixed24 (KIB).

*Main filter*: FF = KFF5 = 1, VB = KVB4 = 1 (unity feedback of 16·V_IST) and in VF a PI on the
speed error in series with the extra orders::

    VF(z) = (kp + ki/(1 − z⁻¹) [+ kii/(1 − z⁻¹)²]) · LP(z) [· N(z)]

* LP(z) = (1 − 2r·cos φ + r²)/(1 − 2r·cos φ z⁻¹ + r² z⁻²): a second-order low-pass of unity DC
  gain above the crossover, its poles the images ``z = exp(s·TS_O)`` of
  ``s = 2π·f_lp·(−ζ ± j√(1 − ζ²))`` (ζ = :data:`LOWPASS_DAMPING`: half the phase lag below the
  corner of two real poles, a peak of 1.2 dB). The speed is the position differenced (V_IST,
  ±1 count of quantisation each sample); a PI passes that noise to VF_OUT with its full
  proportional gain up to the Nyquist frequency, the low-pass takes it down there: a torque
  ripple that is heard and heats the motor but moves nothing. The corner is
  :data:`LOWPASS_PER_CROSSOVER` × the plain PI's crossover, and (kp, ki) are searched again with
  the low-pass in the loop, so its phase lag is paid for in the margins.
* N(z): with an identified resonance f_r (``notch_hz``), a notch
  ``(1 − 2cos ω₀ z⁻¹ + z⁻²)/(1 − 2r cos ω₀ z⁻¹ + r² z⁻²)`` (unity DC gain, r from
  :data:`NOTCH_WIDTH`) at ω₀ = 2π·f_r·TS_O.
* kii: a position integral (the PI speed loop's integral of the speed error is a position
  error) when Coulomb friction would otherwise hold the motor outside the in-position window.

VF has at most 5 numerator and 6 denominator taps, within the sixth order (S_ORDER = 6).
KVOUT = J/J_m (register 13) makes the loop gain load-invariant; MODEL_POT (register 154) is the
largest exponent that keeps the largest VF numerator tap at most 1, so the Fixed16 taps keep
16 significant bits. (kp, ki) are normalised as on the MAC050–141 (``kp_n = 16·Kpl·kp``,
``Kpl = COUNTS_PER_RAD·K_vf·TS_O²/(2·J_m)``) and searched on a grid for the largest integral
gain that meets: pole radius < 0.999, PM ≥ 50°, GM ≥ 10 dB nominal; PM ≥ 35° with KVOUT × 0.5
and × 2 and with R, L ±30 % under the current loop.

Quantisation: the family's register table (Fixed16, Fixed24, Int32 ranges) through
:func:`tuning.quantize.quantize_registers` with the sums of :data:`EXACT_SUMS` kept exact (the
integrators' poles at z = 1 and the integral gains). Verification on the quantised registers:
loop metrics of the python-control models (:func:`tuning.verify.loop_metrics`) and
``control.stability_margins`` as a cross-check.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import control as ct
import numpy as np

from .models import (
    MotorData,
    current_open_loop,
    polymul,
    rigid_gain,
    speed_open_loop,
    speed_plant,
)
from .quantize import quantize_registers
from .sixth_order import CURRENT_KEYS, FAMILY_RECORD, TS_O, VFX_KEYS, VFY_KEYS
from .synthesis import design_current_loop
from .verify import (
    POLE_RADIUS_MAX,
    LoopMetrics,
    frequency_grid,
    loop_metrics,
    metrics_from_response,
    with_pole_radius,
)

__all__ = ["EXACT_SUMS", "LOWPASS_PER_CROSSOVER", "LOWPASS_DAMPING", "NOTCH_WIDTH",
           "SixthOrderDesign", "SixthOrderVerification", "design_current_filter",
           "main_filter_registers", "design_main_filter", "synthesize_sixth_order",
           "verify_sixth_order", "check_sixth_order", "quantize_sixth_order"]

#: register groups whose stored sums stay exact (the current PI, VF's integrators and gain)
EXACT_SUMS: tuple[tuple[str, ...], ...] = (("KIFY1", "KIFY0"), ("KIFX2", "KIFX1"), VFY_KEYS,
                                           VFX_KEYS)
LOWPASS_PER_CROSSOVER: float = 4.0  #: low-pass corner / the plain PI's crossover
LOWPASS_DAMPING: float = 0.5  #: ζ of the low-pass's poles
NOTCH_WIDTH: float = 0.9  #: r of the notch's poles (the notch's −3 dB width ≈ (1 − r)/(π·TS_O))


def quantize_sixth_order(regs: Mapping[str, float]) -> dict[str, float]:
    """Quantise to the MAC800 table's formats with :data:`EXACT_SUMS` exact."""
    return quantize_registers(regs, FAMILY_RECORD.table, EXACT_SUMS)


def design_current_filter(motor: MotorData) -> dict[str, float]:
    """The current filter for the motor's coil, quantised (module docstring)."""
    return quantize_sixth_order(design_current_loop(motor).registers)


def _poly_lowpass(f_lp: float | None) -> tuple[np.ndarray, np.ndarray]:
    if not f_lp:
        return np.array([1.0]), np.array([1.0])
    wn = 2.0 * math.pi * f_lp * TS_O
    r = math.exp(-LOWPASS_DAMPING * wn)
    phi = wn * math.sqrt(1.0 - LOWPASS_DAMPING**2)
    den = np.array([1.0, -2.0 * r * math.cos(phi), r * r])
    return np.array([den.sum()]), den


def _poly_notch(f_n: float | None) -> tuple[np.ndarray, np.ndarray]:
    if not f_n:
        return np.array([1.0]), np.array([1.0])
    c = math.cos(2.0 * math.pi * f_n * TS_O)
    r = NOTCH_WIDTH
    num = np.array([1.0, -2.0 * c, 1.0])
    den = np.array([1.0, -2.0 * r * c, r * r])
    return num * den.sum() / num.sum(), den


def main_filter_registers(kp: float, ki: float, kvout: float, f_lp: float | None = None,
                          notch_hz: float | None = None, kii: float = 0.0) -> dict[str, float]:
    """The main filter's registers (unquantised) of the structure in the module docstring.

    Parameters
    ----------
    kp, ki, kii : float
        PI and position-integral gains in VF units (VF_OUT/KVOUT per 1/16 count/sample).
    kvout : float
        KVOUT = J/J_m.
    f_lp, notch_hz : float, optional
        Low-pass corner and notch frequency [Hz]; None: not used.

    Raises
    ------
    ValueError
        The filter needs more than six orders, or a frequency is not below Nyquist.
    """
    for f in (f_lp, notch_hz):
        if f is not None and not 0.0 < f < 0.5 / TS_O:
            raise ValueError(f"filter frequency {f} Hz is not in (0, {0.5 / TS_O:.0f}) Hz")
    if kii > 0.0:
        num = np.array([kp + ki + kii, -2.0 * kp - ki, kp])
        den = np.array([1.0, -2.0, 1.0])
    else:
        num, den = np.array([kp + ki, -kp]), np.array([1.0, -1.0])
    for pn, pd in (_poly_lowpass(f_lp), _poly_notch(notch_hz)):
        num, den = np.polymul(num, pn), np.polymul(den, pd)
    if num.size > len(VFX_KEYS) or den.size - 1 > len(VFY_KEYS):
        raise ValueError("the filter needs more than the six orders of the main filter")
    big = float(np.max(np.abs(num)))
    pot = int(np.clip(math.floor(-math.log2(big)), 0, 16)) if big > 0 else 0
    regs = {"KFF5": 1.0, "KFF4": 0.0, "KFF3": 0.0, "KFF2": 0.0, "KFF1": 0.0, "KFF0": 0.0,
            "KVB4": 1.0, "KVB3": 0.0, "KVB2": 0.0, "KVB1": 0.0, "KVB0": 0.0,
            "KVOUT": kvout, "MODEL_POT": float(pot), "S_ORDER": 6.0}
    for k, name in enumerate(VFX_KEYS):
        regs[name] = float(num[k]) * 2.0**pot if k < num.size else 0.0
    for k, name in enumerate(VFY_KEYS):
        regs[name] = -float(den[k + 1]) if k + 1 < den.size else 0.0
    return regs


@dataclass
class SixthOrderDesign:
    """A MAC800 design: the quantised registers and what the search found."""

    verification: SixthOrderVerification
    #: the quantised and the unquantised registers (name → value)
    registers: dict[str, float]
    ideal: dict[str, float]
    #: normalised PI gains (16·Kpl·kp, 16·Kpl·ki) the search found
    kp_norm: float
    ki_norm: float
    #: low-pass corner and notch frequency [Hz] (None: not used)
    f_lp: float | None = None
    notch_hz: float | None = None
    kii: float = 0.0  #: position-integral gain in VF units (0: none)
    name: str = "pi + low-pass"
    notes: list[str] = field(default_factory=list)


@dataclass
class SixthOrderVerification:
    """Loop metrics of a design on a motor: nominal current and speed loop, the speed loop's
    robustness set, python-control's own margins of the speed loop, and the ideal design's."""

    current: LoopMetrics
    speed: LoopMetrics
    robust: dict[str, LoopMetrics]
    ct_pm_deg: float
    ct_gm_db: float
    ideal_speed: LoopMetrics | None = None

    @property
    def worst_robust_pm(self) -> float:
        """Smallest PM over the robustness set [deg]."""
        return min((m.pm_deg for m in self.robust.values()), default=math.inf)

    @property
    def all_stable(self) -> bool:
        """Every loop's closed-loop poles inside the radius 0.999."""
        return (self.current.stable and self.speed.stable
                and all(m.stable for m in self.robust.values()))


def verify_sixth_order(motor: MotorData, regs: Mapping[str, float], J: float, robust: bool = True
                      ) -> SixthOrderVerification:
    """Verify registers ``regs`` (current and main filter) on ``motor`` with inertia ``J``."""
    cur = loop_metrics(current_open_loop(motor, regs))
    loop = speed_open_loop(speed_plant(motor, regs, J=J), regs, motor.family)
    spd = loop_metrics(loop)
    gm, pm = ct.stability_margins(loop)[:2]
    rob: dict[str, LoopMetrics] = {}
    if robust:
        for fk in (0.5, 2.0):
            rob[f"KVOUT x{fk:g}"] = loop_metrics(
                speed_open_loop(speed_plant(motor, regs, J=J / fk), regs, motor.family))
        for fr in (0.7, 1.3):
            for fl in (0.7, 1.3):
                mm = motor.with_(R_phase=motor.R_phase * fr, L_phase=motor.L_phase * fl)
                rob[f"R x{fr:g}, L x{fl:g}"] = loop_metrics(
                    speed_open_loop(speed_plant(mm, regs, J=J), regs, motor.family))
    gm_db = 20.0 * math.log10(gm) if gm and math.isfinite(gm) and gm > 0 else math.inf
    return SixthOrderVerification(cur, spd, rob, float(pm), gm_db)


def check_sixth_order(v: SixthOrderVerification) -> list[str]:
    """The acceptance checks of a verification; the failures (empty if all pass)."""
    bad = []
    if not (v.current.pm_deg >= 45 and v.current.gm_db >= 6):
        bad.append(f"current margins PM {v.current.pm_deg:.1f} deg, GM {v.current.gm_db:.1f} dB")
    if not (v.speed.pm_deg >= 45 and v.speed.gm_db >= 8):
        bad.append(f"speed margins PM {v.speed.pm_deg:.1f} deg, GM {v.speed.gm_db:.1f} dB")
    if not v.all_stable:
        bad.append(f"a closed-loop pole at |z| >= {POLE_RADIUS_MAX}")
    if v.robust and not v.worst_robust_pm >= 30:
        bad.append(f"robust PM {v.worst_robust_pm:.1f} deg < 30")
    if v.ideal_speed is not None and abs(v.speed.pm_deg - v.ideal_speed.pm_deg) > 2:
        bad.append(f"quantisation changed the speed PM by "
                   f"{v.speed.pm_deg - v.ideal_speed.pm_deg:.2f} deg")
    return bad


def _search(motor: MotorData, cur: Mapping[str, float], f_lp: float | None,
            notch_hz: float | None) -> tuple[float, float, LoopMetrics]:
    """(kp_n, ki_n, metrics) of the largest integral gain meeting the constraints."""
    w = frequency_grid(TS_O, 800, lowest=1e-3)
    z = np.exp(1j * w * TS_O)
    plant = speed_plant(motor, cur)
    pn = np.asarray(plant.num[0][0], dtype=float)
    pd = np.asarray(plant.den[0][0], dtype=float)
    pw = np.polyval(pn, z) / np.polyval(pd, z)
    corners = []
    for fr in (0.7, 1.3):
        for fl in (0.7, 1.3):
            pc = speed_plant(motor.with_(R_phase=motor.R_phase * fr,
                                         L_phase=motor.L_phase * fl), cur)
            corners.append(np.polyval(pc.num[0][0], z) / np.polyval(pc.den[0][0], z))
    ln, ld = (np.polymul(a, b) for a, b in zip(_poly_lowpass(f_lp), _poly_notch(notch_hz)))
    # filters as polynomials in z: multiply numerator and denominator to equal degree
    deg = max(ln.size, ld.size)
    ln_z = np.r_[ln, np.zeros(deg - ln.size)]
    ld_z = np.r_[ld, np.zeros(deg - ld.size)]
    fw = np.polyval(ln_z, z) / np.polyval(ld_z, z)
    kpl16 = 16.0 * rigid_gain(motor)
    loop_den = polymul(polymul([1.0, -1.0], ld_z), pd)
    best: tuple[float, float, LoopMetrics] | None = None
    for kin in np.geomspace(0.3, 0.002, 48):
        for kpn in np.geomspace(1.2, 0.03, 48):
            kp, ki = kpn / kpl16, kin / kpl16
            cw = 16.0 * (kp + ki * z / (z - 1.0)) * fw
            lw = cw * pw
            m = metrics_from_response(lw, w)
            if not (m.pm_deg >= 50 and m.gm_db >= 10):
                continue
            loop_num = polymul(polymul(16.0 * np.array([kp + ki, -kp]), ln_z), pn)
            m = with_pole_radius(m, np.polyadd(loop_den, loop_num))
            if not m.stable:
                continue
            if min(metrics_from_response(lw * s, w).pm_deg for s in (0.5, 2.0)) < 35:
                continue
            char2 = np.polyadd(loop_den, 2.0 * loop_num)
            if np.max(np.abs(np.roots(char2))) >= POLE_RADIUS_MAX:
                continue
            if min(metrics_from_response(cw * pc, w).pm_deg for pc in corners) < 35:
                continue
            if best is None or kpn > best[0]:
                best = (float(kpn), float(kin), m)
        if best is not None:
            return best
    raise ValueError("no speed-loop gains meet the margin constraints")


def design_main_filter(motor: MotorData, cur: Mapping[str, float], J: float,
                       lowpass: bool = True, notch_hz: float | None = None
                      ) -> tuple[dict[str, float], float, float, float | None, list[str]]:
    """Search (kp, ki) (module docstring); the main filter's ideal registers, kp_n, ki_n, the
    low-pass corner [Hz] (None without) and notes."""
    notes: list[str] = []
    kpn, kin, m = _search(motor, cur, None, notch_hz)
    f_lp = None
    if lowpass:
        f_lp = min(LOWPASS_PER_CROSSOVER * m.crossover_hz, 0.4 / TS_O)
        kpn, kin, m = _search(motor, cur, f_lp, notch_hz)
        notes.append(f"low-pass at {f_lp:.0f} Hz ({LOWPASS_PER_CROSSOVER:g} x the plain PI's "
                     f"crossover)")
    kpl16 = 16.0 * rigid_gain(motor)
    regs = main_filter_registers(kpn / kpl16, kin / kpl16, J / motor.J_m, f_lp, notch_hz)
    return regs, kpn, kin, f_lp, notes


def synthesize_sixth_order(motor: MotorData, J: float, current: Mapping[str, float] | None = None,
                           lowpass: bool = True, notch_hz: float | None = None) -> SixthOrderDesign:
    """Design, quantise and verify the current filter (unless ``current`` is given, e.g. the
    one the identification wrote) and the main filter for inertia ``J`` [kg·m²]."""
    cur = dict(current) if current is not None else design_current_filter(motor)
    spd, kpn, kin, f_lp, notes = design_main_filter(motor, cur, J, lowpass, notch_hz)
    ideal = {**{k: cur[k] for k in CURRENT_KEYS}, **spd}
    regs = quantize_sixth_order(ideal)
    ver = verify_sixth_order(motor, regs, J)
    ver.ideal_speed = verify_sixth_order(motor, ideal, J, robust=False).speed
    name = "pi + low-pass" if f_lp else "pi"
    if notch_hz:
        name += " + notch"
    return SixthOrderDesign(ver, regs, ideal, kpn, kin, f_lp=f_lp, notch_hz=notch_hz,
                            name=name, notes=notes)
