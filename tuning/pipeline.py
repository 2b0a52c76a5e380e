"""The tuning pipeline, one for every family: identify → design → quantise → verify → accept →
write (docs/tuning.md, "Pipeline").

What differs between families — how a motor is identified, which filter is designed and how it
is quantised and verified — is the family's :class:`tuning.strategy.Strategy`. What is the same
is here:

* the *acceptance step* (:func:`accept`): every candidate the strategy designed and the motor
  type's default setup run the same move (the servo families: a position-mode move, mode 2,
  :func:`position_trial`) on a ``MotorArray`` built from the *identified* motor (the
  strategy's :meth:`~tuning.strategy.Strategy.simulation_motor`). A design with good margins
  can still position worse than the default setup (with Coulomb friction a PI speed loop is a
  PD position loop that stops anywhere within its friction dead band), so the candidate that
  settles first in the in-position window (INPOSWIN; MAC050–141 manual 3.2.33, MAC800
  register 33) wins; ties and moves that never settle are decided by the final position
  error, then by the strategy's order (the design asked for first). The default setup may be
  kept only when it passes the strategy's checks on the identified motor. The reason goes
  into the report;
* the setup file (:func:`setup_text`, :func:`write_setup`): the family's ``configs/setups``
  format, values typed by the register table (fixed-point formats as floats, integer formats as
  integers).
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import yaml

from jvl_gym.families import family_of_motor
from jvl_gym.motor.noise import motor_keys
from jvl_gym.registers import Format

from .trial_types import DEFAULT_NAME, Candidate, Move, Result
from .verify import position_move

if TYPE_CHECKING:  # pragma: no cover
    from .strategy import Strategy

__all__ = ["DEFAULT_NAME", "Candidate", "Move", "Result", "Progress", "position_trial", "accept",
           "design_and_accept", "autotune", "settle_text", "setup_text", "write_setup"]

_FIXED = (Format.FIXED4, Format.FIXED8, Format.FIXED16, Format.FIXED24)

Progress = Callable[[str], None]


def _quiet(_: str) -> None:
    return None


def position_trial(m: Any, move: Move) -> tuple[np.ndarray, np.ndarray]:
    """Run ``move`` as a position-mode move (mode 2, :func:`tuning.verify.position_move`) on
    every motor of ``m``; settle times [s] (inf: never) and the largest |P_IST − P_SOLL| over
    the last 0.2 s [counts], shape (N,) each."""
    dt = 1.0 / m.OUTER_HZ
    res = position_move(m, move.distance, move.v_soll, move.a_soll, seconds=move.seconds,
                        window=move.window, dt=dt)
    tail = max(1, int(round(0.2 / dt)))
    target = np.asarray(m.read("P_SOLL"), dtype=float)
    return res.settle_s, np.max(np.abs(res.position[-tail:] - target), axis=0)


def settle_text(t: float, seconds: float = 2.0) -> str:
    """A settle time [s] of a move simulated for ``seconds`` as text for the report."""
    return f"never ({seconds:g} s)" if not math.isfinite(t) else f"{1e3 * t:.0f} ms"


def _reason(chosen: Candidate, asked: str, settle: Mapping[str, float], seconds: float) -> str:
    """Why ``chosen`` was kept, one line (``seconds``: how long the move was simulated)."""
    when = {name: settle_text(t, seconds) for name, t in settle.items()}
    if chosen.name == asked:
        return (f"kept the {asked} design: it settles in {when[asked]} on the identified motor, "
                f"the default setup in {when[DEFAULT_NAME]}")
    return (f"kept the {chosen.name}{'' if chosen.name == DEFAULT_NAME else ' design'} instead "
            f"of the {asked} design: it settles in {when[chosen.name]} on the identified motor, "
            f"the {asked} design in {when[asked]}"
            + ("" if chosen.name == DEFAULT_NAME else
               f", the default setup in {when[DEFAULT_NAME]}"))


def accept(strategy: Strategy, idents: Sequence[Any], candidates: Sequence[Sequence[Candidate]],
           defaults: Sequence[Candidate], seed: int = 0,
           default_allowed: Sequence[bool] | None = None) -> list[Result]:
    """Simulate every candidate and the default setup on its identified motor; keep the best
    (module docstring).

    Parameters
    ----------
    strategy : Strategy
        Gives the identified motor (:meth:`~tuning.strategy.Strategy.simulation_motor`), the
        move (:meth:`~tuning.strategy.Strategy.move`) and runs it
        (:meth:`~tuning.strategy.Strategy.trial`).
    idents : sequence
        The identified motors, length N.
    candidates : sequence of sequence of Candidate
        Per motor, the designs to try, preferred first.
    defaults : sequence of Candidate
        Per motor, the default setup (:data:`DEFAULT_NAME`), simulated last.
    seed : int
        Noise seed of the simulation.
    default_allowed : sequence of bool, optional
        Per motor, whether the default setup may be kept (it is simulated and reported in any
        case); default: everywhere.

    Returns
    -------
    list of Result
        One per motor.
    """
    from jvl_gym import MotorArray

    lanes = [(i, c) for i, cands in enumerate(candidates) for c in [*cands, defaults[i]]]
    keys = motor_keys(seed, len(lanes))  # a lane's noise as in one array of every lane
    settle = np.empty(len(lanes))
    err = np.empty(len(lanes))
    moves = [strategy.move(idn) for idn in idents]
    for i, ident in enumerate(idents):
        js = [j for j, (k, _) in enumerate(lanes) if k == i]
        motor, params = strategy.simulation_motor(ident)
        m = MotorArray(motor, n=len(js), seed=keys[js], **params)
        for q, j in enumerate(js):
            if lanes[j][1].registers:
                m.load_setup({"registers": lanes[j][1].registers}, index=[q])
        settle[js], err[js] = strategy.trial(m, moves[i])
    out = []
    for i, ident in enumerate(idents):
        js = [j for j, (k, _) in enumerate(lanes) if k == i]
        names = [lanes[j][1].name for j in js]
        times = {n: float(settle[j]) for n, j in zip(names, js)}
        final = {n: float(err[j]) for n, j in zip(names, js)}
        ok = [q for q in range(len(js)) if default_allowed is None or default_allowed[i]
              or names[q] != DEFAULT_NAME]
        best = min(ok, key=lambda q: (settle[js[q]], err[js[q]], q))
        chosen = lanes[js[best]][1]
        out.append(Result(ident, chosen, times, final, moves[i],
                          _reason(chosen, names[0], times, moves[i].seconds),
                          [lanes[j][1] for j in js]))
    return out


def design_and_accept(strategy: Strategy, idents: Sequence[Any],
                      settings: Mapping[str, Any] | None = None, seed: int = 0
                      ) -> list[Result]:
    """Design, quantise and verify the strategy's candidates for every identified motor, and
    keep the best by simulation (:func:`accept`; the default setup only where it passes the
    strategy's checks)."""
    settings = dict(settings or {})
    cands = [strategy.candidates(idn, settings) for idn in idents]
    defaults = [strategy.default_candidate(idn) for idn in idents]
    allowed = [not strategy.failures(d) for d in defaults]
    return accept(strategy, idents, cands, defaults, seed=seed, default_allowed=allowed)


def autotune(m: Any, strategy: Strategy, settings: Mapping[str, Any] | None = None,
             seed: int = 0, progress: Progress = _quiet) -> list[Result]:
    """Identify every motor of ``m`` and keep the best of the strategy's candidates
    (:func:`design_and_accept`).

    Parameters
    ----------
    m : MotorArray or compatible
        The motors, at rest in the mode the strategy starts from.
    strategy : Strategy
        The family's strategy (:func:`tuning.strategy.strategy_of`).
    settings : mapping, optional
        Strategy options by name (:attr:`tuning.strategy.Strategy.options`).
    seed : int
        Noise seed of the acceptance step's simulation.
    progress : callable
        Receives one line of text per stage.
    """
    idents = strategy.identify(m, dict(settings or {}), progress)
    progress("synthesis, quantisation, verification and the acceptance step (candidates "
             "simulated on the identified motor)")
    return design_and_accept(strategy, idents, settings, seed)


def setup_text(motor_type: str, regs: Mapping[str, float], note: str) -> str:
    """A setup file of the motor type's family (``configs/setups`` format: motor, provenance,
    registers) with ``note`` as its header; fixed-point registers as floats, the others as
    integers (the family's register table)."""
    table = family_of_motor(motor_type).table
    clean = {k: (float(v) if k not in table or table.lookup(k).format in _FIXED else int(v))
             for k, v in regs.items()}
    text = "".join(f"# {ln}\n" for ln in note.splitlines())
    return text + yaml.safe_dump({"motor": motor_type, "provenance": "jvl-tune",
                                  "registers": clean}, sort_keys=False)


def write_setup(path: str | os.PathLike[str], motor_type: str, regs: Mapping[str, float],
                note: str) -> Path:
    """Write :func:`setup_text` to ``path`` (its folder created)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(setup_text(motor_type, regs, note))
    return path
