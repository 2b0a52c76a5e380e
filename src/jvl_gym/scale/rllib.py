"""The jvl_gym envs as RLlib environments, and PPO with RLlib on GearSync.

RLlib's env runners build their envs with ``gymnasium.make_vec(id, num_envs,
vectorization_mode=config.gym_env_vectorize_mode, **env_config)``. Given the id
``"jvl_gym:jvl_gym/GearSync-v0"`` (the ``module:`` prefix makes every Ray worker import
``jvl_gym``, which registers the ids) and ``gym_env_vectorize_mode="vector_entry_point"``, each
env runner steps the native vector env (one batched ``MotorArray`` for its copies) in its
default NEXT_STEP autoreset mode, which is the mode RLlib's episode bookkeeping expects.

Example (also ``python -m jvl_gym.scale.rllib --iterations 20 --out rllib_out``)::

    import os
    from jvl_gym.scale.rllib import ppo_config
    algo = ppo_config("jvl_gym/GearSync-v0", num_env_runners=1).build_algo()
    for _ in range(20):
        result = algo.train()
        print(result["env_runners"]["episode_return_mean"])
    algo.save(os.path.abspath("rllib_out/checkpoint"))  # RLlib wants an absolute path or URI

:func:`train_ppo` runs the same as one Ray Tune trial (its directory under ``--out``).
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Any

from ..cli.app import writable_dir_arg

__all__ = ["rllib_env_id", "ppo_config", "train_ppo", "main"]


def rllib_env_id(env_id: str) -> str:
    """``"jvl_gym:<id>"``: the id with the module that registers it."""
    return env_id if ":" in env_id else f"jvl_gym:{env_id}"


def ppo_config(env_id: str = "jvl_gym/GearSync-v0", num_env_runners: int = 0,
               num_envs_per_runner: int = 16, env_kwargs: dict[str, Any] | None = None,
               train_batch_size: int = 4096, minibatch_size: int = 512, num_epochs: int = 10,
               lr: float = 3e-4, gamma: float = 0.995, hidden: tuple[int, ...] = (64, 64),
               seed: int = 0) -> Any:
    """An RLlib ``PPOConfig`` on a jvl_gym env's native vector env.

    Parameters
    ----------
    env_id : str
        Registered jvl_gym id.
    num_env_runners : int
        Remote env runners (0: sample in the driver's process), one CPU each.
    num_envs_per_runner : int
        Copies of the native vector env per runner.
    env_kwargs : dict, optional
        Env constructor arguments (``gymnasium.make_vec`` keyword arguments).
    train_batch_size, minibatch_size, num_epochs : int
        PPO batch [env steps], minibatch [env steps], epochs per batch.
    lr, gamma : float
        Learning rate and discount.
    hidden : tuple of int
        Hidden layer sizes of the policy and value networks.
    seed : int
        Seed of the env runners and the networks.
    """
    from .extra import require_ray

    require_ray()
    from ray.rllib.algorithms.ppo import PPOConfig
    from ray.rllib.core.rl_module.default_model_config import DefaultModelConfig

    return (PPOConfig()
            .environment(rllib_env_id(env_id), env_config=dict(env_kwargs or {}))
            .framework("torch")
            .env_runners(num_env_runners=num_env_runners,
                         num_envs_per_env_runner=num_envs_per_runner,
                         gym_env_vectorize_mode="vector_entry_point",
                         num_cpus_per_env_runner=1)
            .learners(num_learners=0)
            .training(train_batch_size_per_learner=train_batch_size,
                      minibatch_size=minibatch_size, num_epochs=num_epochs, lr=lr,
                      gamma=gamma)
            .rl_module(model_config=DefaultModelConfig(fcnet_hiddens=list(hidden)))
            .debugging(seed=seed))


def train_ppo(env_id: str = "jvl_gym/GearSync-v0", iterations: int = 20,
              out: str | Path | None = None, address: str | None = None,
              num_cpus: int | None = None, progress: Any = print, **config: Any
              ) -> list[dict[str, float]]:
    """Train PPO with RLlib for ``iterations`` iterations as one Ray Tune trial.

    Parameters
    ----------
    env_id : str
        Registered jvl_gym id.
    iterations : int
        Training iterations (``algo.train()`` calls).
    out : path, optional
        Ray Tune's directory for the run (``<out>/ppo``, with the final checkpoint); a
        temporary directory, removed afterwards, when not given.
    address : str, optional
        Ray cluster (``None``: local Ray).
    num_cpus : int, optional
        CPUs of the local Ray.
    progress : callable
        Receives one line per iteration.
    **config
        Arguments of :func:`ppo_config`.

    Returns
    -------
    list of dict
        ``iteration``, ``env_steps`` (sampled in total), ``episode_return_mean`` (NaN before
        the first episode ends) and ``time_s`` per iteration.
    """
    import tempfile

    from ray import tune

    from .ray_session import connect

    connect(address, num_cpus)
    rows: list[dict[str, float]] = []

    class _Rows(tune.Callback):
        def on_trial_result(self, iteration: int, trials: list[Any], trial: Any,
                            result: dict[str, Any], **info: Any) -> None:
            runners = result.get("env_runners", {})
            ret = runners.get("episode_return_mean")
            row = {"iteration": float(result["training_iteration"]),
                   "env_steps": float(runners.get("num_env_steps_sampled_lifetime", math.nan)),
                   "episode_return_mean": math.nan if ret is None else float(ret),
                   "time_s": float(result.get("time_total_s", math.nan))}
            rows.append(row)
            progress(f"iteration {row['iteration']:.0f}: {row['env_steps']:.0f} env steps, "
                     f"episode return {row['episode_return_mean']:.2f}, "
                     f"{row['time_s']:.0f} s")

    cfg = ppo_config(env_id, **config)
    with tempfile.TemporaryDirectory(prefix="jvl-rllib-") as tmp:
        root = Path(out).resolve() if out is not None else Path(tmp)
        # the algorithm's class, not its name: a name makes Tune import every RLlib algorithm,
        # and one of them builds a debugging env at import that trips gymnasium's checks
        tuner = tune.Tuner(
            cfg.algo_class, param_space=cfg,
            run_config=tune.RunConfig(
                name="ppo", storage_path=str(root), verbose=0, callbacks=[_Rows()],
                stop={"training_iteration": int(iterations)},
                checkpoint_config=tune.CheckpointConfig(checkpoint_at_end=out is not None)))
        result = tuner.fit()[0]
        if result.error is not None:
            raise result.error
        if out is not None and result.checkpoint is not None:
            progress(f"checkpoint: {result.checkpoint.path}")
    return rows


def main(argv: list[str] | None = None) -> None:
    """``python -m jvl_gym.scale.rllib``: PPO with RLlib on a jvl_gym env."""
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--env", default="jvl_gym/GearSync-v0")
    p.add_argument("--iterations", type=int, default=20)
    p.add_argument("--runners", type=int, default=1, help="remote env runners")
    p.add_argument("--envs-per-runner", type=int, default=16)
    p.add_argument("--batch", type=int, default=4096, help="train batch [env steps]")
    p.add_argument("--out", default=None, type=writable_dir_arg,
                   help="Ray Tune's directory (with the checkpoint; checked writable first)")
    p.add_argument("--address", default=None, help="Ray cluster (default: local Ray)")
    a = p.parse_args(argv)
    train_ppo(a.env, a.iterations, a.out, a.address, num_env_runners=a.runners,
              num_envs_per_runner=a.envs_per_runner, train_batch_size=a.batch,
              minibatch_size=min(512, a.batch))


if __name__ == "__main__":
    main()
