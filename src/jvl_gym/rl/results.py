"""The results page: every registered env × every family it runs on × {trained policies,
baseline, random policy} on the held-out seeds (:mod:`.evaluate`), as ``results.md``, and one
learning-curve plot per training whose log exists.

The envs come from the registration (``jvl_gym.envs.ENV_IDS``), their families from each env's
``supported_families()``, the trainings from ``configs/rl`` (:func:`.config.rl_runs`), the
models from ``RUNS`` (what ``jvl-gym train`` writes) or else the package's shipped policies,
whose training logs are shipped beside them.
Per task, ``configs/rl/notes.md`` (a ``## <env id>`` section each) gives the notes. The page
holds nothing but what the evaluation computes from the seeds, so two runs on the same models
write the same page, but for its last section: the transfer gap (:func:`evaluate_transfer`),
each env's link-trained policy and the same config trained without the link (the config's
``variants``), each in simulation, behind the link model and deployed in real time over a
twin's MacTalk link, whose deployed returns, loop rate and latency are measured on the machine
at the time (with its load average).
"""

from __future__ import annotations

import re
from collections import Counter
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..families.config import configs_dir
from .config import env_families, family_motor_type, rl_config, rl_runs, rl_variants
from .evaluate import ControllerResult, evaluate_controllers, held_out_seeds
from .train import SHIPPED_DIR, log_path, model_path, training_log

__all__ = ["Row", "evaluate_all", "write_page", "plot_curve", "read_notes",
           "evaluate_transfer", "transfer_section", "write_transfer_section",
           "TRANSFER_HEADING"]

#: the heading of the transfer gap's section of the page
TRANSFER_HEADING = "## Transfer: simulation, link model, deployed"

#: a policy beats the baseline when it wins at least this fraction of the seeds
WIN_FRACTION = 0.8


@dataclass
class Row:
    """One env on one family: its controllers' results and the trainings without a model."""

    env_id: str
    family: str
    motor_type: str
    results: dict[str, ControllerResult]
    sources: dict[str, str]
    untrained: list[str]
    step_seconds: float
    seeds: list[int]


def _models(env_id: str, family: str, runs: Path, config_dir: Path | None
            ) -> tuple[dict[str, Path], dict[str, str], list[str]]:
    """Label -> model file of each configured training of ``env_id`` on ``family`` that has
    one (in ``runs``, else shipped), label -> where it came from, and the algorithms that
    have none."""
    models, sources, missing = {}, {}, []
    for env, key, algo in rl_runs(config_dir):
        if (env, key) != (env_id, family):
            continue
        ran = model_path(runs, env_id, family, algo)
        shipped = model_path(SHIPPED_DIR, env_id, family, algo)
        if ran.is_file():
            models[algo], sources[algo] = ran, f"`{ran.name}` in the runs directory"
        elif shipped.is_file():
            models[algo], sources[algo] = shipped, "shipped"
        else:
            missing.append(algo)
    return models, sources, missing


def evaluate_all(runs: str | Path = "runs", n_seeds: int | None = None,
                 episodes_per_seed: int | None = None, max_episode_steps: int | None = None,
                 config_dir: str | Path | None = None, progress_bar: bool = False
                 ) -> list[Row]:
    """Evaluate every registered env on every family it runs on (see the module docstring)."""
    from ..envs import ENV_IDS
    from ..envs.registration import vector_class

    cdir = Path(config_dir) if config_dir is not None else None
    rows = []
    for env_id in ENV_IDS:
        for key in env_families(env_id):
            models, sources, missing = _models(env_id, key, Path(runs), cdir)
            cfg = rl_config(env_id, cdir, family=key)
            kwargs = cfg["env_kwargs"]
            seeds = held_out_seeds(cfg["eval"]["seed_offset"],
                                   int(n_seeds or cfg["eval"]["n_seeds"]))
            motor = kwargs.get("motor_type")
            cls = vector_class(env_id)
            step = cls.step_seconds(motor, kwargs.get("decimation"))
            label = (", ".join(motor) if isinstance(motor, list)
                     else motor or "the env's default")
            res = evaluate_controllers(env_id, models, family=key, n_seeds=n_seeds,
                                       episodes_per_seed=episodes_per_seed,
                                       max_episode_steps=max_episode_steps,
                                       config_dir=cdir, progress_bar=progress_bar)
            rows.append(Row(env_id, key, label, res, sources, missing, step, seeds))
    return rows


