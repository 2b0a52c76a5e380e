"""Speed of this tree beside another git revision, measured in one run (``make bench-compare``).

Runs the headline figures of ``bench_sim.py`` and ``bench_envs.py`` — motor-inner-steps/s at
N = 4096, outer steps/s at N = 1 (one ``step(1)`` call each), and each compiled env's single
steps/s and 1024-copy env-steps/s — for both trees, alternating them ``--rounds`` times so that
a drift of the machine affects both alike, and prints the best of each with the ratio new/old.
Each rate is the best of ``--windows`` equal windows of its measuring time (``best_rate``, the
same in both trees): on a loaded machine, more and shorter windows make it likelier that the
best of each tree saw a quiet moment. Each measurement runs in a fresh process of its tree
(``PYTHONPATH``) after a warm-up that compiles what it needs (numba's cache of each tree is its
own). The revision is checked out once into ``.bench/<revision>`` (git worktree) and kept, so
that its compiled cache is reused.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
FIGURES = """
import json, sys
sys.path.insert(0, "benchmarks")
import best_rate
best_rate.WINDOWS = WINDOWS
import bench_sim, bench_envs
out = {"motor-inner-steps/s, N=4096": bench_sim.inner_steps_per_second(4096),
       "outer steps/s, N=1 (calls)": bench_sim.outer_steps_per_second_single(True)}
for name in ("Positioning", "GearSync", "CoilWinding"):
    env_id = f"jvl_gym/{name}-v0"
    out[f"{name} single steps/s"] = bench_envs.single_steps_per_second(env_id)
    out[f"{name} 1024 env-steps/s"] = bench_envs.vector_steps_per_second(env_id)
print(json.dumps(out))
"""


def figures(tree: Path, windows: int) -> dict[str, float]:
    """The figures of the source tree ``tree``, measured in a new process, each the best of
    ``windows`` windows."""
    env = {**os.environ, "PYTHONPATH": f"{tree / 'src'}{os.pathsep}{tree}",
           "JVL_QUIET_COMPILE": "1"}
    code = FIGURES.replace("= WINDOWS", f"= {int(windows)}")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, env=env, cwd=tree)
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("baseline", help="git revision to compare with")
    parser.add_argument("--rounds", type=int, default=2, help="alternations (best of each)")
    parser.add_argument("--windows", type=int, default=20,
                        help="windows per rate (best of; more and shorter on a loaded machine)")
    args = parser.parse_args()
    if args.rounds < 1 or args.windows < 1:
        parser.error("--rounds and --windows must be at least 1")
    base = ROOT / ".bench" / args.baseline.replace("/", "_")
    if not base.exists():
        subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", "-q", str(base),
                        args.baseline], check=True)
    best: dict[str, dict[str, float]] = {"old": {}, "new": {}}
    for _ in range(args.rounds):
        for label, tree in (("old", base), ("new", ROOT)):
            for key, value in figures(tree, args.windows).items():
                best[label][key] = max(value, best[label].get(key, 0.0))
    print(f"{'figure':36s} {args.baseline[:10]:>14s} {'this tree':>14s} {'new/old':>8s}")
    for key, old in best["old"].items():
        new = best["new"][key]
        print(f"{key:36s} {old:14,.0f} {new:14,.0f} {new / old:8.3f}")


if __name__ == "__main__":
    main()
