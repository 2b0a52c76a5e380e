"""Policy vs baseline on held-out randomisations: mean ± std over seeds.

Each seed resets a native vector env of ``episodes_per_seed`` copies with
``seed_offset + k`` (training never uses seeds that high: SB3 seeds its envs with small
integers), runs every copy to the end of its first episode and averages the returns; the table
reports mean ± std of those per-seed means over ``n_seeds`` seeds.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from .config import rl_config

__all__ = ["episode_returns", "evaluate", "format_table"]


def episode_returns(env_id: str, policy: Callable[[np.ndarray], np.ndarray], seed: int,
                    n_episodes: int, env_kwargs: dict[str, Any] | None = None,
                    reset_policy: Callable[[np.ndarray | None], None] | None = None
                    ) -> np.ndarray:
    """Returns of the first episode of ``n_episodes`` copies seeded ``seed + i``."""
    import gymnasium as gym
    from gymnasium.vector import AutoresetMode

    import jvl_gym  # noqa: F401

    env = gym.make_vec(env_id, num_envs=n_episodes, vectorization_mode="vector_entry_point",
                       autoreset_mode=AutoresetMode.DISABLED, **(env_kwargs or {}))
    obs, _ = env.reset(seed=seed)
    if reset_policy is not None:
        reset_policy(None)
    ret = np.zeros(n_episodes)
    alive = np.ones(n_episodes, dtype=bool)
    core = env.unwrapped
    while alive.any():
        obs, reward, terminated, truncated = core._step_batch(policy(obs))
        ret += np.where(alive, reward, 0.0)
        alive &= ~(terminated | truncated)
    env.close()
    return ret


def evaluate(env_id: str, model_file: str | Path | None, n_seeds: int | None = None,
             episodes_per_seed: int | None = None, progress_bar: bool = True,
             config_dir: str | Path | None = None) -> dict[str, tuple[float, float]]:
    """Mean ± std (over seeds) of the per-seed mean return of the policy and the baseline,
    and ``seeds_won``: (seeds where the policy's mean beats the baseline's, seeds)."""
    from ..envs.baselines import BASELINES, make_baseline
    from ..envs.registration import vector_class

    cfg = rl_config(env_id, config_dir)
    ev = cfg["eval"]
    n_seeds = int(n_seeds or ev["n_seeds"])
    n_ep = int(episodes_per_seed or ev["episodes_per_seed"])
    seeds = [int(ev["seed_offset"]) + 1000 * k for k in range(n_seeds)]
    kwargs = dict(cfg["env_kwargs"])
    base = BASELINES[env_id]
    rows: dict[str, list[float]] = {"baseline": []}
    model = None
    if model_file is not None:
        from stable_baselines3 import PPO, SAC

        algo = {"PPO": PPO, "SAC": SAC}[cfg["algo"]]
        model = algo.load(str(model_file), device="cpu")
        rows["policy"] = []
    iterator: Any = seeds
    if progress_bar:
        from tqdm import tqdm

        iterator = tqdm(seeds, desc=f"evaluate {env_id}")
    for seed in iterator:
        bl = make_baseline(env_id, n_ep, len(vector_class(env_id).act_labels),
                           decimation=kwargs.get("decimation"),
                           motor_type=kwargs.get("motor_type"))
        rows["baseline"].append(float(episode_returns(
            env_id, bl, seed, n_ep, {**kwargs, **base.env_kwargs}, bl.reset).mean()))
        if model is not None:
            def policy(obs: np.ndarray) -> np.ndarray:
                return model.predict(obs, deterministic=True)[0]

            rows["policy"].append(float(episode_returns(env_id, policy, seed, n_ep,
                                                        kwargs).mean()))
    out = {k: (float(np.mean(v)), float(np.std(v))) for k, v in rows.items()}
    if "policy" in rows:
        wins = sum(p > b for p, b in zip(rows["policy"], rows["baseline"]))
        out["seeds_won"] = (float(wins), float(n_seeds))
    return out


def format_table(results: dict[str, dict[str, tuple[float, float]]]) -> str:
    """Markdown table: env, policy, baseline (mean ± std over seeds), winner, seeds won."""
    lines = ["| env | policy | baseline | better | seeds won by the policy |",
             "|---|---|---|---|---|"]
    for env_id, r in results.items():
        b = r["baseline"]
        p = r.get("policy")
        pol = f"{p[0]:.2f} ± {p[1]:.2f}" if p else "—"
        better = "—" if p is None else ("policy" if p[0] > b[0] else "baseline")
        won = f"{int(r['seeds_won'][0])}/{int(r['seeds_won'][1])}" if "seeds_won" in r else "—"
        lines.append(f"| {env_id} | {pol} | {b[0]:.2f} ± {b[1]:.2f} | {better} | {won} |")
    return "\n".join(lines)
