"""SDO access of the simulated MIS with the ``canopen`` package as master (MIS manual §11.4.1,
§11.4.6, §11.3.2, §11.9.4): every communication object, the register objects with the manual's
example, store and restore, and the abort codes of bad requests."""

from __future__ import annotations

import struct
from collections.abc import Iterator

import canopen
import pytest

from canopen_rig import Rig
from jvl_gym.protocol.canopen.objects import LOAD, SAVE


@pytest.fixture
def rig() -> Iterator[Rig]:
    r = Rig()
    yield r
    r.close()


def _abort(node: canopen.RemoteNode, index: int, sub: int, value: int | None = None) -> int:
    with pytest.raises(canopen.SdoAbortedError) as info:
        if value is None:
            node.sdo.upload(index, sub)
        else:
            var = node.object_dictionary.get_variable(index, sub)
            node.sdo.download(index, sub, var.encode_raw(value))
    return info.value.code


def test_communication_objects_read_their_values(rig: Rig) -> None:
    """§11.4.1: device type 0x40192, name "JVL A/S", vendor 117h, defaults."""
    node = rig.node()
    m = rig.m
    assert node.sdo[0x1000].raw == 0x40192
    assert node.sdo[0x1001].raw == 0
    assert node.sdo[0x1003][0].raw == 0
    assert node.sdo[0x1005].raw == 0x80
    assert node.sdo[0x1008].raw == "JVL A/S"  # 7 bytes: a segmented upload
    assert isinstance(node.sdo[0x1009].raw, str) and isinstance(node.sdo[0x100A].raw, str)
    assert node.sdo[0x100C].raw == 0 and node.sdo[0x100D].raw == 0
    assert node.sdo[0x1010][1].raw == 1 and node.sdo[0x1011][1].raw == 1
    assert node.sdo[0x1014].raw == 0x85
    assert node.sdo[0x1016][0].raw == 3
    assert [node.sdo[0x1016][k].raw for k in (1, 2, 3)] == [0, 0, 0]
    assert node.sdo[0x1017].raw == 0
    assert node.sdo[0x1018][0].raw == 4
    assert node.sdo[0x1018][1].raw == 0x117
    assert node.sdo[0x1018][2].raw == int(m.read_raw("MOTORTYPE")[0])
    assert node.sdo[0x1018][3].raw == int(m.read_raw("PROG_VERSION")[0])
    assert node.sdo[0x1018][4].raw == int(m.read_raw("SERIAL_NUMBER")[0]) & 0xFFFFFFFF


def test_communication_objects_take_writes(rig: Rig) -> None:
    node = rig.node()
    for index, sub, value in ((0x1005, 0, 0x81), (0x1006, 0, 10000), (0x100C, 0, 100),
                              (0x100D, 0, 3), (0x1014, 0, 0x90), (0x1016, 1, 0x0001_00C8),
                              (0x1017, 0, 250)):
        var = node.sdo[index][sub] if sub else node.sdo[index]
        var.raw = value
        assert var.raw == value


@pytest.mark.parametrize("index, sub", [(0x1000, 0), (0x1001, 0), (0x1008, 0), (0x1018, 1),
                                        (0x1018, 4), (0x6041, 0), (0x6064, 0),
                                        (0x6074, 0), (0x6077, 0)])
def test_read_only_objects_refuse_writes(rig: Rig, index: int, sub: int) -> None:
    node = rig.node()
    before = node.sdo.upload(index, sub)
    with pytest.raises(canopen.SdoAbortedError) as info:
        node.sdo.download(index, sub, b"\x01\x00\x00\x00"[:max(1, len(before))])
    assert info.value.code == 0x06010002
    assert node.sdo.upload(index, sub) == before


def test_manual_example_position_mode_by_sdo(rig: Rig) -> None:
    """§11.3.2: MODE_REG 2, V_SOLL 10000 (100 RPM), P_SOLL 4096000 (10 revolutions), then
    the motor is there; back with -4096000 at 200 RPM."""
    node = rig.node()
    node.sdo[0x2012][2].raw = 2
    node.sdo[0x2012][5].raw = 10000
    node.sdo[0x2012][3].raw = 4096000
    rig.advance(3.0)
    assert 0 < node.sdo[0x2012][10].raw < 4096000  # under way: 6 s at 100 RPM
    rig.advance(4.0)
    assert node.sdo[0x2012][10].raw == 4096000
    assert rig.m.read("P_IST")[0] == 4096000
    assert abs(rig.m.position_rad[0] / (2 * 3.141592653589793) - 10.0) < 0.01
    node.sdo[0x2012][2].raw = 0
    node.sdo[0x2012][2].raw = 2
    node.sdo[0x2012][5].raw = 20000
    node.sdo[0x2012][3].raw = (-4096000) & 0xFFFFFFFF
    rig.advance(6.5)  # 20 revolutions at 200 RPM
    assert rig.m.read("P_IST")[0] == -4096000


