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

from collections.abc import Callable, Hashable
from typing import Any

import numpy as np
from gymnasium.vector import AutoresetMode

from .validation import env_name

__all__ = ["Stepping", "TERMINATED", "TIME_LIMIT"]

_FLOAT64 = np.dtype(np.float64)
#: ``info["termination_reason"]`` of a copy truncated at its horizon
TIME_LIMIT = "time limit: max_episode_steps reached (truncated)"
#: the reason of a copy terminated by its task for none of the reasons the task names
TERMINATED = "terminated by the task"
#: the distinct texts :meth:`Stepping._kept_texts` keeps per kind before it starts anew
_KEPT_TEXTS = 4096


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
        # counted, not reduced with any()/all(): a count of 1024 flags is a third of the time
        n_before = np.count_nonzero(done_before)
        mode = self.autoreset_mode
        if mode == AutoresetMode.DISABLED and n_before:
            raise RuntimeError("AutoresetMode.DISABLED: reset the finished copies (reset_mask) "
                               "before stepping")
        infos: dict[str, Any] = {}
        if mode == AutoresetMode.NEXT_STEP and n_before == self.num_envs:
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
        n_done = np.count_nonzero(done)
        if n_done:
            ended = done & ~done_before if n_before else done
            if not n_before or np.count_nonzero(ended):
                infos.update(self._end_info(ended, terminated))
        if mode == AutoresetMode.NEXT_STEP and n_before:
            idx = done_before.nonzero()[0]
            self._reset_envs(idx, [None] * idx.size, None)
            reward[idx] = 0.0
            terminated[idx] = False
            truncated[idx] = False
            done[idx] = False
        elif mode == AutoresetMode.SAME_STEP:
            if n_done:
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
        """Why each of the copies ``idx`` ((M,) int), terminated by the last step, ended (one
        text per copy). Here: the motor error bits; a task adds its own reasons."""
        return self._kept_texts(self._error_bits_of(idx).tolist(), self._error_or_task, ())

    def _error_or_task(self, bits: int) -> str:
        """The reason of a copy terminated with the error bits ``bits``: their text, or "by the
        task" when none is set."""
        return self._error_text(bits) or TERMINATED

    def _error_text(self, bits: int) -> str:
        """``bits`` of :attr:`error_register` as text (kept per value: a step may end many
        copies)."""
        texts = self._error_texts
        text = texts.get(bits)
        if text is None:
            names = "+".join(name for name, bit in self.terminal_errors if bits & bit)
            text = texts[bits] = f"motor error {names} ({self.error_register})" if bits else ""
        return text

    def _kept_texts(self, codes: list[Hashable], make: Callable[[Any], str],
                    key: tuple[Any, ...]) -> list[str]:
        """The text ``make(code)`` of each of ``codes`` (one per copy), made once per distinct
        code and then looked up.

        The texts are kept per ``make`` (a named method or function: its name tells the kinds of
        text apart) and ``key``: ``key`` holds the values of the attributes besides the code that
        a text is made of (e.g. a threshold it names), so that a text made before such an
        attribute changes is not reused after.
        """
        every = self.__dict__.get("_texts_kept")
        if every is None:
            every = self._texts_kept = {}
        kept = every.get((make.__name__, *key))
        if kept is None:
            kept = every[(make.__name__, *key)] = {}
        try:
            return [kept[code] for code in codes]
        except KeyError:  # a code's first time
            if len(kept) > _KEPT_TEXTS:  # e.g. a count in the texts: keep the dict bounded
                kept.clear()
            for code in codes:
                if code not in kept:
                    kept[code] = make(code)
            return [kept[code] for code in codes]

    def _end_reasons(self, idx: np.ndarray, by_task: np.ndarray) -> list[str]:
        """Why the episode of each of the copies ``idx`` ((M,) int) ended with the last step:
        the task's reason (:meth:`_termination_reasons`) where ``by_task`` ((M,) bool:
        terminated), :data:`TIME_LIMIT` where not (truncated)."""
        flags = by_task.tolist()
        if not any(flags):
            return [TIME_LIMIT] * idx.size
        if all(flags):
            return self._termination_reasons(idx)
        task = iter(self._termination_reasons(idx[by_task]))
        return [next(task) if flag else TIME_LIMIT for flag in flags]

    def _episode_stats(self, idx: np.ndarray) -> dict[str, np.ndarray]:
        """The statistics (:attr:`episode_stats`) of the episodes of copies ``idx`` ((M,) int)
        that ended with the last step, name -> (M,) float64; read before the copies are reset.
        Here: none; a task reports its own."""
        return {}

    def _end_info(self, ended: np.ndarray, terminated: np.ndarray) -> dict[str, np.ndarray]:
        """``{"termination_reason": (N,) object array, "_termination_reason": ended}`` for the
        copies ``ended`` (bool (N,)) whose episode ended with the last step: the task's reason
        when terminated (:meth:`_termination_reasons`), :data:`TIME_LIMIT` when truncated, ''
        for the other copies; and per episode statistic ``name`` (:meth:`_episode_stats`)
        ``info[name]``, (N,) float64 (0 for copies that did not end), with its mask
        ``info["_" + name]``. Every mask is an array of its own (a copy of ``ended``)."""
        n = self.num_envs
        idx = ended.nonzero()[0]
        task = idx[terminated[idx]]  # the copies the task terminated
        reasons = np.empty(n, dtype=object)
        if task.size == idx.size:
            reasons.fill("")
            reasons.put(idx, self._termination_reasons(idx))
        else:  # TIME_LIMIT for every ended copy, then the task's reasons over it
            if idx.size == n:
                reasons.fill(TIME_LIMIT)
            else:
                reasons.fill("")
                reasons.put(idx, TIME_LIMIT)
            if task.size:
                reasons.put(task, self._termination_reasons(task))
        out = {"termination_reason": reasons, "_termination_reason": ended.copy()}
        every = idx.size == n
        for name, values in self._episode_stats(idx).items():
            if every:  # idx is 0 … N-1
                column = np.empty(n)
                column[:] = values
            else:
                column = np.zeros(n)
                column[idx] = values
            out[name], out["_" + name] = column, ended.copy()
        return out

    def error_bits(self) -> np.ndarray:
        """The error bits that end an episode (:attr:`terminal_errors` of
        :attr:`error_register`), (N,) int64 (0 when none is set)."""
        mask = self._error_mask()
        if not mask:
            return np.zeros(self.num_envs, dtype=np.int64)
        return self.motors.read_raw(self.error_register) & mask

    def _error_bits_of(self, idx: np.ndarray) -> np.ndarray:
        """:meth:`error_bits` of the copies ``idx`` ((M,) int) alone, (M,) int64."""
        mask = self._error_mask()
        if not mask:
            return np.zeros(idx.size, dtype=np.int64)
        return self.motors.read_raw(self.error_register, idx) & mask

    def _error_mask(self) -> np.int64:
        """The mask of the bits of :attr:`terminal_errors` (an int64 scalar: the cheaper operand
        of ``&`` with an int64 array), kept while the attribute holds the same object."""
        errors = self.terminal_errors
        kept = self.__dict__.get("_error_mask_kept")
        if kept is None or kept[0] is not errors:
            mask = 0
            for _, bit in errors or ():
                mask |= bit
            kept = self._error_mask_kept = (errors, np.int64(mask))
        return kept[1]
