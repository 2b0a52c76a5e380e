"""The engine's public pieces: specialised drivers, the compile notice, and the operations a
task uses instead of kernel arrays (start_under_load, reseed, write_many)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

from jvl_gym import MotorArray
from jvl_gym.families.mac050_141 import constants as c

ROOT = Path(__file__).resolve().parents[1]


def _python(code: str, cache_dir: Path, **env: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True,
                          text=True, check=True, cwd=ROOT,
                          env={**os.environ, "NUMBA_CACHE_DIR": str(cache_dir), **env})


PROBE = """
import json
from numba import njit
from jvl_gym.engine.specialize import specialise


def _template(x):
    return hook(x) + offset


@njit(cache=True, inline="always")
def double(x):
    return 2 * x


@njit(cache=True, inline="always")
def negate(x):
    return -x


def run():
    out = {}
    for tag, hook in (("double", double), ("negate", negate)):
        f = specialise({"_template": _template}, {"hook": hook, "offset": 1}, tag, __file__,
                       {"_template": {"cache": True}})["_template"]
        out[tag] = [f(3), sum(f.stats.cache_hits.values())]
    return json.dumps(out)
"""


def test_specialised_drivers_bind_their_names_and_are_cached_apart(tmp_path: Path) -> None:
    """Two specialisations of one template with the same signature compute with their own
    bindings, and a second process loads both from numba's cache."""
    (tmp_path / "probe_templates.py").write_text(PROBE)
    code = f"import sys; sys.path.insert(0, {str(tmp_path)!r}); import probe_templates as t; " \
           "print(t.run())"
    first = _python(code, tmp_path / "cache")
    second = _python(code, tmp_path / "cache")
    a, b = json.loads(first.stdout), json.loads(second.stdout)
    assert a["double"][0] == 7 and a["negate"][0] == -2
    assert b["double"] == [7, 1] and b["negate"] == [-2, 1]  # loaded, not compiled again


def test_a_compile_says_so_on_stderr_first_and_a_cached_start_does_not(tmp_path: Path) -> None:
    code = """
    import numpy as np
    import jvl_gym
    from jvl_gym.motor.keywords import first_bad_value
    first_bad_value(np.zeros((1, 2)), np.zeros(1, dtype=np.int64))
    """
    cold = _python(code, tmp_path)
    assert "jvl_gym: compiling numba code for this machine" in cold.stderr
    assert "compiling jvl_gym.motor.keywords.first_bad_value" in cold.stderr
    warm = _python(code, tmp_path)
    assert "compiling" not in warm.stderr
    quiet = _python(code, tmp_path / "other", JVL_QUIET_COMPILE="1")
    assert quiet.stderr == ""


def _loaded(hold: bool) -> MotorArray:
    m = MotorArray("MAC140", n=2, seed=0, load_inertia=2e-5)
    m.write_many({"V_SOLL": 0, "MODE_REG": c.V_MODE})
    torque = np.array([0.1, -0.15])
    if hold:
        m.start_under_load(torque)
        np.testing.assert_array_equal(m.inputs[:, m.INPUTS["load_torque"]], torque)  # the load too
    else:
        m.set_input(load_torque=torque)
    return m


def test_start_under_load_starts_a_motor_that_already_carries_its_load() -> None:
    held, free = _loaded(True), _loaded(False)
    for m in (held, free):
        m.step(30)
    # without it the load pulls the shaft until the speed loop's integrator has caught up
    assert np.all(np.abs(held.position_rad) < 0.2 * np.abs(free.position_rad))


@pytest.mark.parametrize("torque", [np.nan, np.inf, [0.1, 0.2, 0.3], "0.1"])
def test_start_under_load_refuses_bad_values_and_changes_nothing(torque: object) -> None:
    m = MotorArray("MAC140", n=2, seed=0)
    state = m.state.copy()
    with pytest.raises(ValueError):
        m.start_under_load(torque)
    np.testing.assert_array_equal(m.state, state)


def test_reseed_gives_new_noise_streams_and_refuses_other_types() -> None:
    a = MotorArray("MAC140", n=2, seed=1, current_noise=0.5)
    b = MotorArray("MAC140", n=2, seed=2, current_noise=0.5)
    b.reseed(a.keys.copy())
    for m in (a, b):
        m.write_many({"V_SOLL": 800, "MODE_REG": c.V_MODE})
        m.step(20)
    np.testing.assert_array_equal(a.state, b.state)
    keys = b.keys.copy()
    for bad in (np.array([1.0, 2.0]), np.array([1, 2, 3], dtype=np.uint64), [1, 2]):
        with pytest.raises(ValueError):
            b.reseed(bad)
        np.testing.assert_array_equal(b.keys, keys)


