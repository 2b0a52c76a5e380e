"""Strategy ``"buffer_sixth_order"``: identification from sample-buffer records of torque steps
and the sixth-order main filter (MAC800 register overview §1.2; docs/tuning.md, "MAC800
family").

* identify: a coil step at the current-loop rate → R, L, PWM delay; the current loop designed
  and written; torque steps at two levels → J, T_c, b (:mod:`tuning.identify_buffer`);
* design, quantise, verify: the PI with the low-pass in the extra orders (and a notch at
  ``notch_hz`` when a resonance is known), then the plain PI if it passes the checks
  (:mod:`tuning.design_sixth_order`);
* the default setup: the motor type's ``configs/setups`` filter registers, not verified (the
  family's own setup may always be kept);
* the identified motor for the acceptance step: the motor config with the identified coil, the
  rotor inertia of the type and the rest of J as load (all of it as rotor when J < J_m), the
  friction as identified (:meth:`BufferSixthOrderStrategy.simulation_motor`); the move's
  A_SOLL is half the peak torque over the identified J within 10 … 200 (register 6).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from jvl_gym.families import Family, family_of_motor

from ..design_sixth_order import (
    SixthOrderVerification,
    check_sixth_order,
    synthesize_sixth_order,
    verify_sixth_order,
)
from ..identify_buffer import BufferIdentification, identify_from_buffer
from ..identify_mechanics import electrical_position
from ..models import MotorData
from ..pipeline import DEFAULT_NAME, Candidate, Move, Result
from ..sixth_order import CURRENT_KEYS, MAIN_KEYS, default_registers
from ..verify import LoopMetrics
from .servo import ServoLoops, motor_data

__all__ = ["BufferSixthOrderStrategy", "MOVE_DISTANCE", "MOVE_V_SOLL", "move_acceleration"]

MOVE_DISTANCE: int = 20000  #: acceptance move [counts] (2.5 revolutions)
MOVE_V_SOLL: int = 2000  #: its velocity [1/16 count/sample] (722 RPM, register 5)
REPEATS: int = 4  #: repetitions of the two torque levels (Student t with 3 dof)


def move_acceleration(ident: BufferIdentification) -> int:
    """A_SOLL of the acceptance move [1/16 count/sample²]: half the peak torque over the
    identified J, within 10 … 200 (register 6)."""
    md, J = ident.motor, ident.mechanics.J
    fam = md.family
    alpha = 0.5 * family_of_motor(md.name).constants.VF_FULL * md.torque_per_vf / J
    return int(np.clip(alpha * fam.counts_per_rad * fam.outer_dt**2 * fam.speed_units, 10, 200))


def _verification(candidate: Candidate, motor: MotorData, J: float) -> SixthOrderVerification:
    if candidate.design is not None:
        return candidate.design.verification
    return verify_sixth_order(motor, {**default_registers(motor.name), **candidate.registers}, J)


def _step_response(ident: BufferIdentification, vf: float, n: int) -> np.ndarray:
    """Position [counts] of a torque step of VF_OUT ``vf`` from rest on the identified motor,
    ``n`` servo samples: the model the mechanics were fitted with (electrical: the current loop
    and the back-EMF, :func:`tuning.identify_mechanics.electrical_position`; else the rigid
    rotor)."""
    md, mech, fam = ident.motor, ident.mechanics, ident.motor.family
    if mech.model == "electrical":
        return electrical_position(n, vf, mech.J, mech.viscous, mech.coulomb, md,
                                   ident.current_registers, mech.phase_comp / 256.0)
    omega, theta = 0.0, 0.0
    out = np.zeros(n)
    for k in range(1, n):
        acc = (md.torque_per_vf * vf - mech.coulomb - mech.viscous * omega) / mech.J
        theta += omega * fam.outer_dt + 0.5 * acc * fam.outer_dt**2
        omega += acc * fam.outer_dt
        out[k] = theta * fam.counts_per_rad
    return out


class BufferSixthOrderStrategy(ServoLoops):
    """The ``"buffer_sixth_order"`` strategy (module docstring) for the family ``family``."""

    options = frozenset({"notch_hz"})

    def __init__(self, family: Family) -> None:
        self.family = family

    # ------------------------------------------------------------------ pipeline steps
    def simulator(self, motor: str, load_inertia: float, viscous: float, coulomb: float,
                  noise: bool, settings: Mapping[str, Any]) -> dict[str, Any]:
        """Load and friction; with ``noise`` 0.85 counts of position noise."""
        params: dict[str, Any] = {"load_inertia": load_inertia, "viscous_friction": viscous,
                                  "coulomb_friction": coulomb}
        if noise:
            params["position_noise"] = 0.85
        return params

    def identify(self, m: Any, settings: Mapping[str, Any],
                 progress: Callable[[str], None]) -> list[BufferIdentification]:
        """:func:`tuning.identify_buffer.identify_from_buffer` with :data:`REPEATS`."""
        return identify_from_buffer(m, repeats=REPEATS, progress=progress)

    def candidates(self, ident: BufferIdentification, settings: Mapping[str, Any]
                   ) -> list[Candidate]:
        """The PI with the low-pass (and the notch at ``notch_hz`` of ``settings``), then the
        plain PI if it passes :func:`tuning.design_sixth_order.check_sixth_order`."""
        md, J = ident.motor, ident.mechanics.J
        first = synthesize_sixth_order(md, J, ident.current_registers, lowpass=True,
                                       notch_hz=settings.get("notch_hz"))
        out = [Candidate(first.name, first.registers, first)]
        plain = synthesize_sixth_order(md, J, ident.current_registers, lowpass=False)
        if not check_sixth_order(plain.verification):
            out.append(Candidate(plain.name, plain.registers, plain))
        return out

    def default_candidate(self, ident: BufferIdentification) -> Candidate:
        """The current and main filter registers of the type's default setup."""
        regs = default_registers(ident.motor.name)
        return Candidate(DEFAULT_NAME, {k: regs[k] for k in (*CURRENT_KEYS, *MAIN_KEYS)})

    def failures(self, candidate: Candidate) -> list[str]:
        """:func:`tuning.design_sixth_order.check_sixth_order` of the candidate's design."""
        if candidate.design is None:
            return []
        return check_sixth_order(candidate.design.verification)

    def simulation_motor(self, ident: BufferIdentification) -> tuple[Any, dict[str, float]]:
        """The config with the identified coil, and the keywords load_inertia and the
        friction (module docstring)."""
        md, mech = ident.motor, ident.mechanics
        cfg = self.family.load_motor(md.name)
        rotor = md.J_m if mech.J >= md.J_m else mech.J
        cfg = cfg.model_copy(update={"phase_resistance": md.R_phase,
                                     "phase_inductance": md.L_phase,
                                     "pwm_delay_samples": int(md.pwm_delay),
                                     "rotor_inertia": rotor})
        return cfg, {"load_inertia": max(mech.J - rotor, 0.0),
                     "viscous_friction": max(mech.viscous, 0.0),
                     "coulomb_friction": max(mech.coulomb, 0.0)}

    def move(self, ident: BufferIdentification) -> Move:
        """:data:`MOVE_DISTANCE` at :data:`MOVE_V_SOLL` with :func:`move_acceleration`."""
        return Move(MOVE_DISTANCE, MOVE_V_SOLL, move_acceleration(ident))

    def problems(self, ident: BufferIdentification) -> list[str]:
        """Nothing: the fits refuse what is not physical (:mod:`tuning.identify_buffer`)."""
        return []

    def setup_note(self, result: Result) -> str:
        """The motor type, the identified J, R and L, and the reason for the kept setup."""
        idn = result.ident
        return (f"jvl-tune autotune: {idn.motor.name}, identified J = {idn.mechanics.J:.4g} "
                f"kg m^2, R = {idn.coil.R_phase:.4g} ohm, L = {idn.coil.L_phase:.4g} H\n"
                f"{result.reason}")

    # ------------------------------------------------------------------ design and verification
    def synthesize(self, motor: str, inertia: float, settings: Mapping[str, Any]
                   ) -> tuple[Candidate, MotorData]:
        """The sixth-order design with the low-pass
        (:func:`tuning.design_sixth_order.synthesize_sixth_order`) on the type's data (R, L
        from ``resistance``, ``inductance`` of ``settings`` where given)."""
        md = motor_data(motor, settings)
        d = synthesize_sixth_order(md, inertia)
        return Candidate(d.name, d.registers, d), md

    def loop_rows(self, candidate: Candidate, motor: MotorData, J: float
                  ) -> list[tuple[str, LoopMetrics]]:
        """Current and speed loop, nominal, and the speed loop over the robustness set."""
        v = _verification(candidate, motor, J)
        return [("current, nominal", v.current), ("speed, nominal", v.speed),
                *((f"speed, {k}", mt) for k, mt in v.robust.items())]

    def design_lines(self, candidate: Candidate, motor: MotorData, J: float) -> list[str]:
        """python-control's own margins of the speed loop, the checks, the designer's notes."""
        v = _verification(candidate, motor, J)
        lines = [f"speed loop: crossover {v.speed.crossover_hz:.1f} Hz, python-control PM "
                 f"{v.ct_pm_deg:.1f} deg, GM {v.ct_gm_db:.1f} dB; checks "
                 f"{'; '.join(check_sixth_order(v)) or 'ok'}"]
        notes = candidate.design.notes if candidate.design is not None else [
            "the motor type's default setup (the family's configs/setups)"]
        return lines + [f"note: {n}" for n in notes]

    def verify_setup(self, motor: str | None, setup: Path, inertia: float | None
                     ) -> tuple[list[str], list[str], bool]:
        """``jvl-tune verify``: the setup validated by the family's loader, the filter
        registers it leaves out from the type's default setup, the loops' margins and the
        checks. Returns notes (none), the lines to print and whether every loop is stable."""
        import typer
        import yaml

        from jvl_gym import MotorArray

        data = yaml.safe_load(setup.read_text()) if setup.is_file() else None
        named = data.get("motor") if isinstance(data, dict) else None
        if motor is not None and named is not None and motor != named:
            raise typer.BadParameter(f"{setup} is a setup for {named}, not {motor}",
                                     param_hint="'--motor'")
        name = motor if motor is not None else named
        MotorArray(name, n=1, setup=setup)  # validates the setup, naming it in the error
        regs = {k: float(x) for k, x in ((data or {}).get("registers") or {}).items()}
        md = MotorData.from_config(name, amplitude=regs.get("AMPLITUDE"))
        full = {**default_registers(name), **regs}
        J = inertia if inertia else full.get("KVOUT", 1.0) * md.J_m
        v = verify_sixth_order(md, full, J)
        lines = []
        for label, n, worst in (("current", v.current, math.inf),
                                ("speed", v.speed, v.worst_robust_pm)):
            lines.append(f"{label}: PM {n.pm_deg:.1f} deg, GM {n.gm_db:.1f} dB, BW "
                         f"{n.bandwidth_hz:.1f} Hz, |z|max {n.pole_radius:.4f}"
                         + (f", worst robust PM {worst:.1f} deg" if math.isfinite(worst) else "")
                         + f", all stable {v.all_stable}")
        bad = check_sixth_order(v)
        if bad:
            lines.append("checks: " + "; ".join(bad))
        return [], lines, v.all_stable

    # ------------------------------------------------------------------ report
    def identified_rows(self, ident: BufferIdentification) -> list[Any]:
        """Coil (per-phase R, L with their intervals, PWM delay) and mechanics (J, KVOUT, b,
        T_c with their intervals), a friction or J whose interval reaches 0 flagged "not
        detected"."""
        c, m, md = ident.coil, ident.mechanics, ident.motor
        lo, hi = m.ci_J
        ci_r, ci_l = c.ci.get("R_phase"), c.ci.get("L_phase")
        rows: list[Any] = [("R phase [ohm]", c.R_phase, ci_r, "R_phase", ""),
                           ("L phase [mH]", 1e3 * c.L_phase,
                            None if ci_l is None else (1e3 * ci_l[0], 1e3 * ci_l[1]),
                            "L_phase_mH", ""),
                           ("PWM delay [samples]", c.delay, None, "delay", "")]
        for label, val, key in (("J total [kg m^2]", m.J, "J"),
                                ("KVOUT = J/J_m", m.J / md.J_m, "kvout"),
                                ("viscous b [N m s/rad]", m.viscous, "viscous"),
                                ("Coulomb Tc [N m]", m.coulomb, "coulomb")):
            ci = (lo / md.J_m, hi / md.J_m) if key == "kvout" else m.ci.get(key)
            flag = ("  not detected (interval reaches 0)"
                    if key != "kvout" and not m.detected.get(key, True) else "")
            rows.append((label, val, ci, key, flag))
        return rows

    def identification_lines(self, ident: BufferIdentification) -> list[str]:
        """The fits' NRMSE and how the intervals were computed."""
        m, c = ident.mechanics, ident.coil
        model = ("current loop (its rounding averaged) and back-EMF modelled"
                 if m.model == "electrical" else "rigid model")
        return [f"coil step fit {c.nrmse:.2f} % NRMSE; torque-step fit "
                f"{m.nrmse:.3f} % NRMSE (rigid model, the start of the fit)",
                f"coil: intervals: spread of {len(c.repeats)} coil steps (Student t, K-1 dof)",
                f"mechanics: {model}; intervals: spread of {len(m.repeats)} repeated two-level "
                "steps (Student t, K-1 dof) + quantisation; J of each: "
                + ", ".join(f"{j:.5g}" for j in m.repeats)]

    def fit_figure(self, ident: BufferIdentification) -> Any:
        """The coil step with the identified coil's response (back-EMF left out), and the
        torque steps with the identified motor's response from rest in the model the
        mechanics were fitted with (:func:`_step_response`)."""
        import matplotlib.pyplot as plt

        md, fam, mech = ident.motor, ident.motor.family, ident.mechanics
        fig, ax = plt.subplots(1, 2, figsize=(10, 3.8))
        r = ident.coil_record
        if r is not None:
            a = math.exp(-md.R_phase * fam.inner_dt / md.L_phase)
            g = md.with_(supply_voltage=r.bus_voltage).coil_gain
            d = int(ident.coil.delay)
            for cur, u, label in ((r.ia, r.ua, "IA_IST"), (r.ib, r.ub, "IB_IST")):
                model = np.zeros(cur.size)
                model[0] = cur[0]
                for k in range(cur.size - 1):
                    model[k + 1] = a * model[k] + g * (1 - a) * (u[k - d] if k >= d else 0.0)
                line = ax[0].plot(cur, "o", ms=3, label=f"{label} measured")[0]
                ax[0].plot(model, "-", color=line.get_color(), label=f"model, d = {d}")
        ax[0].set(xlabel=f"inner sample ({1e6 * fam.inner_dt:.0f} us)",
                  ylabel="phase current [ADC counts]", title="coil step fit")
        ax[0].legend(fontsize=8)
        seen: set[float] = set()
        for rec in ident.torque_records:
            vf = float(np.median(rec.vf_out))
            first = vf not in seen  # repetitions of a level: unlabelled, lighter
            seen.add(vf)
            model = _step_response(ident, vf, rec.position.size)
            line = ax[1].plot(rec.position - rec.position[0], "o", ms=3,
                              alpha=1.0 if first else 0.3,
                              label=f"P_IST, VF_OUT {vf:.0f}" if first else None)[0]
            ax[1].plot(model, "-", color=line.get_color(), alpha=1.0 if first else 0.3)
        ax[1].set(xlabel=f"outer sample ({1e3 * fam.outer_dt:.2f} ms)",
                  ylabel="position from the step [counts]",
                  title=f"torque-step fit ({mech.model} model)")
        ax[1].legend(fontsize=8)
        fig.tight_layout()
        return fig

