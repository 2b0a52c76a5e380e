"""What makes the scope a scope: a trigger on any channel, a time base, cursors, per-trace
scale and offset, and recording to a file.

The same tools serve the live scope (:mod:`.scope`, points read over time) and the motor's
sample buffer (:mod:`.capture`, samples at the firmware's exact rate): both give a series
(``"t [s]"`` and ``"<channel> [<unit>]"`` → arrays).

* :class:`Trigger`: a level on a channel, the rising or falling edge, the pre-trigger share of
  the window; :func:`find_trigger` finds the first sample at or past the level after one
  before it, :func:`crossing_time` the time the straight line between them crosses it.
* :class:`TriggerMode`: auto (a window even without a trigger), normal (a window on a trigger
  only), single (one window, then stop).
* :func:`window`: the window of a time base around the trigger, time 0 at the crossing.
* :func:`cursors`: Δt, Δvalue and 1/Δt between two cursors on a trace.
* :func:`scaled`: a trace times its scale plus its offset, for one shared axis.
* :class:`Recorder`: chosen channels to CSV (Parquet where pyarrow is installed) for as long
  as it runs, with its elapsed time and size.
"""

from __future__ import annotations

import csv
import enum
import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

__all__ = ["Edge", "Trigger", "TriggerMode", "find_trigger", "crossing_time", "window",
           "Cursors", "cursors", "scaled", "Recorder", "TIME"]

#: the time column of a series
TIME = "t [s]"


class Edge(str, enum.Enum):
    """The edge a trigger fires on."""

    RISING = "rising"
    FALLING = "falling"


class TriggerMode(str, enum.Enum):
    """Auto: a window every time, triggered where a trigger is found; normal: a window only
    on a trigger; single: the first triggered window, then the scope stops."""

    AUTO = "auto"
    NORMAL = "normal"
    SINGLE = "single"


@dataclass(frozen=True)
class Trigger:
    """A trigger.

    Attributes
    ----------
    channel : str
        The series key it watches (``"V_IST [rpm]"``).
    level : float
        The level, in the channel's unit.
    edge : Edge
        Rising (from below the level to at or above it) or falling.
    pre : float
        Share of the window before the trigger, 0 … 1.
    """

    channel: str
    level: float
    edge: Edge = Edge.RISING
    pre: float = 0.2

    def __post_init__(self) -> None:
        if not 0.0 <= self.pre <= 1.0:
            raise ValueError(f"pre-trigger share: 0 … 1, got {self.pre}")
        if not math.isfinite(self.level):
            raise ValueError(f"trigger level: a finite number, got {self.level}")
        object.__setattr__(self, "edge", Edge(self.edge))


def find_trigger(values: Sequence[float] | np.ndarray, trigger: Trigger, start: int = 1
                 ) -> int | None:
    """The index of the first sample at or past the level whose sample before is on the other
    side (the edge), from ``start``; None if the edge is not in ``values``."""
    v = np.asarray(values, dtype=float)
    if len(v) < 2:
        return None
    a, b = v[:-1], v[1:]
    if trigger.edge is Edge.RISING:
        hits = np.flatnonzero((a < trigger.level) & (b >= trigger.level)) + 1
    else:
        hits = np.flatnonzero((a > trigger.level) & (b <= trigger.level)) + 1
    hits = hits[hits >= max(1, start)]
    return int(hits[0]) if len(hits) else None


def crossing_time(t: np.ndarray, values: np.ndarray, index: int, level: float) -> float:
    """The time the straight line between samples ``index - 1`` and ``index`` crosses
    ``level`` (within that sample interval)."""
    t0, t1 = float(t[index - 1]), float(t[index])
    v0, v1 = float(values[index - 1]), float(values[index])
    if v1 == v0:
        return t1
    return t0 + (level - v0) / (v1 - v0) * (t1 - t0)


def window(series: Mapping[str, np.ndarray], trigger: Trigger | None, span: float,
           mode: TriggerMode = TriggerMode.AUTO) -> dict[str, np.ndarray] | None:
    """The window of ``span`` seconds (the time base) of ``series``.

    With a trigger found: the window holds ``pre · span`` before the crossing, time 0 at the
    crossing (:func:`crossing_time`). Without: auto mode gives the last ``span`` seconds
    (times as they are), normal and single give None (nothing to show yet). Single mode counts
    a crossing only once the ``(1 − pre) · span`` after it is recorded (within a sample): the
    one window it holds is a whole one, not the edge alone.

    Raises
    ------
    ValueError
        A span that is not > 0, or a trigger on a channel the series does not have.
    """
    if not span > 0:
        raise ValueError(f"time base: a span > 0 s, got {span}")
    t = np.asarray(series[TIME], dtype=float)
    if trigger is not None and trigger.channel not in series:
        raise ValueError(f"no channel {trigger.channel!r} to trigger on; the scope shows "
                         + ", ".join(k for k in series if k != TIME))
    index = None
    if trigger is not None:
        v = np.asarray(series[trigger.channel], dtype=float)
        # the latest crossing with the pre-trigger share of the window recorded before it
        first = int(np.searchsorted(t, t[0] + trigger.pre * span)) if len(t) else 0
        hits = []
        k = find_trigger(v, trigger, max(1, first))
        while k is not None:
            hits.append(k)
            k = find_trigger(v, trigger, k + 1)
        if hits and mode is TriggerMode.SINGLE:
            # the sweep after the crossing recorded to the end of the window, within a sample
            dt = float(t[-1] - t[-2]) if len(t) > 1 else 0.0
            hits = [k for k in hits if t[-1] + dt
                    >= crossing_time(t, v, k, trigger.level) + (1.0 - trigger.pre) * span]
        if hits:
            index = hits[-1]
    if index is None:
        if mode is not TriggerMode.AUTO and trigger is not None:
            return None
        keep = t >= (t[-1] - span) if len(t) else np.zeros(0, dtype=bool)
        return {k: np.asarray(a, dtype=float)[keep] for k, a in series.items()}
    assert trigger is not None
    v = np.asarray(series[trigger.channel], dtype=float)
    t0 = crossing_time(t, v, index, trigger.level)
    keep = (t >= t0 - trigger.pre * span) & (t <= t0 + (1.0 - trigger.pre) * span)
    out = {k: np.asarray(a, dtype=float)[keep] for k, a in series.items()}
    out[TIME] = out[TIME] - t0
    return out


