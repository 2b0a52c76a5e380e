"""Strategy ``"testu_pi"``: identification from the TESTU/TESTA test modes and a PI speed loop in
the fourth-order speed filter (MAC050–141 manual 4.2, 4.3, 4.4.9, 4.4.10; docs/tuning.md).

* identify: TESTU → R, L, PWM delay; the current loop designed and written; the two-level TESTA
  procedure → J, KVOUT, b, T_c (:func:`tuning.autotune.identify_motors`);
* design, quantise, verify: :func:`tuning.autotune.synthesize` — the structure asked for (PI
  with the dead-band rule for the position integral, or I-P: the proportional part in VB,
  manual 4.2), then the same speed loop with the position integral switched the other way and
  the other structure (:func:`candidate_designs`);
* the default setup: the motor type's ``configs/setups`` registers with the design point of
  :mod:`tuning.defaults`, verified on the identified motor (:func:`default_design`); it may be
  kept only if it passes :func:`tuning.autotune.verify_design`;
* the identified motor for the acceptance step: R, L and the PWM delay from TESTU, the rotor
  inertia of the type and the rest of J as load (all of it as rotor inertia when J < J_m), b
  and T_c as reported (0 when not detected), the current noise seen in TESTU
  (:func:`simulation_parameters`); the move's A_SOLL is the T_SOLL guidance's A_SOLL_max
  within 10 … 200 (:func:`move_acceleration`).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from jvl_gym.families import Family

from ..autotune import (
    CURRENT_KEYS,
    RECOMMENDED_COIL_SAMPLES,
    RECOMMENDED_MECH_SAMPLES,
    SPEED_KEYS,
    Design,
    Identification,
    identify_motors,
    synthesize,
    verify_design,
)
from ..credibility import problems
from ..family import default_filters
from ..models import MotorData
from ..pipeline import DEFAULT_NAME, Candidate, Move, Result
from ..synthesis import torque_guidance
from ..verify import LoopMetrics, verify_current_loop, verify_speed_loop
from .servo import ServoLoops, motor_data

__all__ = ["TestuPiStrategy", "MOVE_DISTANCE", "MOVE_V_SOLL", "simulation_parameters",
           "move_acceleration", "candidate_designs", "default_design"]

MOVE_DISTANCE: int = 20000  #: acceptance move [counts] (4.9 revolutions)
MOVE_V_SOLL: int = 2000  #: its velocity [1/16 count/sample] (953.7 rpm, manual 3.2.5)


def simulation_parameters(ident: Identification) -> dict[str, float]:
    """``MotorArray`` keywords of the identified motor (SI units, docs/model.md "Plant"; module
    docstring); current noise = the TESTU residual's standard deviation [ADC counts] (it
    includes the 1-count quantisation)."""
    md, c, m = ident.motor, ident.coil, ident.mechanics
    params: dict[str, float] = {
        "phase_resistance": c.R_phase, "phase_inductance": c.L_phase,
        "pwm_delay_samples": float(min(max(c.delay, 0), 1)),
        "viscous_friction": max(m.viscous, 0.0), "coulomb_friction": max(m.coulomb, 0.0),
        "current_noise": float(c.residual.get("sigma", 0.0)),
    }
    if m.J >= md.J_m:
        params.update(rotor_inertia=md.J_m, load_inertia=m.J - md.J_m)
    else:
        params.update(rotor_inertia=m.J, load_inertia=0.0)
    return params


def move_acceleration(ident: Identification) -> int:
    """A_SOLL of the acceptance move: the T_SOLL guidance's A_SOLL_max within 10..200."""
    g = torque_guidance(ident.motor, ident.mechanics.J, ident.mechanics.coulomb)
    return int(max(10, min(200, g["A_SOLL_max"])))


def _name(d: Design) -> str:
    """Candidate name of a design: its speed-loop structure and the position integral."""
    if d.speed.structure == "ip":
        return "ip"
    return "pi + position integral" if d.speed.kii > 0.0 else "pi"


