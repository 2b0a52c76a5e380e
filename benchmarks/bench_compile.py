"""First-use time (``make bench-compile``): prints its figures, asserts nothing.

numba compiles the kernel and an environment's step on first use and caches the result next to
the sources; later processes load it from there. This script measures what a new user waits:
each case runs in a fresh process whose numba cache is an empty temporary directory
(``NUMBA_CACHE_DIR``), so the project's own cache is neither used nor touched, and then once
more with that directory filled (the time every later process pays).

Cases: a ``MotorArray`` advanced by one outer sample, and the first ``reset`` + ``step`` of the
single env and of a 64-copy vector env (threaded step) of GearSync, CoilWinding and Positioning.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile

CASES = {
    "MotorArray step": "from jvl_gym import MotorArray\n"
                       "MotorArray('MAC140', n=4, seed=0).step(1)",
    **{f"{name} {kind}": (
        "import gymnasium as gym, jvl_gym\n"
        + (f"e = gym.make('jvl_gym/{name}-v0')\n" if kind == "single" else
           f"e = gym.make_vec('jvl_gym/{name}-v0', num_envs=64, "
           "vectorization_mode='vector_entry_point')\n")
        + "e.reset(seed=0)\ne.step(e.action_space.sample())")
       for name in ("GearSync", "CoilWinding", "Positioning")
       for kind in ("single", "vector")},
}

TIMED = """
import time
t0 = time.perf_counter()
{code}
print(time.perf_counter() - t0)
"""


def seconds(code: str, cache_dir: str) -> float:
    """Wall time [s] of ``code`` in a new Python process with numba's cache in ``cache_dir``."""
    out = subprocess.run([sys.executable, "-c", TIMED.format(code=code)], capture_output=True,
                         text=True, check=True, env={**os.environ, "NUMBA_CACHE_DIR": cache_dir})
    return float(out.stdout.strip().splitlines()[-1])


def main() -> None:
    print(f"{'first use (empty numba cache)':34s} {'cold s':>8s} {'cached s':>9s}")
    for name, code in CASES.items():
        with tempfile.TemporaryDirectory(prefix="jvl-numba-") as cache_dir:
            cold = seconds(code, cache_dir)
            warm = seconds(code, cache_dir)
        print(f"{name:34s} {cold:8.1f} {warm:9.1f}", flush=True)


if __name__ == "__main__":
    main()
