"""Controllers against the baseline on held-out randomisations: mean ± std over seeds.

Each seed resets a native vector env of ``episodes_per_seed`` copies with
``seed_offset + 1000·k`` (training never uses seeds that high: SB3 seeds its envs with small
integers), runs every copy to the end of its first episode and averages the returns; the table
reports mean ± std of those per-seed means over ``n_seeds`` seeds. Everything is a pure
function of the seeds: the trained policies act deterministically and the random policy draws
its actions from a generator seeded with the episode seed.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .config import env_families, rl_config

__all__ = ["Episodes", "ControllerResult", "RandomPolicy", "run_episodes", "episode_returns",
           "evaluate", "evaluate_controllers", "held_out_seeds", "format_table"]

Policy = Callable[[np.ndarray], np.ndarray]


@dataclass(frozen=True)
class Episodes:
    """The first episode of each copy of one seeded vector env.

    Attributes
    ----------
    returns : ndarray, shape (N,)
        Undiscounted returns.
    lengths : ndarray of int, shape (N,)
        Steps.
    reasons : list of str
        ``info["termination_reason"]`` of each copy's last step.
    stats : dict of str to ndarray, shape (N,)
        The env's episode statistics (its ``episode_stats``) of each copy's last step.
    """

    returns: np.ndarray
    lengths: np.ndarray
    reasons: list[str]
    stats: dict[str, np.ndarray] = field(default_factory=dict)


@dataclass
class ControllerResult:
    """One controller on every held-out seed: the per-seed mean returns and every episode's
    length [steps], end reason and statistics (name -> one value per episode)."""

    seed_means: list[float] = field(default_factory=list)
    lengths: list[int] = field(default_factory=list)
    reasons: list[str] = field(default_factory=list)
    stats: dict[str, list[float]] = field(default_factory=dict)

    def add(self, episodes: Episodes) -> None:
        """Append one seed's episodes."""
        self.seed_means.append(float(episodes.returns.mean()))
        self.lengths.extend(int(n) for n in episodes.lengths)
        self.reasons.extend(episodes.reasons)
        for name, values in episodes.stats.items():
            self.stats.setdefault(name, []).extend(float(v) for v in values)

    @property
    def mean_std(self) -> tuple[float, float]:
        """Mean and standard deviation of the per-seed mean returns."""
        return float(np.mean(self.seed_means)), float(np.std(self.seed_means))

    def seeds_won(self, other: ControllerResult) -> int:
        """Seeds where this controller's mean return is above ``other``'s."""
        return sum(a > b for a, b in zip(self.seed_means, other.seed_means))


class RandomPolicy:
    """Uniform random actions in [-1, 1] from a generator seeded with ``seed``.

    Parameters
    ----------
    num_envs, act_dim : int
        Copies and action components.
    seed : int
        Seed of the generator (the same seed draws the same actions).
    """

    def __init__(self, num_envs: int, act_dim: int, seed: int) -> None:
        self.shape = (num_envs, act_dim)
        self.rng = np.random.default_rng(seed)

    def __call__(self, obs: np.ndarray) -> np.ndarray:
        return self.rng.uniform(-1.0, 1.0, self.shape).astype(np.float32)


def run_episodes(env_id: str, policy: Policy, seed: int, n_episodes: int,
                 env_kwargs: dict[str, Any] | None = None,
                 reset_policy: Callable[[np.ndarray | None], None] | None = None,
                 link: str | None = None) -> Episodes:
    """Run the first episode of ``n_episodes`` copies seeded ``seed + i`` under ``policy``
    (``(N, K) observations -> (N, A) actions``), behind ``link`` if given
    (``jvl_gym.envs.link``: ``"mactalk:19200"`` …).

    The vector env autoresets in SAME_STEP mode; a copy's steps after its first episode are
    not counted.
    """
    import gymnasium as gym
    from gymnasium.vector import AutoresetMode

    import jvl_gym  # noqa: F401

    from ..envs.registration import vector_class

    names = tuple(vector_class(env_id).episode_stats)
    stats = {name: np.zeros(n_episodes) for name in names}
    if link is not None:
        from ..envs.link import make_link_vec

        env = make_link_vec(env_id, n_episodes, link, AutoresetMode.SAME_STEP,
                            **(env_kwargs or {}))
    else:
        env = gym.make_vec(env_id, num_envs=n_episodes,
                           vectorization_mode="vector_entry_point",
                           autoreset_mode=AutoresetMode.SAME_STEP, **(env_kwargs or {}))
    obs, _ = env.reset(seed=seed)
    if reset_policy is not None:
        reset_policy(None)
    ret = np.zeros(n_episodes)
    length = np.zeros(n_episodes, dtype=np.int64)
    reasons = [""] * n_episodes
    alive = np.ones(n_episodes, dtype=bool)
    while alive.any():
        obs, reward, terminated, truncated, info = env.step(policy(obs))
        ret += np.where(alive, reward, 0.0)
        length += alive
        ended = alive & (terminated | truncated)
        if ended.any():
            for i in np.flatnonzero(ended):
                reasons[i] = str(info["termination_reason"][i])
            for name in names:
                stats[name][ended] = info[name][ended]
        alive &= ~ended
    env.close()
    return Episodes(ret, length, reasons, stats)