def read_notes(path: str | Path | None = None) -> dict[str, str]:
    """The ``## <env id>`` sections of the notes file (default ``configs/rl/notes.md``)."""
    path = Path(path) if path is not None else configs_dir() / "rl" / "notes.md"
    if not path.is_file():
        return {}
    notes: dict[str, list[str]] = {}
    current = None
    for line in path.read_text().splitlines():
        if line.startswith("## "):
            current = line[3:].strip()
            notes[current] = []
        elif current is not None:
            notes[current].append(line)
    return {k: "\n".join(v).strip() for k, v in notes.items()}


def _outcomes(reasons: list[str]) -> str:
    """How the episodes ended: each reason (numbers as N) with its count, most common first."""
    counts = Counter(re.sub(r"\d+", "N", r) or "?" for r in reasons)
    return "; ".join(f"{reason} ×{n}" for reason, n in
                     sorted(counts.items(), key=lambda kv: (-kv[1], kv[0])))


def _mean(values: list[float]) -> str:
    """The mean of an episode statistic's values to 3 significant digits ("—" for none)."""
    finite = [v for v in values if np.isfinite(v)]
    return f"{np.mean(finite):.3g}" if finite else "—"


def plot_curve(log: str | Path, out: str | Path, title: str) -> Path:
    """Episode return against environment steps from a training log (:func:`.train.log_path`,
    plain or gzipped):
    each episode and the running mean of 100; written as PNG to ``out``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    data = np.genfromtxt(log, delimiter=",", skip_header=2, ndmin=2)
    if data.size == 0:
        raise ValueError(f"{log}: the training log has no finished episode")
    ret, length = data[:, 0], data[:, 1]
    steps = np.cumsum(length)
    k = min(100, ret.size)
    smooth = np.convolve(ret, np.ones(k) / k, mode="valid")
    fig, ax = plt.subplots(figsize=(6, 3.2))
    ax.plot(steps, ret, ".", ms=1, alpha=0.3, color="0.5", label="episode")
    ax.plot(steps[k - 1:], smooth, color="C0", label=f"mean of {k}")
    ax.set_xlabel("environment steps")
    ax.set_ylabel("episode return")
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=8)
    fig.tight_layout()
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=100, metadata={"Software": None})
    plt.close(fig)
    return out


def _verdict(row: Row) -> str:
    base = row.results["baseline"]
    n = len(base.seed_means)
    wins = {algo: row.results[algo].seeds_won(base) for algo in row.sources}
    if not wins:
        return "no trained policy: untrained"
    best = max(wins, key=lambda a: (wins[a], row.results[a].mean_std[0]))
    beats = wins[best] >= WIN_FRACTION * n
    return f"{best} {'beats' if beats else 'does not beat'} the baseline ({wins[best]}/{n} seeds)"


def write_page(rows: list[Row], out_dir: str | Path, runs: str | Path = "runs",
               notes: dict[str, str] | None = None, max_episode_steps: int | None = None,
               transfer: list[Any] | None = None) -> Path:
    """Write ``out_dir/results.md`` and ``out_dir/results/<model>.png`` (one learning curve per
    training whose log exists); returns the page's path."""
    from ..envs.registration import vector_class

    out_dir = Path(out_dir)
    notes = read_notes() if notes is None else notes
    lines = ["# Results", "",
             "<!-- generated by `jvl-gym evaluate --all` (`make results`): edit "
             "configs/rl/notes.md and the configs, not this page -->", "",
             "Every env on every motor family it runs on, on held-out seeds (offset + 1000·k, "
             "never used in training)"
             + ("" if max_episode_steps is None
                else f", episodes cut at {max_episode_steps} steps")
             + ": the trained policies "
             "(deterministic actions), the task's baseline and a uniform random policy. "
             "Return: mean ± std over the held-out seeds of the per-seed mean episode return. "
             "Seeds won: seeds on which the controller's mean return is above the baseline's. "
             "Episode: mean length in seconds of motor time. Ended: the envs' "
             "`info[\"termination_reason\"]` of every episode (numbers shown as N). The "
             "columns after it: the mean over the episodes of each statistic the env reports "
             "in `info` at an episode's end (its `episode_stats`, docs/envs.md).",
             "", "| env | family | best trained policy |", "|---|---|---|"]
    for row in rows:
        lines.append(f"| {row.env_id} | {row.family} | {_verdict(row)} |")
    lines.append("")
    curves: dict[str, list[str]] = {}
    for env_id in dict.fromkeys(r.env_id for r in rows):
        stats = vector_class(env_id).episode_stats
        lines += [f"## {env_id}", ""]
        if notes.get(env_id):
            lines += [notes[env_id], ""]
        for row in (r for r in rows if r.env_id == env_id):
            base = row.results["baseline"]
            n = len(base.seed_means)
            lines += [f"### {row.family}", "",
                      f"Motor type: {row.motor_type}. Seeds {', '.join(map(str, row.seeds))}, "
                      f"{len(base.lengths) // n} episodes each.", "",
                      "| controller | return | seeds won | episode [s] | ended |"
                      + "".join(f" {label} |" for label in stats.values()),
                      "|---|---|---|---|---|" + "---|" * len(stats)]
            for label, res in row.results.items():
                m, s = res.mean_std
                name = f"{label} ({row.sources[label]})" if label in row.sources else label
                won = "—" if label == "baseline" else f"{res.seeds_won(base)}/{n}"
                secs = float(np.mean(res.lengths)) * row.step_seconds
                lines.append(f"| {name} | {m:.2f} ± {s:.2f} | {won} | {secs:.3f} | "
                             f"{_outcomes(res.reasons)} |"
                             + "".join(f" {_mean(res.stats.get(k, []))} |" for k in stats))
            for algo in row.untrained:
                lines.append(f"| {algo}: no trained policy (train one: `jvl-gym train "
                             f"{row.env_id} --family {row.family} --algo {algo.lower()}`) "
                             "| — | — | — | — |" + " — |" * len(stats))
            lines.append("")
            for algo in (*row.sources, *row.untrained):
                for base_dir in (Path(runs), SHIPPED_DIR):
                    model = model_path(base_dir, row.env_id, row.family, algo)
                    log = training_log(model)
                    if log is not None:
                        png = plot_curve(log, out_dir / "results" / f"{log_path(model).stem}.png",
                                         f"{row.env_id} {row.family} {algo}")
                        curves.setdefault(env_id, []).append(
                            f"![{row.family} {algo}](results/{png.name})")
                        break
        lines += [*curves.get(env_id, []), ""] if env_id in curves else []
    if transfer:
        lines += transfer_section(transfer)
    page = out_dir / "results.md"
    out_dir.mkdir(parents=True, exist_ok=True)
    page.write_text("\n".join(lines).rstrip("\n") + "\n")
    return page


