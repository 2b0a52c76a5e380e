"""Speed of this tree beside the reference revision and the previous one, measured in one run
(``make bench-compare``).

Runs the headline figures of ``bench_sim.py`` and ``bench_envs.py`` — motor-inner-steps/s at
N = 4096, outer steps/s at N = 1 (one ``step(1)`` call each), and each compiled env's single
steps/s and 1024-copy env-steps/s — for this tree (its working files), the reference revision
named in ``benchmarks/REFERENCE`` and a second revision (default ``HEAD~1``, the one before),
alternating them ``--rounds`` times so that a drift of the machine affects all alike, and
prints the best of each with the ratios this/reference and this/previous.

The reference is fixed: a change that keeps within a few per cent of the tree before it can
still lose ground step by step, and only a fixed point shows the sum. It moves forward
(``--advance`` writes HEAD into the file) only when every figure of the run is at or above it.

Each rate is the best of ``--windows`` equal windows of its measuring time (``best_rate``, the
same in every tree): on a loaded machine, more and shorter windows make it likelier that the
best of each tree saw a quiet moment. Each measurement runs in a fresh process of its tree
(``PYTHONPATH``: each tree's own benchmark code and modules, whatever they were called then)
after a warm-up that compiles what it needs (numba's cache of each tree is its own). A revision
is checked out once into ``.bench/<commit>`` (git worktree) and kept, so that its compiled
cache is reused.

    python benchmarks/bench_compare.py [REVISION] [--reference REV] [--rounds 2] [--advance]
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
import json, sys, time
if CLOCK == "cpu":  # before the benchmark modules read the clock
    time.perf_counter = time.process_time
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


def figures(tree: Path, windows: int, clock: str = "wall") -> dict[str, float]:
    """The figures of the source tree ``tree``, measured in a new process, each the best of
    ``windows`` windows of the clock ``clock`` (``"wall"`` or ``"cpu"``: see ``--clock``)."""
    env = {**os.environ, "PYTHONPATH": f"{tree / 'src'}{os.pathsep}{tree}",
           "JVL_QUIET_COMPILE": "1"}
    code = FIGURES.replace("= WINDOWS", f"= {int(windows)}").replace(
        "if CLOCK ==", f"if {clock!r} ==")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, env=env, cwd=tree)
    return json.loads(out.stdout.strip().splitlines()[-1])


REFERENCE_FILE = ROOT / "benchmarks" / "REFERENCE"


def read_reference(text: str) -> str:
    """The revision named in the text of ``benchmarks/REFERENCE``: its last line that is neither
    empty nor a comment (``#``)."""
    names = [line.strip() for line in text.splitlines()
             if line.strip() and not line.lstrip().startswith("#")]
    if not names:
        raise ValueError("benchmarks/REFERENCE names no revision")
    return names[-1]


def with_reference(text: str, revision: str) -> str:
    """The text of ``benchmarks/REFERENCE`` with its revision replaced by ``revision`` (the
    comments kept)."""
    kept = [line for line in text.splitlines() if line.lstrip().startswith("#")]
    return "\n".join([*kept, revision]) + "\n"


def commit_of(revision: str) -> str:
    """The abbreviated commit of ``revision`` (ValueError: not a commit of the repository)."""
    out = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--verify", "-q", "--short=10",
                          f"{revision}^{{commit}}"], capture_output=True, text=True)
    if out.returncode != 0:
        raise ValueError(f"{revision!r} is not a revision of this repository")
    return out.stdout.strip()


def checkout(commit: str) -> Path:
    """The kept checkout ``.bench/<commit>`` of ``commit`` (made on first use)."""
    tree = ROOT / ".bench" / commit
    if not tree.exists():
        subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", "-q", str(tree),
                        commit], check=True)
    return tree


def report(best: dict[str, dict[str, float]], labels: dict[str, str]) -> list[str]:
    """The lines of the table: one per figure, the best rate of each tree (``best``: tree key
    -> figure -> rate; keys ``this``, ``reference`` and optionally ``previous``, whose column
    titles are ``labels``) and the ratios of this tree to the others."""
    others = [key for key in ("reference", "previous") if key in best]
    head = f"{'figure':36s}" + "".join(f" {labels[k][:14]:>14s}" for k in others)
    head += f" {'this tree':>14s}" + "".join(f" {'/' + k[:4]:>8s}" for k in others)
    lines = [head]
    for key, new in best["this"].items():
        row = f"{key:36s}" + "".join(f" {best[k].get(key, float('nan')):14,.0f}" for k in others)
        row += f" {new:14,.0f}"
        row += "".join(f" {new / best[k][key]:8.3f}" if best[k].get(key) else f" {'—':>8s}"
                       for k in others)
        lines.append(row)
    return lines


def below(best: dict[str, dict[str, float]], other: str = "reference") -> list[str]:
    """The figures of this tree below those of ``other`` (none: every figure at or above)."""
    return [key for key, new in best["this"].items()
            if key in best[other] and new < best[other][key]]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("revision", nargs="?", default="HEAD~1",
                        help="the revision compared beside the reference (default HEAD~1)")
    parser.add_argument("--reference", help="the reference revision (default: the one in "
                        "benchmarks/REFERENCE)")
    parser.add_argument("--rounds", type=int, default=2, help="alternations (best of each)")
    parser.add_argument("--windows", type=int, default=20,
                        help="windows per rate (best of; more and shorter on a loaded machine)")
    parser.add_argument("--clock", choices=("wall", "cpu"), default="wall",
                        help="wall: rates per second of elapsed time; cpu: per CPU-second of "
                        "the measuring process, all its threads (for a machine so busy that "
                        "few wall windows are quiet; a threaded figure then counts the CPU "
                        "of every thread)")
    parser.add_argument("--advance", action="store_true",
                        help="write HEAD into benchmarks/REFERENCE when every figure is at or "
                        "above the reference's (and the working files are committed)")
    args = parser.parse_args()
    if args.rounds < 1 or args.windows < 1:
        parser.error("--rounds and --windows must be at least 1")
    try:
        reference = args.reference or read_reference(REFERENCE_FILE.read_text())
        commits = {"reference": commit_of(reference), "previous": commit_of(args.revision)}
    except (OSError, ValueError) as err:
        parser.error(str(err))
    labels = {"reference": f"ref {commits['reference'][:7]}",
              "previous": f"{args.revision} {commits['previous'][:7]}"}
    trees = {"reference": checkout(commits["reference"]), "this": ROOT}
    if commits["previous"] != commits["reference"]:
        trees["previous"] = checkout(commits["previous"])
    best: dict[str, dict[str, float]] = {key: {} for key in trees}
    for _ in range(args.rounds):
        for key, tree in trees.items():
            for name, value in figures(tree, args.windows, args.clock).items():
                best[key][name] = max(value, best[key].get(name, 0.0))
    print("\n".join(report(best, labels)))
    lost = below(best)
    if lost:
        print(f"below the reference {commits['reference']}: {', '.join(lost)}")
    else:
        print(f"every figure at or above the reference {commits['reference']}")
    if args.advance:
        dirty = subprocess.run(["git", "-C", str(ROOT), "status", "--porcelain",
                                "--untracked-files=no"], capture_output=True, text=True,
                               check=True).stdout.strip()
        if lost or dirty:
            why = "figures below it" if lost else "uncommitted changes"
            print(f"reference not moved: {why}")
        else:
            head = commit_of("HEAD")
            REFERENCE_FILE.write_text(with_reference(REFERENCE_FILE.read_text(), head))
            print(f"benchmarks/REFERENCE now names {head} (commit it)")


if __name__ == "__main__":
    main()
