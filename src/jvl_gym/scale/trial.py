"""One sweep trial: train on the native vector env, evaluate on held-out seeds.

The trial trains exactly as ``jvl-gym train`` does (the SB3 adapter over
``gymnasium.make_vec(..., vectorization_mode="vector_entry_point")``, ``VecMonitor``, the
configured algorithm on the CPU), with the trial's configs/rl entry
(:func:`jvl_gym.scale.sweep_spec.trial_config`), and reports a learning-curve point after each
rollout: the mean reward per env-step of the rollout and, once episodes have ended, SB3's mean
episode return. It then evaluates the saved model with :func:`jvl_gym.rl.evaluate.evaluate`
(policy and baseline on the held-out seeds of the trial's entry).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import yaml

__all__ = ["train_and_evaluate", "tune_trainable", "CURVE_POINTS"]

#: Learning-curve points reported per trial (at most; one per rollout when rollouts are fewer).
CURVE_POINTS = 50

Report = Callable[[dict[str, Any], "Path | None"], None]


def _write_config(directory: Path, env_id: str, cfg: dict[str, Any]) -> Path:
    directory.mkdir(parents=True, exist_ok=True)
    path = directory / "trial.yml"
    path.write_text(yaml.safe_dump({env_id: cfg}, sort_keys=False))
    return directory


def train_and_evaluate(env_id: str, cfg: dict[str, Any], work_dir: str | Path,
                       report: Report, threads: int = 1) -> dict[str, Any]:
    """Train ``cfg`` (a configs/rl entry) on ``env_id``, evaluate it, and report.

    Parameters
    ----------
    env_id : str
        Registered env id.
    cfg : dict
        Complete configs/rl entry (algo, n_envs, total_timesteps, policy, env_kwargs,
        hyperparams, eval, seed).
    work_dir : path
        Where the model (``<EnvName>.zip``) and the entry (``config/trial.yml``) are written.
    report : callable
        ``report(metrics, checkpoint_dir)``: called after each rollout with
        ``{"timesteps", "reward_per_step", "ep_return_mean", "elapsed_s"}`` and
        ``checkpoint_dir=None``, and once at the end with the final metrics and ``work_dir``.
    threads : int
        torch and numba threads.

    Returns
    -------
    dict
        Final metrics: ``policy_mean``, ``policy_std``, ``baseline_mean``, ``baseline_std``
        (returns, mean ± std over held-out seeds), ``seeds_won``, ``n_seeds``, ``train_s``,
        ``eval_s``, ``wall_s`` [s], ``cpu_s`` (CPU time of the trial's process, all its
        threads) [s], ``timesteps``, ``env_steps_per_s`` and ``curve`` (list of
        ``[timesteps, reward_per_step, ep_return_mean]``).
    """
    import numba
    import torch
    from stable_baselines3 import PPO, SAC
    from stable_baselines3.common.callbacks import BaseCallback
    from stable_baselines3.common.vec_env import VecMonitor

    from jvl_gym.rl.evaluate import evaluate
    from jvl_gym.rl.sb3_adapter import make_sb3_env
    from jvl_gym.rl.train import model_path

    work_dir = Path(work_dir)
    t0 = time.perf_counter()
    c0 = time.process_time()
    torch.set_num_threads(max(1, int(threads)))
    numba.set_num_threads(max(1, min(int(threads), numba.config.NUMBA_NUM_THREADS)))
    steps = int(cfg["total_timesteps"])
    every = max(1, steps // CURVE_POINTS)
    curve: list[list[float]] = []

    class _Curve(BaseCallback):
        def __init__(self) -> None:
            super().__init__()
            self.sum = 0.0
            self.count = 0
            self.next_report = every

        def _on_step(self) -> bool:
            rewards = np.asarray(self.locals["rewards"], dtype=float)
            self.sum += float(rewards.sum())
            self.count += rewards.size
            return True

        def _on_rollout_end(self) -> None:
            if self.num_timesteps < self.next_report or self.count == 0:
                return
            self.next_report = self.num_timesteps + every
            eps = [ep["r"] for ep in self.model.ep_info_buffer]
            point = [float(self.num_timesteps), self.sum / self.count,
                     float(np.mean(eps)) if eps else float("nan")]
            self.sum, self.count = 0.0, 0
            curve.append(point)
            report({"timesteps": point[0], "reward_per_step": point[1],
                    "ep_return_mean": point[2], "elapsed_s": time.perf_counter() - t0}, None)

    venv = VecMonitor(make_sb3_env(env_id, int(cfg["n_envs"]), **cfg["env_kwargs"]))
    algo = {"PPO": PPO, "SAC": SAC}[cfg["algo"]]
    model = algo(cfg["policy"], venv, seed=int(cfg["seed"]), verbose=0, device="cpu",
                 **dict(cfg["hyperparams"]))
    model.learn(total_timesteps=steps, callback=_Curve(), progress_bar=False)
    trained = int(model.num_timesteps)
    path = model_path(work_dir, env_id)
    path.parent.mkdir(parents=True, exist_ok=True)
    model.save(path)
    venv.close()
    t1 = time.perf_counter()
    cfg_dir = _write_config(work_dir / "config", env_id, cfg)
    res = evaluate(env_id, path, progress_bar=False, config_dir=cfg_dir)
    t2 = time.perf_counter()
    final = {"policy_mean": res["policy"][0], "policy_std": res["policy"][1],
             "baseline_mean": res["baseline"][0], "baseline_std": res["baseline"][1],
             "seeds_won": int(res["seeds_won"][0]), "n_seeds": int(res["seeds_won"][1]),
             "train_s": t1 - t0, "eval_s": t2 - t1, "wall_s": t2 - t0,
             "cpu_s": time.process_time() - c0,
             "timesteps": float(trained), "env_steps_per_s": trained / max(t1 - t0, 1e-9),
             "curve": curve, "finished": True}
    report(final, work_dir)
    return final


def tune_trainable(config: dict[str, Any]) -> None:
    """Ray Tune function trainable: ``config = {"env_id", "cfg", "threads", "trial_id"}``.

    Reports the learning-curve points with :func:`ray.tune.report` and the final metrics with
    a checkpoint holding the model and its configs/rl entry.
    """
    import tempfile

    from ray import tune

    def report(metrics: dict[str, Any], checkpoint_dir: Path | None) -> None:
        if checkpoint_dir is None:
            tune.report(metrics)
        else:
            tune.report(metrics, checkpoint=tune.Checkpoint.from_directory(str(checkpoint_dir)))

    with tempfile.TemporaryDirectory(prefix="jvl-trial-") as tmp:
        train_and_evaluate(config["env_id"], config["cfg"], tmp, report,
                           threads=int(config.get("threads", 1)))
