"""``engine.two_cores``: a cold start compiles half of a family's pieces, or an env's own step
functions, in a second process."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: a stand-in for a family's compiled module: two independent pieces
PROBE = '''
import os
from numba import njit, types

if os.environ.get("PROBE_FAILS_BESIDE") and os.environ.get("JVL_COMPILE_ALONE"):
    raise RuntimeError("the second process cannot import this module")


@njit(cache=True)
def inner(x):
    return 2.0 * x


@njit(cache=True)
def outer(x):
    return x + 1.0


def compile_split(arrays):
    return [(inner, (types.float64,))], [(outer, (types.float64,))]
'''

RUN = """
import json, probe_two_cores as m
from jvl_gym.engine import two_cores
two_cores.prepare(m, ())
print(json.dumps({"inner_loaded": sum(m.inner._cache_hits.values()),
                  "outer_loaded": sum(m.outer._cache_hits.values()),
                  "value": m.inner(3.0) + m.outer(3.0)}))
"""


def _run(folder: Path, **env: str) -> dict:
    return _run_code(RUN, folder, **env)


def _run_code(code: str, folder: Path, **env: str) -> dict:
    out = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True,
                         text=True, check=True, cwd=ROOT,
                         env={**os.environ, "NUMBA_CACHE_DIR": str(folder / "cache"),
                              "PYTHONPATH": os.pathsep.join([str(folder), str(ROOT / "src")]),
                              **env})
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_a_cold_start_loads_what_the_second_process_compiled(tmp_path: Path) -> None:
    (tmp_path / "probe_two_cores.py").write_text(PROBE)
    cold = _run(tmp_path)
    # the inner half came from the other process's cache, the outer half was compiled here
    assert cold == {"inner_loaded": 1, "outer_loaded": 0, "value": 10.0}
    warm = _run(tmp_path)
    assert warm == {"inner_loaded": 1, "outer_loaded": 1, "value": 10.0}


def test_alone_or_when_the_second_process_fails_this_one_compiles_everything(
        tmp_path: Path) -> None:
    for name in ("a", "b"):
        (tmp_path / name).mkdir()
        (tmp_path / name / "probe_two_cores.py").write_text(PROBE)
    compiled_here = {"inner_loaded": 0, "outer_loaded": 0, "value": 10.0}
    assert _run(tmp_path / "a", JVL_COMPILE_ALONE="1") == compiled_here
    assert _run(tmp_path / "b", PROBE_FAILS_BESIDE="1") == compiled_here


RUN_BESIDE = """
import json, probe_two_cores as m
from numba import types
from jvl_gym.engine import two_cores
beside = [(m.inner, (types.float64,))]
two_cores.start_beside("probe", lambda: beside)
m.outer(3.0)  # what this process compiles meanwhile
two_cores.finish_beside("probe", lambda: beside)
print(json.dumps({"inner_loaded": sum(m.inner._cache_hits.values()),
                  "outer_loaded": sum(m.outer._cache_hits.values()),
                  "value": m.inner(3.0) + m.outer(3.0)}))
"""


def test_a_task_s_functions_compile_beside_its_first_reset(tmp_path: Path) -> None:
    """``start_beside`` / ``finish_beside`` (an env's own step functions, ``Task.beside``): on a
    cold cache the second process compiles them and this one loads them; alone, this one
    compiles them; warm, both are loaded."""
    for name in ("a", "b"):
        (tmp_path / name).mkdir()
        (tmp_path / name / "probe_two_cores.py").write_text(PROBE)
    cold = _run_code(RUN_BESIDE, tmp_path / "a")
    assert cold == {"inner_loaded": 1, "outer_loaded": 0, "value": 10.0}
    assert _run_code(RUN_BESIDE, tmp_path / "a") == {"inner_loaded": 1, "outer_loaded": 1,
                                                    "value": 10.0}
    assert _run_code(RUN_BESIDE, tmp_path / "b", JVL_COMPILE_ALONE="1") == {
        "inner_loaded": 0, "outer_loaded": 0, "value": 10.0}


def test_an_env_s_step_uses_the_types_its_task_compiles_beside() -> None:
    """Each function a task lists in ``Task.beside`` is compiled once by the env's first step,
    for exactly the argument types listed: the second process compiles what the step uses."""
    import gymnasium as gym

    import jvl_gym  # noqa: F401
    from jvl_gym.envs import ENV_IDS

    checked = 0
    for env_id in ENV_IDS:
        env = gym.make(env_id)
        core = env.unwrapped.core
        if getattr(core.task, "beside", None) is None:
            continue
        env.reset(seed=0)
        env.step(env.action_space.sample())
        for dispatcher, sig in core.task.beside(core):
            assert tuple(sig) in dispatcher.overloads, (env_id, dispatcher, sig)
            assert len(dispatcher.overloads) == 1, (env_id, dispatcher,
                                                    list(dispatcher.overloads))
        checked += 1
    assert checked >= 2  # GearSync: its speed profile and web steps; CoilWinding: turn, layer
