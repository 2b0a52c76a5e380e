"""How an env steps: the action checks, the step of every copy, the autoreset modes and why an
episode ended (a part of :class:`~jvl_gym.envs.base.MotorVectorEnv`).

Autoreset (``gymnasium.vector.AutoresetMode``): ``NEXT_STEP`` resets a finished copy on its next
step (its actions ignored, reward 0); ``SAME_STEP`` resets it in the step that ended it and
reports the final observation in ``info["final_obs"]``; ``DISABLED`` refuses to step a finished
copy until it is reset (``reset_mask``). ``info["termination_reason"]`` says why each episode
that ended in a step ended, and the task's episode statistics (``episode_stats``: settle time,
tension error, lost steps, copper loss …) say how it went, one ``info[name]`` each, read from the
task's state and the motors when the episode ends.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium.vector import AutoresetMode

from .validation import env_name

__all__ = ["Stepping", "TIME_LIMIT"]

_FLOAT64 = np.dtype(np.float64)
#: ``info["termination_reason"]`` of a copy truncated at its horizon
TIME_LIMIT = "time limit: max_episode_steps reached (truncated)"


class Stepping:
    """The steps of an env's copies."""

    num_envs: int
    act_labels: tuple[str, ...]
    autoreset_mode: AutoresetMode
    render_mode: str | None
    terminal_errors: tuple[tuple[str, int], ...]
    error_register: str
    #: the statistics of an ended episode a task reports in ``info`` (:meth:`_episode_stats`):
    #: name -> what it is, with its unit
    episode_stats: dict[str, str] = {}
    motors: Any
    _action_shape: tuple[int, int]
    _has_reset: bool
    _autoreset: np.ndarray
    _obs: np.ndarray
    _reward: np.ndarray
    _terminated: np.ndarray
    _truncated: np.ndarray

    def _step_batch(self, actions: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray,
                                                  np.ndarray]:
        """One step of every copy, without autoreset.

        Returns the internal (obs, reward, terminated, truncated) buffers: copy what you keep.
        """
        if not self._has_reset:
            raise RuntimeError("call reset() before step()")
        a = actions if type(actions) is np.ndarray else np.asarray(actions)
        if a.shape != self._action_shape or a.dtype.kind not in "fiu":
            self._refuse_action(a)
        if a.dtype is not _FLOAT64 or not a.flags.c_contiguous:  # as the compiled step takes it
            a = np.ascontiguousarray(a, dtype=np.float64)
        self._step_actions(a)
        return self._obs, self._reward, self._terminated, self._truncated

    def _step_actions(self, actions: np.ndarray) -> None:
        """One step of every copy, without autoreset, with checked ``actions`` ((N, A)
        float64, C-contiguous): raises RuntimeError before the first reset, ValueError
        (nothing stepped) when an action is not finite; fills the (obs, reward, terminated,
        truncated) buffers."""
        if not self._has_reset:
            raise RuntimeError("call reset() before step()")
        if not self._step_copies(actions):
            raise ValueError("action must be finite")
        if self.render_mode is not None:
            self._record_scope()

    def _refuse_action(self, a: np.ndarray, shape: tuple[int, ...] | None = None) -> None:
        """Raise the ValueError of an action array ``a`` that is not real numbers of shape
        ``shape`` (default: (num_envs, actions))."""
        shape = self._action_shape if shape is None else shape
        labels = ", ".join(self.act_labels)
        if a.shape != shape:
            hint = " (transposed?)" if a.shape == shape[::-1] and len(shape) == 2 else ""
            raise ValueError(f"{env_name(type(self))}: action must have shape {shape} "
                             f"({labels}), got {a.shape}{hint}; nothing was stepped")
        raise ValueError(f"{env_name(type(self))}: action must be real numbers (a float "
                         f"array), got dtype {a.dtype}; nothing was stepped")

    def step(self, actions: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray,
                                          dict[str, Any]]:
        """Step every copy; finished copies are reset as ``autoreset_mode`` says."""
        done_before = self._autoreset.copy()
        if self.autoreset_mode == AutoresetMode.DISABLED and done_before.any():
            raise RuntimeError("AutoresetMode.DISABLED: reset the finished copies (reset_mask) "
                               "before stepping")
        infos: dict[str, Any] = {}
        if self.autoreset_mode == AutoresetMode.NEXT_STEP and done_before.all():
            # every copy starts a new episode: nothing to step (the actions are ignored)
            self._reset_envs(np.arange(self.num_envs), [None] * self.num_envs, None)
            self._autoreset[:] = False
            self._record_scope()
            zeros = np.zeros(self.num_envs, dtype=np.bool_)
            return self._obs.copy(), np.zeros(self.num_envs), zeros, zeros.copy(), infos
        obs, reward, terminated, truncated = self._step_batch(actions)
        reward = reward.copy()
        terminated = terminated.copy()
        truncated = truncated.copy()
        done = terminated | truncated
        any_done = done.any()
        if any_done:
            ended = done & ~done_before
            if ended.any():
                infos.update(self._end_info(ended, terminated))
        if self.autoreset_mode == AutoresetMode.NEXT_STEP and done_before.any():
            idx = done_before.nonzero()[0]
            self._reset_envs(idx, [None] * idx.size, None)
            reward[idx] = 0.0
            terminated[idx] = False
            truncated[idx] = False
            done[idx] = False
        elif self.autoreset_mode == AutoresetMode.SAME_STEP:
            if any_done:
                idx = done.nonzero()[0]
                final = np.full(self.num_envs, None, dtype=object)
                for i in idx:
                    final[i] = obs[i].copy()
                self._reset_envs(idx, [None] * idx.size, None)
                infos.update({"final_obs": final, "_final_obs": done.copy(),
                              "final_info": {}, "_final_info": done.copy()})
        self._autoreset = done
        return self._obs.copy(), reward, terminated, truncated, infos

    # ------------------------------------------------------------------ why episodes end
    def _termination_reasons(self, idx: np.ndarray) -> list[str]:
        """Why each of the copies ``idx``, terminated by the last step, ended (one text per
        copy). Here: the motor error bits; a task adds its own reasons."""
        return [text or "terminated by the task" for text in self._error_reasons(idx)]

    def _error_reasons(self, idx: np.ndarray) -> list[str]:
        """The error bits that end an episode of each copy of ``idx``, as text ('' if none)."""
        return [self._error_text(bits) for bits in self.error_bits()[idx].tolist()]

    def _error_text(self, bits: int) -> str:
        """``bits`` of :attr:`error_register` as text (kept per value: a step may end many
        copies)."""
        texts = self._error_texts
        text = texts.get(bits)
        if text is None:
            names = "+".join(name for name, bit in self.terminal_errors if bits & bit)
            text = texts[bits] = f"motor error {names} ({self.error_register})" if bits else ""
        return text

    def _end_reasons(self, idx: np.ndarray, by_task: np.ndarray) -> list[str]:
        """Why the episode of each of the copies ``idx`` ended with the last step: the task's
        reason (:meth:`_termination_reasons`) where ``by_task`` ((M,) bool: terminated),
        :data:`TIME_LIMIT` where not (truncated)."""
        flags = by_task.tolist()
        if not any(flags):
            return [TIME_LIMIT] * idx.size
        task = iter(self._termination_reasons(idx[by_task]))
        return [next(task) if flag else TIME_LIMIT for flag in flags]

    def _episode_stats(self, idx: np.ndarray) -> dict[str, np.ndarray]:
        """The statistics (:attr:`episode_stats`) of the episodes of copies ``idx`` that ended
        with the last step, name -> (M,) float64; read before the copies are reset. Here:
        none; a task reports its own."""
        return {}

    def _end_info(self, ended: np.ndarray, terminated: np.ndarray) -> dict[str, np.ndarray]:
        """``{"termination_reason": (N,) object array, "_termination_reason": ended}`` for the
        copies ``ended`` (bool (N,)) whose episode ended with the last step: the task's reason
        when terminated (:meth:`_termination_reasons`), :data:`TIME_LIMIT` when truncated;
        and per episode statistic ``name`` (:meth:`_episode_stats`) ``info[name]``, (N,)
        float64 (0 for copies that did not end), with its mask ``info["_" + name]``."""
        reasons = np.empty(self.num_envs, dtype=object)
        reasons.fill("")
        idx = ended.nonzero()[0]
        reasons[idx] = self._end_reasons(idx, terminated[idx])
        out = {"termination_reason": reasons, "_termination_reason": ended.copy()}
        for name, values in self._episode_stats(idx).items():
            column = np.zeros(self.num_envs)
            column[idx] = values
            out[name], out["_" + name] = column, ended.copy()
        return out

    def error_bits(self) -> np.ndarray:
        """The error bits that end an episode (:attr:`terminal_errors` of
        :attr:`error_register`), (N,) int64 (0 when none is set)."""
        if not self.terminal_errors:
            return np.zeros(self.num_envs, dtype=np.int64)
        mask = 0
        for _, bit in self.terminal_errors:
            mask |= bit
        return self.motors.read_raw(self.error_register) & mask
