"""An SB3 ``VecEnv`` over a native ``gymnasium.vector.VectorEnv`` of jvl_gym.

Stable-Baselines3 cannot take a gymnasium VectorEnv directly. :class:`SB3VecEnv` runs the native
vector env in SAME_STEP autoreset mode and translates its results to SB3's conventions: ``dones =
terminated | truncated``, and for a finished copy ``infos[i]["terminal_observation"]`` (the last
observation of the episode; the returned observation is already the reset one) and
``infos[i]["TimeLimit.truncated"]`` (truncated and not terminated). Seeds set with ``seed()``
and options set with ``set_options()`` are used at the next ``reset()``.

Attributes and methods are those of the one native env, shared by all copies: ``get_attr``
returns the attribute once per requested copy; ``set_attr`` sets it (for a per-copy (N, ...)
ndarray attribute only the requested rows; any other attribute only for all copies).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np
from gymnasium.vector import AutoresetMode
from stable_baselines3.common.vec_env.base_vec_env import VecEnv, VecEnvIndices, VecEnvStepReturn

__all__ = ["SB3VecEnv", "make_sb3_env"]


class SB3VecEnv(VecEnv):
    """SB3 view of a native vector env (which must use ``AutoresetMode.SAME_STEP``).

    Parameters
    ----------
    venv : gymnasium.vector.VectorEnv
        The native vector env.
    """

    def __init__(self, venv: Any) -> None:
        if venv.metadata.get("autoreset_mode") != AutoresetMode.SAME_STEP:
            raise ValueError("SB3VecEnv needs a vector env with AutoresetMode.SAME_STEP")
        self.venv = venv
        self._actions: np.ndarray | None = None
        super().__init__(venv.num_envs, venv.single_observation_space,
                         venv.single_action_space)

    # ------------------------------------------------------------------ stepping
    def reset(self) -> np.ndarray:
        """Reset every copy with the seeds/options set since the last reset."""
        seeds = None if all(s is None for s in self._seeds) else list(self._seeds)
        options = next((o for o in self._options if o), None)
        obs, _ = self.venv.reset(seed=seeds, options=options)
        self.reset_infos = [{} for _ in range(self.num_envs)]
        self._reset_seeds()
        self._reset_options()
        return obs

    def step_async(self, actions: np.ndarray) -> None:
        """Store the actions for :meth:`step_wait`."""
        self._actions = np.asarray(actions)

    def step_wait(self) -> VecEnvStepReturn:
        """Step the native env; finished copies are already reset (SAME_STEP)."""
        if self._actions is None:
            raise RuntimeError("step_async must be called before step_wait")
        actions = self._actions.reshape(self.num_envs, -1)
        obs, reward, terminated, truncated, info = self.venv.step(actions)
        self._actions = None
        dones = terminated | truncated
        infos: list[dict[str, Any]] = [{} for _ in range(self.num_envs)]
        if dones.any():
            final = info["final_obs"]
            for i in np.flatnonzero(dones):
                infos[i]["terminal_observation"] = final[i]
                infos[i]["TimeLimit.truncated"] = bool(truncated[i] and not terminated[i])
        return obs, reward.astype(np.float32), dones, infos

    def close(self) -> None:
        """Close the native env."""
        self.venv.close()

    # ------------------------------------------------------------------ attributes
    def _indices(self, indices: VecEnvIndices) -> list[int]:
        if indices is None:
            return list(range(self.num_envs))
        if isinstance(indices, (int, np.integer)):
            return [int(indices)]
        return [int(i) for i in (indices if isinstance(indices, Iterable) else [indices])]

    def get_attr(self, attr_name: str, indices: VecEnvIndices = None) -> list[Any]:
        """The native env's attribute, once per requested copy (per-copy rows for (N, ...)
        ndarray attributes)."""
        value = getattr(self.venv, attr_name)
        idx = self._indices(indices)
        if isinstance(value, np.ndarray) and value.ndim >= 1 and value.shape[0] == self.num_envs:
            return [value[i] for i in idx]
        return [value for _ in idx]

    def set_attr(self, attr_name: str, value: Any, indices: VecEnvIndices = None) -> None:
        """Set an attribute (see the module docstring for per-copy attributes)."""
        idx = self._indices(indices)
        current = getattr(self.venv, attr_name, None)
        if (isinstance(current, np.ndarray) and current.ndim >= 1
                and current.shape[0] == self.num_envs):
            current[idx] = value
            return
        if sorted(idx) != list(range(self.num_envs)):
            raise ValueError(f"{attr_name!r} is shared by all copies of the native vector env; "
                             "set it for all indices")
        setattr(self.venv, attr_name, value)

    def env_method(self, method_name: str, *method_args: Any, indices: VecEnvIndices = None,
                   **method_kwargs: Any) -> list[Any]:
        """Call a method of the native env once; its result is returned per requested copy."""
        result = getattr(self.venv, method_name)(*method_args, **method_kwargs)
        return [result for _ in self._indices(indices)]

    def env_is_wrapped(self, wrapper_class: type, indices: VecEnvIndices = None) -> list[bool]:
        """Native copies are never wrapped."""
        return [False for _ in self._indices(indices)]

    def get_images(self) -> Sequence[np.ndarray | None]:
        """One scope image per copy (``render_mode="rgb_array"``)."""
        frames = self.venv.render()
        return list(frames) if frames is not None else [None] * self.num_envs


def make_sb3_env(env_id: str, num_envs: int, link: Any = None, **env_kwargs: Any
                 ) -> SB3VecEnv:
    """``gymnasium.make_vec(env_id, num_envs, vector_entry_point, SAME_STEP)`` for SB3; with
    ``link`` (a ``jvl_gym.envs.link.Link`` or its text, e.g. ``"mactalk:19200"``) the env
    behind that link."""
    import gymnasium as gym

    import jvl_gym  # noqa: F401  (registers the ids)

    if link is not None:
        from ..envs.link import make_link_vec

        return SB3VecEnv(make_link_vec(env_id, num_envs, link, AutoresetMode.SAME_STEP,
                                       **env_kwargs))

    venv = gym.make_vec(env_id, num_envs=num_envs, vectorization_mode="vector_entry_point",
                        autoreset_mode=AutoresetMode.SAME_STEP, **env_kwargs)
    return SB3VecEnv(venv)
