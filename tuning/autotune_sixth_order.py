"""Autotune of MAC800-family motors: identify, design the sixth-order filter, keep the best setup
by simulation, write a setup file the family loads.

1. Identification from sample-buffer records of torque steps (:mod:`tuning.identify_buffer`):
   the coil, the current loop designed for it, then J, T_c, b.
2. Candidates (:mod:`tuning.design_sixth_order`): the PI with the low-pass in the extra orders
   (and a notch at ``notch_hz`` when a resonance is known), the plain PI, and the motor type's
   default setup (``families/mac800/configs/setups``).
3. Acceptance step (as the MAC050–141's, :mod:`tuning.acceptance`): every candidate runs the
   same position-mode move (:data:`MOVE_DISTANCE` counts, mode 2) on a ``MotorArray`` built from
   the *identified* motor (R, L, PWM delay, J, b, T_c); the candidate that settles first in the
   in-position window (INPOSWIN, register 33) wins, ties by the final error, then the order
   above. The reason goes into the report.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from jvl_gym.families.mac800 import constants as _c

from .design_sixth_order import (
    SixthOrderDesign,
    check_sixth_order,
    synthesize_sixth_order,
    verify_sixth_order,
)
from .identify_buffer import BufferIdentification, identify_from_buffer
from .models import MotorData
from .sixth_order import COUNTS_PER_RAD, CURRENT_KEYS, MAIN_KEYS, TS_O, default_registers
from .verify import position_move

__all__ = ["MOVE_DISTANCE", "MOVE_V_SOLL", "DEFAULT_NAME", "SixthOrderCandidate",
           "SixthOrderResult", "move_acceleration", "simulation_motor", "design_candidates",
           "accept_by_move", "autotune_sixth_order", "setup_text", "write_setup",
           "autotune_report", "verify_setup", "default_filters"]

MOVE_DISTANCE: int = 20000  #: acceptance move [counts] (2.5 revolutions)
MOVE_V_SOLL: int = 2000  #: its velocity [1/16 count/sample] (722 RPM, register 5)
DEFAULT_NAME: str = "default setup"
WINDOW: int = 10  #: in-position window of the move [counts] (INPOSWIN's default, register 33)

Progress = Callable[[str], None]


@dataclass
class SixthOrderCandidate:
    """A setup the acceptance step tries: its name, filter registers and design (None for the
    default setup)."""

    name: str
    registers: dict[str, float]
    design: SixthOrderDesign | None = None


@dataclass
class SixthOrderResult:
    """Autotune result of one motor."""

    ident: BufferIdentification
    chosen: SixthOrderCandidate
    settle_s: dict[str, float]
    final_error: dict[str, float]
    move: tuple[int, int, int]
    reason: str
    candidates: list[SixthOrderCandidate] = field(default_factory=list)


def move_acceleration(ident: BufferIdentification) -> int:
    """A_SOLL of the acceptance move [1/16 count/sample²]: half the peak torque over the
    identified J, within 10 … 200 (register 6)."""
    md, J = ident.motor, ident.mechanics.J
    alpha = 0.5 * _c.VF_FULL * md.torque_per_vf / J
    return int(np.clip(alpha * COUNTS_PER_RAD * TS_O**2 * 16.0, 10, 200))


def simulation_motor(ident: BufferIdentification) -> tuple[Any, dict[str, float]]:
    """The identified motor for a ``MotorArray``: the config with the identified coil, and the
    keywords load_inertia (J − J_m; all of J as rotor when J < J_m) and the friction."""
    md, mech = ident.motor, ident.mechanics
    cfg = md.family.load_motor(md.name)
    rotor = md.J_m if mech.J >= md.J_m else mech.J
    cfg = cfg.model_copy(update={"phase_resistance": md.R_phase, "phase_inductance": md.L_phase,
                                 "pwm_delay_samples": int(md.pwm_delay),
                                 "rotor_inertia": rotor})
    return cfg, {"load_inertia": max(mech.J - rotor, 0.0),
                 "viscous_friction": max(mech.viscous, 0.0),
                 "coulomb_friction": max(mech.coulomb, 0.0)}


def default_filters(motor_type: str) -> dict[str, float]:
    """The current and main filter registers of the type's default setup."""
    regs = default_registers(motor_type)
    return {k: regs[k] for k in (*CURRENT_KEYS, *MAIN_KEYS)}