@dataclass(frozen=True)
class Cursors:
    """Two cursors' readings on a trace."""

    t1: float
    t2: float
    v1: float
    v2: float

    @property
    def dt(self) -> float:
        """Δt = t2 − t1 [s]."""
        return self.t2 - self.t1

    @property
    def dvalue(self) -> float:
        """Δvalue = v2 − v1."""
        return self.v2 - self.v1

    @property
    def frequency(self) -> float:
        """1/Δt [Hz] (inf for Δt = 0)."""
        return math.inf if self.dt == 0 else 1.0 / self.dt

    def text(self, unit: str = "") -> str:
        """``"Δt = … s, Δ = … <unit>, 1/Δt = … Hz"``."""
        return (f"Δt = {self.dt:.6g} s, Δ = {self.dvalue:.6g} {unit}".rstrip()
                + f", 1/Δt = {self.frequency:.6g} Hz")


def cursors(series: Mapping[str, np.ndarray], channel: str, t1: float, t2: float) -> Cursors:
    """The readings of cursors at ``t1`` and ``t2`` on ``channel``: its values interpolated
    linearly between samples (held at the ends)."""
    t = np.asarray(series[TIME], dtype=float)
    v = np.asarray(series[channel], dtype=float)
    if len(t) == 0:
        raise ValueError("no samples to put cursors on")
    return Cursors(t1, t2, float(np.interp(t1, t, v)), float(np.interp(t2, t, v)))


def scaled(values: np.ndarray, scale: float = 1.0, offset: float = 0.0) -> np.ndarray:
    """``values · scale + offset``: a trace on the shared axis."""
    if not (math.isfinite(scale) and math.isfinite(offset)):
        raise ValueError(f"scale and offset: finite numbers, got {scale}, {offset}")
    return np.asarray(values, dtype=float) * scale + offset


class Recorder:
    """Chosen channels to a file, row by row, while it runs.

    Parameters
    ----------
    path : path-like
        The file: ``.csv``, or ``.parquet`` (where pyarrow is installed; written when the
        recording stops).
    labels : sequence of str
        The column labels after the time.

    Raises
    ------
    ValueError
        A Parquet file without pyarrow, or another suffix.
    """

    def __init__(self, path: str | os.PathLike[str], labels: Sequence[str]) -> None:
        self.path = Path(path)
        self.labels = [TIME, *labels]
        self.rows = 0
        self.t0: float | None = None
        self.t_last: float | None = None
        suffix = self.path.suffix.lower()
        if suffix == ".parquet":
            try:
                import pyarrow  # noqa: F401
            except ImportError:
                raise ValueError("Parquet needs pyarrow (pip install pyarrow); record to .csv"
                                 ) from None
            self._columns: list[list[float]] | None = [[] for _ in self.labels]
            self._file = None
        elif suffix == ".csv":
            self._columns = None
            self._file = self.path.open("w", newline="", encoding="utf-8")
            self._csv = csv.writer(self._file)
            self._csv.writerow(self.labels)
        else:
            raise ValueError(f"{self.path.name}: record to a .csv or .parquet file")

    def add(self, t: float, values: Sequence[float]) -> None:
        """One row: the time and the channels' values in the order of the labels."""
        if len(values) != len(self.labels) - 1:
            raise ValueError(f"a row has {len(self.labels) - 1} values, got {len(values)}")
        if self.t0 is None:
            self.t0 = t
        self.t_last = t
        self.rows += 1
        if self._columns is not None:
            for col, v in zip(self._columns, (t, *values)):
                col.append(float(v))
        else:
            self._csv.writerow([f"{t:.9g}", *(f"{float(v):.9g}" for v in values)])

    @property
    def elapsed(self) -> float:
        """Recorded time span [s]."""
        return 0.0 if self.t0 is None or self.t_last is None else self.t_last - self.t0

    @property
    def size(self) -> int:
        """Bytes written so far (a Parquet file: 0 until it stops)."""
        if self._file is not None:
            self._file.flush()
        return self.path.stat().st_size if self.path.exists() else 0

    def stop(self) -> Path:
        """Close the file (write the Parquet file) and return its path."""
        if self._file is not None:
            self._file.close()
            self._file = None
        elif self._columns is not None:
            import pyarrow as pa
            import pyarrow.parquet as pq

            pq.write_table(pa.table(dict(zip(self.labels, self._columns))), self.path)
            self._columns = None
        return self.path
