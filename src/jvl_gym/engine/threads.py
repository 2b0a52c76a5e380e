"""How the threads of a threaded step wait for their next piece of work.

The threaded drivers (:data:`jvl_gym.engine.driver.PARALLEL_MIN` copies and more) run on an
OpenMP thread pool (GNU libgomp). A thread that waits — for the other threads at the end of a
step, or for the next step while Python runs between two — spins on its core for a while, then
sleeps. How long it spins is a trade: on a quiet machine a thread that is still spinning when
the next step comes starts it at once, where a sleeping one must be woken; on a machine whose
cores are shared with other work a long spin takes the core from the thread it waits for and
from the Python code between steps. libgomp's default spin (300 000 spins) measured 8 ms of CPU
for a 1024-copy GearSync step at a load of about 8 on two shared cores, where sleeping threads
(``OMP_WAIT_POLICY=PASSIVE``) took 2 ms; but sleeping at once costs 5 to 15 % of the 1024-copy
env-steps/s on a quiet machine.

So the package sets a short spin, :data:`SPIN_COUNT` spins (``GOMP_SPINCOUNT``), unless the user
chose a wait policy or a spin count. Measured with 1024 copies on the 2-core machine, best of
three alternating runs (env-steps/s, Positioning / GearSync / CoilWinding): quiet, sleeping at
once 3.55 M / 1.03 M / 0.73 M and the short spin 3.94 M / 1.11 M / 0.76 M; beside four busy
processes, sleeping at once 0.65 M / 0.33 M / 0.21 M and the short spin 1.08 M / 0.29 M /
0.21 M. The setting changes when a thread runs, never what it computes.
"""

from __future__ import annotations

import os

__all__ = ["SPIN_COUNT", "set_wait_policy"]

#: the spins (libgomp's ``GOMP_SPINCOUNT``) a waiting thread makes before it sleeps, when the
#: environment names neither a spin count nor a wait policy
SPIN_COUNT = 10_000


def set_wait_policy() -> str:
    """Set ``GOMP_SPINCOUNT`` to :data:`SPIN_COUNT` in this process's environment unless it or
    ``OMP_WAIT_POLICY`` is set; OpenMP reads them when its library is loaded, at the first
    threaded step. Returns the setting in effect, ``"NAME=VALUE"``."""
    for name in ("OMP_WAIT_POLICY", "GOMP_SPINCOUNT"):
        if name in os.environ:
            return f"{name}={os.environ[name]}"
    os.environ["GOMP_SPINCOUNT"] = str(SPIN_COUNT)
    return f"GOMP_SPINCOUNT={SPIN_COUNT}"
