"""Train an SB3 policy on a jvl_gym env from its ``configs/rl`` entry."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

from .config import rl_config

__all__ = ["train", "checkpoint_path", "model_path", "log_path", "training_log", "shipped_model",
           "algo_class", "SHIPPED_DIR"]

def algo_class(name: str) -> Any:
    """The stable-baselines3 class of an algorithm name (``PPO``, ``SAC``, ``TD3``)."""
    import stable_baselines3

    return getattr(stable_baselines3, name.upper())


#: trained policies shipped with the package: the models behind docs/results.md, each with its
#: training log gzipped beside it
SHIPPED_DIR = Path(__file__).resolve().parent / "policies"


def model_path(out_dir: str | Path, env_id: str, family: str | None = None,
               algo: str | None = None, variant: str | None = None) -> Path:
    """Where the model of ``env_id`` is saved: ``<out>/<EnvName>-<family>-<algo>.zip`` (algo
    in lower case; a variant's ``<EnvName>-<family>-<variant>-<algo>.zip``), or
    ``<out>/<EnvName>.zip`` when neither family nor algo nor variant is given."""
    name = env_id.split("/")[-1]
    if family is None and algo is None and variant is None:
        return Path(out_dir) / f"{name}.zip"
    from .config import env_families

    key = env_families(env_id)[0] if family is None else family
    tag = "" if variant is None else f"-{variant}"
    return Path(out_dir) / f"{name}-{key}{tag}-{(algo or 'PPO').lower()}.zip"


def log_path(model: str | Path) -> Path:
    """The training log (SB3 ``Monitor`` CSV: return ``r``, length ``l``, time ``t`` of each
    episode) beside a model file."""
    model = Path(model)
    return model.with_name(model.stem + ".monitor.csv")


def training_log(model: str | Path) -> Path | None:
    """The training log of ``model``, if it has one: :func:`log_path` or that file gzipped
    (``….monitor.csv.gz``, as the shipped policies keep theirs); ``None`` otherwise."""
    plain = log_path(model)
    for log in (plain, plain.with_name(plain.name + ".gz")):
        if log.is_file():
            return log
    return None


def shipped_model(env_id: str, family: str | None = None, algo: str = "PPO",
                  variant: str | None = None) -> Path | None:
    """The shipped trained policy of ``env_id`` on ``family`` (default: the env's first) with
    ``algo`` (of ``variant``, if given) (:data:`SHIPPED_DIR`), or None."""
    path = model_path(SHIPPED_DIR, env_id, family, algo, variant)
    return path if path.is_file() else None


def checkpoint_path(model: str | Path, steps: int) -> Path:
    """The checkpoint of a training after ``steps`` environment steps, beside its model:
    ``<model stem>-<steps>.zip``."""
    model = Path(model)
    return model.with_name(f"{model.stem}-{int(steps)}.zip")


def _checkpoints(path: Path, every: int) -> Any:
    """An SB3 callback that saves the model (:func:`checkpoint_path`) at the start of the
    first rollout after each further ``every`` steps: after the update of the rollout before,
    so the checkpoint of ``n`` steps is the model a training of ``n`` steps in all saves
    (``n`` a whole number of rollouts; the algorithms' schedules are constant)."""
    from stable_baselines3.common.callbacks import BaseCallback

    class Checkpoints(BaseCallback):
        def __init__(self) -> None:
            super().__init__()
            self.due = every

        def _on_rollout_start(self) -> None:
            if self.num_timesteps >= self.due:
                self.model.save(checkpoint_path(path, self.num_timesteps))
                self.due = (self.num_timesteps // every + 1) * every

        def _on_step(self) -> bool:
            return True

    return Checkpoints()


def train(env_id: str, out_dir: str | Path = "runs", total_timesteps: int | None = None,
          seed: int | None = None, progress_bar: bool = True, threads: int = 1,
          config_dir: str | Path | None = None, family: str | None = None,
          algo: str | None = None, checkpoint_every: int | None = None,
          link: str | None = None, variant: str | None = None,
          env_kwargs: dict[str, Any] | None = None) -> Path:
    """Train the configured algorithm on ``env_id`` and save it (:func:`model_path`, with the
    training log beside it, :func:`log_path`); returns the model path.

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
    config_dir : path, optional
        Directory of the RL ``*.yml`` (default ``configs/rl``).
    family, algo : str, optional
        Motor family key and algorithm (default: the config's first family and its ``algo``).
    checkpoint_every : int, optional
        Also save the model every this many steps (:func:`checkpoint_path`).
    link : str, optional
        Train behind this link (``jvl_gym.envs.link``: ``"mactalk:19200"``,
        ``"canopen:2ms"``, ``"dac:12"`` …; default: the config's ``link``).
    variant : str, optional
        Train a variant of the config (:func:`~.config.rl_config`; its own model name).
    env_kwargs : dict, optional
        Env arguments over the config's ``env_kwargs`` (an identified motor's,
        :func:`jvl_gym.envs.identified.env_kwargs_from_identification`).
    """
    import numba
    import torch
    from stable_baselines3.common.vec_env import VecMonitor

    from .config import env_families
    from .sb3_adapter import make_sb3_env

    cfg = rl_config(env_id, config_dir, family=family, algo=algo, variant=variant)
    family = env_families(env_id)[0] if family is None else family
    path = model_path(out_dir, env_id, family, cfg["algo"], variant)
    link = cfg.get("link") if link is None else link
    path.parent.mkdir(parents=True, exist_ok=True)
    torch.set_num_threads(int(threads))
    numba.set_num_threads(min(int(threads), numba.config.NUMBA_NUM_THREADS))
    seed = int(cfg["seed"] if seed is None else seed)
    steps = int(cfg["total_timesteps"] if total_timesteps is None else total_timesteps)
    venv = VecMonitor(make_sb3_env(env_id, int(cfg["n_envs"]), link,
                                    **{**cfg["env_kwargs"], **(env_kwargs or {})}),
                      filename=str(log_path(path)))
    hyper: dict[str, Any] = dict(cfg["hyperparams"])
    if cfg.get("init") is not None:  # a fine-tuning of the shipped policy
        if cfg["init"] != "shipped":
            raise ValueError(f"{env_id}: init must be 'shipped', got {cfg['init']!r}")
        start = shipped_model(env_id, family, cfg["algo"])
        if start is None:
            raise FileNotFoundError(f"{env_id}: no shipped {cfg['algo']} policy on {family} "
                                    "to start from")
        model = algo_class(cfg["algo"]).load(str(start), env=venv, device="cpu")
        model.set_random_seed(seed)
    else:
        model = algo_class(cfg["algo"])(cfg["policy"], venv, seed=seed, verbose=0,
                                        device="cpu", **hyper)
    t0 = time.perf_counter()
    callback = None if checkpoint_every is None else _checkpoints(path, int(checkpoint_every))
    model.learn(total_timesteps=steps, progress_bar=progress_bar, callback=callback)
    model.save(path)
    print(f"{env_id}: {steps} steps in {time.perf_counter() - t0:.0f} s -> {path}")
    venv.close()
    return path
