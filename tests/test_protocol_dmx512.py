"""DMX512 of the MIS motors (MIS manual chapter 13): the byte stream with break and start code,
the address channels, the scaling of §13.1.7, the control channel of §13.1.8 (homing after ten
identical values) and jogging by inputs (§13.1.9), and the served twin."""

from __future__ import annotations

import socket
import time

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from jvl_gym import MotorArray
from jvl_gym.protocol.dmx512 import (
    BREAK,
    DmxDecoder,
    DmxPacket,
    DmxReceiver,
    DmxSettings,
    encode_packet,
)
from jvl_gym.protocol.dmx512.server import DmxLine, DmxServer
from jvl_gym.protocol.mactalk.twin16 import Twin


# --- the byte stream -------------------------------------------------------------------------
def test_break_start_code_and_escaped_ff() -> None:
    raw = encode_packet(bytes([1, 255, 0]))
    assert raw == BREAK + bytes([0, 1, 255, 255, 0])
    d = DmxDecoder()
    assert d.feed(raw) == []  # the packet ends at the next break
    assert d.feed(encode_packet(b"\x09", start_code=0xCC)) == [DmxPacket(0, bytes([1, 255, 0]))]
    assert d.flush() == [DmxPacket(0xCC, b"\x09")]


def test_a_full_packet_ends_at_slot_512_and_errors_drop_the_packet() -> None:
    d = DmxDecoder()
    assert d.feed(encode_packet(bytes(512))) == [DmxPacket(0, bytes(512))]
    assert d.feed(b"\x05\x06") == [] and d.errors == 2  # data before a break
    # FFh 01h is a framing error: the packet is dropped, 08h after it is outside a packet
    assert d.feed(BREAK + b"\x00\x07\xff\x01\x08") == [] and d.errors == 4
    assert d.feed(BREAK) == []  # the broken packet is not delivered


@settings(max_examples=100, deadline=None)
@given(st.lists(st.binary(min_size=1, max_size=40), min_size=1, max_size=4),
       st.lists(st.integers(1, 30), max_size=10))
def test_any_chunking_gives_the_same_packets(packets: list[bytes], cuts: list[int]) -> None:
    raw = b"".join(encode_packet(p) for p in packets) + BREAK
    d = DmxDecoder()
    got = []
    k = 0
    for c in [*cuts, len(raw)]:
        got += d.feed(raw[k:k + c])
        k += c
    got += d.feed(raw[k:])
    assert got == [DmxPacket(0, p) for p in packets]


# --- scaling (§13.1.7) ----------------------------------------------------------------------
def test_scaling_formulas() -> None:
    s = DmxSettings(pos_nom=-3, pos_den=2, pos_offset=1000, acc_nom=100, acc_den=3,
                    acc_offset=50, vel_nom=1000, vel_den=7, vel_offset=-20)
    assert s.position(0x00, 0x05) == -7 + 1000  # 5·(−3)/2 = −7.5, truncated
    assert s.position(0xFF, 0xFF) == 65535 * -3 // 2 + 1 + 1000
    assert s.acceleration(255) == 8500 + 50
    assert s.velocity(7) == 1000 - 20
    d = DmxSettings()  # the MacTalk tab's defaults: velocity 10/1, position and acc 1/1
    assert (d.position(0x12, 0x34), d.acceleration(200), d.velocity(255)) == (0x1234, 200, 2550)
    with pytest.raises(ValueError, match="pos_den"):
        DmxSettings(pos_den=0)
    with pytest.raises(ValueError, match="acc_offset"):
        DmxSettings(acc_offset=-1)


# --- receiver -----------------------------------------------------------------------------------
def _frame(sa1: int = 1, sa2: int = 500, pos: int = 0, control: int = 0, acc: int = 0,
           vel: int = 0, size: int = 512) -> DmxPacket:
    slots = bytearray(size)
    slots[sa1 - 1:sa1 + 2] = bytes([pos >> 8, pos & 0xFF, control])
    slots[sa2 - 1:sa2 + 1] = bytes([acc, vel])
    return DmxPacket(0, bytes(slots))


def _motor(**settings: object) -> tuple[MotorArray, DmxReceiver]:
    m = MotorArray("MIS232", seed=0)
    m.write("IN_POSITION_COUNT", 0)
    return m, DmxReceiver(m, 0, DmxSettings(**settings))  # type: ignore[arg-type]


def test_address_channels_and_position_mode_without_homing() -> None:
    """§13.1.6: SA1 + 0/1 position coarse/fine, SA1 + 2 control, SA2 + 0/1 acceleration and
    velocity; control 60–69 transfers the scaled values (homing disabled)."""
    m, r = _motor(start_address1=10, start_address2=300, homing=False, vel_nom=100)
    r.packet(_frame(10, 300, pos=0x0190, control=65, acc=200, vel=150))
    assert [int(m.read_raw(k)[0]) for k in ("MODE_REG", "P_SOLL", "A_SOLL", "V_SOLL")] == [
        2, 400, 200, 15000]
    m.step(300)
    assert m.read_raw("P_IST")[0] == 400
    m.write("P_SOLL", 0)
    r.packet(_frame(10, 300, pos=0x0190, control=61, acc=200, vel=150))
    assert m.read_raw("P_SOLL")[0] == 0  # the same values: nothing new to transfer
    r.packet(_frame(10, 300, pos=0x0191, control=61, acc=0, vel=150))
    assert m.read_raw("P_SOLL")[0] == 401 and m.read_raw("A_SOLL")[0] == 1  # within range
    r.packet(_frame(10, 300, pos=0x0500, control=70))
    assert m.read_raw("P_SOLL")[0] == 401 and m.read_raw("MODE_REG")[0] == 2
    r.packet(_frame(10, 300, control=3))
    assert m.read_raw("MODE_REG")[0] == 0
    r.packet(DmxPacket(0, bytes(301)))  # too short for SA2 + 1: ignored
    r.packet(DmxPacket(0x17, bytes(512)))  # not dimmer data: ignored
    assert m.read_raw("MODE_REG")[0] == 0


