"""J1939 of the MIS motors (MIS manual §11.8): the NAME field and address claim, MAC register
read and write by DM14/DM15/DM16 byte for byte as §11.8.6–11.8.7 show, failures, and the
can-j1939 package's DM14 client against the motor on a python-can virtual bus."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import can
import numpy as np
import pytest

from jvl_gym import MotorArray
from jvl_gym.families import UnsupportedOperation
from jvl_gym.protocol.mactalk.twin16 import Twin
from jvl_gym.protocol.sae_j1939 import J1939Device, Name
from jvl_gym.protocol.sae_j1939.frames import Dm14, can_id, split_id
from jvl_gym.protocol.sae_j1939.node import J1939Node

TOOL = 0xF9
H = bytes.fromhex


def _device() -> tuple[MotorArray, J1939Device]:
    m = MotorArray("MIS232", seed=0)
    return m, J1939Device(m, 0, 5)


def test_a_family_without_j1939_has_no_node() -> None:
    """Only a family that declares the J1939 interface gets a node, with its own NAME."""
    with pytest.raises(UnsupportedOperation, match="J1939"):
        J1939Device(MotorArray("MAC140"), 0, 5)


def _ask(d: J1939Device, pgn: int, data: bytes, now: float = 0.0) -> list[tuple[int, bytes]]:
    return [(f.arbitration_id, f.data) for f in d.handle(can_id(pgn, TOOL, 5), data, now)]


def test_name_field_and_address_claim_as_the_explorer_shows() -> None:
    """§11.8.4: "FF FF FF FF 01 FF FE 80" from node 5, PGN 60928 broadcast, priority 6."""
    m, d = _device()
    name = Name.from_value(m.family.j1939_name)
    assert d.name == name and name.to_bytes() == H("ff ff ff ff 01 ff fe 80")
    assert Name.from_bytes(name.to_bytes()) == name and name.arbitrary_address
    assert (name.ecu_instance, name.function, name.vehicle_system) == (1, 0xFF, 0x7F)
    [claim] = d.claim()
    assert (claim.arbitration_id, claim.data) == (0x18EEFF05, H("ff ff ff ff 01 ff fe 80"))
    assert split_id(0x18EEFF05) == (6, 60928, 5, 255)
    request = d.handle(can_id(59904, TOOL, 255), H("00 ee 00"))  # request for PGN 60928
    assert request == [claim]


def test_read_a_register_byte_for_byte() -> None:
    """§11.8.7 "Normal read operation": proceed, binary data, complete; V_SOLL = 10000."""
    _, d = _device()
    req = H("04 03 05 00 00 80 ff ff")  # length 4, read, pointer 5, extension 80h
    assert Dm14.from_bytes(req) == Dm14(4, 1, 5, 0x80, 0, 0xFFFF)
    assert _ask(d, 55552, req) == [
        (0x18D8F905, H("04 11 ff ff ff ff ff ff")),  # DM15 proceed
        (0x18D7F905, H("04 10 27 00 00 ff ff ff")),  # DM16: 10000
        (0x18D8F905, H("00 19 ff ff ff ff ff ff"))]  # DM15 operation completed
    assert _ask(d, 55552, H("01 09 05 00 00 80 ff ff")) == []  # operation complete
    assert _ask(d, 55552, H("02 03 05 00 00 80 ff ff"))[1][1] == H("02 10 27 ff ff ff ff ff")


def test_write_a_register_byte_for_byte() -> None:
    """§11.8.7 "Memory request Write": proceed; the tool's DM16; complete."""
    m, d = _device()
    assert _ask(d, 55552, H("04 05 05 00 00 80 ff ff")) == [
        (0x18D8F905, H("04 11 ff ff ff ff ff ff"))]
    assert _ask(d, 55040, H("04 20 4e 00 00 ff ff ff"), 0.5) == [
        (0x18D8F905, H("00 19 ff ff ff ff ff ff"))]
    assert m.read_raw("V_SOLL")[0] == 20000
    assert _ask(d, 55552, H("02 05 05 00 00 80 ff ff")) == [
        (0x18D8F905, H("02 11 ff ff ff ff ff ff"))]
    _ask(d, 55040, H("02 18 fc ff ff ff ff ff"))  # −1000 in 2 bytes, sign-extended
    assert m.read_raw("V_SOLL")[0] == -1000


