"""The scope: channels of registers and physical signals, buffered for a live chart.

A channel is a register of the motor (its value in the register's unit) or, on a simulated
motor, a physical signal (:data:`~.motor.PHYSICAL_SIGNALS`: shaft speed, phase currents, …).
:class:`Scope` reads all its channels at once (one batch of register reads) and keeps the last
``depth`` points against the motor's time; :meth:`Scope.csv` and :meth:`Scope.png` export them.
"""

from __future__ import annotations

import io
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from ..registers import from_raw
from .motor import StudioMotor

__all__ = ["Channel", "Scope", "channel_choices", "make_channel", "series_csv", "series_png"]


@dataclass(frozen=True)
class Channel:
    """One scope channel.

    Attributes
    ----------
    name : str
        Register name or physical signal label.
    unit : str
        Its unit.
    number : int or None
        Register number; None for a physical signal.
    """

    name: str
    unit: str
    number: int | None = None


def channel_choices(motor: StudioMotor) -> list[str]:
    """Names of every channel ``motor`` offers: its physical signals, then its registers."""
    from .groups import visible

    return list(motor.physical()) + [r.name for r in motor.table if visible(r)]


def make_channel(motor: StudioMotor, name: str) -> Channel:
    """The channel ``name`` of ``motor`` (a physical signal label or a register name)."""
    phys = motor.physical()
    if name in phys:
        return Channel(name, phys[name][0])
    reg = motor.register(name)
    return Channel(reg.name, reg.unit, reg.number)


class Scope:
    """A live scope of one motor.

    Parameters
    ----------
    motor : StudioMotor
        The motor read.
    channels : sequence of str
        Channel names (:func:`channel_choices`).
    depth : int
        Points kept per channel.
    """

    def __init__(self, motor: StudioMotor, channels: Sequence[str], depth: int = 600) -> None:
        if not channels:
            raise ValueError("pick at least one channel")
        self.motor = motor
        self.channels = [make_channel(motor, c) for c in channels]
        self._phys: dict[str, Callable[[], float]] = {
            k: v[1] for k, v in motor.physical().items()}
        self.t: deque[float] = deque(maxlen=depth)
        self.values: list[deque[float]] = [deque(maxlen=depth) for _ in self.channels]

    def sample(self) -> None:
        """Read every channel once and append the point at the motor's time now; a reading at
        a motor time not later than the last point's (a clock that did not advance between two
        reads) replaces that point, so that the times always increase."""
        numbers = [c.number for c in self.channels if c.number is not None]
        with self.motor.lock:
            t = self.motor.now()
            raws = self.motor.read_raws(numbers) if numbers else {}
            phys = {c.name: self._phys[c.name]() for c in self.channels if c.number is None}
        point = [phys[c.name] if c.number is None
                 else float(from_raw(self.motor.register(c.number), raws[c.number]))
                 for c in self.channels]
        if self.t and t <= self.t[-1]:
            for buf, value in zip(self.values, point):
                buf[-1] = value
            return
        self.t.append(t)
        for buf, value in zip(self.values, point):
            buf.append(value)

    def clear(self) -> None:
        """Forget the points taken."""
        self.t.clear()
        for b in self.values:
            b.clear()

    def series(self) -> dict[str, np.ndarray]:
        """Time [s] and every channel, name → array of the points kept."""
        out = {"t [s]": np.asarray(self.t, dtype=float)}
        for c, b in zip(self.channels, self.values):
            out[self.label(c)] = np.asarray(b, dtype=float)
        return out

    @staticmethod
    def label(c: Channel) -> str:
        """``"<name> [<unit>]"`` (no brackets without a unit)."""
        return f"{c.name} [{c.unit}]" if c.unit else c.name

    def csv(self) -> str:
        """The points as CSV text: a header row of labels, then one row per point."""
        return series_csv(self.series())

    def png(self, title: str = "") -> bytes:
        """The points as a PNG chart, one axis per unit."""
        return series_png(self.series(), title or self.motor.label)


def series_csv(series: dict[str, np.ndarray]) -> str:
    """``series`` (label → equal-length arrays) as CSV text."""
    cols = list(series)
    data = np.column_stack([series[c] for c in cols]) if cols else np.zeros((0, 0))
    buf = io.StringIO()
    buf.write(",".join(f'"{c}"' for c in cols) + "\n")
    for row in data:
        buf.write(",".join(f"{v:.9g}" for v in row) + "\n")
    return buf.getvalue()


def series_png(series: dict[str, np.ndarray], title: str = "") -> bytes:
    """``series`` (the first entry the x axis) as a PNG chart: one subplot per unit."""
    from matplotlib.figure import Figure

    keys = list(series)
    x = series[keys[0]]
    units: dict[str, list[str]] = {}
    for k in keys[1:]:
        unit = k.rpartition("[")[2].rstrip("]") if k.endswith("]") else ""
        units.setdefault(unit, []).append(k)
    fig = Figure(figsize=(8, 1.8 + 1.6 * max(1, len(units))), dpi=100)
    axes = fig.subplots(max(1, len(units)), 1, sharex=True, squeeze=False)[:, 0]
    for ax, (unit, names) in zip(axes, units.items()):
        for k in names:
            ax.plot(x, series[k], label=k, lw=1.2)
        ax.set_ylabel(unit or "value")
        ax.legend(loc="upper left", fontsize=8)
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel(keys[0])
    if title:
        axes[0].set_title(title)
    fig.tight_layout()
    out = io.BytesIO()
    fig.savefig(out, format="png")
    return out.getvalue()