def test_16_bit_access_and_its_sign_rule(rig: Rig) -> None:
    """§11.4.6: 2014h reads the low 16 bits; a 16-bit write is treated as signed."""
    node = rig.node()
    node.sdo[0x2014][3].raw = 0xFFFF  # P_SOLL := -1
    assert rig.m.read_raw("P_SOLL")[0] == -1
    assert node.sdo[0x2012][3].raw == 0xFFFFFFFF
    node.sdo[0x2014][5].raw = 12345
    assert rig.m.read_raw("V_SOLL")[0] == 12345 and node.sdo[0x2014][5].raw == 12345
    rig.m.write_raw("P_SOLL", 0x12345)
    assert node.sdo[0x2014][3].raw == 0x2345


def test_register_refusals_are_aborts_and_change_nothing(rig: Rig) -> None:
    node = rig.node()
    v = int(rig.m.read_raw("V_SOLL")[0])
    assert _abort(node, 0x2012, 5, 400000) == 0x06090030  # out of V_SOLL's range
    assert _abort(node, 0x2012, 12, 5) == 0x06010002  # V_IST is read-only
    assert _abort(node, 0x2012, 11, 5) == 0x06010002  # reserved
    assert _abort(node, 0x2018, 1, 5) == 0x06010002  # no register 257
    assert node.sdo[0x2018][1].raw == 0
    assert _abort(node, 0x2012, 2, 15) == 0x08000022  # safe mode by command only
    assert int(rig.m.read_raw("V_SOLL")[0]) == v and int(rig.m.read_raw("MODE_REG")[0]) == 0


def test_unknown_objects_and_sub_indices(rig: Rig) -> None:
    node = rig.node()
    assert _abort(node, 0x3000, 0) == 0x06020000
    assert _abort(node, 0x1018, 9) == 0x06090011
    assert _abort(node, 0x2012, 255) == 0x06090011


def test_bad_lengths_and_ranges(rig: Rig) -> None:
    node = rig.node()
    with pytest.raises(canopen.SdoAbortedError) as info:
        node.sdo.download(0x1017, 0, b"\x01\x02\x03\x04")
    assert info.value.code == 0x06070012
    with pytest.raises(canopen.SdoAbortedError) as info:
        node.sdo.download(0x2012, 5, b"\x01")
    assert info.value.code == 0x06070013
    assert _abort(node, 0x2100, 0, 3000) == 0x06090031  # homing torque 0 … 2047
    assert _abort(node, 0x1003, 0, 1) == 0x06090030
    assert node.sdo[0x1017].raw == 0 and node.sdo[0x2100].raw == 1024


def test_raw_frames_wrong_length_toggle_and_segments(rig: Rig) -> None:
    """§11.9.4: a request of 7 bytes, a segment without a transfer, a toggle out of order."""
    abort = rig.request(0x605, bytes([0x40, 0x00, 0x10, 0, 0, 0, 0]), 0x585)
    assert abort is not None and abort[0] == 0x80
    assert struct.unpack_from("<L", abort, 4)[0] == 0x05040001
    abort = rig.request(0x605, bytes([0x60, 0, 0, 0, 0, 0, 0, 0]), 0x585)
    assert abort is not None and struct.unpack_from("<L", abort, 4)[0] == 0x05040001
    start = rig.request(0x605, bytes([0x40, 0x08, 0x10, 0, 0, 0, 0, 0]), 0x585)
    assert start is not None and start[0] & 0xE0 == 0x40 and not start[0] & 0x02
    abort = rig.request(0x605, bytes([0x70, 0, 0, 0, 0, 0, 0, 0]), 0x585)  # toggle 1 first
    assert abort is not None and struct.unpack_from("<L", abort, 4)[0] == 0x05030000
    # segmented download to a read-only object is refused at its initiation
    abort = rig.request(0x605, bytes([0x21, 0x08, 0x10, 0, 7, 0, 0, 0]), 0x585)
    assert abort is not None and struct.unpack_from("<L", abort, 4)[0] == 0x06010002


def test_segmented_download_toggle_out_of_order_writes_nothing(rig: Rig) -> None:
    v = int(rig.m.read_raw("V_SOLL")[0])
    ok = rig.request(0x605, bytes([0x21, 0x12, 0x20, 5, 4, 0, 0, 0]), 0x585)
    assert ok is not None and ok[0] == 0x60
    abort = rig.request(0x605, bytes([0x17, 0x39, 0x30, 0, 0, 0, 0, 0]), 0x585)
    assert abort is not None and struct.unpack_from("<L", abort, 4)[0] == 0x05030000
    assert int(rig.m.read_raw("V_SOLL")[0]) == v
    ok = rig.request(0x605, bytes([0x21, 0x12, 0x20, 5, 4, 0, 0, 0]), 0x585)
    done = rig.request(0x605, bytes([0x07, 0x39, 0x30, 0, 0, 0, 0, 0]), 0x585)
    assert done is not None and done[0] == 0x20
    assert int(rig.m.read_raw("V_SOLL")[0]) == 12345


