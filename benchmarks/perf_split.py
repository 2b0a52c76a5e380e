"""Where a 1024-copy env step spends its time, per thread (a measurement, not a benchmark).

Linux ``perf`` samples a running process by CPU clock (the 2-core VM has no hardware counters)
but cannot name numba's machine code: it lives in memory that no file describes. This script
steps an env, writes ``/tmp/perf-<pid>.map`` — the address and name of the machine code of
every compiled function the process has compiled or loaded, which ``perf report`` reads for
such code — records the steps with ``perf record -e cpu-clock`` for ``--seconds`` and prints,
per thread, the share of each compiled function, of OpenMP's waiting threads (``libgomp``), of
Python and numpy, and of libm.

A function's share includes what LLVM inlined into it (the lanes' samples, the outer firmware,
a task's block with its hooks); functions compiled apart (``jvl_gym.engine.apart``) have their
own lines.

    python benchmarks/perf_split.py [--env GearSync] [--copies 1024] [--seconds 8]
"""

from __future__ import annotations

import argparse
import collections
import gc
import os
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path


def write_perf_map() -> Path:
    """Write ``/tmp/perf-<pid>.map`` for the compiled functions of this process (start, size
    up to the next function, ``module.qualified_name``); returns its path."""
    from numba.core.dispatcher import Dispatcher

    names: dict[int, str] = {}
    for obj in gc.get_objects():
        if not isinstance(obj, Dispatcher):
            continue
        for cres in list(obj.overloads.values()):
            try:
                address = cres.library.get_pointer_to_function(cres.fndesc.llvm_func_name)
            except Exception:  # noqa: BLE001  (an overload without machine code of its own)
                continue
            if address:
                names[address] = f"{obj.py_func.__module__}.{obj.py_func.__qualname__}"
    path = Path(f"/tmp/perf-{os.getpid()}.map")
    starts = sorted(names)
    with path.open("w") as out:
        for start, end in zip(starts, [*starts[1:], starts[-1] + (1 << 20)]):
            out.write(f"{start:x} {min(end - start, 1 << 20):x} {names[start]}\n")
    return path


def _kind(where: str) -> str:
    """The line a sample counts in: the compiled function's name, or the library's kind."""
    if "libgomp" in where:
        return "OpenMP waiting (libgomp)"
    if "perf-" in where:
        return where.split(" (")[0].rsplit(".", 1)[-1]
    if "libm." in where:
        return "libm"
    return "Python, numpy, libc and the rest"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--env", default="GearSync")
    parser.add_argument("--copies", type=int, default=1024)
    parser.add_argument("--seconds", type=float, default=8.0)
    args = parser.parse_args()

    import gymnasium as gym
    import numpy as np

    import jvl_gym  # noqa: F401

    venv = gym.make_vec(f"jvl_gym/{args.env}-v0", num_envs=args.copies,
                        vectorization_mode="vector_entry_point")
    venv.reset(seed=0)
    acts = np.random.default_rng(0).uniform(-1, 1, (16, *venv.action_space.shape))
    for _ in range(10):  # compiled, loaded and warm
        for a in acts:
            venv.step(a)
    perf_map = write_perf_map()
    stop = threading.Event()

    def steps() -> None:
        while not stop.is_set():
            for a in acts:
                venv.step(a)

    with tempfile.TemporaryDirectory(prefix="jvl-perf-") as tmp:
        data = Path(tmp) / "perf.data"
        worker = threading.Thread(target=steps)
        worker.start()
        time.sleep(0.5)
        try:
            subprocess.run(["perf", "record", "-q", "-e", "cpu-clock", "-F", "2000", "-p",
                            str(os.getpid()), "-o", str(data), "--", "sleep",
                            str(args.seconds)], check=True, capture_output=True)
        finally:
            stop.set()
            worker.join()
        script = subprocess.run(["perf", "script", "-i", str(data), "-F", "tid,ip,sym,dso"],
                                check=True, capture_output=True, text=True).stdout
    perf_map.unlink(missing_ok=True)
    counts: dict[str, collections.Counter[str]] = collections.defaultdict(collections.Counter)
    for line in script.splitlines():
        parts = line.split(None, 2)
        if len(parts) == 3:
            counts[parts[0]][_kind(parts[2])] += 1
    print(f"{args.env}, {args.copies} copies: CPU-clock samples per thread")
    for tid, kinds in sorted(counts.items(), key=lambda kv: -sum(kv[1].values())):
        total = sum(kinds.values())
        print(f"thread {tid} ({total} samples)")
        for kind, n in kinds.most_common():
            if n >= 0.01 * total:
                print(f"  {100 * n / total:5.1f} %  {kind}")


if __name__ == "__main__":
    sys.exit(main())
