"""PDOs, SYNC and EMCY of the simulated MIS (MIS manual §11.4.2, §11.4.7–11.4.10, §11.9.3,
§11.9.5): the dynamic mapping procedure of §11.4.8 step by step, an RPDO moving the motor,
synchronous TPDOs, EMCY on a follow error and on a PDO of the wrong length."""

from __future__ import annotations

import struct
from collections.abc import Iterator

import canopen
import pytest

from canopen_rig import Rig
from jvl_gym.protocol.canopen.emcy import FOLLOW_ERROR, PDO_LENGTH


@pytest.fixture
def rig() -> Iterator[Rig]:
    r = Rig()
    yield r
    r.close()


def _code(node: canopen.RemoteNode, index: int, sub: int, value: int) -> int:
    with pytest.raises(canopen.SdoAbortedError) as info:
        node.sdo[index][sub].raw = value
    return info.value.code


def test_dynamic_mapping_procedure_then_tpdo_every_100_ms(rig: Rig) -> None:
    """§11.4.8 steps 1–9: TPDO1 remapped to 2012h sub 5 (V_SOLL), type 255, event timer
    100 ms, then it arrives every 100 ms of simulated time with V_SOLL's value."""
    node = rig.node()
    node.nmt.state = "PRE-OPERATIONAL"  # 1
    cob = node.sdo[0x1800][1].raw
    assert cob == 0x80000185  # disabled at boot-up (§11.4.7)
    node.sdo[0x1800][1].raw = cob | 0x80000000  # 2
    node.sdo[0x1A00][0].raw = 0  # 3
    node.sdo[0x1A00][1].raw = 0x20120520  # 4
    node.sdo[0x1A00][0].raw = 1  # 5
    node.sdo[0x1800][2].raw = 255  # 6
    node.sdo[0x1800][5].raw = 100  # 7
    node.sdo[0x1800][1].raw = 0x185  # 8
    rig.clear()
    rig.advance(1.0)
    assert rig.sent(0x185) == []  # PDOs only when operational
    node.nmt.state = "OPERATIONAL"  # 9
    rig.clear()
    rig.advance(1.0)
    frames = rig.sent(0x185)
    assert len(frames) == 10
    assert {struct.unpack("<l", f)[0] for f in frames} == {10000}
    node.sdo[0x2012][5].raw = 25000
    rig.clear()
    rig.advance(0.2)
    assert [struct.unpack("<l", f)[0] for f in rig.sent(0x185)] == [25000, 25000]


def test_mapping_rules_refuse_out_of_order_steps(rig: Rig) -> None:
    node = rig.node()
    node.sdo[0x1800][1].raw = 0x185  # enable with its default mapping
    assert _code(node, 0x1A00, 0, 0) == 0x08000022  # enabled: no remapping
    assert _code(node, 0x1800, 1, 0x186) == 0x06090030  # COB-ID of an enabled PDO
    node.sdo[0x1800][1].raw = 0x80000185
    assert _code(node, 0x1A00, 1, 0x20120520) == 0x08000022  # sub 0 not 0 yet
    node.sdo[0x1A00][0].raw = 0
    assert _code(node, 0x1A00, 1, 0x10000020) == 0x06040041  # 1000h is not mappable
    assert _code(node, 0x1A00, 1, 0x20120510) == 0x06040041  # 32-bit object as 16
    assert _code(node, 0x1A00, 1, 0x30000020) == 0x06020000
    for k in (1, 2, 3):
        node.sdo[0x1A00][k].raw = 0x20120520
    assert _code(node, 0x1A00, 0, 3) == 0x06040042  # 96 bits
    assert _code(node, 0x1A00, 0, 9) == 0x06090031  # at most 8 entries
    assert _code(node, 0x1800, 1, 0x185) == 0x06040043  # nothing mapped
    assert _code(node, 0x1800, 2, 251) == 0x06090030
    assert _code(node, 0x1800, 1, 0x605) == 0x06090030  # an SDO identifier
    node.sdo[0x1600][0].raw = 0
    assert _code(node, 0x1600, 1, 0x60410010) == 0x06040041  # statusword is read-only
    node.sdo[0x1600][0].raw = 1
    node.sdo[0x1A00][0].raw = 2
    node.nmt.state = "OPERATIONAL"
    assert _code(node, 0x1A00, 0, 0) == 0x08000022  # not in operational
    assert node.sdo[0x1A00][0].raw == 2


