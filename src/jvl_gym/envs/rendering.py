"""How an env draws: the scope history of every copy and its plot for
``render_mode="rgb_array"`` (a part of :class:`~jvl_gym.envs.base.MotorVectorEnv`)."""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["Rendering"]


class Rendering:
    """The scope of an env's copies: :attr:`scope_channels` recorded after every reset and
    step (values from :meth:`_scope_values`), the last :attr:`scope_length` drawn."""

    #: names of the scope traces drawn by render (values from :meth:`_scope_values`)
    scope_channels: tuple[str, ...] = ()
    scope_length: int = 400

    num_envs: int
    render_mode: str | None
    motor_types: tuple[str, ...]
    decimation: int
    _scope: np.ndarray | None
    _scope_count: np.ndarray
    _figures: dict[int, Any]

    def _scope_values(self) -> np.ndarray:
        """Scope traces (N, C) in the units of :attr:`scope_channels`."""
        return np.zeros((self.num_envs, len(self.scope_channels)))

    def _record_scope(self) -> None:
        if self.render_mode is None:
            return
        if self._scope is None:
            self._scope = np.zeros((self.num_envs, len(self.scope_channels),
                                    self.scope_length), dtype=np.float32)
        k = self._scope_count % self.scope_length
        self._scope[np.arange(self.num_envs), :, k] = self._scope_values()
        self._scope_count += 1

    def scope_trace(self, index: int = 0) -> np.ndarray:
        """The recorded scope history of copy ``index``, (C, T) oldest first."""
        if self._scope is None:
            return np.zeros((len(self.scope_channels), 0), dtype=np.float32)
        count = int(self._scope_count[index])
        n = min(count, self.scope_length)
        order = (np.arange(count - n, count)) % self.scope_length
        return self._scope[index][:, order]

    def render_env(self, index: int = 0) -> np.ndarray | None:
        """Scope plot of copy ``index``: (H, W, 3) uint8 (``render_mode="rgb_array"``)."""
        if self.render_mode is None:
            return None
        from .scope import draw_scope

        dt = self.step_seconds(self.motor_types, self.decimation)
        return draw_scope(self._figures, index, self.scope_trace(index), self.scope_channels, dt,
                          title=f"{type(self).__name__.replace('VectorEnv', '')} #{index}")

    def render(self) -> tuple[np.ndarray, ...] | None:
        """One scope image per copy (``render_mode="rgb_array"``), else None."""
        if self.render_mode is None:
            return None
        return tuple(self.render_env(i) for i in range(self.num_envs))

    def close_extras(self, **kwargs: Any) -> None:
        """Release the scope figures."""
        from .scope import close_figures

        close_figures(self._figures)
