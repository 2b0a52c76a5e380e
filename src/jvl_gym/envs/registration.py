"""Gymnasium registration of the jvl_gym environments (no kernel compilation at import)."""

from __future__ import annotations

from typing import Any

import gymnasium as gym

__all__ = ["ENV_IDS", "register_envs", "vector_class"]

#: env id -> (module, single class, vector class, max_episode_steps)
_ENVS = {
    "jvl_gym/Positioning-v0": ("positioning", "PositioningEnv", "PositioningVectorEnv", 300),
    "jvl_gym/FilterTuning-v0": ("filter_tuning", "FilterTuningEnv", "FilterTuningVectorEnv", 1),
    "jvl_gym/GearSync-v0": ("gear_sync", "GearSyncEnv", "GearSyncVectorEnv", 1500),
    "jvl_gym/CoilWinding-v0": ("coil_winding", "CoilWindingEnv", "CoilWindingVectorEnv", 1200),
    "jvl_gym/StepperIndexing-v0": ("stepper_indexing", "StepperIndexingEnv",
                                   "StepperIndexingVectorEnv", 1000),
}
ENV_IDS: tuple[str, ...] = tuple(_ENVS)


def register_envs() -> None:
    """Register every env id with ``entry_point``, ``vector_entry_point`` and
    ``max_episode_steps`` (idempotent)."""
    for env_id, (module, single, vector, steps) in _ENVS.items():
        if env_id in gym.registry:
            continue
        gym.register(
            id=env_id,
            entry_point=f"jvl_gym.envs.{module}:{single}",
            vector_entry_point=f"jvl_gym.envs.{module}:{vector}",
            max_episode_steps=steps,
        )


def vector_class(env_id: str) -> Any:
    """The native vector env class of ``env_id`` (its ``vector_entry_point``), imported."""
    import importlib

    register_envs()
    module, _, cls = gym.spec(env_id).vector_entry_point.partition(":")
    return getattr(importlib.import_module(module), cls)
