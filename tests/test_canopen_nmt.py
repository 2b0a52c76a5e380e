"""NMT, boot-up, heartbeat and node guarding of the simulated MIS (MIS manual §11.4.3,
§11.9.2, §11.9.6, §11.9.7), several motors on one bus."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from canopen_rig import Rig
from jvl_gym.protocol.canopen.emcy import NODE_GUARD


@pytest.fixture
def rig() -> Iterator[Rig]:
    r = Rig()
    yield r
    r.close()


def test_boot_up_message_at_node_id_from_register() -> None:
    """§11.9.2: 700h + node id, one byte 0; the node id is register 166 (default 5)."""
    rig = Rig(n=2, node_ids=[5, 9])
    try:
        assert [int(v) for v in rig.m.read_raw("FBUS_NODE_ID")] == [5, 9]
        assert rig.slave.node_id == 5 and rig.server.slaves[1].node_id == 9
        rig.clear()
        rig.node(9).nmt.send_command(0x82)  # reset communication of node 9 only
        assert rig.sent(0x709) == [b"\x00"] and rig.sent(0x705) == []
        assert rig.node(9).sdo[0x1018][1].raw == 0x117
        assert rig.node(5).sdo[0x1014].raw == 0x85 and rig.node(9).sdo[0x1014].raw == 0x89
    finally:
        rig.close()


def test_repeated_node_id_is_refused() -> None:
    with pytest.raises(ValueError, match="node id 5"):
        Rig(n=2)


def test_heartbeat_period_and_states(rig: Rig) -> None:
    """1017h = 100 ms: ten heartbeats a simulated second, with the NMT state (§11.9.7)."""
    node = rig.node()
    rig.advance(1.0)
    rig.clear()
    rig.advance(1.0)
    assert rig.sent(0x705) == []  # none enabled at start-up
    node.sdo[0x1017].raw = 100
    rig.clear()
    rig.advance(1.0)
    assert rig.sent(0x705) == [b"\x7f"] * 10
    node.nmt.state = "OPERATIONAL"
    rig.clear()
    rig.advance(0.5)
    assert rig.sent(0x705) == [b"\x05"] * 5
    node.nmt.state = "STOPPED"
    rig.clear()
    rig.advance(0.3)
    assert rig.sent(0x705) == [b"\x04"] * 3
    node.nmt.state = "PRE-OPERATIONAL"
    node.sdo[0x1017].raw = 250
    rig.clear()
    rig.advance(1.0)
    assert rig.sent(0x705) == [b"\x7f"] * 4


def test_stopped_node_answers_no_sdo(rig: Rig) -> None:
    node = rig.node()
    node.nmt.state = "STOPPED"
    assert rig.request(0x605, bytes([0x40, 0x00, 0x10, 0, 0, 0, 0, 0]), 0x585) is None
    node.nmt.state = "PRE-OPERATIONAL"
    assert node.sdo[0x1000].raw == 0x40192


def test_node_guarding_toggle_and_life_guarding(rig: Rig) -> None:
    """§11.9.7: the answer is the state with a toggle bit starting at 0; no request within
    guard time × life time factor raises EMCY 8130h."""
    node = rig.node()
    node.sdo[0x100C].raw = 100
    node.sdo[0x100D].raw = 3
    answers = []
    for _ in range(3):
        rig.clear()
        rig.send(0x705, remote=True)
        answers += rig.sent(0x705)
    assert answers == [b"\x7f", b"\xff", b"\x7f"]
    rig.clear()
    rig.advance(0.25)
    assert rig.sent(0x85) == []
    rig.advance(0.1)
    emcy = rig.sent(0x85)
    assert len(emcy) == 1 and int.from_bytes(emcy[0][:2], "little") == NODE_GUARD
    assert emcy[0][2] & 0x11 == 0x11  # generic + communication
    node.nmt.send_command(0x82)  # reset communication resets the toggle
    rig.clear()
    rig.send(0x705, remote=True)
    assert rig.sent(0x705) == [b"\x7f"]


def test_reset_node_restarts_the_motor_from_flash(rig: Rig) -> None:
    node = rig.node()
    node.sdo[0x2012][5].raw = 777  # not stored
    node.sdo[0x1017].raw = 100
    rig.clear()
    node.nmt.send_command(0x81)
    assert rig.sent(0x705) == [b"\x00"]
    assert node.sdo[0x2012][5].raw == 10000 and node.sdo[0x1017].raw == 0


def test_nmt_frames_of_other_nodes_and_lengths_are_ignored(rig: Rig) -> None:
    node = rig.node()
    rig.send(0x000, bytes([0x01, 0x06]))
    rig.send(0x000, bytes([0x01]))
    rig.send(0x000, bytes([0x01, 0x05, 0x00]))
    node.sdo[0x1017].raw = 100
    rig.clear()
    rig.advance(0.1)
    assert rig.sent(0x705) == [b"\x7f"]
    rig.send(0x000, bytes([0x01, 0x00]))  # all nodes
    rig.clear()
    rig.advance(0.1)
    assert rig.sent(0x705) == [b"\x05"]