def design_candidates(ident: BufferIdentification, notch_hz: float | None = None
                     ) -> list[SixthOrderCandidate]:
    """The designs to try, the preferred first: PI with the low-pass (and the notch), then the
    plain PI; designs that fail :func:`tuning.design_sixth_order.check_sixth_order` are left
    out except the first (flagged by its verification)."""
    md, J = ident.motor, ident.mechanics.J
    first = synthesize_sixth_order(md, J, ident.current_registers, lowpass=True, notch_hz=notch_hz)
    out = [SixthOrderCandidate(first.name, first.registers, first)]
    plain = synthesize_sixth_order(md, J, ident.current_registers, lowpass=False)
    if not check_sixth_order(plain.verification):
        out.append(SixthOrderCandidate(plain.name, plain.registers, plain))
    return out


def accept_by_move(idents: Sequence[BufferIdentification],
                   candidates: Sequence[Sequence[SixthOrderCandidate]], seconds: float = 2.0,
                   seed: int = 0) -> list[SixthOrderResult]:
    """Simulate every candidate and the default setup on its identified motor; keep the best
    (module docstring, step 3)."""
    from jvl_gym import MotorArray

    out = []
    for ident, cands in zip(idents, candidates):
        lanes = [*cands, SixthOrderCandidate(DEFAULT_NAME, default_filters(ident.motor.name))]
        cfg, params = simulation_motor(ident)
        m = MotorArray(cfg, n=len(lanes), seed=seed, **params)
        for j, c in enumerate(lanes):
            m.load_setup({"registers": c.registers}, index=[j])
        acc = move_acceleration(ident)
        mv = position_move(m, MOVE_DISTANCE, MOVE_V_SOLL, acc, seconds=seconds, window=WINDOW,
                           dt=TS_O)
        tail = max(1, int(round(0.2 / TS_O)))
        target = np.asarray(m.read("P_SOLL"), dtype=float)
        err = np.max(np.abs(mv.position[-tail:] - target), axis=0)
        settle = {c.name: float(mv.settle_s[j]) for j, c in enumerate(lanes)}
        final = {c.name: float(err[j]) for j, c in enumerate(lanes)}
        best = min(range(len(lanes)), key=lambda j: (mv.settle_s[j], err[j], j))
        chosen, asked = lanes[best], lanes[0].name
        if chosen.name == asked:
            why = (f"kept the {asked} design: it settles in {_ms(settle[asked])} on the "
                   f"identified motor, the default setup in {_ms(settle[DEFAULT_NAME])}")
        else:
            why = (f"kept the {chosen.name}{'' if chosen.design is None else ' design'} instead "
                   f"of the {asked} design: it settles in {_ms(settle[chosen.name])} on the "
                   f"identified motor, the {asked} design in {_ms(settle[asked])}"
                   + ("" if chosen.name == DEFAULT_NAME else
                      f", the default setup in {_ms(settle[DEFAULT_NAME])}"))
        out.append(SixthOrderResult(ident, chosen, settle, final,
                                    (MOVE_DISTANCE, MOVE_V_SOLL, acc), why, list(cands)))
    return out


def _ms(t: float) -> str:
    return "never (2 s)" if not math.isfinite(t) else f"{1e3 * t:.0f} ms"


