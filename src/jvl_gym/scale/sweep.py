"""``jvl-gym sweep``: the trials of a sweep file as Ray Tune trials.

Each Ray Tune trial runs :func:`jvl_gym.scale.trial.tune_trainable` with ``cpus_per_trial``
CPUs reserved (its torch and numba threads); a worker process that finished a trial takes the
next one (``reuse_actors``), so torch, SB3 and the compiled env are loaded once per worker.
The driver prints a line when a trial starts, its latest learning-curve point every
:data:`PROGRESS_EVERY_S` seconds, and a line when it finishes; it writes a finished trial's
entry to the :class:`~jvl_gym.scale.ledger.Ledger` and copies its model next to it. A sweep run
again with the same ``--out`` runs only the trials without an entry. At the end it writes the
results table and the learning-curve plot (:mod:`jvl_gym.scale.sweep_report`) over every
finished trial.

Ray Tune keeps its own experiment directories under ``<out>/ray`` (``run00``, ``run01``, … one
per invocation; ``storage`` overrides the location, e.g. a shared filesystem or ``s3://`` on a
multi-node cluster).
"""

from __future__ import annotations

import logging
import math
import os
import shutil
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .ledger import Ledger
from .ray_session import connect
from .sweep_report import fmt_params, write_results
from .sweep_spec import SweepSpec, Trial, trial_config

__all__ = ["run_sweep", "SweepOutcome", "fmt_params"]

Progress = Callable[[str], None]

#: Seconds between two progress lines of one trial.
PROGRESS_EVERY_S = 15.0


@dataclass
class SweepOutcome:
    """What a sweep run did.

    Attributes
    ----------
    total : int
        Trials of the sweep file.
    skipped : list of str
        Trials finished by an earlier run (not run again).
    finished : list of str
        Trials finished by this run.
    failed : list of str
        Trials that raised.
    files : list of Path
        Results CSV, markdown table and learning-curve plot (when any trial has finished).
    """

    total: int
    skipped: list[str]
    finished: list[str]
    failed: list[str]
    files: list[Path]

    @property
    def complete(self) -> bool:
        """Every trial of the sweep has an entry."""
        return len(self.skipped) + len(self.finished) == self.total


def _callbacks(spec: SweepSpec, by_id: dict[str, Trial], ledger: Ledger, total: int,
               done_before: int, progress: Progress, outcome: SweepOutcome) -> list[Any]:
    from ray.tune import Callback

    def tid(trial: Any) -> str:
        return str(trial.config["trial"]["trial_id"])

    class SweepCallback(Callback):
        def __init__(self) -> None:
            self.printed: dict[str, float] = {}

        def on_trial_start(self, iteration: int, trials: list[Any], trial: Any,
                           **info: Any) -> None:
            t = by_id[tid(trial)]
            progress(f"start {t.trial_id}: {fmt_params(t.params)} seed={t.seed}")

        def on_trial_result(self, iteration: int, trials: list[Any], trial: Any,
                            result: dict[str, Any], **info: Any) -> None:
            t = by_id[tid(trial)]
            if result.get("finished"):
                entry = {"trial_id": t.trial_id, "params": t.params, "seed": t.seed,
                         "env": spec.env, "metrics": {k: v for k, v in result.items()
                                                      if k in _FINAL_KEYS},
                         "curve": result.get("curve", [])}
                ledger.write(t.trial_id, entry)
                _copy_models(str(trial.path), ledger.path(t.trial_id).parent)
                outcome.finished.append(t.trial_id)
                n = done_before + len(outcome.finished)
                progress(f"done  {t.trial_id} ({n}/{total}): policy "
                         f"{result['policy_mean']:.2f} ± {result['policy_std']:.2f}, baseline "
                         f"{result['baseline_mean']:.2f} ± {result['baseline_std']:.2f}, "
                         f"{result['wall_s']:.0f} s")
                return
            now = time.monotonic()
            if now - self.printed.get(t.trial_id, -math.inf) >= PROGRESS_EVERY_S:
                self.printed[t.trial_id] = now
                ep = result.get("ep_return_mean", math.nan)
                ep_text = "" if ep is None or math.isnan(ep) else f", episode return {ep:.2f}"
                rate = result["timesteps"] / max(result["elapsed_s"], 1e-9)
                progress(f"      {t.trial_id}: {int(result['timesteps'])}/{spec.timesteps} "
                         f"steps, reward/step {result['reward_per_step']:.3f}{ep_text}, "
                         f"{rate:.0f} steps/s")

        def on_trial_error(self, iteration: int, trials: list[Any], trial: Any,
                           **info: Any) -> None:
            t = by_id[tid(trial)]
            outcome.failed.append(t.trial_id)
            progress(f"FAILED {t.trial_id}: see {trial.local_path or trial.path}/error.txt")

    return [SweepCallback()]


_FINAL_KEYS = ("policy_mean", "policy_std", "baseline_mean", "baseline_std", "seeds_won",
               "n_seeds", "train_s", "eval_s", "wall_s", "cpu_s", "timesteps", "env_steps_per_s")