def candidate_designs(ident: Identification, structure: str = "pi") -> list[Candidate]:
    """The designs to try for one motor, the one asked for (``structure``) first.

    ``"pi"``: the PI with the dead-band rule for the position integral, then the same PI with
    the integral switched the other way, then I-P; ``"ip"``: I-P, then both PI variants.
    Designs that fail :func:`tuning.autotune.verify_design` are left out (the one asked for is
    kept and flagged by the caller). The alternatives share the asked design's current loop
    and speed-loop gains (kp, ki): PI and I-P have the same loop transfer function
    (:mod:`tuning.synthesis`), so the gain search runs once.
    """
    md, mech = ident.motor, ident.mechanics
    first = synthesize(md, mech.J, mech.coulomb, structure=structure)
    out = [Candidate(_name(first), first.registers, first)]
    alts: list[Any] = []
    if structure == "pi":
        alts.append(dict(structure="pi", position_integral=first.speed.kii == 0.0))
        alts.append(dict(structure="ip"))
    else:
        alts += [dict(structure="pi", position_integral=False),
                 dict(structure="pi", position_integral=True)]
    same = dict(current_gains=(first.current.loop_gain, first.current.ki_norm),
                speed_gains=(first.speed.kp_norm, first.speed.ki_norm))
    for kw in alts:
        try:
            d = synthesize(md, mech.J, mech.coulomb, **kw, **same)
        except ValueError:
            continue
        if kw.get("position_integral") and d.speed.kii == 0.0:
            continue  # no position integral meets the margins: the same as the plain PI
        if not verify_design(d) and _name(d) not in {c.name for c in out}:
            out.append(Candidate(_name(d), d.registers, d))
    return out


def default_design(ident: Identification) -> Design:
    """The motor type's default setup as a :class:`tuning.autotune.Design`, verified on the
    identified motor: the design point of :mod:`tuning.defaults` (fixed normalised gains, PI,
    KVOUT = 1) with the registers of the family's ``configs/setups/<TYPE>.yaml``."""
    from ..defaults import DEFAULT_CURRENT_GAINS, DEFAULT_SPEED_GAINS

    md = ident.motor
    d = synthesize(md, md.J_m, structure="pi", current_gains=DEFAULT_CURRENT_GAINS,
                   speed_gains=DEFAULT_SPEED_GAINS)
    regs = default_filters(md.name, (*CURRENT_KEYS, *SPEED_KEYS))
    d.registers = regs
    d.current_report = verify_current_loop(md, regs)
    d.speed_report = verify_speed_loop(md, regs, ident.mechanics.J)
    d.notes = ["the motor type's default setup (the family's configs/setups), kept by the "
               "acceptance step"]
    return d


def _ci(ci: tuple[float, float]) -> tuple[float, float]:
    return (float(ci[0]), float(ci[1]))


