"""First-use time (``make bench-compile``): prints its figures, asserts nothing.

numba compiles the kernel and an environment's step on first use and caches the result; later
processes load it. This script measures what a new user waits, in the order a user meets it:
every case runs in a fresh process with numba's cache in one empty temporary directory per
source tree (``NUMBA_CACHE_DIR``, so the project's own cache is neither used nor touched):

1. the first ``MotorArray`` step (the kernel compiles);
2. then, for each environment, the first ``reset`` + ``step`` of the single env, then of a
   64-copy vector env (threaded step), each with what the earlier cases compiled already cached;
3. the first step again, now from the filled cache (what every later process pays).

``--baseline REV`` measures the source tree of git revision ``REV`` (checked out into a temporary
worktree) the same way and prints both side by side.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
ENVS = ("Positioning", "GearSync", "CoilWinding")

MOTORS = "from jvl_gym import MotorArray\nMotorArray('MAC140', n=4, seed=0).step(1)"


def _env_code(name: str, kind: str) -> str:
    make = (f"e = gym.make('jvl_gym/{name}-v0')\n" if kind == "single" else
            f"e = gym.make_vec('jvl_gym/{name}-v0', num_envs=64, "
            "vectorization_mode='vector_entry_point')\n")
    return ("import gymnasium as gym, jvl_gym\n" + make
            + "e.reset(seed=0)\ne.step(e.action_space.sample())")


CASES: list[tuple[str, str]] = [
    ("MotorArray first step", MOTORS),
    *[(f"{name} {kind} (kernel cached)", _env_code(name, kind))
      for name in ENVS for kind in ("single", "vector")],
    ("MotorArray step, cache filled", MOTORS),
]

TIMED = """
import time
t0 = time.perf_counter()
{code}
print(time.perf_counter() - t0)
"""


def seconds(code: str, tree: Path, cache_dir: str) -> float:
    """Wall time [s] of ``code`` in a new Python process importing jvl_gym from ``tree`` with
    numba's cache in ``cache_dir``."""
    env = {**os.environ, "NUMBA_CACHE_DIR": cache_dir, "JVL_QUIET_COMPILE": "1",
           "PYTHONPATH": f"{tree / 'src'}{os.pathsep}{tree}"}
    out = subprocess.run([sys.executable, "-c", TIMED.format(code=code)], capture_output=True,
                         text=True, check=True, env=env, cwd=tree)
    return float(out.stdout.strip().splitlines()[-1])


def measure(tree: Path) -> list[float]:
    """Wall times [s] of :data:`CASES` for the source tree ``tree``, in order, one cache."""
    with tempfile.TemporaryDirectory(prefix="jvl-numba-") as cache_dir:
        return [seconds(code, tree, cache_dir) for _, code in CASES]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--baseline", help="git revision to measure beside this tree")
    args = parser.parse_args()
    columns = [("this tree", ROOT)]
    with tempfile.TemporaryDirectory(prefix="jvl-baseline-") as base:
        if args.baseline:
            subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", "-q", base,
                            args.baseline], check=True)
            columns.insert(0, (args.baseline[:10], Path(base)))
        try:
            results = [measure(tree) for _, tree in columns]
        finally:
            if args.baseline:
                subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", base],
                               check=False)
    print(f"{'first use, empty numba cache [s]':40s}"
          + "".join(f"{label:>14s}" for label, _ in columns))
    for k, (name, _) in enumerate(CASES):
        print(f"{name:40s}" + "".join(f"{r[k]:14.1f}" for r in results))


if __name__ == "__main__":
    main()