def _copy_models(trial_path: str, dest: Path) -> None:
    """Copy the model zip of a trial's checkpoint next to its entry (local storage only: the
    trial persists its checkpoint before the driver sees the final result)."""
    if "://" in trial_path:
        return
    for f in sorted(Path(trial_path).glob("checkpoint_*/*.zip")):
        dest.mkdir(parents=True, exist_ok=True)
        shutil.copy2(f, dest / f.name)


def _stopper(n: int | None) -> Any:
    if n is None:
        return None
    from ray.tune import Stopper

    class StopAfter(Stopper):
        """Stop the whole sweep once ``n`` trials have reported their final metrics."""

        def __init__(self) -> None:
            self.count = 0

        def __call__(self, trial_id: str, result: dict[str, Any]) -> bool:
            if result.get("finished"):
                self.count += 1
            return False

        def stop_all(self) -> bool:
            return self.count >= n

    return StopAfter()


def run_sweep(spec: SweepSpec, out: str | Path, address: str | None = None,
              num_cpus: int | None = None, max_concurrent: int | None = None,
              stop_after: int | None = None, storage: str | None = None,
              progress: Progress = print, verbose: bool = False) -> SweepOutcome:
    """Run the trials of ``spec`` that have no entry under ``out`` yet, then write the results.

    Parameters
    ----------
    spec : SweepSpec
        The sweep.
    out : path
        Output directory: ``trials/<id>/`` (entries, models), ``results.csv``,
        ``results.md``, ``learning_curves.png``, ``ray/`` (Ray Tune's directories).
    address : str, optional
        Ray cluster (``None``: local Ray).
    num_cpus : int, optional
        CPUs of the local Ray (default all).
    max_concurrent : int, optional
        Trials at once (overrides the file's ``resources.max_concurrent``).
    stop_after : int, optional
        Stop the sweep once this many trials have finished in this run (run again to resume).
    storage : str, optional
        Ray Tune's storage path or URI (default ``<out>/ray``).
    progress : callable
        Receives the progress lines.
    verbose : bool
        Ray Tune's own progress output and the workers' logs too.
    """
    out = Path(out).resolve()
    ledger = Ledger(out / "trials")
    trials = spec.trials()
    by_id = {t.trial_id: t for t in trials}
    done = ledger.finished(list(by_id))
    todo = [t for t in trials if t.trial_id not in done]
    outcome = SweepOutcome(len(trials), sorted(done), [], [], [])
    progress(f"{spec.env}: {len(trials)} trials of {spec.timesteps} steps, "
             f"{len(done)} finished earlier, {len(todo)} to run")
    if todo:
        if not verbose:  # Ray Tune's legacy reporter honours verbose=0 (no experiment box)
            os.environ.setdefault("RAY_AIR_NEW_OUTPUT", "0")
        connect(address, num_cpus, log_to_driver=verbose)
        from ray import tune

        threads = max(1, int(spec.cpus_per_trial))
        configs = [{"trial_id": t.trial_id, "env_id": spec.env, "threads": threads,
                    "cfg": trial_config(spec, t)} for t in todo]
        root = storage or str(out / "ray")
        runs = Path(root) / "run00"
        k = 0
        while "://" not in root and runs.exists():
            k += 1
            runs = Path(root) / f"run{k:02d}"

        def name(trial: Any) -> str:
            return str(trial.config["trial"]["trial_id"])

        tuner = tune.Tuner(
            tune.with_resources(_trainable, {"cpu": spec.cpus_per_trial}),
            param_space={"trial": tune.grid_search(configs)},
            tune_config=tune.TuneConfig(
                max_concurrent_trials=max_concurrent or spec.max_concurrent,
                reuse_actors=True, trial_name_creator=name, trial_dirname_creator=name),
            run_config=tune.RunConfig(
                name=f"run{k:02d}", storage_path=root, stop=_stopper(stop_after),
                callbacks=_callbacks(spec, by_id, ledger, len(trials), len(done), progress,
                                     outcome),
                verbose=1 if verbose else 0,
                failure_config=tune.FailureConfig(max_failures=0, fail_fast=False)))
        # Ray Tune's own "resume with Tuner.restore(...)" advice does not apply: running the
        # command again resumes (the line below says so)
        tune_log = logging.getLogger("ray.tune.tune")
        level = tune_log.level
        if not verbose:
            tune_log.setLevel(logging.CRITICAL)
        try:
            tuner.fit()
        finally:
            tune_log.setLevel(level)
    rows = [e for t in trials if (e := ledger.read(t.trial_id)) is not None]
    if rows:
        outcome.files = write_results(spec, rows, out)
    missing = outcome.total - len(rows)
    progress(f"{len(rows)}/{outcome.total} trials finished"
             + (f"; {missing} left: run the same command again to finish them" if missing
                else "") + (f"; results: {', '.join(str(f) for f in outcome.files)}"
                            if outcome.files else ""))
    return outcome


def _trainable(config: dict[str, Any]) -> None:
    from .trial import tune_trainable

    tune_trainable(config["trial"])
