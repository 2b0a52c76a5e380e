"""Train an SB3 policy on a jvl_gym env from its ``configs/rl`` entry."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

from .config import rl_config

__all__ = ["train", "model_path", "shipped_model", "SHIPPED_DIR"]

#: trained policies shipped with the package: the models behind docs/envs.md "Results"
SHIPPED_DIR = Path(__file__).resolve().parent / "policies"


def model_path(out_dir: str | Path, env_id: str) -> Path:
    """Where the model of ``env_id`` is saved (``<out>/<EnvName>.zip``)."""
    return Path(out_dir) / f"{env_id.split('/')[-1]}.zip"


def shipped_model(env_id: str) -> Path | None:
    """The shipped trained policy of ``env_id`` (:data:`SHIPPED_DIR`), or None."""
    path = model_path(SHIPPED_DIR, env_id)
    return path if path.is_file() else None


def train(env_id: str, out_dir: str | Path = "runs", total_timesteps: int | None = None,
          seed: int | None = None, progress_bar: bool = True, threads: int = 1,
          config_dir: str | Path | None = None) -> Path:
    """Train the configured algorithm on ``env_id`` and save it; returns the model path.

    Parameters
    ----------
    env_id : str
        Registered id, e.g. ``"jvl_gym/GearSync-v0"``.
    out_dir : path
        Directory for the model.
    total_timesteps, seed : int, optional
        Override the config.
    progress_bar : bool
        Show SB3's progress bar.
    threads : int
        torch and numba threads (1 lets two trainings share 2 cores; a vector env of 32 or
        more copies runs the motor kernel on numba's thread pool).
    """
    import numba
    import torch
    from stable_baselines3 import PPO, SAC
    from stable_baselines3.common.vec_env import VecMonitor

    from .sb3_adapter import make_sb3_env

    cfg = rl_config(env_id, config_dir)
    torch.set_num_threads(int(threads))
    numba.set_num_threads(min(int(threads), numba.config.NUMBA_NUM_THREADS))
    seed = int(cfg["seed"] if seed is None else seed)
    steps = int(cfg["total_timesteps"] if total_timesteps is None else total_timesteps)
    venv = VecMonitor(make_sb3_env(env_id, int(cfg["n_envs"]), **cfg["env_kwargs"]))
    algo = {"PPO": PPO, "SAC": SAC}[cfg["algo"]]
    hyper: dict[str, Any] = dict(cfg["hyperparams"])
    model = algo(cfg["policy"], venv, seed=seed, verbose=0, device="cpu", **hyper)
    t0 = time.perf_counter()
    model.learn(total_timesteps=steps, progress_bar=progress_bar)
    path = model_path(out_dir, env_id)
    path.parent.mkdir(parents=True, exist_ok=True)
    model.save(path)
    print(f"{env_id}: {steps} steps in {time.perf_counter() - t0:.0f} s -> {path}")
    venv.close()
    return path