def autotune_sixth_order(m: Any, notch_hz: float | None = None, repeats: int = 2, seed: int = 0,
                         progress: Progress = lambda _: None) -> list[SixthOrderResult]:
    """Identify every motor of ``m``, design, verify and keep the best setup (module
    docstring)."""
    idents = identify_from_buffer(m, repeats=repeats, progress=progress)
    progress("synthesis of the sixth-order filter, quantisation, verification")
    cands = [design_candidates(i, notch_hz) for i in idents]
    progress(f"acceptance step: a {MOVE_DISTANCE}-count move of every candidate on the "
             "identified motor")
    return accept_by_move(idents, cands, seed=seed)


def setup_text(motor_type: str, regs: dict[str, float], note: str) -> str:
    """A setup file of the MAC800 family (``configs/setups`` format: motor, provenance,
    registers) with ``note`` as its header."""
    clean = {k: (int(v) if k in ("MODEL_POT", "S_ORDER") else float(v)) for k, v in regs.items()}
    text = "".join(f"# {ln}\n" for ln in note.splitlines())
    return text + yaml.safe_dump({"motor": motor_type, "provenance": "jvl-tune",
                                  "registers": clean}, sort_keys=False)


def write_setup(path: str | os.PathLike[str], result: SixthOrderResult) -> Path:
    """Write the kept setup of ``result`` with the identified values and the reason."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    idn = result.ident
    note = (f"jvl-tune autotune: {idn.motor.name}, identified J = {idn.mechanics.J:.4g} kg m^2, "
            f"R = {idn.coil.R_phase:.4g} ohm, L = {idn.coil.L_phase:.4g} H\n{result.reason}")
    path.write_text(setup_text(idn.motor.name, result.chosen.registers, note))
    return path


def autotune_report(result: SixthOrderResult) -> str:
    """The text report of one motor's autotune."""
    idn, mech = result.ident, result.ident.mechanics
    lines = [f"MAC800-family autotune: {idn.motor.name}",
             f"  coil: R {idn.coil.R_phase:.4g} ohm, L {1e3 * idn.coil.L_phase:.4g} mH per phase, "
             f"PWM delay {idn.coil.delay}, fit NRMSE {idn.coil.nrmse:.2f} %",
             f"  mechanics: J {mech.J:.5g} kg m^2 (95 % {mech.ci_J[0]:.5g} .. {mech.ci_J[1]:.5g}), "
             f"KVOUT {mech.J / idn.motor.J_m:.3f}, Tc {mech.coulomb:.4g} N m, "
             f"b {mech.viscous:.4g} N m s/rad, fit NRMSE {mech.nrmse:.3f} %"]
    for c in result.candidates:
        v = c.design.verification if c.design else None
        if v is None:
            continue
        lines.append(f"  {c.name}: speed PM {v.speed.pm_deg:.1f} deg (python-control "
                     f"{v.ct_pm_deg:.1f}), GM {v.speed.gm_db:.1f} dB, crossover "
                     f"{v.speed.crossover_hz:.1f} Hz, |z|max {v.speed.pole_radius:.4f}, worst "
                     f"robust PM {v.worst_robust_pm:.1f} deg; current PM {v.current.pm_deg:.1f} "
                     f"deg; checks {'; '.join(check_sixth_order(v)) or 'ok'}")
        lines.extend(f"    {n}" for n in c.design.notes)
    d, vs, a = result.move
    lines.append(f"Acceptance step: {d}-count move, V_SOLL {vs}, A_SOLL {a} on the identified "
                 "motor")
    for k, t in result.settle_s.items():
        lines.append(f"  {k}: settles {_ms(t)}, final error {result.final_error[k]:.0f} counts")
    lines.append(f"  {result.reason}")
    return "\n".join(lines) + "\n"


def verify_setup(motor_type: str, regs: dict[str, float], J: float | None = None
                ) -> tuple[Any, list[str]]:
    """Verify a MAC800 register set on the motor type's data (J default KVOUT·J_m)."""
    md = MotorData.from_config(motor_type, amplitude=regs.get("AMPLITUDE"))
    full = {**default_filters(motor_type), **regs}
    J = J if J else full.get("KVOUT", 1.0) * md.J_m
    v = verify_sixth_order(md, full, J)
    return v, check_sixth_order(v)
