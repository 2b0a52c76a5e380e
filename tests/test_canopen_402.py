"""The DSP-402 drive of the simulated MIS driven by ``canopen``'s ``BaseNode402`` (MIS manual
§11.5): the state machine, profile position, homing, cyclic synchronous position with SYNC,
the fault reaction, the factors and the decisions where the manual contradicts itself."""

from __future__ import annotations

import struct
from collections.abc import Iterator

import canopen
import pytest
from canopen.profiles.p402 import BaseNode402

from canopen_rig import Rig
from jvl_gym.protocol.canopen.emcy import HOMING_PROFILE

REV = 409600


@pytest.fixture
def rig() -> Iterator[Rig]:
    r = Rig(node_class=BaseNode402)
    yield r
    r.close()


def _node(rig: Rig) -> BaseNode402:
    node = rig.node()
    node.nmt.state = "PRE-OPERATIONAL"
    node.setup_402_state_machine()
    return node


def test_state_machine_to_operation_enabled_and_back(rig: Rig) -> None:
    node = _node(rig)
    assert node.state == "SWITCH ON DISABLED"
    assert rig.m.read_raw("MODE_REG")[0] == 0
    node.state = "READY TO SWITCH ON"
    node.state = "SWITCHED ON"
    node.op_mode = "PROFILED POSITION"
    node.state = "OPERATION ENABLED"
    assert node.state == "OPERATION ENABLED"
    assert node.sdo[0x6041].raw & 0x6F == 0x27
    assert rig.m.read_raw("MODE_REG")[0] == 2  # the motor holds its position
    node.state = "SWITCHED ON"
    assert rig.m.read_raw("MODE_REG")[0] == 0
    node.state = "OPERATION ENABLED"
    node.state = "QUICK STOP ACTIVE"
    rig.advance(0.05)
    assert node.state == "SWITCH ON DISABLED"  # 605Ah = 2: stop, then switch on disabled
    node.state = "OPERATION ENABLED"
    node.state = "SWITCH ON DISABLED"
    assert rig.m.read_raw("MODE_REG")[0] == 0


def test_mode_changes_only_while_not_enabled(rig: Rig) -> None:
    """§11.5.3; 6060h values outside §11.5.1's list are refused."""
    node = _node(rig)
    node.op_mode = "PROFILED POSITION"
    node.state = "OPERATION ENABLED"
    with pytest.raises(canopen.SdoAbortedError) as info:
        node.sdo[0x6060].raw = 3
    assert info.value.code == 0x08000022
    node.state = "SWITCHED ON"
    node.sdo[0x6060].raw = 3
    assert node.sdo[0x6061].raw == 3
    for bad in (2, 5, 11, -1):
        with pytest.raises(canopen.SdoAbortedError):
            node.sdo[0x6060].raw = bad
    assert node.sdo[0x6502].raw == 0b1111101101  # modes 1, 3, 4, 6, 7, 8, 9, 10


def test_profile_position_move_to_a_target(rig: Rig) -> None:
    """§11.5.4: new set-point (bit 4), acknowledge (status bit 12), target reached (bit 10);
    relative (bit 6) adds to the last target."""
    node = _node(rig)
    node.op_mode = "PROFILED POSITION"
    node.state = "OPERATION ENABLED"
    node.sdo[0x6081].raw = 30000  # 300 RPM
    node.sdo[0x6083].raw = 3000
    node.sdo[0x607A].raw = 5 * REV
    node.controlword = 0x1F
    sw = node.sdo[0x6041].raw
    assert sw & 0x1000 and not sw & 0x400
    node.controlword = 0x0F
    assert not node.sdo[0x6041].raw & 0x1000
    rig.advance(0.5)
    assert 0 < node.sdo[0x6064].raw < 5 * REV
    rig.advance(1.5)
    assert node.sdo[0x6064].raw == 5 * REV
    assert node.sdo[0x6041].raw & 0x400
    node.sdo[0x607A].raw = -REV
    node.controlword = 0x5F  # relative
    node.controlword = 0x4F
    rig.advance(1.0)
    assert node.sdo[0x6064].raw == 4 * REV


def test_profile_position_sequential_and_immediate_set_points(rig: Rig) -> None:
    node = _node(rig)
    node.op_mode = "PROFILED POSITION"
    node.state = "OPERATION ENABLED"
    node.sdo[0x6081].raw = 10000
    node.sdo[0x607A].raw = REV
    node.controlword = 0x1F
    node.controlword = 0x0F
    rig.advance(0.1)
    node.sdo[0x607A].raw = 2 * REV  # queued behind the first (bit 5 = 0)
    node.controlword = 0x1F
    assert rig.m.read_raw("P_SOLL")[0] == REV
    rig.advance(1.0)
    assert rig.m.read_raw("P_SOLL")[0] == 2 * REV
    node.controlword = 0x0F
    node.sdo[0x607A].raw = 0
    node.controlword = 0x3F  # change set immediately
    assert rig.m.read_raw("P_SOLL")[0] == 0