def episode_returns(env_id: str, policy: Policy, seed: int, n_episodes: int,
                    env_kwargs: dict[str, Any] | None = None,
                    reset_policy: Callable[[np.ndarray | None], None] | None = None
                    ) -> np.ndarray:
    """Returns of the first episode of ``n_episodes`` copies seeded ``seed + i``."""
    return run_episodes(env_id, policy, seed, n_episodes, env_kwargs, reset_policy).returns


def held_out_seeds(offset: int, n_seeds: int) -> list[int]:
    """The held-out seeds: ``offset + 1000·k`` for k < ``n_seeds``."""
    return [int(offset) + 1000 * k for k in range(n_seeds)]


def _model_policy(model_file: str | Path, default_algo: str) -> Policy:
    """The deterministic policy of a saved SB3 model; the algorithm is the last part of its
    file name (``*-ppo.zip``), else ``default_algo``."""
    from .config import ALGOS
    from .train import algo_class

    stem = Path(model_file).stem.rpartition("-")[2].upper()
    model = algo_class(stem if stem in ALGOS else default_algo).load(str(model_file),
                                                                     device="cpu")

    def policy(obs: np.ndarray) -> np.ndarray:
        return model.predict(obs, deterministic=True)[0]

    return policy


def evaluate_controllers(env_id: str, models: dict[str, str | Path], *,
                         family: str | None = None, n_seeds: int | None = None,
                         episodes_per_seed: int | None = None,
                         max_episode_steps: int | None = None, random_policy: bool = True,
                         config_dir: str | Path | None = None, progress_bar: bool = False,
                         link: str | None = None, env_kwargs: dict[str, Any] | None = None
                         ) -> dict[str, ControllerResult]:
    """The baseline, each model of ``models`` (label -> file) and (``random_policy``) uniform
    random actions on the held-out seeds of ``env_id`` on ``family`` (behind ``link`` if
    given, :func:`run_episodes`).

    ``env_kwargs`` go over the config's (an identified motor's,
    :func:`jvl_gym.envs.identified.env_kwargs_from_identification`).
    ``max_episode_steps`` shortens the episodes (never lengthens them). Keys of the result:
    ``"baseline"``, the labels of ``models``, ``"random"``.
    """
    import gymnasium as gym

    from ..envs.baselines import BASELINES, make_baseline
    from ..envs.registration import vector_class

    cfg = rl_config(env_id, config_dir, family=family)
    ev = cfg["eval"]
    n_ep = int(episodes_per_seed or ev["episodes_per_seed"])
    seeds = held_out_seeds(ev["seed_offset"], int(n_seeds or ev["n_seeds"]))
    kwargs = {**cfg["env_kwargs"], **(env_kwargs or {})}
    limit = gym.spec(env_id).max_episode_steps
    if max_episode_steps is not None and (limit is None or max_episode_steps < limit):
        kwargs["max_episode_steps"] = int(max_episode_steps)
    act_dim = len(vector_class(env_id).act_labels)
    policies = {label: _model_policy(path, cfg["algo"]) for label, path in models.items()}
    out = {label: ControllerResult() for label in ("baseline", *models)}
    if random_policy:
        out["random"] = ControllerResult()
    iterator: Any = seeds
    if progress_bar:
        from tqdm import tqdm

        iterator = tqdm(seeds, desc=f"evaluate {env_id} ({family or env_families(env_id)[0]})")
    for seed in iterator:
        bl = make_baseline(env_id, n_ep, act_dim, decimation=kwargs.get("decimation"),
                           motor_type=kwargs.get("motor_type"))
        out["baseline"].add(run_episodes(env_id, bl, seed, n_ep,
                                         {**kwargs, **BASELINES[env_id].env_kwargs}, bl.reset,
                                         link))
        for label, policy in policies.items():
            out[label].add(run_episodes(env_id, policy, seed, n_ep, kwargs, link=link))
        if random_policy:
            out["random"].add(run_episodes(env_id, RandomPolicy(n_ep, act_dim, seed), seed,
                                           n_ep, kwargs))
    return out


def evaluate(env_id: str, model_file: str | Path | None, n_seeds: int | None = None,
             episodes_per_seed: int | None = None, progress_bar: bool = True,
             config_dir: str | Path | None = None, family: str | None = None,
             link: str | None = None, env_kwargs: dict[str, Any] | None = None
             ) -> dict[str, tuple[float, float]]:
    """Mean ± std (over seeds) of the per-seed mean return of the policy and the baseline
    (behind ``link`` if given, on the env of ``env_kwargs`` over the config's), and
    ``seeds_won``: (seeds where the policy's mean beats the baseline's, seeds)."""
    models = {} if model_file is None else {"policy": model_file}
    res = evaluate_controllers(env_id, models, family=family, n_seeds=n_seeds,
                               episodes_per_seed=episodes_per_seed, random_policy=False,
                               config_dir=config_dir, progress_bar=progress_bar, link=link,
                               env_kwargs=env_kwargs)
    out = {k: v.mean_std for k, v in res.items()}
    if "policy" in res:
        out["seeds_won"] = (float(res["policy"].seeds_won(res["baseline"])),
                            float(len(res["baseline"].seed_means)))
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
