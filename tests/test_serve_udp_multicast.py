"""Doors that open from another process: ``jvl-gym serve --canopen`` and ``--j1939`` on
python-can's ``udp_multicast`` bus (loopback only), reached by a master in this process while
the twin runs in a process of its own: an SDO read of the device type (1000h, MIS manual §11.4)
and a request for address claimed (SAE J1939/81, MIS manual §11.8.3)."""

from __future__ import annotations

import os
import random
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import can
import canopen
import pytest

from jvl_gym import MotorArray
from jvl_gym.protocol.canopen.eds import shipped_path
from jvl_gym.protocol.sae_j1939 import Name
from jvl_gym.protocol.sae_j1939.frames import can_id

ROOT = Path(__file__).resolve().parents[1]
TOOL = 0xF9


@pytest.fixture(scope="module")
def group() -> str:
    """A multicast group of this test run's own (administratively scoped)."""
    return f"239.255.{random.randrange(1, 255)}.{random.randrange(1, 255)}"


@pytest.fixture(scope="module")
def served(group: str) -> Iterator[subprocess.Popen[str]]:
    """``jvl-gym serve`` of one MIS232 as CANopen slave (node 5) and J1939 node (address 5)
    on ``udp_multicast`` in a process of its own, running."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT / "src"), str(ROOT)])}
    proc = subprocess.Popen(
        [sys.executable, "-m", "jvl_gym.cli", "serve", "-m", "MIS232", "-a", "1", "--canopen",
         "--can-interface", "udp_multicast", "--can-channel", group,
         "--j1939", f"udp_multicast:{group}"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    assert proc.stdout is not None
    lines = []
    for line in proc.stdout:  # the banner, up to "running at speed …"
        lines.append(line)
        if line.startswith("running"):
            break
    else:
        proc.wait(timeout=60)
        pytest.fail(f"serve did not start: {''.join(lines)} {proc.stderr.read()}")
    assert any(f"canopen udp_multicast:{group}" in line for line in lines), lines
    yield proc
    proc.send_signal(signal.SIGINT)
    proc.wait(timeout=60)


def test_a_master_in_another_process_reads_the_device_type_over_canopen(served, group):
    network = canopen.Network()
    network.connect(interface="udp_multicast", channel=group, hop_limit=0)
    try:
        node = network.add_node(5, str(shipped_path()))
        node.sdo.RESPONSE_TIMEOUT = 5.0
        value = int.from_bytes(node.sdo.upload(0x1000, 0), "little")
        assert value == node.object_dictionary[0x1000].default != 0
    finally:
        network.disconnect()


def test_a_tool_in_another_process_gets_the_address_claim_over_j1939(served, group):
    bus = can.Bus(interface="udp_multicast", channel=group, hop_limit=0)
    try:
        bus.send(can.Message(arbitration_id=can_id(59904, TOOL, 255),
                             data=bytes.fromhex("00ee00"), is_extended_id=True))
        name = Name.from_value(MotorArray("MIS232").family.j1939_name).to_bytes()
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline:
            msg = bus.recv(1.0)
            if msg is not None and msg.is_extended_id and msg.arbitration_id == 0x18EEFF05:
                assert bytes(msg.data) == name
                break
        else:
            pytest.fail("no address claim from node 5")
    finally:
        bus.shutdown()