def test_homing_run_with_basenode402() -> None:
    """§11.5.6: method 19 (as 3, home switch, negative direction, without index) as the
    motor's zero search; time moves 10 ms per request of the master, which polls the
    statusword."""
    rig = Rig(node_class=BaseNode402, step_per_frame=0.01, home_position=-3.0)
    try:
        node = _node(rig)
        node.sdo[0x2012][132].raw = 8  # HOME_MASK: input 4 (§11.5.6: "Input 4 is default")
        node.sdo[0x6098].raw = 19
        node.sdo[0x6099][1].raw = 5000
        node.sdo[0x607C].raw = 1000
        assert node.homing(timeout=30)
        sw = node.sdo[0x6041].raw
        assert sw & 0x3400 == 0x1400  # homing attained, target reached
        assert rig.m.read_raw("STATUSBITS")[0] & (1 << 7)
        assert abs(rig.m.position_rad[0] + 3.0) < 0.05
        assert rig.m.read_raw("MODE_REG")[0] == 2  # holds its position in operation
        node.op_mode = "PROFILED POSITION"  # allowed after a completed homing (§11.5.3)
    finally:
        rig.close()


def test_homing_methods_decision(rig: Rig) -> None:
    """§11.5.6: the standard methods 1–14, 17–30, 33, 34 and the table's −3, −4; the reserved
    15, 16, 31, 32 and the table's "No" (−2, −1, 35) are refused; starting with method 0 is a
    homing error with EMCY 1010h."""
    node = _node(rig)
    for method in (1, 2, 3, 4, 5, 6, 7, 14, 17, 22, 30, 33, 34, -3, -4):
        node.sdo[0x6098].raw = method
    for method in (-2, -1, 15, 16, 31, 32, 35):
        with pytest.raises(canopen.SdoAbortedError) as info:
            node.sdo[0x6098].raw = method
        assert info.value.code == 0x06090030
    node.sdo[0x6098].raw = 0
    node.op_mode = "HOMING"
    node.state = "OPERATION ENABLED"
    rig.clear()
    node.controlword = 0x1F
    assert node.sdo[0x6041].raw & 0x3400 == 0x2400  # homing error
    emcy = rig.sent(0x85)
    assert len(emcy) == 1 and struct.unpack_from("<H", emcy[0])[0] == HOMING_PROFILE


def test_torque_mode_number_decision(rig: Rig) -> None:
    """§11.5.7 names 6060h = 3 for profile torque, as §11.5.5 does for velocity; DSP-402's
    profile torque is 4: 3 is velocity, 4 is torque (current)."""
    node = _node(rig)
    current = int(rig.m.read_raw("RUN_CURRENT")[0])
    node.sdo[0x6071].raw = 500
    node.sdo[0x6087].raw = 10000
    node.sdo[0x60FF].raw = 10000
    node.op_mode = "PROFILED TORQUE"
    assert node.sdo[0x6061].raw == 4
    node.state = "OPERATION ENABLED"
    rig.advance(0.5)
    assert rig.m.read_raw("MODE_REG")[0] == 1
    assert rig.m.read_raw("RUN_CURRENT")[0] == round(current / 2)
    assert node.sdo[0x6077].raw == 500
    node.state = "SWITCHED ON"
    assert rig.m.read_raw("RUN_CURRENT")[0] == current
    node.op_mode = "PROFILED VELOCITY"
    node.state = "OPERATION ENABLED"
    rig.advance(1.0)
    assert node.sdo[0x606C].raw == 10000 and node.sdo[0x6041].raw & 0x400


def test_csp_with_sync(rig: Rig) -> None:
    """§11.5.9: RPDO 3 (target position) of transmission type 1, the master's SYNC every
    10 ms (60C2h); every set-point is reached within its period."""
    node = _node(rig)
    node.sdo[0x60C2][1].raw = 10
    node.rpdo.read()
    rp = node.rpdo[3]
    rp.cob_id = 0x405
    rp.trans_type = 1
    rp.enabled = True
    rp.save()
    node.nmt.state = "OPERATIONAL"
    node.op_mode = "CYCLIC SYNCHRONOUS POSITION"
    node.state = "OPERATION ENABLED"
    node.controlword = 0x1F  # ENABLE_CSP_MODE
    assert node.sdo[0x6041].raw & 0x400
    targets = []
    for k in range(1, 101):  # a 1 s move of one revolution, speed rising and falling
        x = k / 100
        targets.append(round(REV * x * x * (3 - 2 * x)))
        rp[0].raw = targets[-1]
        rp[1].raw = 0
        rp.transmit()
        rig.advance(0)
        assert rig.m.read_raw("P_SOLL")[0] == (targets[-2] if k > 1 else 0)
        rig.net.sync.transmit()
        rig.advance(0.01)
        assert rig.m.read_raw("P_IST")[0] == targets[-1]
    assert node.sdo[0x6064].raw == REV