def test_canopen_pdo_api_configures_an_rpdo_that_moves_the_motor(rig: Rig) -> None:
    """RPDO 21 (P_SOLL, V_SOLL, A_SOLL, §11.4.9) set up with canopen's PDO API; one frame
    starts a move in position mode."""
    node = rig.node()
    node.rpdo.read()
    rp = node.rpdo[21]
    assert [(v.index, v.subindex) for v in rp] == [(0x2012, 3), (0x2014, 5), (0x2014, 6)]
    rp.cob_id = 0x215
    rp.trans_type = 255
    rp.enabled = True
    rp.save()
    node.sdo[0x2012][2].raw = 2
    node.nmt.state = "OPERATIONAL"
    rp[0].raw = 409600 * 3
    rp[1].raw = 30000
    rp[2].raw = 5000
    rp.transmit()
    rig.advance(0.001)
    assert rig.m.read_raw("P_SOLL")[0] == 409600 * 3
    assert rig.m.read_raw("V_SOLL")[0] == 30000 and rig.m.read_raw("A_SOLL")[0] == 5000
    rig.advance(1.5)
    assert rig.m.read_raw("P_IST")[0] == 409600 * 3
    # a frame of the wrong length changes nothing and raises EMCY 8210h
    rig.clear()
    rig.send(0x215, struct.pack("<lh", 7, 100))
    emcy = rig.sent(0x85)
    assert len(emcy) == 1 and struct.unpack_from("<H", emcy[0])[0] == PDO_LENGTH
    assert emcy[0][2] & 0x10
    assert rig.m.read_raw("P_SOLL")[0] == 409600 * 3
    assert node.sdo[0x1003][1].raw & 0xFFFF == PDO_LENGTH
    # out of range in a PDO: refused, the rest of the frame is carried out
    rig.send(0x215, struct.pack("<lhh", 5, 100, 0))  # A_SOLL 0 is out of range
    assert rig.m.read_raw("A_SOLL")[0] == 5000


def test_synchronous_tpdo_and_rpdo(rig: Rig) -> None:
    """Type 1: a TPDO after every SYNC; type 2: every second; an RPDO of a synchronous type
    is carried out at the next SYNC."""
    node = rig.node()
    node.sdo[0x1800][1].raw = 0x185  # 6064h + 6041h, type 1 by default
    node.sdo[0x1802][2].raw = 2
    node.sdo[0x1802][1].raw = 0x385
    node.sdo[0x1414][1].raw = 0x215
    node.sdo[0x1414][2].raw = 1
    node.nmt.state = "OPERATIONAL"
    rig.clear()
    for _ in range(4):
        rig.send(0x80)
    assert len(rig.sent(0x185)) == 4
    assert len(rig.sent(0x385)) == 2
    pos, sw = struct.unpack("<lH", rig.sent(0x185)[0])
    assert pos == 0 and sw & 0x4F == 0x40  # switch on disabled
    rig.send(0x215, struct.pack("<lhh", 1234, 100, 100))
    assert rig.m.read_raw("P_SOLL")[0] == 0
    rig.send(0x80)
    assert rig.m.read_raw("P_SOLL")[0] == 1234


def test_remote_request_of_a_tpdo(rig: Rig) -> None:
    node = rig.node()
    node.sdo[0x1802][2].raw = 253
    node.sdo[0x1802][1].raw = 0x385
    node.nmt.state = "OPERATIONAL"
    rig.clear()
    rig.advance(0.5)
    assert rig.sent(0x385) == []
    rig.send(0x385, remote=True)
    assert len(rig.sent(0x385)) == 1


def test_emcy_on_follow_error() -> None:
    """§11.4.2: the motor's follow error (ERR_BITS bit 1) → EMCY 1003h with the error register
    and ERR_BITS; 1003h keeps it; writing 0 to 1003h sub 0 clears it and the motor's errors."""
    rig = Rig(encoder_type=1, end_stop_high=1.0)
    try:
        node = rig.node()
        node.sdo[0x2012][22].raw = 5000  # FLWERRMAX
        node.sdo[0x2012][2].raw = 2
        node.sdo[0x2012][3].raw = 409600  # one revolution, the end stop at 1 rad
        rig.clear()
        rig.advance(1.0)
        emcy = rig.sent(0x85)
        assert len(emcy) == 1
        code, reg, err = struct.unpack_from("<HBH", emcy[0])
        assert code == FOLLOW_ERROR and err & 0x2 and reg & 0x21 == 0x21
        assert node.sdo[0x1001].raw == reg
        assert node.sdo[0x1003][0].raw == 1
        assert node.sdo[0x1003][1].raw == (err << 16) | FOLLOW_ERROR
        rig.clear()
        node.sdo[0x1003][0].raw = 0
        rig.advance(0.01)
        assert node.sdo[0x1003][0].raw == 0 and rig.m.read_raw("ERR_BITS")[0] == 0
        assert [struct.unpack_from("<HB", f) for f in rig.sent(0x85)] == [(0, 0)]
    finally:
        rig.close()


def test_beckhoff_mode_enables_pdos_1_to_4() -> None:
    """§11.4.11–14: SETUP_BITS bit 14 → PDOs 1–4 enabled at boot with the Beckhoff maps."""
    rig = Rig()
    try:
        node = rig.node()
        node.sdo[0x2012][124].raw = 1 << 14
        node.nmt.send_command(0x82)
        rig.settle()
        assert node.sdo[0x1400][1].raw == 0x205 and node.sdo[0x1803][1].raw == 0x485
        assert node.sdo[0x1600][1].raw == 0x20120320
        assert node.sdo[0x1A03][3].raw == 0x2014A110
        node.sdo[0x2012][2].raw = 2
        node.nmt.state = "OPERATIONAL"
        rig.send(0x205, struct.pack("<lhh", 409600, 20000, 3000))
        rig.advance(1.0)
        assert rig.m.read_raw("P_IST")[0] == 409600
        rig.clear()
        rig.send(0x185, remote=True)
        p_ist, v_ist, err = struct.unpack("<lhH", rig.sent(0x185)[0])
        assert (p_ist, v_ist, err) == (409600, 0, 0)
    finally:
        rig.close()
