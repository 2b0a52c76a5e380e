"""How the threads of a threaded step wait for their next piece of work.

The threaded drivers (:data:`jvl_gym.engine.driver.PARALLEL_MIN` copies and more) run on an
OpenMP thread pool. By default OpenMP (GNU libgomp) lets a thread that waits — for the other
threads at the end of a step, or for the next step — spin on its core for a long while before
it sleeps. On a machine whose cores are shared with other work, the spinning thread takes the
core from the thread it waits for and from the Python code between steps: measured on two
shared cores (load ≈ 8), a 1024-copy GearSync step took 8 ms of CPU with spinning threads and
2 ms with sleeping ones. So the package asks OpenMP to let waiting threads
sleep (``OMP_WAIT_POLICY=PASSIVE``) unless the user chose a policy. The policy changes when a
thread runs, never what it computes.
"""

from __future__ import annotations

import os

__all__ = ["WAIT_POLICY", "set_wait_policy"]

#: the OpenMP wait policy the package sets when the environment names none
WAIT_POLICY = "PASSIVE"


def set_wait_policy() -> str:
    """Set ``OMP_WAIT_POLICY`` to :data:`WAIT_POLICY` in this process's environment unless it
    is set (or ``GOMP_SPINCOUNT``, libgomp's own spin setting, is); OpenMP reads it when its
    library is loaded, at the first threaded step. Returns the policy in effect ('' when
    ``GOMP_SPINCOUNT`` decides)."""
    if "GOMP_SPINCOUNT" in os.environ and "OMP_WAIT_POLICY" not in os.environ:
        return ""
    return os.environ.setdefault("OMP_WAIT_POLICY", WAIT_POLICY)
