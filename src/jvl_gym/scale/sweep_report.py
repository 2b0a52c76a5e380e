"""Results of a sweep: ``results.csv``, ``results.md`` and ``learning_curves.png``.

One row per finished trial: trial id, its parameters, the training seed, the policy's and the
baseline's return (mean ± std over the held-out seeds, as ``jvl-gym evaluate`` reports them),
the seeds won by the policy, the env steps trained and the wall time (training + evaluation).
The plot shows each trial's learning curve: the mean reward per env-step of each rollout (top)
and SB3's mean episode return (bottom, once episodes have ended) against env steps.
"""

from __future__ import annotations

import csv
import math
from pathlib import Path
from typing import Any

from .sweep_spec import SweepSpec

__all__ = ["write_results", "markdown_table", "plot_curves", "fmt_params"]


def fmt_params(params: dict[str, Any]) -> str:
    """``learning_rate=0.0003 n_epochs=5``: dotted keys shortened to their last part.

    Parameters
    ----------
    params : dict
        Dotted key -> value.

    Returns
    -------
    str
        Space-separated ``name=value`` pairs (floats with 3 significant digits).
    """
    parts = []
    for key, value in params.items():
        name = key.split(".")[-1]
        text = f"{value:.3g}" if isinstance(value, float) else str(value)
        parts.append(f"{name}={text}".replace(" ", ""))
    return " ".join(parts)


def _param_keys(rows: list[dict[str, Any]]) -> list[str]:
    keys: list[str] = []
    for r in rows:
        keys += [k for k in r["params"] if k not in keys]
    return keys


def _num(value: Any, fmt: str = ".2f") -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "—"
    return f"{value:{fmt}}"


def markdown_table(rows: list[dict[str, Any]]) -> str:
    """The results table in markdown (one row per trial).

    Parameters
    ----------
    rows : list of dict
        Ledger entries (``trial_id``, ``params``, ``seed``, ``metrics``), in trial order.

    Returns
    -------
    str
        Header, separator and one line per trial; returns are the env's reward units, wall
        time in seconds.
    """
    lines = ["| trial | parameters | seed | policy | baseline | better | seeds won | steps | "
             "wall time [s] |", "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        m = r["metrics"]
        better = "policy" if m["policy_mean"] > m["baseline_mean"] else "baseline"
        lines.append(
            f"| {r['trial_id']} | {fmt_params(r['params']) or '—'} | {r['seed']} | "
            f"{_num(m['policy_mean'])} ± {_num(m['policy_std'])} | "
            f"{_num(m['baseline_mean'])} ± {_num(m['baseline_std'])} | {better} | "
            f"{m['seeds_won']}/{m['n_seeds']} | {int(m['timesteps'])} | {m['wall_s']:.0f} |")
    return "\n".join(lines)


def plot_curves(rows: list[dict[str, Any]], path: str | Path, title: str = "") -> Path:
    """Learning curves of every trial (module docstring) as a PNG.

    Parameters
    ----------
    rows : list of dict
        Ledger entries; ``curve`` holds ``[env steps, reward per env-step, mean episode
        return]`` points.
    path : path
        The PNG to write.
    title : str
        Figure title.

    Returns
    -------
    Path
        ``path``.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (top, bottom) = plt.subplots(2, 1, figsize=(8, 6.5), sharex=True)
    for r in rows:
        curve = [p for p in r.get("curve", []) if p and p[0] is not None]
        label = f"{r['trial_id'].split('-')[0]} {fmt_params(r['params'])} s{r['seed']}"
        x = [p[0] for p in curve]
        top.plot(x, [p[1] for p in curve], marker=".", label=label)
        y = [math.nan if p[2] is None else p[2] for p in curve]
        bottom.plot(x, y, marker=".", label=label)
    top.set_ylabel("reward per env-step (rollout mean)")
    bottom.set_ylabel("episode return (SB3 mean)")
    bottom.set_xlabel("env steps")
    top.set_title(title)
    top.grid(True, alpha=0.3)
    bottom.grid(True, alpha=0.3)
    top.legend(fontsize=7)
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def write_results(spec: SweepSpec, rows: list[dict[str, Any]], out: str | Path) -> list[Path]:
    """Write ``results.csv``, ``results.md`` and ``learning_curves.png`` into ``out``.

    Parameters
    ----------
    spec : SweepSpec
        The sweep (for the title).
    rows : list of dict
        Ledger entries (:class:`jvl_gym.scale.ledger.Ledger`), in trial order.
    out : path
        Output directory.

    Returns
    -------
    list of Path
        The three files.
    """
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    keys = _param_keys(rows)
    metrics = ["policy_mean", "policy_std", "baseline_mean", "baseline_std", "seeds_won",
               "n_seeds", "timesteps", "train_s", "eval_s", "wall_s", "cpu_s", "env_steps_per_s"]
    csv_path = out / "results.csv"
    with csv_path.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["trial", *keys, "seed", *metrics])
        for r in rows:
            w.writerow([r["trial_id"], *(r["params"].get(k, "") for k in keys), r["seed"],
                        *(r["metrics"].get(m, "") for m in metrics)])
    md_path = out / "results.md"
    src = f" ({spec.path})" if spec.path is not None else ""
    md_path.write_text(f"# Sweep {spec.env}{src}\n\n{spec.search} search, {spec.timesteps} "
                       f"env steps per trial, evaluated on {spec.eval_seeds} held-out seeds x "
                       f"{spec.episodes_per_seed} episodes (mean ± std over seeds)\n\n"
                       + markdown_table(rows) + "\n")
    png = plot_curves(rows, out / "learning_curves.png", f"{spec.env}: learning curves")
    return [csv_path, md_path, png]