def test_compile_caches_are_dropped_when_compiled_sources_change(tmp_path):
    """An edit of any file with compiled code removes every cache file of the package (numba
    alone would keep a caller's cache with the old callee inlined); other edits remove none."""
    from jvl_gym.engine.cache import drop_stale_caches

    pkg = tmp_path / "pkg"
    (pkg / "sub" / "__pycache__").mkdir(parents=True)
    kernel = pkg / "sub" / "kernel.py"
    kernel.write_text("from numba import njit\n")
    plain = pkg / "cli.py"
    plain.write_text("x = 1\n")
    cache = pkg / "sub" / "__pycache__" / "caller.f-1.py311.nbi"

    def make_cache():
        cache.write_bytes(b"x")
        cache.with_suffix(".nbc").write_bytes(b"x")

    make_cache()
    assert drop_stale_caches(pkg) == 2  # no stamp yet: caches of unknown sources go
    make_cache()
    assert drop_stale_caches(pkg) == 0 and cache.exists()  # unchanged sources
    plain.write_text("x = 2\n")
    assert drop_stale_caches(pkg) == 0 and cache.exists()  # no compiled code changed
    kernel.write_text("from numba import njit\n# edited\n")
    assert drop_stale_caches(pkg) == 2 and not cache.exists()
    make_cache()
    assert drop_stale_caches(pkg) == 0 and cache.exists()


@pytest.mark.parametrize("name", ["constants.py", "registers.csv"])
def test_an_edited_family_fact_drops_the_caches_that_froze_it(tmp_path, name):
    """A family's constants and register table are frozen into compiled code as numbers, though
    their files use no numba: an edit of them drops the caches too."""
    from jvl_gym.engine.cache import drop_stale_caches

    folder = tmp_path / "pkg" / "families" / "toy"
    (folder / "__pycache__").mkdir(parents=True)
    (folder / "kernel.py").write_text("from numba import njit\n")
    fact = folder / name
    fact.write_text("x = 1\n")
    cache = folder / "__pycache__" / "kernel.f-1.py311.nbi"
    drop_stale_caches(tmp_path / "pkg")
    cache.write_bytes(b"x")
    fact.write_text("x = 2\n")
    assert drop_stale_caches(tmp_path / "pkg") == 1 and not cache.exists()


def test_stale_caches_under_numba_cache_dir_are_dropped_too(tmp_path, monkeypatch):
    from jvl_gym.engine.cache import drop_stale_caches

    pkg = tmp_path / "pkg"
    pkg.mkdir()
    (pkg / "kernel.py").write_text("from numba import njit\n")
    user = tmp_path / "numba-cache"
    import hashlib
    import os

    mirrored = user / f"pkg_{hashlib.sha1(os.path.abspath(pkg).encode()).hexdigest()}"
    mirrored.mkdir(parents=True)
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(user))
    drop_stale_caches(pkg)
    (mirrored / "kernel.f-1.py311.nbi").write_bytes(b"x")
    (pkg / "kernel.py").write_text("from numba import njit\n# edited\n")
    assert drop_stale_caches(pkg) == 1
    assert not (mirrored / "kernel.f-1.py311.nbi").exists()


def test_task_driver_runner_is_its_step_for_the_number_of_copies() -> None:
    """An env keeps the driver's compiled step (``TaskDriver.runner``): the serial one below
    ``PARALLEL_MIN`` copies, the threaded one from there, the same as ``step`` calls, by its
    machine code's own entry (``jvl_gym.engine.entry``)."""
    import gymnasium as gym

    from jvl_gym.engine.driver import PARALLEL_MIN
    from jvl_gym.engine.entry import entry_point

    for n, attr in ((1, "serial"), (PARALLEL_MIN, "parallel")):
        core = gym.make_vec("jvl_gym/Positioning-v0", num_envs=n,
                            vectorization_mode="vector_entry_point").unwrapped
        core.reset(seed=0)
        assert core._driver.runner(core.motors.engine_view()) is getattr(core._driver, attr)
        actions = np.zeros((n, 1), dtype=np.float32)
        core.step(actions)
        step = getattr(core._driver, attr)
        entry = entry_point(step, (*core._step_head, actions.astype(np.float64), core.decimation))
        assert entry is not step  # the machine code's own entry, found once
        assert core._run is entry
