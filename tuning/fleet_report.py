"""The fleet report: ``fleet.csv``, ``fleet.md`` and ``fleet.png``.

``fleet.md``: a summary (motors, credible identifications, designs passing the checks, motors
settling faster than with the default setup, largest J error when the truth is known), the
table of every motor (identified J with its 95 % interval, J error, T_c, b, margins, the design
the acceptance step kept, settle times with the default setup and with the kept one) and the
list of motors whose identification is not credible, with the reasons. ``fleet.png``:
histograms of the identified KVOUT = J/J_m, T_c and b, of the J, R and L errors (where the truth
is known), of the speed- and current-loop phase margins, and the settle times kept vs default.
"""

from __future__ import annotations

import csv
import math
from pathlib import Path
from typing import Any

import numpy as np

from .fleet_spec import FleetSpec

__all__ = ["write_fleet_report", "fleet_markdown", "plot_fleet"]

_COLUMNS = ["motor", "type", "source", "credible", "reasons", "design", "checks", "J", "J_lo",
            "J_hi", "true_J", "J_err", "kvout", "coulomb", "true_coulomb", "viscous",
            "true_viscous", "R_line", "L_line", "R_err", "L_err", "testu_fit", "testa_fit",
            "current_pm", "current_gm", "speed_pm", "speed_gm", "speed_bw", "robust_pm",
            "a_soll", "settle_default_s", "settle_tuned_s", "overshoot_default",
            "overshoot_tuned", "move_model", "wall_s", "cpu_s"]


def _f(value: Any, fmt: str) -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "—"
    return f"{value:{fmt}}"


def _settle(value: float, spec: FleetSpec) -> str:
    """Settle time [ms]; ``> T`` when the move did not settle within its ``T`` ms."""
    if not math.isfinite(value):
        return f"> {1e3 * spec.move['seconds']:.0f}"
    return f"{1e3 * value:.0f}"


