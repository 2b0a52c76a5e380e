"""The ``gymnasium.Env`` view of a task: a one-copy :class:`~jvl_gym.envs.base.MotorVectorEnv`.

Single and vector envs share one implementation, so a single env seeded ``s`` and copy ``i`` of
a vector env seeded ``s - i`` produce identical trajectories for the same actions.
"""

from __future__ import annotations

from typing import Any, ClassVar

import gymnasium as gym
import numpy as np
from gymnasium.vector import AutoresetMode

from .base import MotorVectorEnv

__all__ = ["MotorEnv"]


class MotorEnv(gym.Env):
    """Single-copy environment over the vector core ``vector_class`` (see subclasses)."""

    vector_class: ClassVar[type[MotorVectorEnv]] = MotorVectorEnv
    metadata: dict[str, Any] = {"render_modes": ["rgb_array"], "render_fps": 25}

    def __init__(self, render_mode: str | None = None, **kwargs: Any) -> None:
        if "num_envs" in kwargs or "autoreset_mode" in kwargs:
            raise TypeError("a single env takes neither num_envs nor autoreset_mode")
        self.core = self.vector_class(num_envs=1, render_mode=render_mode,
                                      autoreset_mode=AutoresetMode.DISABLED, **kwargs)
        self.render_mode = render_mode
        self.observation_space = self.core.single_observation_space
        self.action_space = self.core.single_action_space
        self._ended = False
        self._action_shape = self.action_space.shape
        #: the action as the core takes it, (1, A) float64 (filled at each step)
        self._action = np.zeros((1, *self._action_shape))

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None
              ) -> tuple[np.ndarray, dict[str, Any]]:
        """Start an episode (see the class docstring, "Starting State")."""
        super().reset(seed=seed)
        if options and "reset_mask" in options:
            raise ValueError("reset_mask is a vector-env option")
        obs, _ = self.core.reset(seed=None if seed is None else [seed], options=options)
        self._ended = False
        return obs[0], {}

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        """Advance by ``decimation`` outer samples with ``action`` (see "Action Space").

        When the episode ends, ``info["termination_reason"]`` says why and ``info[name]`` gives
        each of the task's episode statistics (``episode_stats``) as a float. Stepping an ended
        episode raises RuntimeError (call :meth:`reset`), as the vector env does.
        """
        if self._ended:
            raise RuntimeError(f"{type(self).__name__}: the episode has ended (terminated or "
                               "truncated); call reset() before step()")
        a = action if type(action) is np.ndarray else np.asarray(action)
        core = self.core
        if a.shape != self._action_shape or a.dtype.kind not in "fiu":
            core._refuse_action(a, self._action_shape)
        self._action[...] = a
        core._step_actions(self._action)
        if core._terminated.item() or core._truncated.item():
            return self._end_of_episode(core)
        return core._obs.ravel().copy(), core._reward.item(), False, False, {}

    def _end_of_episode(self, core: MotorVectorEnv) -> tuple[np.ndarray, float, bool, bool,
                                                             dict[str, Any]]:
        """What :meth:`step` returns for the step that ended the episode (the episode marked
        ended): the info holds why it ended and the task's episode statistics."""
        self._ended = True
        first = np.zeros(1, dtype=np.int64)
        info: dict[str, Any] = {"termination_reason": core._end_reasons(first,
                                                                        core._terminated)[0]}
        info.update({name: float(values[0])
                     for name, values in core._episode_stats(first).items()})
        return (core._obs.ravel().copy(), core._reward.item(), core._terminated.item(),
                core._truncated.item(), info)

    def render(self) -> np.ndarray | None:
        """The scope plot as an (H, W, 3) uint8 image when ``render_mode="rgb_array"``."""
        return self.core.render_env(0)

    def close(self) -> None:
        """Release the scope figure."""
        self.core.close()

    @property
    def motors(self) -> Any:
        """The one-motor :class:`~jvl_gym.MotorArray` under the env."""
        return self.core.motors