def test_store_reset_value_back() -> None:
    """§11.4.5: "save" stores the registers in the motor's flash; after a reset node the value
    is back (and a motor in an active mode refuses: 0800 0022h)."""
    rig = Rig()
    try:
        node = rig.node()
        node.sdo[0x2012][5].raw = 23456
        node.sdo[0x6094][1].raw = 3
        node.sdo[0x1010][1].raw = SAVE
        node.sdo[0x2012][5].raw = 111
        node.sdo[0x6094][1].raw = 7
        node.nmt.send_command(0x81)
        rig.settle()
        assert rig.m.read("V_SOLL")[0] == 23456
        assert node.sdo[0x2012][5].raw == 23456
        assert node.sdo[0x6094][1].raw == 3
        node.sdo[0x2012][2].raw = 2
        assert _abort(node, 0x1010, 1, SAVE) == 0x08000022
        assert _abort(node, 0x1010, 1, 0x12345678) == 0x08000020
        node.sdo[0x1011][1].raw = LOAD
        assert node.sdo[0x6094][1].raw == 1  # factory default, not stored
    finally:
        rig.close()


def test_store_survives_power_on(tmp_path: object) -> None:
    """The stored registers are in the twin's flash file: a new twin (power-on) has them."""
    rig = Rig(flash_dir=tmp_path)
    try:
        node = rig.node()
        node.sdo[0x2012][6].raw = 4321
        node.sdo[0x1010][1].raw = SAVE
    finally:
        rig.close()
    again = Rig(flash_dir=tmp_path)
    try:
        assert again.node().sdo[0x2012][6].raw == 4321
    finally:
        again.close()


def test_the_eds_says_which_register_objects_take_writes(rig: Rig) -> None:
    """§11.4.6 objects as the EDS describes them: a sub-index the EDS marks ``rw`` takes a
    write of its own value back; one it marks ``ro`` (a read-only, reserved or absent
    register) is refused with 0601 0002h and keeps its value. (A 16-bit value with bit 15 set
    is not written back: the motor reads a 16-bit write as signed.)"""
    node = rig.node()
    kinds = {"rw": 0, "ro": 0}
    for index in (0x2012, 0x2014, 0x2018, 0x201A):
        for sub in range(1, 255):
            var = node.object_dictionary[index][sub]
            before = node.sdo.upload(index, sub)
            if len(before) == 2 and before[1] & 0x80:
                continue
            if var.access_type == "ro":
                with pytest.raises(canopen.SdoAbortedError) as info:
                    node.sdo.download(index, sub, before)
                assert info.value.code == 0x06010002, (hex(index), sub, var.name)
            else:
                assert var.access_type == "rw"
                node.sdo.download(index, sub, before)
            assert node.sdo.upload(index, sub) == before, (hex(index), sub, var.name)
            kinds[var.access_type] += 1
    assert kinds["rw"] > 200 and kinds["ro"] > 200


def test_a_segmented_download_past_its_limit_is_aborted_at_once(rig: Rig) -> None:
    """Segments without a size beyond MAX_DOWNLOAD bytes: aborted 0607 0012h at the segment
    that passes the limit (the server holds no more), nothing written; with a size, at the
    segment that passes it."""
    from jvl_gym.protocol.canopen.sdo import MAX_DOWNLOAD

    v = int(rig.m.read_raw("V_SOLL")[0])
    assert rig.request(0x605, bytes([0x20, 0x12, 0x20, 5, 0, 0, 0, 0]), 0x585)[0] == 0x60
    toggle, reply = 0, None
    for _ in range(MAX_DOWNLOAD // 7 + 1):
        reply = rig.request(0x605, bytes([toggle, 1, 2, 3, 4, 5, 6, 7]), 0x585)
        assert reply is not None
        if reply[0] == 0x80:
            break
        toggle ^= 0x10
    assert reply[0] == 0x80 and struct.unpack_from("<L", reply, 4)[0] == 0x06070012
    assert int(rig.m.read_raw("V_SOLL")[0]) == v
    ok = rig.request(0x605, bytes([0x21, 0x12, 0x20, 5, 4, 0, 0, 0]), 0x585)  # size 4
    assert ok is not None and ok[0] == 0x60
    abort = rig.request(0x605, bytes([0x00, 1, 2, 3, 4, 5, 6, 7]), 0x585)  # 7 > 4
    assert abort is not None and struct.unpack_from("<L", abort, 4)[0] == 0x06070012
    assert int(rig.m.read_raw("V_SOLL")[0]) == v


def test_a_save_by_the_command_object_reaches_the_flash_file(tmp_path) -> None:
    """The motor's command (2010h sub 1, MIS manual §8.2.22) "save to flash" writes the flash
    file as 1010h does: a new twin (power-on) has the saved register."""
    import json

    rig = Rig(flash_dir=tmp_path)
    try:
        node = rig.node()
        node.sdo[0x2012][6].raw = 4321
        node.sdo[0x2010][1].raw = rig.server.slaves[0].facts.cmd_save
        saved = json.loads((tmp_path / "flash_0.json").read_text())["registers"]
        assert saved == {str(k): v for k, v in sorted(rig.m.flash_image(0).items())}
    finally:
        rig.close()
    again = Rig(flash_dir=tmp_path)
    try:
        assert again.node().sdo[0x2012][6].raw == 4321
    finally:
        again.close()
