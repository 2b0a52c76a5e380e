"""Functions compiled apart (``jvl_gym.engine.apart``): their compiled callers call their
machine code instead of linking a copy, in the process that compiles the caller and in every
later one that loads it from numba's cache."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from numba import njit

from jvl_gym import MotorArray
from jvl_gym.engine.apart import apart
from jvl_gym.motor.stepping import driver as motor_driver

ROOT = Path(__file__).resolve().parents[1]

PROBE = """
import numpy as np
from numba import njit
from jvl_gym.engine.apart import apart

ROW = np.dtype([("gain", np.float64), ("count", np.int64)])


@apart
@njit(cache=True, _nrt=False)
def weigh(rows, x):
    if x < 0.0:
        raise ValueError("negative weight")
    total = 0.0
    for i in range(rows.shape[0]):
        rows[i].count += 1
        total += rows[i].gain * x
    return total


@njit(cache=True, _nrt=False)
def caller(rows, x):
    return weigh(rows, x) + weigh(rows, 2.0 * x)
"""

RUN = """
import json, sys
import numpy as np
sys.path.insert(0, {folder!r})
import probe_apart as p
rows = np.zeros(3, p.ROW)
rows["gain"] = [1.0, 2.0, 3.0]
out = {{"value": p.caller(rows, 1.0), "counts": rows["count"].tolist(),
       "caller_loaded": sum(p.caller.stats.cache_hits.values())}}
try:
    p.caller(rows, -1.0)
except ValueError as e:
    out["error"] = str(e)
ir = p.caller.inspect_llvm(p.caller.signatures[0])
out["declared"] = any(line.startswith("declare") and "jvl_gym.apart." in line
                      for line in ir.splitlines())
out["copied"] = "negative weight" in ir
print(json.dumps(out))
"""


def _run(folder: Path) -> dict:
    out = subprocess.run([sys.executable, "-c", textwrap.dedent(RUN.format(folder=str(folder)))],
                         capture_output=True, text=True, check=True, cwd=ROOT,
                         env={**os.environ, "NUMBA_CACHE_DIR": str(folder / "cache")})
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_a_cached_caller_calls_the_apart_function_compiled_in_any_process(tmp_path: Path) -> None:
    """The caller holds a call, not a copy; a second process loads the caller from the cache
    and calls the callee it loads; a third compiles the callee anew (its cache removed) and the
    cached caller calls that one (numba's own names of the callee differ between processes:
    a record type in the arguments is numbered per process)."""
    (tmp_path / "probe_apart.py").write_text(PROBE)
    first = _run(tmp_path)
    assert first == {"value": 18.0, "counts": [2, 2, 2], "caller_loaded": 0,
                     "error": "negative weight", "declared": True, "copied": False}
    second = _run(tmp_path)
    assert second["value"] == 18.0 and second["caller_loaded"] == 1
    assert second["error"] == "negative weight"
    for path in (tmp_path / "cache").rglob("probe_apart.weigh-*"):
        path.unlink()
    third = _run(tmp_path)
    assert third["value"] == 18.0 and third["counts"] == [2, 2, 2]
    assert third["caller_loaded"] == 1


def test_apart_refuses_a_function_compiled_already() -> None:
    @njit
    def twice(x):  # pragma: no cover - compiled
        return 2 * x

    twice(1)
    with pytest.raises(ValueError, match="compiled already"):
        apart(twice)


def test_a_motor_driver_calls_the_family_kernel_without_a_copy_of_it() -> None:
    """The serial driver of a motor array calls the block step, which calls the firmware step
    and the inner samples: none of them is linked into the driver."""
    from jvl_gym.engine.apart import Apart
    from jvl_gym.families.mac050_141 import inner, kernel

    m = MotorArray("MAC140", n=2, seed=0)
    m.step(1)
    assert np.isfinite(m.state).all()
    assert isinstance(kernel.outer_firmware, Apart) and isinstance(inner.inner_samples_one, Apart)
    driver = motor_driver("mac050_141").serial
    if driver.stats.cache_hits:
        # numba shows no IR of code loaded from its cache (`jvl-gym compile` filled it): the
        # cross-process cases above check a caller loaded from the cache
        return
    ir = driver.inspect_llvm(driver.signatures[0])
    defined = [line for line in ir.splitlines() if line.startswith("define")]
    assert not any("outer_firmware" in line or "inner_samples" in line for line in defined)
    assert any(line.startswith("declare") and "_advance_block" in line
               for line in ir.splitlines())
