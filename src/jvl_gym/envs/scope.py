"""Scope plots for ``render_mode="rgb_array"``: recorded traces drawn as an RGB image."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

__all__ = ["draw_scope", "close_figures", "panels"]

WIDTH_PX, HEIGHT_PX, DPI = 640, 400, 80


def panels(labels: Sequence[str]) -> list[tuple[str, list[int]]]:
    """The panels of a scope: (y label, channels). A reference channel (``"tension ref [N]"``)
    shares the panel of the channel it is the reference of (``"tension [N]"``)."""
    out: dict[str, list[int]] = {}
    for k, label in enumerate(labels):
        out.setdefault(label.replace(" ref ", " ").replace(" ref", ""), []).append(k)
    return list(out.items())


def draw_scope(figures: dict[int, Any], key: int, trace: np.ndarray, labels: Sequence[str],
               dt: float, title: str = "") -> np.ndarray:
    """Draw ``trace`` (C, T), one panel per quantity (:func:`panels`), and return an
    (H, W, 3) uint8 image.

    The figure is kept in ``figures[key]`` and reused (creating a figure is the slow part).
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    groups = panels(labels) or [("", [])]
    n = len(groups)
    fig = figures.get(key)
    if fig is None or len(fig.axes) != n:
        fig = Figure(figsize=(WIDTH_PX / DPI, HEIGHT_PX / DPI), dpi=DPI)
        FigureCanvasAgg(fig)
        fig.subplots(n, 1, sharex=True)
        figures[key] = fig
    t = np.arange(trace.shape[1]) * dt
    for ax, (ylabel, channels) in zip(fig.axes, groups):
        ax.clear()
        for k in channels:
            if k < trace.shape[0]:
                ref = len(channels) > 1 and k != channels[0]
                ax.plot(t, trace[k], lw=1.0, color=f"C{k}", ls="--" if ref else "-",
                        label=labels[k])
        if len(channels) > 1:
            ax.legend(loc="upper left", fontsize=6)
        ax.set_ylabel(ylabel, fontsize=7)
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