def fleet_markdown(spec: FleetSpec, rows: list[dict[str, Any]]) -> str:
    """The markdown report (module docstring).

    Parameters
    ----------
    spec : FleetSpec
        The fleet (source, settle-time move).
    rows : list of dict
        One row per motor (:func:`tuning.fleet_motor.tune_motor`); J in kg m^2, T_c in
        N m, b in N m s/rad, settle times in s.

    Returns
    -------
    str
        The report.
    """
    n = len(rows)
    credible = sum(bool(r.get("credible")) for r in rows)
    ok = sum(r.get("checks") == "ok" for r in rows)
    moved = [r for r in rows if "settle_tuned_s" in r]
    faster = sum(r["settle_tuned_s"] < r["settle_default_s"] for r in moved)
    errs = [abs(r["J_err"]) for r in rows if r.get("J_err") is not None]
    lines = [f"# Fleet report ({spec.source})", "",
             f"- motors: {n}; credible identifications: {credible}/{n}; designs passing the "
             f"checks: {ok}/{n}",
             f"- settle faster than the default setup: {faster}/{len(moved)} "
             f"(move of {spec.move['distance']:.0f} counts)"]
    if errs:
        lines.append(f"- J error where the truth is known: largest {100 * max(errs):.2f} %, "
                     f"rms {100 * math.sqrt(float(np.mean(np.square(errs)))):.2f} %")
    lines += ["", "| motor | J [kg m²] (95 %) | J error | T_c [N m] | b [N m s/rad] | speed PM/GM "
              "| current PM/GM | design kept | settle default → kept [ms] | credible | checks |",
              "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        if "J" not in r:
            lines.append(f"| {r['motor']} | — | — | — | — | — | — | — | — | no | "
                         f"{r.get('reasons', '')} |")
            continue
        jerr = f"{100 * r['J_err']:+.2f} %" if r.get("J_err") is not None else "—"
        spd = (f"{_f(r.get('speed_pm'), '.1f')}° / {_f(r.get('speed_gm'), '.1f')} dB"
               if "speed_pm" in r else "—")
        cur = (f"{_f(r.get('current_pm'), '.1f')}° / {_f(r.get('current_gm'), '.1f')} dB"
               if "current_pm" in r else "—")
        settle = (f"{_settle(r['settle_default_s'], spec)} → "
                  f"{_settle(r['settle_tuned_s'], spec)}" if "settle_tuned_s" in r else "—")
        lines.append(f"| {r['motor']} | {r['J']:.4g} [{r['J_lo']:.4g}, {r['J_hi']:.4g}] | "
                     f"{jerr} | {r['coulomb']:.3g} | {r['viscous']:.3g} | {spd} | {cur} | "
                     f"{r.get('design', '—')} | {settle} | "
                     f"{'yes' if r.get('credible') else 'no'} | {r.get('checks', '—')} |")
    bad = [r for r in rows if not r.get("credible")]
    lines += ["", "## Identifications that are not credible", ""]
    lines += [f"- {r['motor']}: {r.get('reasons')}" for r in bad] or ["None."]
    if any(r.get("move_model") == "identified model" for r in rows):
        lines += ["", "Settle times of recorded motors are simulated on a motor with the "
                  "identified inertia and friction."]
    return "\n".join(lines) + "\n"


def plot_fleet(rows: list[dict[str, Any]], path: str | Path) -> Path:
    """Histograms of the identified parameters, their errors, margins and settle times.

    Parameters
    ----------
    rows : list of dict
        One row per motor.
    path : path
        The PNG to write (3 x 3 panels).

    Returns
    -------
    Path
        ``path``.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    def col(key: str, scale: float = 1.0) -> np.ndarray:
        v = [scale * r[key] for r in rows if r.get(key) is not None]
        a = np.asarray(v, dtype=float)
        return a[np.isfinite(a)]

    panels = [("KVOUT = J / J_m", col("kvout")), ("Coulomb T_c [N m]", col("coulomb")),
              ("viscous b [N m s/rad]", col("viscous")), ("J error [%]", col("J_err", 100)),
              ("R error [%]", col("R_err", 100)), ("L error [%]", col("L_err", 100)),
              ("speed-loop PM [deg]", col("speed_pm")), ("current-loop PM [deg]",
                                                          col("current_pm"))]
    fig, axes = plt.subplots(3, 3, figsize=(11, 8.5))
    for ax, (title, data) in zip(axes.flat, panels):
        if data.size:
            ax.hist(data, bins=min(20, max(5, data.size)), color="tab:blue", alpha=0.8)
        else:
            ax.text(0.5, 0.5, "truth unknown", ha="center", va="center",
                    transform=ax.transAxes)
        ax.set_title(title, fontsize=9)
    ax = axes.flat[-1]
    moved = [r for r in rows if "settle_tuned_s" in r]
    cap = max([r["settle_default_s"] for r in moved if math.isfinite(r["settle_default_s"])]
              + [r["settle_tuned_s"] for r in moved if math.isfinite(r["settle_tuned_s"])]
              + [0.1])
    edge = 1.1 * cap * 1e3  # where a motor that did not settle is drawn, beyond every time
    sd = np.array([r["settle_default_s"] for r in moved]) * 1e3
    st = np.array([r["settle_tuned_s"] for r in moved]) * 1e3
    settled = np.isfinite(sd) & np.isfinite(st)
    colors = np.array(["tab:green" if r.get("credible") else "tab:red" for r in moved])
    ax.scatter(sd[settled], st[settled], c=colors[settled].tolist(), label="settled")
    if not settled.all():
        ax.scatter(np.where(np.isfinite(sd), sd, edge)[~settled],
                   np.where(np.isfinite(st), st, edge)[~settled], c=colors[~settled].tolist(),
                   marker="x", label="did not settle (drawn on the dotted edge)")
        for line in (ax.axvline, ax.axhline):
            line(edge, color="0.5", lw=0.8, ls=":")
    lim = 1.15 * cap * 1e3
    ax.plot([0, lim], [0, lim], "k--", lw=0.8)
    ax.set_xlabel("settle, default setup [ms]")
    ax.set_ylabel("settle, designed [ms]")
    if moved:
        ax.legend(fontsize=7, loc="lower right")
    ax.set_title("settle times (red: not credible; x: did not\nsettle within the move)",
                 fontsize=8)
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def write_fleet_report(spec: FleetSpec, rows: list[dict[str, Any]], out: str | Path
                       ) -> list[Path]:
    """Write ``fleet.csv``, ``fleet.md`` and ``fleet.png`` into ``out``; returns the paths."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    csv_path = out / "fleet.csv"
    with csv_path.open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=_COLUMNS, extrasaction="ignore")
        w.writeheader()
        for r in rows:
            w.writerow({k: r.get(k, "") for k in _COLUMNS})
    md = out / "fleet.md"
    md.write_text(fleet_markdown(spec, rows))
    return [csv_path, md, plot_fleet(rows, out / "fleet.png")]
