"""``jvl-gym serve --canopen``: the motors as CANopen slaves on a python-can bus beside the
serial endpoints of the same twin; bad options and a bus that cannot be opened are one line."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import canopen
import pytest

from jvl_gym.cli.main import app
from jvl_gym.cli.serve import build_line, canopen_server
from jvl_gym.protocol.canopen.eds import shipped_path
from jvl_gym.protocol.mactalk import codec32 as m32


@pytest.mark.parametrize("argv, words", [
    (["--canopen", "--can-interface", "nosuch", "--can-channel", "x"], "cannot open CAN bus"),
    (["-m", "MAC140", "--canopen", "--can-interface", "virtual"], "no CANopen interface"),
    (["--pty", "--node-id", "5"], "give --canopen too"),
    (["-a", "1", "-a", "2", "--canopen", "--can-interface", "virtual", "--node-id", "5"],
     "one --node-id per --address"),
    (["-a", "1", "-a", "2", "--canopen", "--can-interface", "virtual"], "node id 5"),
    (["--canopen", "--can-interface", "virtual", "--node-id", "128"], "1..127"),
])
def test_bad_options_are_one_line_errors(argv: list[str], words: str,
                                         capsys: pytest.CaptureFixture[str]) -> None:
    motor = [] if "-m" in argv else ["-m", "MIS232"]
    with pytest.raises(SystemExit) as info:
        app(["serve", *motor, *argv])
    assert info.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len([line for line in err if "compil" not in line]) == 1 and words in err[-1]


def test_two_motors_on_one_bus_beside_mactalk() -> None:
    """Two MIS at node ids 5 and 6 on a virtual bus; MacTalk reads the register the CANopen
    master wrote (one twin, one clock)."""
    line, _ = build_line(["MIS232", "MIS232"], [1, 2])
    server = canopen_server(line, "virtual", "serve-test", [5, 6], 1.0, run_clock=False)
    net = canopen.Network()
    net.connect(interface="virtual", channel="serve-test")
    try:
        server.start()
        a = net.add_node(5, str(shipped_path()))
        b = net.add_node(6, str(shipped_path()))
        a.sdo[0x2012][5].raw = 11111
        b.sdo[0x2012][5].raw = 22222
        session = line.session()
        reply = session.feed(m32.encode_read(2, 5))
        assert reply == m32.encode_reply(5, (22222).to_bytes(4, "little"))
        assert [int(v) for v in line.m.read_raw("V_SOLL")] == [11111, 22222]
    finally:
        server.stop()
        net.disconnect()


def test_serve_process_prints_its_nodes_and_stops_on_sigint(tmp_path: Path) -> None:
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
    proc = subprocess.Popen(
        [sys.executable, "-m", "jvl_gym.cli", "serve", "-m", "MIS232", "--canopen",
         "--can-interface", "virtual", "--can-channel", "proc", "--node-id", "9", "--speed",
         "4", "--flash-dir", str(tmp_path)],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env)
    try:
        lines = []
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline:
            text = proc.stdout.readline() if proc.stdout else ""
            lines.append(text)
            if "Ctrl-C" in text or not text:
                break
        assert any("canopen virtual:proc: motor 0 node id 9" in t for t in lines), lines
        proc.send_signal(signal.SIGINT)  # serve takes Ctrl-C from its ready line on
        out, _ = proc.communicate(timeout=30)
        assert proc.returncode == 0 and "stopped" in out
    finally:
        if proc.poll() is None:
            proc.kill()
