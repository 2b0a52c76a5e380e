"""Gymnasium environments over the batched motor simulators.

Every env is a ``gymnasium.Env`` (``*Env``) and a native ``gymnasium.vector.VectorEnv``
(``*VectorEnv``) sharing one implementation (:mod:`jvl_gym.envs.base`). Ids:
``jvl_gym/Positioning-v0``, ``jvl_gym/FilterTuning-v0``, ``jvl_gym/GearSync-v0``,
``jvl_gym/CoilWinding-v0`` on the MAC050–141 servos (all but CoilWinding also on the MAC800
family: the family follows from ``motor_type``), ``jvl_gym/StepperIndexing-v0`` on the MIS
step motors (registered when ``jvl_gym`` is imported). See ``docs/envs.md``.
"""

from __future__ import annotations

from typing import Any

from .registration import ENV_IDS, register_envs

__all__ = ["ENV_IDS", "register_envs"]

_CLASSES = {
    "PositioningEnv": "positioning", "PositioningVectorEnv": "positioning",
    "FilterTuningEnv": "filter_tuning", "FilterTuningVectorEnv": "filter_tuning",
    "GearSyncEnv": "gear_sync", "GearSyncVectorEnv": "gear_sync",
    "CoilWindingEnv": "coil_winding", "CoilWindingVectorEnv": "coil_winding",
    "StepperIndexingEnv": "stepper_indexing", "StepperIndexingVectorEnv": "stepper_indexing",
}


def __getattr__(name: str) -> Any:
    if name in _CLASSES:
        import importlib

        return getattr(importlib.import_module(f".{_CLASSES[name]}", __name__), name)
    raise AttributeError(f"module 'jvl_gym.envs' has no attribute {name!r}")
