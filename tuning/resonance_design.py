"""A speed loop for a two-mass load: a notch or low-pass in the VF filter's free order
(docs/tuning.md, "Two-mass loads").

VF (manual 4.2, 3.2.93–3.2.100) has four numerator and four denominator coefficients; the PI
(or I-P) of :mod:`tuning.synthesis` uses two and one of them. A second-order section with unity
gain at DC, ``N(z) = (n0 + n1 z⁻¹ + n2 z⁻²)/(1 + d1 z⁻¹ + d2 z⁻²)``, multiplied into VF fills
them: ``VF·N`` has a numerator of order 3 (KVFX4..KVFX1) and a denominator ``(1 − z⁻¹)(1 + d1 z⁻¹
+ d2 z⁻²)`` of order 3 (KVFY3..KVFY1). The section is

* a **notch** at the resonance as the speed loop sees it (the mode under the design's current
  loop, :func:`tuning.identify_resonance.apparent_resonance`): VF runs at 520.8 Hz, so a
  resonance above 260.4 Hz appears at its alias ``|f − round(f/f_s)·f_s|``;
  ``N = g·(1 − 2 cos ω₀ z⁻¹ + z⁻²)/(1 − 2 r cos ω₀ z⁻¹ + r² z⁻²)``, width set by the pole
  radius r, g for unity DC gain;
* or a **low-pass**, a double real pole at p: ``N = (1 − p)²/(1 − 2p z⁻¹ + p² z⁻²)``.

With a position integral (VF of order 2 over 2) the section does not fit and only the plain
design is offered. Each candidate scales the design's crossover by a factor g (kp × g,
ki × g², :func:`scaled_gains`), moves gain between VF's numerator and KVOUT so quantisation
keeps the integral gain (:func:`balanced`) and is quantised (:mod:`tuning.quantize`). On the
two-mass plants of :func:`design_cases` (the identified load and the corners of its intervals;
:func:`two_mass_plant`: :func:`tuning.models.speed_plant` with the coupling and the back-EMF,
lifted exactly to the outer rate, so the aliasing is in it) the fastest candidate of each kind
that is stable with PM ≥ 45° and GM ≥ 6 dB on all of them is kept: one without a section, one
with a notch, one with a low-pass. :func:`choose` then simulates them and the plain design on
the identified motor and keeps the one that settles first without a sustained oscillation.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import control as ct
import numpy as np

from jvl_gym.families import TuningSpec

from .identify_resonance import apparent_resonance, coupling_of
from .models import MotorData, freqresp, speed_open_loop, speed_plant
from .quantize import quantize_registers
from .testmode_facts import record_facts_of
from .verify import LoopMetrics, frequency_grid, metrics_from_response

__all__ = ["FilteredDesign", "TwoMassChoice", "choose", "move_on", "scaled_gains", "alias_hz",
           "notch_section", "lowpass_section", "with_section", "coupling_of",
           "two_mass_plant", "loop_metrics", "balanced", "two_mass_metrics", "design_cases",
           "resonance_designs", "PM_MIN", "GM_MIN"]

PM_MIN: float = 45.0  #: phase margin every kept candidate has after quantisation [deg]
GM_MIN: float = 6.0  #: gain margin [dB]
GAIN_FACTORS = tuple(float(g) for g in np.geomspace(1.0, 0.04, 20))
#: least relative spread of the resonance, beyond its identified interval, the candidates must
#: keep their margins over (:func:`design_cases`)
F_SPREAD: float = 0.03
NUM_MAX: float = 6.0  #: largest |KVFX| :func:`balanced` makes (Fixed4 holds ±8)
RATIO_MIN: float = 0.05  #: smallest load ratio J_l/J_m a design case takes
NOTCH_RADII = (0.3, 0.5, 0.65, 0.8)
LOWPASS_POLES = (0.2, 0.35, 0.5, 0.65)


@dataclass
class FilteredDesign:
    """One speed-loop candidate for a two-mass load.

    Attributes
    ----------
    name : str
        "no filter", "notch r=…" or "low-pass p=…" with the gain factor.
    kind : str
        "none", "notch" or "lowpass".
    registers : dict
        All speed-loop registers (quantised).
    metrics : LoopMetrics
        Margins on the identified two-mass plant, after quantisation.
    gain : float
        Factor g on the design's crossover (:func:`scaled_gains`).
    section : (ndarray, ndarray)
        The section's numerator and denominator in powers of z⁻¹.
    """

    name: str
    kind: str
    registers: dict[str, float]
    metrics: LoopMetrics
    gain: float
    section: tuple[np.ndarray, np.ndarray]


def alias_hz(f_hz: float, fs: float) -> float:
    """The frequency [Hz] at which a sampled loop at ``fs`` [Hz] (the family's servo rate)
    sees ``f_hz``."""
    return abs(f_hz - round(f_hz / fs) * fs)


def notch_section(f_hz: float, radius: float, ts_o: float) -> tuple[np.ndarray, np.ndarray]:
    """Notch at the alias of ``f_hz`` with pole radius ``radius`` in a loop sampled every
    ``ts_o`` [s] (the family's servo sample time), unity DC gain (z⁻¹ powers)."""
    w0 = 2 * math.pi * alias_hz(f_hz, 1.0 / ts_o) * ts_o
    num = np.array([1.0, -2 * math.cos(w0), 1.0])
    den = np.array([1.0, -2 * radius * math.cos(w0), radius**2])
    return num * den.sum() / num.sum(), den


def lowpass_section(pole: float) -> tuple[np.ndarray, np.ndarray]:
    """Double real pole at ``pole``, unity DC gain (z⁻¹ powers)."""
    return np.array([(1 - pole) ** 2, 0.0, 0.0]), np.array([1.0, -2 * pole, pole**2])


def with_section(regs: Mapping[str, float], section: tuple[np.ndarray, np.ndarray]
                 ) -> dict[str, float]:
    """The registers with VF multiplied by the section ``N`` (module docstring).

    Raises
    ------
    ValueError
        VF's numerator or denominator is of order > 1 (a position integral): no room.
    """
    num = np.array([regs["KVFX4"], regs["KVFX3"], regs["KVFX2"], regs["KVFX1"]])
    den = np.array([1.0, -regs["KVFY3"], -regs["KVFY2"], -regs["KVFY1"], -regs["KVFY0"]])
    if np.any(num[2:] != 0.0) or np.any(den[2:] != 0.0):
        raise ValueError("VF already uses more than first order (position integral): no free "
                         "order for a filter section")
    n = np.convolve(num[:2], section[0])
    d = np.convolve(den[:2], section[1])
    out = dict(regs)
    out.update({"KVFX4": n[0], "KVFX3": n[1], "KVFX2": n[2], "KVFX1": n[3],
                "KVFY3": -d[1], "KVFY2": -d[2], "KVFY1": -d[3], "KVFY0": 0.0})
    return out


def scaled_gains(regs: Mapping[str, float], g: float) -> dict[str, float]:
    """The speed-loop registers with the crossover scaled by about ``g``: kp × g and ki × g²,
    so the PI's zero keeps its place relative to the crossover. "pi" (KVFX4 = kp + ki,
    KVFX3 = −kp) and "ip" (KVFX4 = ki, VB = 1 + (kp/ki)(1 − z⁻¹)) structures
    (:func:`tuning.synthesis.speed_registers`)."""
    out = dict(regs)
    if regs["KVFX3"] == 0.0 and regs["KVB2"] != 0.0:  # I-P
        c = -regs["KVB2"] / g
        out.update({"KVFX4": regs["KVFX4"] * g * g, "KVB3": 1.0 + c, "KVB2": -c})
        if regs["KFF2"] != 0.0:  # setpoint weight β: FF = 1 + β c (1 − z⁻¹)
            beta = -regs["KFF2"] / -regs["KVB2"]
            out.update({"KFF3": 1.0 + beta * c, "KFF2": -beta * c})
        return out
    kp, ki = -regs["KVFX3"], regs["KVFX4"] + regs["KVFX3"]
    out.update({"KVFX4": g * kp + g * g * ki, "KVFX3": -g * kp})
    return out


def balanced(regs: Mapping[str, float]) -> dict[str, float]:
    """The same speed loop with VF's numerator (KVFX4..KVFX1) × s and KVOUT / s (they multiply,
    manual 4.2, 3.2.13), s chosen so that quantisation costs the integral gain (the sum of the
    numerator, Fixed4) and KVOUT (Fixed8) the same relative resolution, the numerator within
    ±:data:`NUM_MAX`. A scaled-down crossover (:func:`scaled_gains`) leaves the integral gain
    few Fixed4 steps otherwise."""
    keys = ("KVFX4", "KVFX3", "KVFX2", "KVFX1")
    num = np.array([regs[k] for k in keys])
    ki, kvout = float(num.sum()), float(regs["KVOUT"])
    if ki <= 0.0 or kvout <= 0.0:
        return dict(regs)
    s = min(math.sqrt(kvout / (16.0 * ki)), NUM_MAX / float(np.max(np.abs(num))))
    out = dict(regs)
    out.update({k: v * s for k, v in zip(keys, num)})
    out["KVOUT"] = kvout / s
    return out


def two_mass_plant(motor: MotorData, regs: Mapping[str, float],
                   coupling: tuple[float, float, float], b: float = 0.0) -> ct.TransferFunction:
    """The speed plant VF_OUT → V_IST of the two-mass load (rotor ``motor.J_m``, ``coupling =
    (J_l, k, d)``) under the current loop of ``regs``, the back-EMF included
    (:func:`tuning.models.speed_plant`)."""
    return speed_plant(motor, regs, motor.J_m, b, coupling, back_emf=True)


def loop_metrics(plant: ct.TransferFunction, regs: Mapping[str, float],
                 family: TuningSpec) -> LoopMetrics:
    """Speed-loop margins with the registers ``regs`` on ``plant`` (``family``'s speed
    filter), closed-loop poles for stability."""
    loop = speed_open_loop(plant, regs, family)
    w = frequency_grid(family.outer_dt, 2500, lowest=1e-3)
    num = np.asarray(loop.num[0][0], dtype=float)
    den = np.asarray(loop.den[0][0], dtype=float)
    return metrics_from_response(freqresp(loop, w), w, np.polyadd(den, num))


def two_mass_metrics(motor: MotorData, regs: Mapping[str, float],
                     coupling: tuple[float, float, float], b: float = 0.0) -> LoopMetrics:
    """Speed-loop margins with the registers ``regs`` on the two-mass plant
    (:func:`two_mass_plant`)."""
    return loop_metrics(two_mass_plant(motor, regs, coupling, b), regs, motor.family)


def _ok(m: LoopMetrics) -> bool:
    return bool(m.stable and m.pm_deg >= PM_MIN and m.gm_db >= GM_MIN)


def design_cases(f_res: float, load_ratio: float, zeta: float,
                 ci: Mapping[str, tuple[float, float]] | None = None
                 ) -> list[tuple[float, float, float]]:
    """The two-mass loads ``(f_res, load_ratio, zeta)`` a candidate must keep its margins on:
    the identified one and the corners of the intervals ``ci`` ("f_res" widened to at least
    ±:data:`F_SPREAD`, "load_ratio", the low end of "zeta")."""
    ci = ci or {}
    f_lo, f_hi = ci.get("f_res", (f_res, f_res))
    f_lo, f_hi = min(f_lo, f_res * (1 - F_SPREAD)), max(f_hi, f_res * (1 + F_SPREAD))
    r_lo, r_hi = ci.get("load_ratio", (load_ratio, load_ratio))
    r_lo = max(min(r_lo, load_ratio), RATIO_MIN)
    z_lo = min(ci.get("zeta", (zeta, zeta))[0], zeta)
    return [(f_res, load_ratio, zeta)] + [(f, r, z_lo) for f in (f_lo, f_hi)
                                          for r in dict.fromkeys((r_lo, max(r_hi, r_lo)))]


def resonance_designs(motor: MotorData, regs: Mapping[str, float], f_res: float,
                      load_ratio: float, zeta: float = 0.02, b: float = 0.0,
                      ci: Mapping[str, tuple[float, float]] | None = None
                      ) -> list[FilteredDesign]:
    """The fastest acceptable candidate of each kind (no filter, notch, low-pass) for the
    registers ``regs`` of a design (current and speed loop) on the identified two-mass load
    (the coupling's resonance ``f_res`` [Hz], ``load_ratio`` J_l/J_m, damping ratio ``zeta``,
    their 95 % intervals ``ci`` as :class:`tuning.identify_resonance.ResonanceEstimate.ci`).

    A candidate is acceptable when it has the margins (:data:`PM_MIN`, :data:`GM_MIN`, stable)
    on every load of :func:`design_cases`; the metrics kept are the worst. The notch sits at
    the resonance the speed loop sees under the design's current loop
    (:func:`tuning.identify_resonance.apparent_resonance`). Returns the candidates found, in
    that order; a kind none of whose candidates meets the margins is left out.
    """
    load_ratio = max(load_ratio, RATIO_MIN)
    plants = [two_mass_plant(motor, regs, coupling_of(motor.J_m, r, f, z), b)
              for f, r, z in design_cases(f_res, load_ratio, zeta, ci)]
    f_notch = apparent_resonance(motor, regs, load_ratio, f_res, zeta)[0]
    sections: list[tuple[str, str, tuple[np.ndarray, np.ndarray]]] = [
        ("none", "no filter", (np.array([1.0, 0.0, 0.0]), np.array([1.0, 0.0, 0.0])))]
    ts_o = motor.family.outer_dt
    table = record_facts_of(motor).table
    sections += [("notch", f"notch {alias_hz(f_notch, 1.0 / ts_o):.0f} Hz r={r}",
                  notch_section(f_notch, r, ts_o)) for r in NOTCH_RADII]
    sections += [("lowpass", f"low-pass p={p}", lowpass_section(p)) for p in LOWPASS_POLES]
    best: dict[str, FilteredDesign] = {}
    for kind, name, sec in sections:
        for g in GAIN_FACTORS:
            if kind in best and best[kind].gain >= g:
                break
            try:
                q = quantize_registers(balanced(with_section(scaled_gains(regs, g), sec)), table)
            except ValueError:
                break
            ms = []
            for plant in plants:
                ms.append(loop_metrics(plant, q, motor.family))
                if not _ok(ms[-1]):
                    break
            m = min(ms, key=lambda x: (_ok(x), x.pm_deg))
            if _ok(m) and len(ms) == len(plants):
                best[kind] = FilteredDesign(f"{name}, gain × {g:g}", kind, q, m, g, sec)
                break
    return [best[k] for k in ("none", "notch", "lowpass") if k in best]


@dataclass
class TwoMassChoice:
    """The acceptance step's choice for a two-mass load.

    Attributes
    ----------
    chosen : FilteredDesign or None
        The kept candidate (None: none met the margins; the plain design stays).
    settle_s, oscillation : dict
        Candidate name → settle time [s] (inf: never) and the peak-to-peak position error over
        the last 0.3 s of the move [counts], on the identified two-mass motor.
    reason : str
        One line for the report.
    """

    chosen: FilteredDesign | None
    settle_s: dict[str, float]
    oscillation: dict[str, float]
    reason: str


def move_on(motor_type: str, params: Mapping[str, float], setups: list[Mapping[str, float]],
            a_soll: int, distance: int = 20000, v_soll: int = 2000, seconds: float = 2.0,
            seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Settle times [s] and peak-to-peak position error over the last 0.3 s [counts] of one
    P_MODE move (:func:`tuning.verify.position_move`) per register set in ``setups`` on
    motors of type ``motor_type`` with the ``MotorArray`` keywords ``params``."""
    from jvl_gym import MotorArray

    from .verify import position_move

    m = MotorArray(motor_type, n=len(setups), seed=seed, **params)
    for j, regs in enumerate(setups):
        if regs:
            m.load_setup({"registers": dict(regs)}, index=[j])
    mv = position_move(m, distance, v_soll, a_soll, seconds=seconds)
    tail = mv.position[-int(round(0.3 / record_facts_of(m).ts_o)):]
    return mv.settle_s, tail.max(axis=0) - tail.min(axis=0)


def choose(motor_type: str, params: Mapping[str, float], plain: Mapping[str, float],
           cands: list[FilteredDesign], a_soll: int, window: int = 10) -> TwoMassChoice:
    """Simulate the plain design (``plain``, no filter, as synthesised for a rigid load) and
    the candidates on the identified two-mass motor (``params``: ``MotorArray`` keywords with
    the coupling) and keep the candidate that settles first without a sustained oscillation
    (peak-to-peak over the last 0.3 s within 2·``window`` counts); ties go to the order of
    ``cands``."""
    names = ["plain design", *[c.name for c in cands]]
    settle, osc = move_on(motor_type, params, [plain, *[c.registers for c in cands]], a_soll)
    st = {n: float(t) for n, t in zip(names, settle)}
    oc = {n: float(o) for n, o in zip(names, osc)}
    quiet = [k for k in range(len(cands)) if oc[cands[k].name] <= 2 * window]
    if not quiet:
        return TwoMassChoice(None, st, oc, "no filtered candidate settles without oscillation "
                             "on the identified motor; the plain design is kept")
    best = min(quiet, key=lambda k: (st[cands[k].name], k))
    c = cands[best]
    plain_txt = (f"the plain design settles in {st['plain design'] * 1e3:.0f} ms"
                 if np.isfinite(st["plain design"]) else "the plain design never settles")
    why = (f"kept {c.name}: PM {c.metrics.pm_deg:.0f}°, GM {c.metrics.gm_db:.0f} dB on the "
           f"identified two-mass plant after quantisation, settles in "
           f"{st[c.name] * 1e3:.0f} ms; {plain_txt} (oscillation "
           f"{oc['plain design']:.0f} counts p-p)")
    return TwoMassChoice(c, st, oc, why)
