"""A task whose step is written in numpy over the copies instead of compiled hooks.

For tasks whose step is not dominated by the motor kernel (FilterTuning runs a whole
commissioning trial per step). The task is declared like every other
(:class:`~jvl_gym.envs.task.Task`: the capabilities it needs), without hooks, and its env
implements four methods vectorised over the copies.
"""

from __future__ import annotations

from abc import abstractmethod

import numpy as np

from ..engine.driver import all_finite
from ..motor.noise import normals
from .base import MotorVectorEnv
from .compiled import OBS_BOUND

__all__ = ["NumpyTaskEnv"]


class NumpyTaskEnv(MotorVectorEnv):
    """A task whose step is :meth:`_apply_action`, :meth:`_advance`,
    :meth:`_reward_termination` and :meth:`_observe`, in numpy over the copies."""

    @abstractmethod
    def _apply_action(self, action: np.ndarray) -> None:
        """Apply the (N, A) action in [-1, 1] (inputs, register writes)."""

    def _advance(self) -> None:
        """Advance the motors and the process by ``self.decimation`` outer samples."""
        self.motors.step(self.decimation)

    @abstractmethod
    def _reward_termination(self, action: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Reward (N,) float64 and termination (N,) bool after a step."""

    @abstractmethod
    def _observe(self) -> np.ndarray:
        """Normalised observation (N, K) before noise and clipping."""

    def _finish_obs(self, obs: np.ndarray) -> np.ndarray:
        if self.obs_noise > 0.0:
            obs = obs + self.obs_noise * normals(self._noise_key, self._t, obs.shape[1])
        return np.clip(obs, -OBS_BOUND, OBS_BOUND).astype(np.float32)

    def _observe_copies(self, idx: np.ndarray) -> None:
        self._obs[idx] = self._finish_obs(self._observe())[idx]

    def _step_copies(self, actions: np.ndarray) -> bool:
        if not all_finite(actions):
            return False
        a = np.clip(actions, -1.0, 1.0)
        self._apply_action(a)
        self._advance()
        self._t += 1
        reward, terminated = self._reward_termination(a)
        self._reward[:] = reward
        self._terminated[:] = terminated
        self._truncated[:] = (self._t >= self.max_episode_steps) & ~terminated
        self._prev_action[:] = a
        self._obs[:] = self._finish_obs(self._observe())
        return True
