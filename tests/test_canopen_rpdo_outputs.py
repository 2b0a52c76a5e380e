"""Receive PDO 24 of the simulated MIS (MIS manual §11.4.9, "Updates the output"): mapped to
the output register (2014h sub 13h, register 19 OUTPUTS; docs/protocol.md, CANopen
decisions), so that an RPDO sets the outputs, and a master that reads the PDO set-up and writes
it back unchanged (``canopen``'s ``read()`` then ``save()``) is not refused."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from canopen_rig import Rig


@pytest.fixture
def rig() -> Iterator[Rig]:
    r = Rig()
    yield r
    r.close()


@pytest.mark.statements("mis:11.4.9:1")
def test_rpdo_24_default_mapping_is_the_output_register(rig: Rig) -> None:
    node = rig.node()
    assert node.sdo[0x1617][0].raw == 1
    assert node.sdo[0x1617][1].raw == 0x20141310  # 2014h sub 13h (register 19), 16 bits


@pytest.mark.statements("mis:11.4.9:1", "mis:11.4.9:2")
def test_read_then_save_of_every_pdo_set_up_is_accepted(rig: Rig) -> None:
    """The default set-up of every receive and transmit PDO, read and written back in
    pre-operational by the library's own procedure, is accepted unchanged."""
    node = rig.node()
    node.nmt.state = "PRE-OPERATIONAL"
    node.rpdo.read()
    node.tpdo.read()
    before = {k: node.sdo[0x1600 + k][1].raw for k in range(6)}
    node.rpdo.save()
    node.tpdo.save()
    assert {k: node.sdo[0x1600 + k][1].raw for k in range(6)} == before
    assert node.sdo[0x1617][1].raw == 0x20141310


@pytest.mark.statements("mis:11.4.9:1")
def test_rpdo_24_sets_the_outputs(rig: Rig) -> None:
    """RPDO 24 enabled with its default mapping: a frame's two bytes are written to OUTPUTS
    (register 19, §8.2.17)."""
    node = rig.node()
    node.nmt.state = "PRE-OPERATIONAL"
    node.rpdo.read()
    rp = node.rpdo[24]
    rp.cob_id = 0x4F5
    rp.trans_type = 255
    rp.enabled = True
    rp.save()
    node.nmt.state = "OPERATIONAL"
    rp[0].raw = 0b1010_0101
    rp.transmit()
    rig.advance(0.01)
    assert rig.m.read_raw("OUTPUTS")[0] == 0b1010_0101
