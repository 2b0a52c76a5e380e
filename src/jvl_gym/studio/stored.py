"""Stored traces: a capture saved to a file, and a stored one loaded to overlay a chart.

A capture (the scope's window or the motor's sample buffer, :mod:`.trigger`'s series: ``"t
[s]"`` and ``"<channel> [<unit>]"`` → arrays) is saved as CSV (:func:`.scope.series_csv`) or
Parquet (where pyarrow is installed). :func:`load` reads such a file back, and the recorder's
files (:class:`.trigger.Recorder`) too; :func:`aligned` puts a loaded trace on the chart's
trigger: its time 0 at its own crossing of the trigger's level on the trigger's edge
(:func:`.trigger.find_trigger`, :func:`.trigger.crossing_time`), as the captured trace it is
drawn over. A stored trace keeps its own times: it is drawn on the same time axis, not
resampled.

A file that is not such a trace is a :class:`StoredTraceError` with one line saying what is
wrong; nothing is loaded.
"""

from __future__ import annotations

import csv
import io
import os
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from .scope import series_csv
from .trigger import TIME, Trigger, crossing_time, find_trigger

__all__ = ["StoredTraceError", "save", "load", "aligned", "stored_label"]

#: suffixes a stored trace may have
SUFFIXES = (".csv", ".parquet")


class StoredTraceError(ValueError):
    """A stored trace that cannot be saved or loaded (one line: the file, what is wrong)."""


def _suffix(path: Path) -> str:
    suffix = path.suffix.lower()
    if suffix not in SUFFIXES:
        raise StoredTraceError(f"{path.name}: a stored trace is a .csv or .parquet file")
    return suffix


def save(series: Mapping[str, np.ndarray], path: str | os.PathLike[str]) -> Path:
    """Write ``series`` (a capture: ``"t [s]"`` first) to ``path`` (``.csv`` or ``.parquet``)
    and return the path.

    Raises
    ------
    StoredTraceError
        Nothing captured yet, another suffix, or Parquet without pyarrow (nothing written).
    """
    path = Path(path)
    suffix = _suffix(path)
    if not series or len(next(iter(series.values()))) == 0 or len(series) < 2:
        raise StoredTraceError("nothing captured to save yet")
    if TIME not in series:
        raise StoredTraceError(f"a stored trace has a '{TIME}' column; this record counts "
                               f"{next(iter(series))!r} (export it with CSV)")
    if suffix == ".parquet":
        try:
            import pyarrow as pa
            import pyarrow.parquet as pq
        except ImportError:
            raise StoredTraceError("Parquet needs pyarrow (pip install pyarrow); save to .csv"
                                   ) from None
        pq.write_table(pa.table({k: np.asarray(v, dtype=float) for k, v in series.items()}),
                       path)
    else:
        path.write_text(series_csv({k: np.asarray(v, dtype=float) for k, v in series.items()}),
                        encoding="utf-8")
    return path


def _columns_csv(path: Path) -> dict[str, list[str]]:
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise StoredTraceError(f"{path.name}: not a text CSV file") from None
    rows = [r for r in csv.reader(io.StringIO(text)) if r]
    if not rows:
        raise StoredTraceError(f"{path.name}: empty")
    header, body = [h.strip() for h in rows[0]], rows[1:]
    twice = sorted({h for h in header if header.count(h) > 1})
    if twice:
        raise StoredTraceError(f"{path.name}: column '{twice[0]}' more than once")
    for n, row in enumerate(body, start=2):
        if len(row) != len(header):
            raise StoredTraceError(f"{path.name}, line {n}: {len(row)} values for "
                                   f"{len(header)} columns")
    return {h: [r[k] for r in body] for k, h in enumerate(header)}


def _columns_parquet(path: Path) -> dict[str, list]:
    try:
        import pyarrow.parquet as pq
    except ImportError:
        raise StoredTraceError("Parquet needs pyarrow (pip install pyarrow)") from None
    try:
        table = pq.read_table(path)
    except Exception as exc:  # noqa: BLE001 - pyarrow's errors are of several kinds
        first = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise StoredTraceError(f"{path.name}: not a Parquet file ({first})") from None
    return {name: table.column(name).to_pylist() for name in table.column_names}


def load(path: str | os.PathLike[str]) -> dict[str, np.ndarray]:
    """The stored trace in ``path``: ``"t [s]"`` and its channels → arrays.

    The file is a saved capture (:func:`save`) or a recording (:class:`.trigger.Recorder`):
    a ``t [s]`` column of increasing finite times and at least one channel of numbers, at least
    two rows.

    Raises
    ------
    StoredTraceError
        A missing or unreadable file, another suffix, no ``t [s]`` column, no channel, fewer
        than two rows, a value that is not a number, a repeated column or times that do not
        increase.
    """
    path = Path(path)
    suffix = _suffix(path)
    if not path.is_file():
        raise StoredTraceError(f"{path}: no such file")
    columns = _columns_csv(path) if suffix == ".csv" else _columns_parquet(path)
    if "" in columns:
        raise StoredTraceError(f"{path.name}: a column without a name")
    if TIME not in columns:
        raise StoredTraceError(f"{path.name}: no '{TIME}' column (columns: "
                               + ", ".join(columns)[:120] + ")")
    if len(columns) < 2:
        raise StoredTraceError(f"{path.name}: no channel beside '{TIME}'")
    out: dict[str, np.ndarray] = {}
    for name in [TIME, *(c for c in columns if c != TIME)]:
        try:
            values = np.asarray([float(v) for v in columns[name]], dtype=float)
        except (TypeError, ValueError):
            raise StoredTraceError(f"{path.name}: column '{name}' holds a value that is not a "
                                   "number") from None
        out[name] = values
    t = out[TIME]
    if len(t) < 2:
        raise StoredTraceError(f"{path.name}: {len(t)} rows, a trace needs at least 2")
    if not (np.all(np.isfinite(t)) and np.all(np.diff(t) > 0)):
        raise StoredTraceError(f"{path.name}: the times of '{TIME}' do not increase")
    return out


def aligned(stored: Mapping[str, np.ndarray], trigger: Trigger | None
            ) -> tuple[dict[str, np.ndarray], str]:
    """``stored`` on the chart's ``trigger`` and how it was placed.

    With a trigger on a channel the stored trace has: time 0 at the trace's first crossing of
    the level on the edge. Otherwise (no trigger, or the channel is not stored) the times as
    stored: a saved triggered capture has time 0 at its crossing already.

    Returns
    -------
    series : dict
        The stored trace with its times shifted.
    how : str
        ``"aligned at the trigger"`` or why it is not.

    Raises
    ------
    StoredTraceError
        The stored trace has the trigger's channel but does not cross the level on the edge.
    """
    out = {k: np.asarray(v, dtype=float) for k, v in stored.items()}
    if trigger is None:
        return out, "times as stored (the trigger is off)"
    if trigger.channel not in out:
        return out, f"times as stored (no {trigger.channel} stored)"
    t, v = out[TIME], out[trigger.channel]
    k = find_trigger(v, trigger)
    if k is None:
        raise StoredTraceError(f"the stored {trigger.channel} does not cross "
                               f"{trigger.level:g} ({trigger.edge.value})")
    out[TIME] = t - crossing_time(t, v, k, trigger.level)
    return out, "aligned at the trigger"


def stored_label(name: str, label: str) -> str:
    """The legend entry of channel ``label`` of the stored trace ``name`` (its file's
    stem): ``"<label> · <name>"``."""
    return f"{label} · {name}"
