"""Rate of a piece of work on a shared machine: the best of equal time windows.

Other load on a shared machine only ever slows a window down, so the best window is the
closest to the code's own speed. Plain Python (no project imports): ``bench_envs.py`` also sends
this file's source to gym-electric-motor's separate venv, so both sides are measured alike.
"""

from __future__ import annotations

import time
from collections.abc import Callable

#: each rate is the best of this many equal windows of the measuring time
WINDOWS = 5


def best_rate(run: Callable[[int], None], batch: int, seconds: float) -> float:
    """Best rate [units of work per second] over :data:`WINDOWS` windows sharing ``seconds``;
    ``run(batch)`` does ``batch`` units of work."""
    best = 0.0
    for _ in range(WINDOWS):
        n, t0 = 0, time.perf_counter()
        while time.perf_counter() - t0 < seconds / WINDOWS:
            run(batch)
            n += batch
        best = max(best, n / (time.perf_counter() - t0))
    return best