class TestuPiStrategy(ServoLoops):
    """The ``"testu_pi"`` strategy (module docstring) for the family ``family``."""

    options = frozenset({"port", "resonance", "coupling_stiffness", "coupling_damping",
                         "n_coil", "n_mech", "structure", "current_bw", "speed_bw", "coulomb"})

    def __init__(self, family: Family) -> None:
        self.family = family

    # ------------------------------------------------------------------ pipeline steps
    def simulator(self, motor: str, load_inertia: float, viscous: float, coulomb: float,
                  noise: bool, settings: Mapping[str, Any]) -> dict[str, Any]:
        """Load, friction and the coupling of ``settings``; with ``noise`` 2 ADC counts of
        current noise and 0.85 counts of position noise."""
        params: dict[str, Any] = {
            "load_inertia": load_inertia, "viscous_friction": viscous,
            "coulomb_friction": coulomb,
            "coupling_stiffness": settings.get("coupling_stiffness") or 0.0,
            "coupling_damping": settings.get("coupling_damping") or 0.0}
        if noise:
            params.update(current_noise=2.0, position_noise=0.85)
        return params

    def identify(self, m: Any, settings: Mapping[str, Any],
                 progress: Callable[[str], None]) -> list[Identification]:
        """TESTU and the two-level TESTA (:func:`tuning.autotune.identify_motors`) with the
        record lengths ``n_coil``, ``n_mech`` of ``settings``."""
        return identify_motors(m, settings.get("n_coil") or RECOMMENDED_COIL_SAMPLES,
                               settings.get("n_mech") or RECOMMENDED_MECH_SAMPLES,
                               progress=progress)

    def candidates(self, ident: Identification, settings: Mapping[str, Any]
                   ) -> list[Candidate]:
        """:func:`candidate_designs` of the ``structure`` of ``settings`` (default PI)."""
        return candidate_designs(ident, settings.get("structure") or "pi")

    def default_candidate(self, ident: Identification) -> Candidate:
        """:func:`default_design` as a candidate."""
        d = default_design(ident)
        return Candidate(DEFAULT_NAME, d.registers, d)

    def failures(self, candidate: Candidate) -> list[str]:
        """:func:`tuning.autotune.verify_design` of the candidate's design."""
        return [] if candidate.design is None else verify_design(candidate.design)

    def simulation_motor(self, ident: Identification) -> tuple[Any, dict[str, float]]:
        """The motor type and :func:`simulation_parameters`."""
        return ident.motor.name, simulation_parameters(ident)

    def move(self, ident: Identification) -> Move:
        """:data:`MOVE_DISTANCE` at :data:`MOVE_V_SOLL` with :func:`move_acceleration`."""
        return Move(MOVE_DISTANCE, MOVE_V_SOLL, move_acceleration(ident))

    def problems(self, ident: Identification) -> list[str]:
        """:func:`tuning.credibility.problems` of the coil and the mechanics."""
        return problems(ident.motor, mech=ident.mechanics, coil=ident.coil)

    def setup_note(self, result: Result) -> str:
        """The motor type and the identified J."""
        return (f"jvl-tune autotune: {result.ident.motor.name}, identified J = "
                f"{result.ident.mechanics.J:.4g} kg m^2")

    # ------------------------------------------------------------------ design and verification
    def synthesize(self, motor: str, inertia: float, settings: Mapping[str, Any]
                   ) -> tuple[Candidate, MotorData]:
        """:func:`tuning.autotune.synthesize` on the type's data (R, L from ``resistance``,
        ``inductance`` of ``settings`` where given) with the bandwidths, structure (default
        I-P) and Coulomb friction of ``settings``."""
        md = motor_data(motor, settings)
        d = synthesize(md, inertia, settings.get("coulomb") or 0.0,
                       settings.get("current_bw"), settings.get("speed_bw"),
                       settings.get("structure") or "ip")
        return Candidate(_name(d), d.registers, d), md

    def _verified(self, candidate: Candidate, motor: MotorData, J: float) -> Any:
        if candidate.design is not None:
            return candidate.design
        regs = candidate.registers
        return Design(regs, regs, None, None, verify_current_loop(motor, regs),  # type: ignore[arg-type]
                      verify_speed_loop(motor, regs, J), {}, {})

    def loop_rows(self, candidate: Candidate, motor: MotorData, J: float
                  ) -> list[tuple[str, LoopMetrics]]:
        """Current and speed loop, nominal and over the robustness set
        (:func:`tuning.verify.verify_current_loop`, :func:`tuning.verify.verify_speed_loop`)."""
        d = self._verified(candidate, motor, J)
        cr, sr = d.current_report, d.speed_report
        return [("current, nominal", cr.nominal),
                *((f"current, {k}", mt) for k, mt in cr.robust.items()),
                ("speed, nominal", sr.nominal),
                *((f"speed, {k}", mt) for k, mt in sr.robust.items())]

    def design_lines(self, candidate: Candidate, motor: MotorData, J: float) -> list[str]:
        """The speed loop's reference bandwidth and overshoot, the quantisation's changes of
        the margins, the T_SOLL guidance, the designer's notes."""
        d = self._verified(candidate, motor, J)
        sr = d.speed_report
        lines = [f"speed reference bandwidth {sr.reference_bandwidth_hz:.1f} Hz, "
                 f"step overshoot {100 * sr.step_overshoot:.1f} %"]
        if d.quantization_delta:
            lines.append("quantisation changes: " + ", ".join(
                f"{k} {v:+.3f}" for k, v in d.quantization_delta.items()))
        g = d.guidance
        if g:
            lines.append(f"T_SOLL guidance: T_SOLL {g['T_SOLL']:.0f} = {g['torque_Nm']:.3f} N m; "
                         f"profiles up to A_SOLL {g['A_SOLL_max']:.0f} keep half of it for "
                         "regulation")
        lines += [f"note: {n}" for n in d.notes]
        return lines

    def verify_setup(self, motor: str | None, setup: Path, inertia: float | None
                     ) -> tuple[list[str], list[str], bool]:
        """``jvl-tune verify``: the setup validated as the simulator validates it, the
        registers it does not give from the motor type's defaults (what a motor keeps), the
        loops' margins. Returns notes (which loop registers came from the defaults), the lines
        to print and whether every loop is stable."""
        from ..setups import complete_setup

        name, regs, notes = complete_setup(motor, setup, (*CURRENT_KEYS, "KVFX4", "KVFX3",
                                                          "KVFX2", "KVFX1", "KVFY3", "KVFY2",
                                                          "KVFY1", "KVFY0", "KVOUT"))
        md = MotorData.from_config(name)
        J = inertia if inertia else regs.get("KVOUT", 1.0) * md.J_m
        cr = verify_current_loop(md, regs)
        sr = verify_speed_loop(md, regs, J)
        lines = []
        for label, rep in (("current", cr), ("speed", sr)):
            n = rep.nominal
            lines.append(f"{label}: PM {n.pm_deg:.1f} deg, GM {n.gm_db:.1f} dB, BW "
                         f"{n.bandwidth_hz:.1f} Hz, |z|max {n.pole_radius:.4f}, worst robust PM "
                         f"{rep.worst_robust_pm:.1f} deg, all stable {rep.all_stable}")
        return notes, lines, cr.all_stable and sr.all_stable

    # ------------------------------------------------------------------ report
    def identified_rows(self, ident: Identification) -> list[Any]:
        """Coil (line-to-line R, L, pole, gain, PWM delay) and mechanics (J, KVOUT, b, T_c),
        a friction or J whose interval reaches 0 flagged "not detected"."""
        c, m = ident.coil, ident.mechanics
        rows = [
            ("R line-line [ohm]", c.R_line, c.ci["R_line"], "R_line"),
            ("L line-line [mH]", c.L_line * 1e3, (c.ci["L_line"][0] * 1e3,
                                                   c.ci["L_line"][1] * 1e3), "L_line_mH"),
            ("coil pole a", c.pole, c.ci["pole"], "pole"),
            ("coil gain g [cnt/cnt]", c.gain, c.ci["gain"], "gain"),
            ("PWM delay [samples]", c.delay, c.ci.get("delay", (c.delay, c.delay)), "delay"),
            ("J total [kg m^2]", m.J, m.ci["J"], "J"),
            ("KVOUT = J/J_m", m.kvout, m.ci["kvout"], "kvout"),
            ("viscous b [N m s/rad]", m.viscous, m.ci["viscous"], "viscous"),
            ("Coulomb Tc [N m]", m.coulomb, m.ci["coulomb"], "coulomb"),
        ]
        out = []
        for label, val, ci, key in rows:
            flag = ""
            if key in ("viscous", "coulomb", "J") and not m.detected.get(key, True):
                flag = "  not detected (interval reaches 0)"
            out.append((label, val, _ci(ci), key, flag))
        return out

    def identification_lines(self, ident: Identification) -> list[str]:
        """The fits' NRMSE and residual whiteness, how the intervals were computed."""
        c, m = ident.coil, ident.mechanics
        lines = [f"TESTU fit {c.nrmse_fit:.2f} % NRMSE, residual white: "
                 f"{c.residual['white']} (Box-Pierce p = {c.residual['box_pierce_p']:.2f}); "
                 f"TESTA fit {m.nrmse_fit:.2f} %, residual white: {m.residual['white']}"]
        n_u = sum(r.kind == "TESTU" for r in ident.records)
        lines.append("TESTU intervals: " + ("whole-record jackknife over "
                                            f"{n_u} records + quantisation floor" if n_u >= 3
                                            else "fit covariance x correlation inflation"))
        if m.repeats > 1:
            lines.append(f"TESTA intervals: spread of {m.repeats} repeated two-level sets "
                         "(Student t, K-1 dof) + quantisation and coil-uncertainty terms; J of "
                         "each set: " + ", ".join(f"{j:.5g}" for j in m.J_repeats))
        else:
            lines.append("TESTA intervals: one fit (statistical only, too narrow under model "
                         "error; record the two levels repeatedly)")
        return lines

    def fit_figure(self, ident: Identification) -> Any:
        """The TESTU and TESTA records with the fitted model outputs."""
        import matplotlib.pyplot as plt

        fam = ident.motor.family
        fig, ax = plt.subplots(1, 2, figsize=(10, 3.8))
        r = next(rec for rec in ident.records if rec.kind == "TESTU")
        k = np.arange(r.n)
        ax[0].plot(k, r.output, "o", ms=3, label="IC_IST measured")
        ax[0].plot(k, ident.coil.fitted[0], "-", label=f"model, d = {ident.coil.delay}")
        ax[0].set(xlabel=f"inner sample ({1e6 * fam.inner_dt:.0f} us)", ylabel="ADC counts",
                  title="TESTU fit")
        ax[0].legend()
        seen: set[float] = set()
        testa = [rec for rec in ident.records if rec.kind == "TESTA"]
        for rec, fv in zip(testa, ident.mechanics.fitted_velocity):
            kk = np.arange(rec.n)
            first = rec.input[0] not in seen  # repetitions of a level: unlabelled, lighter
            seen.add(rec.input[0])
            ax[1].plot(kk, rec.output, "o", ms=3, alpha=1.0 if first else 0.3,
                       label=f"V_IST, T_SOLL {rec.input[0]:.0f}" if first else None)
            ax[1].plot(kk, fv, "-", alpha=1.0 if first else 0.3)
        ax[1].set(xlabel=f"outer sample ({1e3 * fam.outer_dt:.2f} ms)", ylabel="counts/sample",
                  title="TESTA fit")
        ax[1].legend()
        fig.tight_layout()
        return fig

