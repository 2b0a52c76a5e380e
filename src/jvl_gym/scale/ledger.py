"""Finished trials on disk: ``<out>/trials/<trial_id>/result.json``.

The sweep driver writes a trial's entry when the trial reports its final metrics; a sweep run
again with the same ``--out`` skips every trial that has one. Entries are written atomically
(temporary file, then rename), so an interrupted sweep never leaves a half-written entry.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Any

__all__ = ["Ledger"]


def _clean(value: Any) -> Any:
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {str(k): _clean(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_clean(v) for v in value]
    if hasattr(value, "item"):
        return _clean(value.item())
    return value


class Ledger:
    """The finished trials of a sweep directory.

    Parameters
    ----------
    root : path
        ``<out>/trials``.
    """

    def __init__(self, root: str | Path) -> None:
        self.root = Path(root)

    def path(self, trial_id: str) -> Path:
        """The entry file of a trial."""
        return self.root / trial_id / "result.json"

    def write(self, trial_id: str, entry: dict[str, Any]) -> Path:
        """Store a finished trial's entry (JSON; NaN and inf become ``null``)."""
        path = self.path(trial_id)
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(".tmp")
        tmp.write_text(json.dumps(_clean(entry), indent=1))
        os.replace(tmp, path)
        return path

    def read(self, trial_id: str) -> dict[str, Any] | None:
        """A trial's entry, or ``None`` when it has not finished."""
        path = self.path(trial_id)
        if not path.is_file():
            return None
        try:
            return json.loads(path.read_text())
        except json.JSONDecodeError:
            return None

    def finished(self, trial_ids: list[str]) -> set[str]:
        """The ids among ``trial_ids`` that have an entry."""
        return {t for t in trial_ids if self.read(t) is not None}
