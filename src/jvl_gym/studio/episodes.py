"""One episode of a registered env with its shipped policy or its baseline.

The env is made as :func:`jvl_gym.rl.evaluate.episode_returns` makes it (a native vector env
of one copy with the RL config's env arguments), the baseline is the env's
(:data:`jvl_gym.envs.baselines.BASELINES`), the policy the one shipped with the package
(:func:`jvl_gym.rl.train.shipped_model`, needs the RL extra). Every step's observation,
action and reward is kept for the Episodes page.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["Episode", "run_episode", "controllers"]


@dataclass
class Episode:
    """The signals of one episode.

    Attributes
    ----------
    env_id : str
        The env.
    controller : str
        ``"baseline"`` or ``"policy"``.
    seed : int
        The reset seed.
    signals : dict
        Label → array (n_steps,): every observation and action component, and the reward.
    total : float
        The return (sum of rewards).
    """

    env_id: str
    controller: str
    seed: int
    signals: dict[str, np.ndarray]
    total: float


def controllers(env_id: str) -> list[str]:
    """The controllers ``env_id`` can run: ``"baseline"`` and, if one is shipped, ``"policy"``."""
    from ..rl.train import shipped_model

    return ["baseline"] + (["policy"] if shipped_model(env_id) is not None else [])


def _policy(env_id: str, controller: str, kwargs: dict[str, Any], act_dim: int) -> tuple[
        Any, Any, dict[str, Any]]:
    from ..envs.baselines import BASELINES, make_baseline

    if controller == "baseline":
        bl = make_baseline(env_id, 1, act_dim, decimation=kwargs.get("decimation"),
                           motor_type=kwargs.get("motor_type"))
        return bl, bl.reset, dict(BASELINES[env_id].env_kwargs)
    if controller != "policy":
        raise ValueError(f"controller is 'baseline' or 'policy', not {controller!r}")
    from ..rl.config import rl_config
    from ..rl.train import shipped_model

    path = shipped_model(env_id)
    if path is None:
        raise ValueError(f"{env_id} has no shipped policy; run its baseline")
    try:
        from stable_baselines3 import PPO, SAC
    except ImportError as exc:
        from ..cli.app import RL_EXTRA_HINT

        raise ValueError(f"the shipped policy {RL_EXTRA_HINT}") from exc
    algo = {"PPO": PPO, "SAC": SAC}[rl_config(env_id)["algo"]]
    model = algo.load(str(path), device="cpu")
    return (lambda obs: model.predict(obs, deterministic=True)[0]), None, {}


def run_episode(env_id: str, controller: str = "baseline", seed: int = 0,
                max_steps: int = 100_000) -> Episode:
    """Run one episode of ``env_id`` on ``seed`` with ``controller`` and keep its signals.

    Raises
    ------
    ValueError
        An env jvl_gym does not register, or a controller it does not have.
    """
    import gymnasium as gym
    from gymnasium.vector import AutoresetMode

    from ..envs import ENV_IDS
    from ..envs.registration import vector_class
    from ..rl.config import rl_config

    if env_id not in ENV_IDS:
        raise ValueError(f"unknown env {env_id!r}; known: {', '.join(ENV_IDS)}")
    cls = vector_class(env_id)
    kwargs = dict(rl_config(env_id)["env_kwargs"])
    policy, reset, extra = _policy(env_id, controller, kwargs, len(cls.act_labels))
    env = gym.make_vec(env_id, num_envs=1, vectorization_mode="vector_entry_point",
                       autoreset_mode=AutoresetMode.DISABLED, **{**kwargs, **extra})
    try:
        obs, _ = env.reset(seed=seed)
        if reset is not None:
            reset(None)
        core = env.unwrapped
        rows_obs, rows_act, rewards = [], [], []
        for _ in range(max_steps):
            action = np.asarray(policy(obs), dtype=np.float32).reshape(1, -1)
            rows_obs.append(np.asarray(obs, dtype=float)[0])
            rows_act.append(action[0].astype(float))
            obs, reward, terminated, truncated = core._step_batch(action)
            rewards.append(float(np.asarray(reward)[0]))
            if bool(np.asarray(terminated)[0] or np.asarray(truncated)[0]):
                break
    finally:
        env.close()
    signals: dict[str, np.ndarray] = {}
    o, a = np.asarray(rows_obs), np.asarray(rows_act)
    for k, label in enumerate(cls.obs_labels):
        signals[f"obs: {label}"] = o[:, k]
    for k, label in enumerate(cls.act_labels):
        signals[f"action: {label}"] = a[:, k]
    signals["reward"] = np.asarray(rewards)
    return Episode(env_id, controller, seed, signals, float(np.sum(rewards)))
