"""One address per node wherever a line is served: ``jvl-gym serve`` refuses two motors at one
address on the MacTalk line, on Modbus RTU and on the DMX512 line (their MacTalk address, which
Modbus takes as its slave address, MIS manual §12.1), in one line, before serving anything. (The
DMX512 start addresses may be shared: DMX receivers never answer, and fixtures on one start
address follow the same channels, MIS manual §13.1.6.)"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("mode", [[], ["--modbus"], ["--dmx"]])
def test_two_motors_at_one_address_are_refused_in_one_line(mode: list[str]) -> None:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT / "src"), str(ROOT)])}
    try:
        run = subprocess.run([sys.executable, "-m", "jvl_gym.cli", "serve", "-m", "MIS232",
                              "-a", "7", "-a", "7", "--tcp", "127.0.0.1:0", *mode],
                             capture_output=True, text=True, timeout=300, env=env)
    except subprocess.TimeoutExpired:
        pytest.fail("serve ran with two motors at one address")
    assert run.returncode == 2
    err = run.stderr.strip().splitlines()
    assert len(err) == 1 and "same address 7" in err[0] and "--address" in err[0]