def test_fault_reaction_and_reset() -> None:
    """A motor error makes the drive FAULT and the motor passive; a fault reset clears it."""
    rig = Rig(node_class=BaseNode402, encoder_type=1, end_stop_high=1.0)
    try:
        node = _node(rig)
        node.sdo[0x2012][22].raw = 5000
        node.op_mode = "PROFILED POSITION"
        node.state = "OPERATION ENABLED"
        node.sdo[0x607A].raw = REV
        node.controlword = 0x1F
        rig.advance(1.0)
        assert node.state == "FAULT" and rig.m.read_raw("MODE_REG")[0] == 0
        node.controlword = 0x00
        node.controlword = 0x80
        assert node.state == "SWITCH ON DISABLED"
        assert rig.m.read_raw("ERR_BITS")[0] == 0
    finally:
        rig.close()


def test_factors_manual_example(rig: Rig) -> None:
    """§11.5.2: a 3.5:1 gear and a 124 mm wheel, positions in mm: 6091h = 35/10, 6092h =
    38956/100; 100 mm is 100 × 3.5 × 409600 / 389.56 counts."""
    node = rig.node()
    node.sdo[0x6091][1].raw = 35
    node.sdo[0x6091][2].raw = 10
    node.sdo[0x6092][1].raw = 38956
    node.sdo[0x6092][2].raw = 100
    rig.m.write_raw("P_IST", round(100 * 3.5 * REV / 389.56))
    assert node.sdo[0x6064].raw == 100
    with pytest.raises(canopen.SdoAbortedError) as info:
        node.sdo[0x6091][2].raw = 0
    assert info.value.code == 0x06090032


def test_interpolated_position_at_each_sync(rig: Rig) -> None:
    """§11.5.8: 60C1h sub 1 is reached by the next period after each SYNC; sub 2 = 1 makes
    it relative."""
    node = _node(rig)
    node.sdo[0x60C2][1].raw = 10
    node.op_mode = "INTERPOLATED POSITION"
    node.state = "OPERATION ENABLED"
    node.controlword = 0x1F  # ENABLE_IP_MODE
    assert node.sdo[0x6041].raw & 0x400  # IP_MODE_READY
    node.sdo[0x60C1][1].raw = 2000
    assert rig.m.read_raw("P_SOLL")[0] == 0  # taken at the SYNC
    rig.send(0x80)
    rig.advance(0.01)
    assert rig.m.read_raw("P_IST")[0] == 2000
    node.sdo[0x60C1][2].raw = 1
    node.sdo[0x60C1][1].raw = 500
    for _ in range(3):
        rig.send(0x80)
        rig.advance(0.01)
    assert rig.m.read_raw("P_IST")[0] == 3500


def test_cyclic_velocity_and_torque(rig: Rig) -> None:
    """§11.5.10–11: CSV takes 60FFh at once, reversed by bit 6 of 607Eh; CST runs at 6080h
    with the current of 6071h."""
    node = _node(rig)
    node.op_mode = "CYCLIC SYNCHRONOUS VELOCITY"
    node.state = "OPERATION ENABLED"
    node.sdo[0x60FF].raw = 5000
    assert rig.m.read_raw("V_SOLL")[0] == 5000 and rig.m.read_raw("MODE_REG")[0] == 1
    rig.advance(0.2)
    assert node.sdo[0x606C].raw == 5000
    node.state = "SWITCHED ON"
    node.sdo[0x607E].raw = 0x40
    node.sdo[0x6080].raw = 2000
    node.sdo[0x6071].raw = 250
    current = int(rig.m.read_raw("RUN_CURRENT")[0])
    node.op_mode = "CYCLIC SYNCHRONOUS TORQUE"
    node.state = "OPERATION ENABLED"
    assert rig.m.read_raw("V_SOLL")[0] == -2000
    assert rig.m.read_raw("RUN_CURRENT")[0] == round(current / 4)
    rig.advance(0.5)
    assert node.sdo[0x606C].raw == -2000


def test_profile_velocity_halt(rig: Rig) -> None:
    """§11.5.5: halt (bit 8) decelerates to 0 (status bit 12 velocity zero); released, the
    motor runs at 60FFh again (bit 10 velocity reached)."""
    node = _node(rig)
    node.sdo[0x60FF].raw = 10000
    node.sdo[0x6083].raw = 5000
    node.op_mode = "PROFILED VELOCITY"
    node.state = "OPERATION ENABLED"
    rig.advance(0.5)
    assert node.sdo[0x6041].raw & 0x1400 == 0x400
    node.controlword = 0x10F
    rig.advance(0.5)
    assert node.sdo[0x606C].raw == 0 and node.sdo[0x6041].raw & 0x1000
    node.controlword = 0x0F
    rig.advance(0.5)
    assert node.sdo[0x606C].raw == 10000
