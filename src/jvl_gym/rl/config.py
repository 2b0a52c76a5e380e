"""RL hyper-parameters: ``configs/rl/*.yml``, each a mapping keyed by env id.

Each entry holds ``algo`` (PPO or SAC), ``n_envs``, ``total_timesteps``, ``policy``,
``env_kwargs`` (constructor arguments), ``hyperparams`` (algorithm keyword arguments;
``policy_kwargs.net_arch`` as a list), ``eval`` (``n_seeds``, ``episodes_per_seed``,
``seed_offset``: held-out seeds start there) and ``seed``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml

from ..config import configs_dir

__all__ = ["load_rl_configs", "rl_config"]

_DEFAULTS: dict[str, Any] = {
    "algo": "PPO", "n_envs": 16, "total_timesteps": 200_000, "policy": "MlpPolicy",
    "env_kwargs": {}, "hyperparams": {}, "seed": 0,
    "eval": {"n_seeds": 5, "episodes_per_seed": 8, "seed_offset": 100_000},
}


def load_rl_configs(directory: str | Path | None = None) -> dict[str, dict[str, Any]]:
    """Every env id's config from the ``*.yml`` files of ``directory`` (default
    ``configs/rl``), with defaults filled in."""
    root = Path(directory) if directory is not None else configs_dir() / "rl"
    out: dict[str, dict[str, Any]] = {}
    for path in sorted(root.glob("*.yml")):
        data = yaml.safe_load(path.read_text()) or {}
        if not isinstance(data, dict):
            raise ValueError(f"{path}: expected a mapping keyed by env id")
        for env_id, cfg in data.items():
            if env_id in out:
                raise ValueError(f"{path}: {env_id} is configured twice")
            unknown = set(cfg) - set(_DEFAULTS)
            if unknown:
                raise ValueError(f"{path}: {env_id}: unknown keys {sorted(unknown)}")
            merged = {**_DEFAULTS, **cfg}
            merged["eval"] = {**_DEFAULTS["eval"], **cfg.get("eval", {})}
            out[env_id] = merged
    return out


def rl_config(env_id: str, directory: str | Path | None = None) -> dict[str, Any]:
    """The config of one env id."""
    configs = load_rl_configs(directory)
    if env_id not in configs:
        raise KeyError(f"no RL config for {env_id!r}; configured: {sorted(configs)}")
    return configs[env_id]