def evaluate_transfer(runs: str | Path = "runs", config_dir: str | Path | None = None,
                      episodes: int = 5, envs: list[str] | None = None) -> list[Any]:
    """The transfer gap (:func:`.transfer.measure_transfer`) of every configured variant with
    a model (in ``runs``, else shipped), of the envs ``envs`` (default: every env with a
    variant behind a link): each deployed over the link of its env's link-trained variant,
    ``episodes`` episodes from the env's held-out seed offset."""
    from .transfer import measure_transfer

    cdir = Path(config_dir) if config_dir is not None else None
    out = []
    variants = rl_variants(cdir)
    for env_id, key, name in variants:
        if envs is not None and env_id not in envs:
            continue
        links = [rl_config(env_id, cdir, family=key, variant=v)["link"]
                 for e, k, v in variants if (e, k) == (env_id, key)]
        link = next((text for text in links if text), None)
        if link is None:
            continue
        cfg = rl_config(env_id, cdir, family=key, variant=name)
        model = model_path(runs, env_id, key, cfg["algo"], name)
        if not model.is_file():
            model = model_path(SHIPPED_DIR, env_id, key, cfg["algo"], name)
        if not model.is_file():
            continue
        motor = cfg["env_kwargs"].get("motor_type") or family_motor_type(key)
        t = measure_transfer(env_id, model, link, motor_type=motor, episodes=episodes,
                             seed=int(cfg["eval"]["seed_offset"]))
        t.label = f"{name} ({model.name}; trained {cfg['total_timesteps']} steps "
        t.label += f"behind {cfg['link']})" if cfg["link"] else "without a link)"
        out.append(t)
    return out


