"""First-use time (``make bench-compile``): prints its figures, asserts nothing.

numba compiles the kernel and an environment's step on first use and caches the result; later
processes load it. This script measures what a new user waits, in the order a user meets it:
every case runs in a fresh process with numba's cache in one empty temporary directory per
source tree (``NUMBA_CACHE_DIR``, so the project's own cache is neither used nor touched):

1. the first ``MotorArray`` step (the kernel compiles);
2. then, for each environment, the first ``reset`` + ``step`` of the single env, then of a
   64-copy vector env (threaded step), each with what the earlier cases compiled already cached;
3. the first step again, now from the filled cache (what every later process pays);
4. in a second empty cache: ``jvl-gym compile`` (what ``make setup`` runs once), then the
   first step of a motor array and of each single env after it (trees without that command
   print "—");
5. per family, in an empty cache: the first step of a motor array of its first motor type under
   numba's compile events (``benchmarks/compile_profile.py``): the CPU seconds of each compiled
   function in numba's typing, IR inlining, lowering and LLVM, and the functions whose passes
   (their own and those of their inlined copies) take the most front-end time.

``--baseline REV`` measures the source tree of git revision ``REV`` (checked out into a temporary
worktree) the same way and prints both side by side.
"""

from __future__ import annotations

import argparse
import json
import math
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
PRECOMPILE = ("try:\n    from jvl_gym.cli.precompile import compile_all\n"
              "except ImportError:  # a tree from before the command line was a package\n"
              "    from jvl_gym.precompile import compile_all\ncompile_all()")
AFTER_PRECOMPILE: list[tuple[str, str]] = [
    ("jvl-gym compile (empty cache)", PRECOMPILE),
    ("MotorArray first step after it", MOTORS),
    *[(f"{name} single first step after it", _env_code(name, "single")) for name in ENVS],
]

TIMED = """
import time
t0 = time.perf_counter()
{code}
print(time.perf_counter() - t0, time.process_time())
"""


def _last_line(args: list[str], tree: Path, cache_dir: str) -> str:
    """The last stdout line of ``python ARGS`` in a new process importing jvl_gym from
    ``tree`` with numba's cache in ``cache_dir``."""
    env = {**os.environ, "NUMBA_CACHE_DIR": cache_dir, "JVL_QUIET_COMPILE": "1",
           "PYTHONPATH": f"{tree / 'src'}{os.pathsep}{tree}"}
    out = subprocess.run([sys.executable, *args], capture_output=True, text=True, check=True,
                         env=env, cwd=tree)
    return out.stdout.strip().splitlines()[-1]


def seconds(code: str, tree: Path, cache_dir: str) -> tuple[float, float]:
    """Wall time [s] of ``code`` and the CPU time [s] of the whole process (imports included)
    in a new Python process importing jvl_gym from ``tree`` with numba's cache in
    ``cache_dir``. The CPU seconds depend much less on the machine's load than the wall
    seconds (a process waiting for a core spends none); they are that process's own, without
    the second process a cold start compiles a family's inner samples in
    (``jvl_gym.engine.two_cores``), which the family profiles count."""
    wall, cpu = _last_line(["-c", TIMED.format(code=code)], tree, cache_dir).split()
    return float(wall), float(cpu)


FAMILY_TYPES = ("from jvl_gym.families import families, family\n"
                "print(' '.join(family(k).motor_types()[0] for k in families()))")
STAGES = ("typing", "inlining", "lowering", "llvm", "other")
#: functions and inlined owners listed per family: those with at least this many seconds
SHOWN_FROM = 1.0


def profile(tree: Path) -> dict[str, dict]:
    """Per family (by its first motor type): the compile profile of a motor array's first
    step in an empty cache (``compile_profile.run``)."""
    with tempfile.TemporaryDirectory(prefix="jvl-numba-") as cache_dir:
        types = _last_line(["-c", FAMILY_TYPES], tree, cache_dir).split()
    result = {}
    for motor_type in types:
        code = f"from jvl_gym import MotorArray\nMotorArray({motor_type!r}, n=4).step(1)"
        with tempfile.TemporaryDirectory(prefix="jvl-numba-") as cache_dir:
            result[motor_type] = json.loads(_last_line(
                [str(Path(__file__).with_name("compile_profile.py")), code], tree, cache_dir))
    return result