def test_homing_starts_after_ten_identical_values_then_position_mode() -> None:
    m = MotorArray("MIS232", seed=0, home_position=-0.3)  # the home sensor on input 4
    m.write_many({"HOME_MASK": 8, "V_HOME": -3000, "IN_POSITION_COUNT": 0})
    r = DmxReceiver(m, 0, DmxSettings(homing_mode=13))
    r.packet(_frame(pos=100, control=65))
    assert m.read_raw("MODE_REG")[0] == 0  # no position before a homing
    for _ in range(9):
        r.packet(_frame(control=185))
    for _ in range(9):
        r.packet(_frame(control=186))
    assert m.read_raw("MODE_REG")[0] == 0  # 9 + 9: no run of ten identical values
    r.packet(_frame(control=186))
    assert m.read_raw("MODE_REG")[0] == 13  # the tenth identical value
    r.packet(_frame(control=0))  # not aborted
    assert m.read_raw("MODE_REG")[0] == 13
    for _ in range(100):
        m.step(50)
        r.poll()
        if not r.homing:
            break
    assert r.homed and m.read_raw("MODE_REG")[0] == 2
    r.packet(_frame(pos=100, control=60, vel=200))
    assert m.read_raw("P_SOLL")[0] == 100 and m.read_raw("V_SOLL")[0] == 2000


def test_reset_error_and_auto_clear() -> None:
    m, r = _motor(homing=False)
    m.write("ERR_BITS", 8)
    r.packet(_frame(control=60, pos=5))
    # refused; the general error bit 0 goes with any error (MIS manual §8.2.31)
    assert m.read_raw("MODE_REG")[0] == 0 and m.read_raw("ERR_BITS")[0] == 8 | 1
    r.packet(_frame(control=204))
    assert m.read_raw("ERR_BITS")[0] == 0
    m, r = _motor(homing=False, auto_clear_errors=True)
    m.write("ERR_BITS", 8)
    r.packet(_frame(control=60, pos=5))
    assert m.read_raw("MODE_REG")[0] == 2 and m.read_raw("P_SOLL")[0] == 5


def test_values_only_with_a_new_position() -> None:
    m, r = _motor(homing=False, values_with_position=True)
    r.packet(_frame(control=60, pos=10, vel=50))
    r.packet(_frame(control=60, pos=10, vel=90))
    assert m.read_raw("V_SOLL")[0] == 500
    r.packet(_frame(control=60, pos=11, vel=90))
    assert m.read_raw("V_SOLL")[0] == 900 and m.read_raw("P_SOLL")[0] == 11


def test_jogging_by_inputs() -> None:
    m, r = _motor(homing=False, jog_velocity=5000, default_velocity=70000)
    r.packet(_frame(control=60, pos=1000))
    m.set_input(digital_inputs=0b001)
    m.step(1)
    r.poll()
    assert m.read_raw("MODE_REG")[0] == 1 and m.read_raw("V_SOLL")[0] == 0
    r.packet(_frame(control=60, pos=2000))
    assert m.read_raw("P_SOLL")[0] == 1000  # DMX data ignored while jogging
    for bits, v in ((0b011, 5000), (0b001, 0), (0b101, -5000)):
        m.set_input(digital_inputs=bits)
        m.step(1)
        r.poll()
        assert m.read_raw("V_SOLL")[0] == v
    m.step(200)
    m.set_input(digital_inputs=0)
    m.step(1)
    r.poll()
    # passive by way of the stop ramp (§5.11.2): the motor decelerates in mode 11 first
    assert m.read_raw("MODE_REG")[0] == 11 and m.read_raw("V_SOLL")[0] == 70000
    assert m.read_raw("P_SOLL")[0] == m.read_raw("P_IST")[0] < 0
    m.step(300)
    assert m.read_raw("MODE_REG")[0] == 0
    r.packet(_frame(control=60, pos=3000))  # homing disabled: taken again at once
    assert m.read_raw("P_SOLL")[0] == 3000


# --- served ------------------------------------------------------------------------------------
def test_served_over_tcp() -> None:
    m = MotorArray("MIS232", n=2, seed=0)
    twin = Twin(m, [1, 2])
    line = DmxLine(twin, [DmxSettings(start_address1=1, homing=False),
                          DmxSettings(start_address1=4, homing=False)])
    with DmxServer(twin, tcp=("127.0.0.1", 0), line=line, speed=1.0) as server:
        port = server.endpoint("dmx", "tcp").port
        with socket.create_connection(("127.0.0.1", port), timeout=2) as s:
            slots = bytearray(512)
            slots[0:6] = bytes([0x01, 0x00, 60, 0x02, 0x00, 61])
            slots[499:501] = bytes([255, 200])
            s.sendall(encode_packet(bytes(slots)) + BREAK)
            deadline = time.monotonic() + 5
            while line.packets < 1 and time.monotonic() < deadline:
                time.sleep(0.01)
    assert [int(v) for v in m.read_raw("P_SOLL")] == [256, 512]
    assert [int(v) for v in m.read_raw("MODE_REG")] == [2, 2]
