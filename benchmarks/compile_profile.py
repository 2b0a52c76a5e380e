"""Where a numba compile spends its time, per compiled function and compiler stage.

numba broadcasts events while it compiles (``numba.core.event``): ``numba:compile`` around the
compile of each dispatcher (only on a cache miss), ``numba:run_pass`` around each compiler pass
(of the function compiled and of each function inlined into it at the IR level), and
``numba:llvm_lock`` while LLVM works (optimising and emitting machine code). A listener on the
three keeps a stack of what runs and charges each interval's own time (without the time of what
runs inside it, such as a callee's compile during type inference) to the innermost function
being compiled and to a stage. Times are CPU seconds of the process (``time.process_time``), so
that a loaded machine gives the figures of a quiet one:

- ``typing``: numba's type inference passes;
- ``inlining``: the passes that inline functions at the IR level (``inline="always"``, overloads);
- ``lowering``: the native lowering passes (numba IR to LLVM IR), LLVM's time excluded;
- ``llvm``: LLVM (while the LLVM lock is held);
- ``other``: the remaining passes of numba's front end (IR building, rewrites, analyses)
  and the dispatcher's own work around them.

``python compile_profile.py CODE`` runs ``CODE`` (in this process alone: ``JVL_COMPILE_ALONE``)
under the listener and prints the totals as
JSON on its last line: ``{function: {stage: seconds}}``, plus ``"__inlined__"``: the front-end
seconds spent in the passes of each function by qualified name (inlined callees included).
"""

from __future__ import annotations

import json
import os
import sys
import time
from collections import defaultdict

from numba.core import event

STAGES = ("typing", "inlining", "lowering", "llvm", "other")


def stage_of(pass_name: str) -> str:
    """The stage of a numba compiler pass by its name."""
    if "type_inference" in pass_name:
        return "typing"
    if "inline" in pass_name:
        return "inlining"
    if "lowering" in pass_name:
        return "lowering"
    return "other"


class Profile(event.Listener):
    """Exclusive time per (compiled function, stage) and front-end time per pass owner."""

    def __init__(self) -> None:
        self.stack: list[list] = []  # [function, stage or None, owner, start, child time]
        self.totals: dict[str, dict[str, float]] = defaultdict(lambda: dict.fromkeys(STAGES, 0.0))
        self.owners: dict[str, float] = defaultdict(float)

    def _function(self) -> str:
        for frame in reversed(self.stack):
            if frame[1] is None:
                return frame[0]
        return "?"

    def on_start(self, ev: event.Event) -> None:
        data = ev.data or {}
        if ev.kind == "numba:compile":
            fn = getattr(data.get("dispatcher"), "py_func", None)
            name = f"{getattr(fn, '__module__', '?')}.{getattr(fn, '__qualname__', '?')}"
            self.stack.append([name, None, name, time.process_time(), 0.0])
        elif ev.kind == "numba:run_pass":
            name = str(data.get("name", "?"))
            self.stack.append([self._function(), stage_of(name.split(" [")[0]),
                               str(data.get("qualname", "?")), time.process_time(), 0.0])
        else:
            self.stack.append([self._function(), "llvm", "", time.process_time(), 0.0])

    def on_end(self, ev: event.Event) -> None:
        if not self.stack:
            return
        function, stage, owner, start, child = self.stack.pop()
        elapsed = time.process_time() - start
        own = elapsed - child
        self.totals[function][stage or "other"] += own
        if stage not in (None, "llvm"):
            self.owners[owner] += own
        if self.stack:
            self.stack[-1][4] += elapsed


def run(code: str) -> dict:
    """Run ``code`` under a :class:`Profile`; its totals (see the module docstring)."""
    profile = Profile()
    for kind in ("numba:compile", "numba:run_pass", "numba:llvm_lock"):
        event.register(kind, profile)
    exec(compile(code, "<profiled>", "exec"), {})
    result: dict = {k: dict(v) for k, v in profile.totals.items()}
    result["__inlined__"] = dict(profile.owners)
    return result


if __name__ == "__main__":
    # the events are this process's: compile everything here, none of it in a second process
    # (``jvl_gym.engine.two_cores``)
    os.environ["JVL_COMPILE_ALONE"] = "1"
    print(json.dumps(run(sys.argv[1])))
