"""The autotune report, one layout for every family: a plain-text table and PNG plots
(matplotlib, Agg backend).

``report.txt``: the identified values with their 95 % intervals (and the simulated truth when
known), the loop verification of the kept registers (margins, bandwidths, pole radii, the
robustness set) with the strategy's further lines, and the acceptance step's settle times and
reason. Plots: ``fits.png`` (the identification's records with the fitted model, the
strategy's :meth:`~tuning.strategy.Strategy.fit_figure`), ``bode.png`` (the current and speed
open loops), ``steps.png`` (the speed step response of the model and, when given, of the
simulator).
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import matplotlib

matplotlib.use("Agg")
import control as ct  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from .models import freqresp, speed_open_loop  # noqa: E402
from .pipeline import Candidate, Result  # noqa: E402
from .verify import frequency_grid, loop_metrics  # noqa: E402

if TYPE_CHECKING:  # pragma: no cover
    from .strategy import Strategy

__all__ = ["identification_table", "design_table", "acceptance_lines", "report_text",
           "bode_figure", "two_mass_bode_figure", "steps_figure", "write_report"]


def _ci(ci: tuple[float, float] | None) -> str:
    return "" if ci is None else f"[{ci[0]:.4g}, {ci[1]:.4g}]"


def identification_table(strategy: Strategy, ident: Any,
                         truth: Mapping[str, float] | None = None) -> list[str]:
    """The identified values (the strategy's rows) with their 95 % intervals and, where
    known, the true values, then the strategy's lines on the fits and the intervals."""
    lines = ["Identified values (95 % confidence intervals)",
             f"{'quantity':<24}{'estimate':>14}  {'95 % interval':<30}{'true':>12}"]
    for name, val, ci, key, flag in strategy.identified_rows(ident):
        tv = "" if not truth or key not in truth else f"{truth[key]:.4g}"
        lines.append(f"{name:<24}{val:>14.5g}  {_ci(ci):<30}{tv:>12}{flag}")
    return lines + strategy.identification_lines(ident)


def design_table(strategy: Strategy, candidate: Candidate, motor: Any, J: float) -> list[str]:
    """The loop verification of a candidate's registers on ``motor`` with total inertia ``J``
    [kg·m²] (the strategy's rows and lines)."""
    lines = ["Loop verification (quantised registers)",
             f"{'loop':<34}{'PM deg':>8}{'GM dB':>8}{'BW Hz':>9}{'|z|max':>8}{'stable':>8}"]
    for name, mt in strategy.loop_rows(candidate, motor, J):
        lines.append(f"{name:<34}{mt.pm_deg:>8.1f}{mt.gm_db:>8.1f}{mt.bandwidth_hz:>9.1f}"
                     f"{mt.pole_radius:>8.3f}{mt.stable!s:>8}")
    lines.append("(BW: the −3 dB bandwidth of the closed loop L/(1+L); bode.png marks it and the "
                 "open loop's gain crossover, |L| = 0 dB)")
    return lines + strategy.design_lines(candidate, motor, J)


def acceptance_lines(result: Result) -> list[str]:
    """The acceptance step: the move, every candidate's settle time and final error, the
    reason for the kept one."""
    mv = result.move
    lines = [f"Acceptance step ({mv.describe()}, simulated on the identified motor; settle = "
             "within the in-position window for good)"]
    for k, t in result.settle_s.items():
        when = f"never within {mv.seconds:g} s" if not math.isfinite(t) else \
            f"settles in {1e3 * t:.0f} ms"
        lines.append(f"  {k:<26}{when}, final error {result.final_error[k]:.0f} counts")
    return [*lines, f"  {result.reason}"]


def report_text(strategy: Strategy, result: Result,
                truth: Mapping[str, float] | None = None) -> str:
    """The text of ``report.txt`` (module docstring)."""
    ident = result.ident
    lines = [*identification_table(strategy, ident, truth), "",
             *design_table(strategy, result.chosen, ident.motor, ident.mechanics.J), "",
             *acceptance_lines(result)]
    return "\n".join(lines) + "\n"


def _phase_crossing_hz(f: np.ndarray, mag_db: np.ndarray, phase_deg: np.ndarray) -> float:
    """Lowest frequency where the phase falls through −180° (mod 360°) with |L| < 1, or nan."""
    wrapped = (phase_deg + 180.0) % 360.0 - 180.0  # −180 … 180, −180° crossings are jumps
    for k in range(1, f.size):
        if wrapped[k] - wrapped[k - 1] > 180.0 and mag_db[k] < 0:
            return float(f[k])
    return math.nan


def bode_figure(loops: Sequence[tuple[str, Any]]) -> Any:
    """Bode plots of the open loops ``loops`` (``(name, discrete transfer function)``, one
    column each) with their gain crossover (and the phase margin there) and their −180°
    crossing (and the gain margin there) marked."""
    fig, ax = plt.subplots(2, len(loops), figsize=(5 * len(loops), 6), sharex="col",
                           squeeze=False)
    for j, (name, lp) in enumerate(loops):
        w = frequency_grid(lp.dt, 800, lowest=1e-3)
        resp = freqresp(lp, w)
        f = w / (2 * math.pi)
        mag = 20 * np.log10(np.abs(resp))
        phase = np.degrees(np.unwrap(np.angle(resp)))
        ax[0, j].semilogx(f, mag)
        ax[0, j].axhline(0, color="k", lw=0.5)
        ax[0, j].set(title=name, ylabel="|L| dB")
        ax[1, j].semilogx(f, phase)
        ax[1, j].axhline(-180, color="k", lw=0.5)
        ax[1, j].set(xlabel="Hz", ylabel="phase deg")
        m = loop_metrics(lp)
        if math.isfinite(m.crossover_hz) and math.isfinite(m.pm_deg):
            fc = m.crossover_hz
            p_c = float(np.interp(math.log(fc), np.log(f), phase))
            for a in ax[:, j]:
                a.axvline(fc, color="C3", lw=0.8, ls=":",
                          label=f"open-loop gain crossover {fc:.3g} Hz (|L| = 0 dB)")
            if math.isfinite(m.bandwidth_hz):
                ax[0, j].axvline(m.bandwidth_hz, color="C1", lw=0.8, ls="--",
                                 label=f"closed-loop BW {m.bandwidth_hz:.3g} Hz (report's BW:"
                                 " −3 dB of L/(1+L))")
            ax[1, j].vlines(fc, p_c - m.pm_deg, p_c, color="C3", lw=2)
            ax[1, j].annotate(f"PM {m.pm_deg:.1f}°", (fc, p_c), xytext=(4, 4),
                              textcoords="offset points", color="C3", fontsize=8)
            ax[0, j].legend(loc="lower left", fontsize=8)
        f180 = _phase_crossing_hz(f, mag, phase)
        if math.isfinite(f180) and math.isfinite(m.gm_db):
            ax[0, j].vlines(f180, -m.gm_db, 0, color="C2", lw=2)
            ax[0, j].annotate(f"GM {m.gm_db:.1f} dB", (f180, -m.gm_db), xytext=(4, -10),
                              textcoords="offset points", color="C2", fontsize=8)
    fig.tight_layout()
    return fig


def two_mass_bode_figure(motor: Any, loops: Sequence[tuple[str, Mapping[str, float]]],
                        coupling: tuple[float, float, float], f_res: float,
                        f_anti: float | None = None) -> Any:
    """Bode plots of speed open loops on a two-mass plant (:mod:`tuning.resonance_design`):
    one curve per ``(name, registers)`` of ``loops`` with its gain crossover, phase margin and
    gain margin marked, and the resonance ``f_res`` [Hz] (with its alias at the outer rate
    when above 260 Hz) and anti-resonance ``f_anti`` marked. ``coupling = (J_l, k, d)``."""
    from .resonance_design import alias_hz, loop_metrics, two_mass_plant

    fig, ax = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
    for q, (name, regs) in enumerate(loops):
        plant = two_mass_plant(motor, regs, tuple(coupling))
        lp = speed_open_loop(plant, regs, motor.family)
        w = frequency_grid(lp.dt, 1500, lowest=1e-3)
        resp = freqresp(lp, w)
        f = w / (2 * math.pi)
        mag = 20 * np.log10(np.abs(resp))
        phase = np.degrees(np.unwrap(np.angle(resp)))
        m = loop_metrics(plant, regs, motor.family)
        color = f"C{q}"
        ax[0].semilogx(f, mag, color=color,
                       label=f"{name}: PM {m.pm_deg:.0f}°, GM {m.gm_db:.1f} dB")
        ax[1].semilogx(f, phase, color=color)
        if math.isfinite(m.crossover_hz):
            fc = m.crossover_hz
            p_c = float(np.interp(math.log(fc), np.log(f), phase))
            ax[0].plot([fc], [0.0], "o", color=color, ms=4)
            ax[1].vlines(fc, p_c - m.pm_deg, p_c, color=color, lw=2)
            ax[1].annotate(f"PM {m.pm_deg:.0f}°", (fc, p_c), xytext=(4, 4),
                           textcoords="offset points", color=color, fontsize=8)
        f180 = _phase_crossing_hz(f, mag, phase)
        if math.isfinite(f180) and math.isfinite(m.gm_db):
            ax[0].vlines(f180, -m.gm_db, 0, color=color, lw=2)
    marks = [(f_res, "resonance"), (alias_hz(f_res, 1.0 / motor.family.outer_dt),
                                     "resonance alias")]
    if f_anti is not None:
        marks.append((f_anti, "anti-resonance"))
    for k, (fm, label) in enumerate(marks):
        if label == "resonance alias" and abs(fm - f_res) < 1e-9:
            continue
        for a in ax:
            a.axvline(fm, color="k", lw=0.8, ls=("--", ":", "-.")[k],
                      label=f"{label} {fm:.0f} Hz" if a is ax[1] else None)
    ax[0].axhline(0, color="k", lw=0.5)
    ax[1].axhline(-180, color="k", lw=0.5)
    ax[0].set(title="speed loop on the two-mass plant", ylabel="|L| dB")
    ax[1].set(xlabel="Hz", ylabel="phase deg")
    ax[0].legend(loc="lower left", fontsize=7)
    ax[1].legend(loc="lower left", fontsize=7)
    fig.tight_layout()
    return fig


def steps_figure(cl: Any, simulated: np.ndarray | None = None,
                 v_step: float | None = None) -> Any:
    """The step response of the closed speed loop ``cl`` (a discrete transfer function,
    reference → speed as a fraction of the reference) and, optionally, the simulator's
    (``simulated``: speed per servo sample over the step's reference ``v_step``, both in the
    reference's unit), both as a fraction of the commanded speed."""
    n = 150
    t, y = ct.step_response(cl, T=np.arange(n) * cl.dt)
    fig, ax = plt.subplots(figsize=(6, 3.8))
    ax.plot(np.arange(n), np.squeeze(y), label="model")
    if simulated is not None and v_step:
        ax.plot(np.arange(simulated.shape[0]), simulated / v_step, ".", ms=3,
                label=f"MotorArray speed step (V_SOLL {v_step:g})")
    ax.axhline(1.0, color="k", lw=0.5)
    ax.set(xlabel=f"outer sample ({1e3 * cl.dt:.2f} ms)", ylabel="speed / commanded speed",
           title="speed step")
    ax.legend(loc="lower right")
    fig.tight_layout()
    return fig


def _save(fig: Any, path: Path) -> Path:
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def write_report(out: str | os.PathLike[str], strategy: Strategy, result: Result,
                 truth: Mapping[str, float] | None = None, simulated: np.ndarray | None = None,
                 v_step: float | None = None) -> list[Path]:
    """Write ``report.txt`` (:func:`report_text`), ``fits.png``, ``bode.png`` and
    ``steps.png`` of ``result`` into directory ``out``; ``simulated``, ``v_step``: a simulated
    speed step with the kept registers (:meth:`~tuning.strategy.Strategy.speed_step`)."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    ident, chosen = result.ident, result.chosen
    md, J = ident.motor, ident.mechanics.J
    text = out / "report.txt"
    text.write_text(report_text(strategy, result, truth))
    steps = steps_figure(strategy.step_loop(chosen, md, J), simulated, v_step)
    return [text, _save(strategy.fit_figure(ident), out / "fits.png"),
            _save(bode_figure(strategy.open_loops(chosen, md, J)), out / "bode.png"),
            _save(steps, out / "steps.png")]
