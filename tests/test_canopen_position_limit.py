"""The software position limit 607Dh of the simulated MIS's DSP-402 drive (MIS manual §11.5.1;
CiA 402: the limits bound the position demand; docs/protocol.md, CANopen decisions): a target
beyond a limit is limited to it, the move ends there and statusword bit 11 (internal limit
active) says so; targets within the limits are untouched."""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from canopen.profiles.p402 import BaseNode402

from canopen_rig import Rig

REV = 409600


@pytest.fixture
def rig() -> Iterator[Rig]:
    r = Rig(node_class=BaseNode402)
    yield r
    r.close()


def _profile_position(rig: Rig) -> BaseNode402:
    node = rig.node()
    node.nmt.state = "PRE-OPERATIONAL"
    node.setup_402_state_machine()
    node.op_mode = "PROFILED POSITION"
    node.state = "OPERATION ENABLED"
    node.sdo[0x6081].raw = 60000  # 600 RPM
    node.sdo[0x6083].raw = 10000
    return node


def _move(rig: Rig, node: BaseNode402, target: int, relative: bool = False) -> None:
    node.sdo[0x607A].raw = target
    node.controlword = 0x5F if relative else 0x1F
    node.controlword = 0x4F if relative else 0x0F
    rig.advance(1.5)


@pytest.mark.statements("mis:11.5.1:1")
def test_a_target_beyond_the_software_limits_ends_at_the_limit(rig: Rig) -> None:
    node = _profile_position(rig)
    node.sdo[0x607D][1].raw = -REV
    node.sdo[0x607D][2].raw = 2 * REV
    _move(rig, node, REV)  # within: untouched
    assert node.sdo[0x6064].raw == REV
    assert not node.sdo[0x6041].raw & 0x800
    _move(rig, node, 5 * REV)
    assert node.sdo[0x6064].raw == 2 * REV
    assert rig.m.read_raw("P_IST")[0] == 2 * REV
    sw = node.sdo[0x6041].raw
    assert sw & 0x800 and sw & 0x400  # internal limit active; target (the limit) reached
    _move(rig, node, REV, relative=True)  # relative to the limited target: limited again
    assert node.sdo[0x6064].raw == 2 * REV
    _move(rig, node, -5 * REV)
    assert node.sdo[0x6064].raw == -REV
    _move(rig, node, 0)
    assert node.sdo[0x6064].raw == 0
    assert not node.sdo[0x6041].raw & 0x800


@pytest.mark.statements("mis:11.5.1:1")
def test_cyclic_synchronous_targets_are_limited_too(rig: Rig) -> None:
    node = rig.node()
    node.nmt.state = "PRE-OPERATIONAL"
    node.setup_402_state_machine()
    node.sdo[0x607D][2].raw = 1000
    node.sdo[0x60C2][1].raw = 10
    node.op_mode = "CYCLIC SYNCHRONOUS POSITION"
    node.state = "OPERATION ENABLED"
    node.controlword = 0x1F
    node.sdo[0x607A].raw = 800
    assert rig.m.read_raw("P_SOLL")[0] == 800
    node.sdo[0x607A].raw = 5000
    assert rig.m.read_raw("P_SOLL")[0] == 1000
    rig.advance(0.05)
    assert rig.m.read_raw("P_IST")[0] == 1000