def print_profile(label: str, profiles: dict[str, dict]) -> None:
    """The per-family compile breakdown of one source tree."""
    print(f"\ncompile of a motor array's first step by stage [CPU s], {label}")
    print(f"{'function':58s}" + "".join(f"{s:>9s}" for s in (*STAGES, "total")))
    for motor_type, functions in profiles.items():
        owners = functions.pop("__inlined__", {})
        family_total = dict.fromkeys(STAGES, 0.0)
        rows = sorted(functions.items(), key=lambda kv: -sum(kv[1].values()))
        for name, stages in rows:
            for s in STAGES:
                family_total[s] += stages.get(s, 0.0)
            if sum(stages.values()) >= SHOWN_FROM:
                print(f"  {name[-56:]:56s}" + "".join(f"{stages.get(s, 0.0):9.1f}"
                                                      for s in STAGES)
                      + f"{sum(stages.values()):9.1f}")
        print(f"{motor_type + ' family, all functions':58s}"
              + "".join(f"{family_total[s]:9.1f}" for s in STAGES)
              + f"{sum(family_total.values()):9.1f}")
        top = sorted(owners.items(), key=lambda kv: -kv[1])
        shown = ", ".join(f"{name} {sec:.1f}" for name, sec in top[:8] if sec >= SHOWN_FROM)
        print(f"  front-end seconds by pass owner (inlined copies included): {shown or '-'}")


def measure(tree: Path, precompile: bool = True) -> list[tuple[float, float]]:
    """(wall, CPU) seconds of :data:`CASES`, then of :data:`AFTER_PRECOMPILE` (NaN where the
    tree has no ``jvl_gym.cli.precompile`` or ``precompile`` is False), for the source tree
    ``tree``, each list in one cache."""
    with tempfile.TemporaryDirectory(prefix="jvl-numba-") as cache_dir:
        times = [seconds(code, tree, cache_dir) for _, code in CASES]
    package = tree / "src" / "jvl_gym"
    if not precompile or not any((package / p).exists()
                                 for p in ("cli/precompile.py", "precompile.py")):
        return times + [(math.nan, math.nan)] * len(AFTER_PRECOMPILE)
    with tempfile.TemporaryDirectory(prefix="jvl-numba-") as cache_dir:
        return times + [seconds(code, tree, cache_dir) for _, code in AFTER_PRECOMPILE]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--baseline", help="git revision to measure beside this tree")
    parser.add_argument("--profile-only", action="store_true",
                        help="only the per-family compile breakdown (step 5)")
    parser.add_argument("--no-precompile", action="store_true",
                        help="leave out step 4 (jvl-gym compile, minutes of both cores)")
    args = parser.parse_args()
    columns = [("this tree", ROOT)]
    with tempfile.TemporaryDirectory(prefix="jvl-baseline-") as base:
        if args.baseline:
            subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", "-q", base,
                            args.baseline], check=True)
            columns.insert(0, (args.baseline[:10], Path(base)))
        try:
            results = [] if args.profile_only else [measure(tree, not args.no_precompile)
                                                    for _, tree in columns]
            profiles = [profile(tree) for _, tree in columns]
        finally:
            if args.baseline:
                subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", base],
                               check=False)
    for (label, _), profiles_of_tree in zip(columns, profiles):
        print_profile(label, profiles_of_tree)
    if not results:
        return
    print(f"\n{'first use, empty numba cache [s]':40s}"
          + "".join(f"{label + ' wall':>16s}{'CPU':>7s}" for label, _ in columns))
    for k, (name, _) in enumerate([*CASES, *AFTER_PRECOMPILE]):
        print(f"{name:40s}" + "".join(f"{r[k][0]:16.1f}{r[k][1]:7.1f}" if r[k][0] == r[k][0]
                                      else f"{'—':>16s}{'—':>7s}" for r in results))


if __name__ == "__main__":
    main()
