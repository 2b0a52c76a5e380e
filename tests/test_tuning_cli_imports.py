"""``jvl-tune --help`` and usage errors answer without loading the numerics: the command
modules (numba, scipy, python-control, matplotlib, the simulator) are imported by the command
that runs, not by the command line's module."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

HEAVY = ("numba", "scipy", "control", "matplotlib", "jvl_gym.sim")

_PROBE = f"""
import json, sys
from tuning.cli import app
try:
    app(sys.argv[1:])
except SystemExit as exc:
    code = exc.code
else:
    code = 0
print(json.dumps({{"code": code, "loaded": [m for m in {HEAVY!r} if m in sys.modules]}}),
      file=sys.stderr)
"""


def _run(*args: str) -> tuple[int, list[str], str]:
    proc = subprocess.run([sys.executable, "-c", _PROBE, *args], capture_output=True,
                          text=True, timeout=120)
    *msgs, last = proc.stderr.strip().splitlines()
    out = json.loads(last)
    return out["code"], out["loaded"], proc.stdout + "\n".join(msgs)


@pytest.mark.parametrize("args", [("--help",), ("autotune", "--help"), ("identify", "--help"),
                                  ("fleet", "--help")])
def test_help_loads_no_numerics(args: tuple[str, ...]) -> None:
    code, loaded, text = _run(*args)
    assert code == 0 and "Usage" in text
    assert loaded == []


def test_a_usage_error_loads_no_numerics() -> None:
    code, loaded, text = _run("autotune", "--load-inertia", "-1")
    assert code == 2 and "must be >= 0" in text
    assert loaded == []


def test_the_help_names_the_recommended_record_lengths() -> None:
    from tuning.autotune import RECOMMENDED_COIL_SAMPLES, RECOMMENDED_MECH_SAMPLES

    _, _, text = _run("autotune", "--help")
    assert f"default: {RECOMMENDED_COIL_SAMPLES}" in text
    assert f"default: {RECOMMENDED_MECH_SAMPLES}" in text


def test_numba_loaded_after_jvl_gym_gets_the_compile_notice_and_keeps_its_loader() -> None:
    probe = ("import sys, jvl_gym; assert 'numba' not in sys.modules; import numba; "
             "from importlib.machinery import SourceFileLoader; "
             "from jvl_gym.engine import notice; "
             "assert isinstance(numba.__spec__.loader, SourceFileLoader); "
             "assert numba.__loader__ is numba.__spec__.loader; "
             "assert len(notice._installed) == 1; print('ok')")
    env = {k: v for k, v in os.environ.items() if k != "JVL_QUIET_COMPILE"}
    proc = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                          timeout=120, env=env)
    assert proc.returncode == 0 and proc.stdout.strip() == "ok", proc.stderr
