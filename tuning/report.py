"""Autotune report: PNG plots (matplotlib, Agg backend) and a plain-text table.

Plots: the TESTU and TESTA fits (measured vs model), Bode plots of the current and speed open
loops, closed-loop step responses (model) and, when given, the simulated step responses.
The table lists the identified values with their 95 % intervals, the margins, bandwidths,
pole radii and the robustness results.
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import control as ct  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from .autotune import Design, Identification  # noqa: E402
from .models import (  # noqa: E402
    current_open_loop,
    freqresp,
    speed_closed_loop,
    speed_open_loop,
    speed_plant,
)
from .verify import frequency_grid, loop_metrics  # noqa: E402

__all__ = ["text_table", "plot_fits", "plot_bode", "plot_steps", "write_report", "bode_figure",
           "two_mass_bode_figure", "steps_figure"]


def _ci(ci: tuple[float, float], scale: float = 1.0, fmt: str = ".4g") -> str:
    return f"[{ci[0] * scale:{fmt}}, {ci[1] * scale:{fmt}}]"


def text_table(ident: Identification | None, design: Design,
               truth: dict[str, float] | None = None) -> str:
    """Identified values (with 95 % intervals and, if known, the true values) and the design's
    margins, bandwidths and robustness as a fixed-width text table."""
    lines = []
    if ident is not None:
        c, m = ident.coil, ident.mechanics
        lines += ["Identified values (95 % confidence intervals)",
                  f"{'quantity':<24}{'estimate':>14}  {'95 % interval':<30}{'true':>12}"]
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
        for name, val, ci, key in rows:
            tv = "" if not truth or key not in truth else f"{truth[key]:.4g}"
            flag = ""
            if key in ("viscous", "coulomb", "J") and not m.detected.get(key, True):
                flag = "  not detected (interval reaches 0)"
            lines.append(f"{name:<24}{val:>14.5g}  {_ci(ci):<30}{tv:>12}{flag}")
        lines.append(f"TESTU fit {c.nrmse_fit:.2f} % NRMSE, residual white: "
                     f"{c.residual['white']} (Box-Pierce p = {c.residual['box_pierce_p']:.2f}); "
                     f"TESTA fit {m.nrmse_fit:.2f} %, residual white: {m.residual['white']}")
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
        lines.append("")
    cr, sr = design.current_report, design.speed_report
    lines += ["Loop verification (quantised registers)",
              f"{'loop':<34}{'PM deg':>8}{'GM dB':>8}{'BW Hz':>9}{'|z|max':>8}{'stable':>8}"]

    lines.append("(BW: the −3 dB bandwidth of the closed loop L/(1+L); bode.png marks it and the "
                 "open loop's gain crossover, |L| = 0 dB)")

    def row(name: str, mt: Any) -> str:
        return (f"{name:<34}{mt.pm_deg:>8.1f}{mt.gm_db:>8.1f}{mt.bandwidth_hz:>9.1f}"
                f"{mt.pole_radius:>8.3f}{mt.stable!s:>8}")

    lines.append(row("current, nominal", cr.nominal))
    for k, mt in cr.robust.items():
        lines.append(row(f"current, {k}", mt))
    lines.append(row("speed, nominal", sr.nominal))
    for k, mt in sr.robust.items():
        lines.append(row(f"speed, {k}", mt))
    lines.append(f"speed reference bandwidth {sr.reference_bandwidth_hz:.1f} Hz, "
                 f"step overshoot {100 * sr.step_overshoot:.1f} %")
    lines.append("quantisation changes: " + ", ".join(
        f"{k} {v:+.3f}" for k, v in design.quantization_delta.items()))
    g = design.guidance
    lines.append(f"T_SOLL guidance: T_SOLL {g['T_SOLL']:.0f} = {g['torque_Nm']:.3f} N m; profiles "
                 f"up to A_SOLL {g['A_SOLL_max']:.0f} keep half of it for regulation")
    for n in design.notes:
        lines.append(f"note: {n}")
    acc = getattr(design, "acceptance", None)
    if acc is not None:
        dist, vs, a = acc.move
        lines += ["", f"Acceptance step (P_MODE move of {dist} counts, V_SOLL {vs}, A_SOLL {a}, "
                  "simulated on the identified motor; settle = within INPOSWIN for good)"]
        lines += [f"  {k:<26}{_settle(v)}" for k, v in acc.settle_s.items()]
        lines.append(f"  {acc.reason}")
    return "\n".join(lines) + "\n"


def _settle(t: float) -> str:
    return "never within 2 s" if not math.isfinite(t) else f"settles in {1e3 * t:.0f} ms"


def plot_fits(ident: Identification, path: str | os.PathLike[str]) -> Path:
    """TESTU and TESTA records with the fitted model outputs."""
    fig, ax = plt.subplots(1, 2, figsize=(10, 3.8))
    r = next(rec for rec in ident.records if rec.kind == "TESTU")
    k = np.arange(r.n)
    ax[0].plot(k, r.output, "o", ms=3, label="IC_IST measured")
    ax[0].plot(k, ident.coil.fitted[0], "-", label=f"model, d = {ident.coil.delay}")
    ax[0].set(xlabel="inner sample (128 us)", ylabel="ADC counts", title="TESTU fit")
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
    ax[1].set(xlabel="outer sample (1.92 ms)", ylabel="counts/sample", title="TESTA fit")
    ax[1].legend()
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return Path(path)


def _phase_crossing_hz(f: np.ndarray, mag_db: np.ndarray, phase_deg: np.ndarray) -> float:
    """Lowest frequency where the phase falls through −180° (mod 360°) with |L| < 1, or nan."""
    wrapped = (phase_deg + 180.0) % 360.0 - 180.0  # −180 … 180, −180° crossings are jumps
    for k in range(1, f.size):
        if wrapped[k] - wrapped[k - 1] > 180.0 and mag_db[k] < 0:
            return float(f[k])
    return math.nan


def bode_figure(design: Design, motor: Any, J_total: float) -> Any:
    """Bode plots of the current and speed open loops with their gain crossover (and the phase
    margin there) and their −180° crossing (and the gain margin there) marked."""
    fig, ax = plt.subplots(2, 2, figsize=(10, 6), sharex="col")
    loops = [("current loop", current_open_loop(motor, design.registers)),
             ("speed loop", speed_open_loop(speed_plant(motor, design.registers, J_total),
                                            design.registers))]
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
        lp = speed_open_loop(plant, regs)
        w = frequency_grid(lp.dt, 1500, lowest=1e-3)
        resp = freqresp(lp, w)
        f = w / (2 * math.pi)
        mag = 20 * np.log10(np.abs(resp))
        phase = np.degrees(np.unwrap(np.angle(resp)))
        m = loop_metrics(plant, regs)
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
    marks = [(f_res, "resonance"), (alias_hz(f_res), "resonance alias")]
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


def plot_bode(design: Design, motor: Any, J_total: float, path: str | os.PathLike[str]
              ) -> Path:
    """Bode plots of the current and speed open loops (:func:`bode_figure`) as a PNG."""
    fig = bode_figure(design, motor, J_total)
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return Path(path)


def steps_figure(design: Design, motor: Any, J_total: float,
                 simulated: np.ndarray | None = None, v_step: float | None = None) -> Any:
    """Closed-loop speed step response of the model and, optionally, of the simulator
    (V_IST over the V_SOLL step), both as a fraction of the commanded speed."""
    cl = speed_closed_loop(speed_plant(motor, design.registers, J_total), design.registers)
    n = 150
    t, y = ct.step_response(cl, T=np.arange(n) * cl.dt)
    fig, ax = plt.subplots(figsize=(6, 3.8))
    ax.plot(np.arange(n), np.squeeze(y), label="model")
    if simulated is not None and v_step:
        ax.plot(np.arange(simulated.shape[0]), 16 * simulated / v_step, ".", ms=3,
                label=f"MotorArray V_MODE step (V_SOLL {v_step:g})")
    ax.axhline(1.0, color="k", lw=0.5)
    ax.set(xlabel="outer sample (1.92 ms)", ylabel="speed / commanded speed",
           title="speed step")
    ax.legend(loc="lower right")
    fig.tight_layout()
    return fig


def plot_steps(design: Design, motor: Any, J_total: float, path: str | os.PathLike[str],
               simulated: np.ndarray | None = None, v_step: float | None = None) -> Path:
    """The speed step responses (:func:`steps_figure`) as a PNG."""
    fig = steps_figure(design, motor, J_total, simulated, v_step)
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return Path(path)


def write_report(out: str | os.PathLike[str], ident: Identification | None, design: Design,
                 motor: Any, J_total: float, truth: dict[str, float] | None = None,
                 simulated: np.ndarray | None = None, v_step: float | None = None
                 ) -> list[Path]:
    """Write ``report.txt`` and the PNG plots into directory ``out``."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    files = [out / "report.txt"]
    files[0].write_text(text_table(ident, design, truth))
    if ident is not None:
        files.append(plot_fits(ident, out / "fits.png"))
    files.append(plot_bode(design, motor, J_total, out / "bode.png"))
    files.append(plot_steps(design, motor, J_total, out / "steps.png", simulated, v_step))
    return files
