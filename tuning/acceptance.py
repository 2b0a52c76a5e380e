"""Acceptance step of the autotune: simulate the candidate setups on the identified motor and
keep the best one (docs/tuning.md, "Acceptance step").

A design with good margins can still position worse than the default setup: with Coulomb
friction a PI speed loop is a PD position loop that stops anywhere within its friction dead
band (:func:`tuning.synthesis.friction_dead_band`), and the default setup may be faster for a
light load. So before a setup is returned, every candidate — the design asked for, the same
speed loop with and without the position integral, the I-P structure (manual 4.2: the
proportional part in VB), and the motor type's default setup
(``families/mac050_141/configs/setups/<TYPE>.yaml``) — runs the same P_MODE move
(:func:`tuning.verify.position_move`) on a ``MotorArray`` built from the *identified* values
(R, L, PWM delay, J, b, T_c, the current noise seen in TESTU).
The candidate that settles first in the in-position window (INPOSWIN, 3.2.33) wins; ties and
moves that never settle are decided by the final position error, then by the order above
(the design asked for first). The reason goes into the report.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from .synthesis import torque_guidance
from .verify import position_move

if TYPE_CHECKING:  # pragma: no cover
    from .autotune import Design, Identification

__all__ = ["Candidate", "Acceptance", "MOVE_DISTANCE", "MOVE_V_SOLL", "DEFAULT_NAME",
           "default_filters", "autotune_designs",
           "simulation_parameters", "move_acceleration", "candidate_designs", "accept"]

MOVE_DISTANCE: int = 20000  #: acceptance move [counts] (4.9 revolutions)
MOVE_V_SOLL: int = 2000  #: its velocity [1/16 count/sample] (953.7 rpm, manual 3.2.5)
DEFAULT_NAME: str = "default setup"


@dataclass
class Candidate:
    """One setup the acceptance step tries.

    Attributes
    ----------
    name : str
        What it is ("pi", "pi + position integral", "ip", "default setup").
    registers : dict
        Filter registers (name → value, quantised); empty for the default setup (the motor
        powers on with it).
    design : Design or None
        The synthesised design (None for the default setup).
    """

    name: str
    registers: dict[str, float]
    design: Design | None = None


@dataclass
class Acceptance:
    """Result of the acceptance step for one motor.

    Attributes
    ----------
    chosen : Candidate
        The candidate kept.
    settle_s : dict
        Candidate name → settle time of the move on the identified motor [s] (inf: never).
    final_error : dict
        Candidate name → largest |P_IST − P_SOLL| over the last 0.2 s [counts].
    move : tuple of int
        (distance [counts], V_SOLL [1/16 count/sample], A_SOLL [1/16 count/sample²]).
    reason : str
        One line for the report.
    """

    chosen: Candidate
    settle_s: dict[str, float]
    final_error: dict[str, float]
    move: tuple[int, int, int]
    reason: str = ""
    notes: list[str] = field(default_factory=list)


def default_filters(motor_type: str) -> dict[str, float]:
    """The filter registers of the motor type's default setup
    (``families/mac050_141/configs/setups``)."""
    from jvl_gym.families.mac050_141.config import load_setup

    from .autotune import CURRENT_KEYS, SPEED_KEYS

    regs = load_setup(motor_type).registers
    return {k: float(regs[k]) for k in (*CURRENT_KEYS, *SPEED_KEYS) if k in regs}


def simulation_parameters(ident: Identification) -> dict[str, float]:
    """``MotorArray`` keywords of the identified motor (SI units, docs/model.md "Plant").

    R, L and the PWM delay from TESTU; rotor inertia J_m of the type and the rest of the
    identified J as load (all of it as rotor inertia when J < J_m); b and T_c as reported
    (0 when not detected); current noise = the TESTU residual's standard deviation
    [ADC counts] (it includes the 1-count quantisation).
    """
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


def candidate_designs(ident: Identification, structure: str = "pi") -> list[Candidate]:
    """The designs to try for one motor, the one asked for (``structure``) first.

    ``"pi"``: the PI with the dead-band rule for the position integral, then the same PI with
    the integral switched the other way, then I-P; ``"ip"``: I-P, then both PI variants.
    Designs that fail :func:`tuning.autotune.verify_design` are left out (the one asked for is
    kept and flagged by the caller). The alternatives share the asked design's current loop
    and speed-loop gains (kp, ki): PI and I-P have the same loop transfer function
    (:mod:`tuning.synthesis`), so the gain search runs once.
    """
    from .autotune import synthesize, verify_design

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


def _name(d: Design) -> str:
    """Candidate name of a design: its speed-loop structure and the position integral."""
    if d.speed.structure == "ip":
        return "ip"
    return "pi + position integral" if d.speed.kii > 0.0 else "pi"


def accept(idents: Sequence[Identification], candidates: Sequence[Sequence[Candidate]],
           a_soll: Sequence[int] | int | None = None, distance: int = MOVE_DISTANCE,
           v_soll: int = MOVE_V_SOLL, seconds: float = 2.0, window: int = 10,
           seed: int = 0, default_allowed: Sequence[bool] | None = None) -> list[Acceptance]:
    """Simulate every candidate (and the default setup) on its identified motor; keep the best.

    Parameters
    ----------
    idents : sequence of Identification
        The identified motors, length N.
    candidates : sequence of sequence of Candidate
        Per motor, the designs to try (:func:`candidate_designs`), preferred first; the default
        setup is added last.
    a_soll : int or sequence of int, optional
        A_SOLL of the move per motor; default :func:`move_acceleration`.
    distance, v_soll : int
        The move [counts] and its velocity [1/16 count/sample].
    seconds : float
        Simulated time [s].
    window : int
        In-position window [counts] (INPOSWIN, 3.2.33).
    seed : int
        Noise seed of the simulation.
    default_allowed : sequence of bool, optional
        Per motor, whether the default setup may be kept (it is simulated and reported in any
        case); :func:`autotune_designs` allows it when it passes
        :func:`tuning.autotune.verify_design` on the identified motor.

    Returns
    -------
    list of Acceptance
        One per motor.
    """
    from jvl_gym import MotorArray

    n = len(idents)
    if a_soll is None:
        acc = [move_acceleration(i) for i in idents]
    else:
        acc = list(np.broadcast_to(np.asarray(a_soll, dtype=int), (n,)))
    lanes: list[tuple[int, Candidate]] = []
    for i, cands in enumerate(candidates):
        for c in [*cands, Candidate(DEFAULT_NAME, {})]:
            lanes.append((i, c))
    per_motor = [simulation_parameters(idn) for idn in idents]
    keys = per_motor[0].keys()
    params = {k: np.array([per_motor[i][k] for i, _ in lanes]) for k in keys}
    types = [idents[i].motor.name for i, _ in lanes]
    m = MotorArray(types, n=len(lanes), seed=seed, **params)
    for j, (_, c) in enumerate(lanes):
        if c.registers:
            m.load_setup({"registers": c.registers}, index=[j])
    # every candidate of a motor runs that motor's move profile
    res = _moves(m, [acc[i] for i, _ in lanes], distance, v_soll, seconds, window)
    out = []
    for i in range(n):
        js = [j for j, (k, _) in enumerate(lanes) if k == i]
        settle = {lanes[j][1].name: float(res[0][j]) for j in js}
        final = {lanes[j][1].name: float(res[1][j]) for j in js}
        ok = [q for q in range(len(js)) if default_allowed is None or default_allowed[i]
              or lanes[js[q]][1].name != DEFAULT_NAME]
        best = min(ok, key=lambda q: (res[0][js[q]], res[1][js[q]], q))
        chosen = lanes[js[best]][1]
        asked = lanes[js[0]][1].name
        d_def, d_ask = settle[DEFAULT_NAME], settle[asked]
        if chosen.name == asked:
            why = (f"kept the {asked} design: it settles in {_ms(d_ask)} on the identified motor, "
                   f"the default setup in {_ms(d_def)}")
        else:
            why = (f"kept the {chosen.name} {'' if chosen.design is None else 'design '}"
                   f"instead of the {asked} design: it settles in {_ms(settle[chosen.name])} "
                   f"on the identified motor, the {asked} design in {_ms(d_ask)}"
                   + ("" if chosen.name == DEFAULT_NAME else
                      f", the default setup in {_ms(d_def)}"))
        out.append(Acceptance(chosen, settle, final, (distance, v_soll, int(acc[i])), why))
    return out


def _ms(t: float) -> str:
    """A settle time [s] as text for the report."""
    return "never (2 s)" if not math.isfinite(t) else f"{1e3 * t:.0f} ms"


def _moves(m: Any, a_soll: list[int], distance: int, v_soll: int, seconds: float,
           window: int) -> tuple[np.ndarray, np.ndarray]:
    """Settle times [s] and final errors [counts] of one P_MODE move per lane, shape (N,)."""
    mv = position_move(m, distance, v_soll, np.asarray(a_soll), seconds=seconds, window=window)
    tail = max(1, int(round(0.2 / (seconds / mv.position.shape[0]))))
    target = np.asarray(m.read("P_SOLL"), dtype=float)
    err = np.max(np.abs(mv.position[-tail:] - target), axis=0)
    return mv.settle_s, err


def autotune_designs(idents: Sequence[Identification], structure: str = "pi",
                     a_soll: Sequence[int] | int | None = None, seed: int = 0,
                     ) -> list[Acceptance]:
    """Design the candidates of every motor and keep the best by simulation (:func:`accept`).

    The returned :class:`Acceptance` holds the kept registers (``chosen.registers``; the
    default setup's filter registers when it wins) and the reason for the report.
    """
    from .autotune import verify_design

    cands = [candidate_designs(idn, structure) for idn in idents]
    defaults = [default_design(idn) for idn in idents]
    allowed = [not verify_design(d) for d in defaults]
    res = accept(idents, cands, a_soll=a_soll, seed=seed, default_allowed=allowed)
    for r, dd in zip(res, defaults):
        if r.chosen.name == DEFAULT_NAME:
            r.chosen = Candidate(DEFAULT_NAME, dd.registers, dd)
        r.notes = [f"{k}: {_ms(v)}" for k, v in r.settle_s.items()]
        r.chosen.design.acceptance = r
    return res


def default_design(ident: Identification) -> Design:
    """The motor type's default setup as a :class:`tuning.autotune.Design`, verified on the
    identified motor: the design point of :mod:`tuning.defaults` (fixed normalised gains, PI,
    KVOUT = 1) with the registers of ``families/mac050_141/configs/setups/<TYPE>.yaml``."""
    from .autotune import synthesize
    from .defaults import DEFAULT_CURRENT_GAINS, DEFAULT_SPEED_GAINS
    from .verify import verify_current_loop, verify_speed_loop

    md = ident.motor
    d = synthesize(md, md.J_m, structure="pi", current_gains=DEFAULT_CURRENT_GAINS,
                   speed_gains=DEFAULT_SPEED_GAINS)
    regs = default_filters(md.name)
    d.registers = regs
    d.current_report = verify_current_loop(md, regs)
    d.speed_report = verify_speed_loop(md, regs, ident.mechanics.J)
    d.notes = ["the motor type's default setup (the family's configs/setups), kept by the "
               "acceptance step"]
    return d