FAILED = [(0x18D8F905, H("00 1b ff ff ff ff ff ff"))]


@pytest.mark.parametrize("req", [
    H("04 03 05 00 00 00 ff ff"),  # pointer extension not 80h
    H("03 03 05 00 00 80 ff ff"),  # length 3
    H("04 03 04 00 00 80 ff ff"),  # reserved register 4
    H("04 03 00 02 00 80 ff ff"),  # register 512: not in the MIS table
    H("04 13 05 00 00 80 ff ff"),  # pointer type 1 (not direct)
    H("04 01 05 00 00 80 ff ff"),  # command 0 (erase)
    H("04 03 05 00 00 80 ff"),  # 7 bytes
])
def test_malformed_requests_fail(req: bytes) -> None:
    m, d = _device()
    regs = m.regs.copy()
    assert _ask(d, 55552, req) == FAILED
    assert np.array_equal(m.regs, regs)


def test_refused_and_late_and_stray_writes_fail() -> None:
    m, d = _device()
    assert _ask(d, 55040, H("04 20 4e 00 00 ff ff ff")) == FAILED  # no write pending
    _ask(d, 55552, H("04 05 05 00 00 80 ff ff"))
    assert _ask(d, 55040, H("04 80 1a 06 00 ff ff ff")) == FAILED  # 400000: out of range
    _ask(d, 55552, H("04 05 05 00 00 80 ff ff"))
    assert _ask(d, 55040, H("02 20 4e ff ff ff ff ff")) == FAILED  # 2 bytes, 4 asked
    _ask(d, 55552, H("04 05 05 00 00 80 ff ff"), 10.0)
    assert _ask(d, 55040, H("04 20 4e 00 00 ff ff ff"), 11.5) == FAILED  # after 1000 ms
    _ask(d, 55552, H("04 05 0c 00 00 80 ff ff"))  # V_IST is read-only
    assert _ask(d, 55040, H("04 20 4e 00 00 ff ff ff")) == FAILED
    assert m.read_raw("V_SOLL")[0] == 10000


def test_address_contention() -> None:
    _, d = _device()
    lower = Name(1, 1, 0, 0, 0, 0, 0, 0, False).to_bytes()
    [again] = d.handle(can_id(60928, 5, 255), lower)
    assert d.address == 129 and again.arbitration_id == 0x18EEFF81
    higher = H("ff ff ff ff ff ff ff ff")
    assert d.handle(can_id(60928, 129, 255), higher)[0].arbitration_id == 0x18EEFF81
    assert d.address == 129


def test_the_can_j1939_client_reads_and_writes_over_a_virtual_bus() -> None:
    """can-j1939's DM14 query (its released 2.0.12) against the motor on python-can."""
    import j1939
    from j1939.memory_access import Dm14Query

    channel = f"j1939-test-{time.monotonic_ns()}"
    m = MotorArray("MIS232", seed=0)
    twin = Twin(m, [5])
    bus = can.Bus(interface="virtual", channel=channel, receive_own_messages=False)
    node = J1939Node(twin, bus, [5]).start()
    ecu = j1939.ElectronicControlUnit()
    ecu.connect(interface="virtual", channel=channel)
    name = j1939.Name(arbitrary_address_capable=0, industry_group=0, vehicle_system_instance=0,
                      vehicle_system=0, function=0, function_instance=0, ecu_instance=0,
                      manufacturer_code=0, identity_number=1)
    ca = j1939.ControllerApplication(name, TOOL, bypass_address_claim=True)
    ecu.add_ca(controller_application=ca)
    ca.start()
    try:
        query = Dm14Query(ca)
        raw = query.read(5, 0, 0x80 << 24 | 5, 4, return_raw_bytes=True)
        assert bytes(raw) == (10000).to_bytes(4, "little")
        ca.unsubscribe(query._parse_dm15)  # the client stays subscribed after a query
        query = Dm14Query(ca)  # its length counts objects: four objects of one byte
        query.write(5, 0, 0x80 << 24 | 5, list((25000).to_bytes(4, "little")))
        assert m.read_raw("V_SOLL")[0] == 25000
    finally:
        ca.stop()
        ecu.disconnect()
        node.close()
        bus.shutdown()


