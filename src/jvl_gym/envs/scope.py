"""Scope plots for ``render_mode="rgb_array"``: recorded traces drawn as an RGB image."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

__all__ = ["draw_scope", "close_figures"]

WIDTH_PX, HEIGHT_PX, DPI = 640, 400, 80


def draw_scope(figures: dict[int, Any], key: int, trace: np.ndarray, labels: Sequence[str],
               dt: float, title: str = "") -> np.ndarray:
    """Draw ``trace`` (C, T), one panel per channel, and return an (H, W, 3) uint8 image.

    The figure is kept in ``figures[key]`` and reused (creating a figure is the slow part).
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    n = max(len(labels), 1)
    fig = figures.get(key)
    if fig is None or len(fig.axes) != n:
        fig = Figure(figsize=(WIDTH_PX / DPI, HEIGHT_PX / DPI), dpi=DPI)
        FigureCanvasAgg(fig)
        fig.subplots(n, 1, sharex=True)
        figures[key] = fig
    t = np.arange(trace.shape[1]) * dt
    for k, ax in enumerate(fig.axes):
        ax.clear()
        if k < trace.shape[0]:
            ax.plot(t, trace[k], lw=1.0, color=f"C{k}")
        ax.set_ylabel(labels[k] if k < len(labels) else "", fontsize=7)
        ax.tick_params(labelsize=6)
        ax.grid(True, lw=0.3)
    fig.axes[-1].set_xlabel("time in window [s]", fontsize=7)
    fig.axes[0].set_title(title, fontsize=8)
    fig.canvas.draw()
    rgba = np.asarray(fig.canvas.buffer_rgba())
    return np.ascontiguousarray(rgba[..., :3])


def close_figures(figures: dict[int, Any]) -> None:
    """Forget the cached figures (they hold no OS resources with the Agg canvas)."""
    figures.clear()