def transfer_section(transfers: list[Any]) -> list[str]:
    """The page's lines of the transfer gap (:func:`evaluate_transfer`)."""
    lines = [TRANSFER_HEADING, "",
             "Each env's policy trained behind the link its deployment runs over, and the same "
             "config trained without it, on the same episodes (seeds from the held-out offset, "
             "one each) three ways: the env as it is (simulation), the env behind the link model "
             "(`jvl_gym.envs.link`: the link's period, latency and quantisation), and deployed "
             "with `jvl-gym deploy` in real time over MacTalk on TCP to a twin whose motor sits "
             "in the env's machine drawn per episode with the same seed (`jvl-gym serve --line` "
             "in a process of its own, docs/deploy.md) at the link model's period, each write "
             "held to the link model's latency and rate-limited as the link model has it. "
             "Kept: 1 − (reference − deployed) / "
             "|reference| of the mean returns (100 %: the deployment lost nothing; over the "
             "deployed episodes that ran to their end when the supervisor stopped the loop "
             "early). Rate and "
             "latency (the read of the observation to the written action) are the deploy "
             "loop's, measured with the machine's load average at the time (2 cores, shared).",
             "", "| env | policy | link (period) | simulation | link model | deployed | "
             "kept of link model | kept of simulation | loop | latency mean / max | load |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for t in transfers:
        m = {k: float(np.mean(getattr(t, k))) for k in ("sim", "link_model", "deployed")}
        dep = f"{m['deployed']:.2f}" if t.deployed else "—"
        if t.reason != "done":  # the mean of the episodes that ran to their end
            dep += f" ({len(t.deployed)} of {len(t.sim)} episodes; stopped: {t.reason})"
        lines.append(
            f"| {t.env_id} | {getattr(t, 'label', '')} | {t.link} ({1e3 * t.period:.1f} ms) | "
            f"{m['sim']:.2f} | {m['link_model']:.2f} | {dep} | "
            f"{100 * t.kept_of_link_model:.1f} % | {100 * t.kept_of_sim:.1f} % | "
            f"{t.rate_hz:.1f} Hz | {1e3 * t.latency_mean:.1f} / {1e3 * t.latency_max:.1f} ms | "
            f"{t.load[0]:.1f} |")
    return [*lines, ""]


def write_transfer_section(page: str | Path, transfers: list[Any]) -> Path:
    """Put the transfer gap's section into an existing results page (in place of the one it
    has, or at its end), leaving the rest as it is."""
    page = Path(page)
    text = page.read_text() if page.is_file() else "# Results\n"
    head, _, tail = text.partition(TRANSFER_HEADING)
    rest = tail.partition("\n## ")[2] if tail else ""
    new = head.rstrip("\n") + "\n\n" + "\n".join(transfer_section(transfers))
    if rest:
        new = new.rstrip("\n") + "\n\n## " + rest
    page.write_text(new.rstrip("\n") + "\n")
    return page