# ----------------------------------------------------------------------------- one address
def test_a_node_refuses_two_motors_at_one_address() -> None:
    twin = Twin(MotorArray("MIS232", n=2, seed=0), [1, 2])
    bus = can.Bus(interface="virtual", channel=f"j1939-dup-{time.monotonic_ns()}")
    try:
        with pytest.raises(ValueError, match="motor 0 and motor 1 have J1939 address 7"):
            J1939Node(twin, bus, [7, 7])
    finally:
        bus.shutdown()


@pytest.mark.parametrize("extra", [[], ["--j1939-address", "7", "--j1939-address", "7"]])
def test_serve_refuses_two_motors_at_one_j1939_address_in_one_line(extra) -> None:
    """Both at the default (each motor's FBUS_NODE_ID, 5) or both given 7: one line, exit ≠ 0,
    nothing served (a process of its own: a served line would run until stopped)."""
    root = Path(__file__).resolve().parents[1]
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(root / "src"), str(root)])}
    try:
        run = subprocess.run([sys.executable, "-m", "jvl_gym.cli", "serve", "-m", "MIS232",
                              "-a", "1", "-a", "2", "--j1939",
                              f"virtual:dup-{time.monotonic_ns()}", *extra],
                             capture_output=True, text=True, timeout=300, env=env)
    except subprocess.TimeoutExpired:
        pytest.fail("serve ran with two motors at one J1939 address")
    assert run.returncode not in (0, None)
    err = run.stderr.strip().splitlines()
    assert len(err) == 1 and "J1939 address" in err[0] and "--j1939-address" in err[0]


def test_a_node_without_arbitrary_address_gives_up_and_cannot_claim() -> None:
    """SAE J1939/81: a claim of our address by a lower NAME (higher priority) takes it: a node
    that is not arbitrary address capable sends "cannot claim" (the claim from the null
    address 254) and answers a request for address claimed with it; it serves nothing more."""
    m = MotorArray("MIS232", seed=0)
    mine = Name.from_value(m.family.j1939_name & ~(1 << 63))
    d = J1939Device(m, 0, 5, name=mine)
    lower = Name(1, 1, 0, 0, 0, 0, 0, 0, False).to_bytes()
    [cannot] = d.handle(can_id(60928, 5, 255), lower)
    assert d.address == 254 and (cannot.arbitration_id, cannot.data) == (0x18EEFFFE,
                                                                        mine.to_bytes())
    request = d.handle(can_id(59904, TOOL, 255), H("00 ee 00"))
    assert [(f.arbitration_id, f.data) for f in request] == [(0x18EEFFFE, mine.to_bytes())]
    assert _ask(d, 55552, H("04 03 05 00 00 80 ff ff")) == []  # no address: no service


def test_the_motors_of_one_node_hear_each_others_claims() -> None:
    """Motor 0 at 5 loses its address to a lower NAME and takes a negotiable address: not 129,
    which its neighbour in the twin claimed, but 130."""
    channel = f"j1939-siblings-{time.monotonic_ns()}"
    twin = Twin(MotorArray("MIS232", n=2, seed=0), [1, 2])
    tool = can.Bus(interface="virtual", channel=channel)
    node = J1939Node(twin, can.Bus(interface="virtual", channel=channel), [5, 129]).start()
    try:
        seen = {tool.recv(5).arbitration_id for _ in range(2)}
        assert seen == {0x18EEFF05, 0x18EEFF81}
        lower = Name(1, 1, 0, 0, 0, 0, 0, 0, False).to_bytes()
        tool.send(can.Message(arbitration_id=can_id(60928, 5, 255), data=lower,
                              is_extended_id=True))
        reply = tool.recv(5)
        assert reply is not None and reply.arbitration_id == 0x18EEFF82
        assert [d.address for d in node.devices] == [130, 129]
    finally:
        node.close()
        node.bus.shutdown()
        tool.shutdown()


def test_a_node_that_hears_its_own_claim_keeps_its_address() -> None:
    """A bus that loops frames back (python-can's udp_multicast) brings the node its own
    claim: the same address with the same NAME is no contender."""
    _, d = _device()
    [claim] = d.claim()
    assert d.handle(claim.arbitration_id, claim.data) == [] and d.address == 5
    assert d.handle(can_id(59904, TOOL, 255), H("00 ee 00")) == [claim]
