"""Modbus RTU of the MIS/SMC motors (MIS manual §12): codec, slave, timeout, MacTalk → Modbus
switch, fuzzing, and pymodbus as the client over TCP (RTU framer) and a pty.

The devices are in-memory maps of 32-bit registers (:class:`RegisterFile`) with the MIS register
numbers where the manual's examples use them.
"""

from __future__ import annotations

import inspect
import os
import time

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from jvl_gym.protocol import FrameError
from jvl_gym.protocol.modbus import codec as mb
from jvl_gym.protocol.modbus.server import (
    MIS_REGISTERS,
    ActiveProtocol,
    ModbusBus,
    ModbusRegisters,
    ModbusServer,
    ModbusSession,
    ModbusSlave,
    ProtocolSwitch,
    RegisterAccess,
    RegisterFile,
    SwitchingSession,
    exception_code,
)

EC = mb.ExceptionCode
FUZZ = settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])

P_IST, V_SOLL, MODE_REG, STATUS = 10, 5, 2, 25


def mis_device(node_id: int = 42, **extra: int) -> RegisterFile:
    """A few MIS registers (MIS manual §8.2 numbers) in memory."""
    values = {MODE_REG: 2, 3: 0, V_SOLL: 10000, P_IST: 0, 12: 0, STATUS: 0x10, 65: 0, 66: 0,
              67: 0, 121: 0, 146: 1, 150: node_id, 199: 0, 200: 0, 201: 0}
    values.update({int(k[1:]): v for k, v in extra.items()})
    return RegisterFile(node_id, values, read_only=[12, STATUS],
                        ranges={V_SOLL: (-300_000, 300_000), MODE_REG: (0, 14)})


def reply(bus: ModbusBus, frame: bytes, now: float = 0.0) -> bytes:
    return bus.handle(frame, now)[0]


def exception_of(frame: bytes) -> int:
    r = mb.decode_response(frame)
    assert isinstance(r, mb.ExceptionResponse), r
    return r.code


# ----------------------------------------------------------------------------- CRC
@pytest.mark.parametrize("data, crc", [
    (b"123456789", 0x4B37),  # CRC-16/MODBUS check value
    (bytes.fromhex("01 03 00 00 00 01"), 0x0A84),  # sent as 84 0A
    (bytes.fromhex("11 03 00 6B 00 03"), 0x8776),  # Modbus spec example: sent as 76 87
    (b"", 0xFFFF),
])
def test_crc16_examples(data, crc):
    assert mb.crc16(data) == crc
    assert mb.append_crc(data)[-2:] == crc.to_bytes(2, "little")
    assert mb.crc_ok(mb.append_crc(data)) == (len(data) >= 2)


def test_hypothesis_examples_have_no_wall_clock_deadline():
    # the suite's profile (conftest.py): on a busy machine an example of the CRC comparison
    # below took 351 ms, past hypothesis' default deadline of 200 ms
    from hypothesis import settings

    assert settings.default.deadline is None


@given(st.binary(max_size=64))
def test_crc16_matches_pymodbus(data):
    rtu = pytest.importorskip("pymodbus.framer.rtu")
    assert rtu.FramerRTU.compute_CRC(data) == int.from_bytes(
        mb.crc16(data).to_bytes(2, "little"), "big")


# ----------------------------------------------------------------------------- manual examples
# MIS manual §12.4: "Read actual position (register 10) from motor with slave address 42"
READ_42 = bytes((0x2A, 0x03, 0x00, 0x14, 0x00, 0x02))
READ_42_REPLY = bytes((0x2A, 0x03, 0x04, 0xCD, 0x15, 0x07, 0x5B))
# MIS manual §12.5: Velocity 1 (65) = 409600 and Velocity 2 (66) = 13 on slave 60 (the manual's
# "x00" in the 15th byte is read as 0x00)
WRITE_60 = bytes((0x3C, 0x10, 0x00, 0x82, 0x00, 0x04, 0x08, 0x40, 0x00, 0x00, 0x06, 0x00, 0x0D,
                  0x00, 0x00))
WRITE_60_REPLY = bytes((0x3C, 0x10, 0x00, 0x82, 0x00, 0x04))


def test_manual_word_order_example():
    """MIS manual §12.3: 123456789 (0x075BCD15) at indices 20, 21 reads {CD 15 07 5B}."""
    lo, hi = mb.words_of(123456789)
    assert (lo, hi) == (0xCD15, 0x075B)
    assert lo.to_bytes(2, "big") + hi.to_bytes(2, "big") == bytes((0xCD, 0x15, 0x07, 0x5B))
    assert mb.value_of(lo, hi) == 123456789
    assert mb.words_of(-1) == (0xFFFF, 0xFFFF) and mb.value_of(0xFFFF, 0xFFFF) == -1


def test_manual_read_actual_position_of_slave_42():
    frame = mb.encode_read_request(42, 2 * P_IST, 2)
    assert frame[:-2] == READ_42 and frame == mb.append_crc(READ_42)
    assert mb.decode_request(frame) == mb.ReadRequest(42, 20, 2)
    bus = ModbusBus(mis_device(42, r10=123456789))
    out = reply(bus, frame)
    assert out == mb.append_crc(READ_42_REPLY)
    assert out == mb.encode_read_response(42, [0xCD15, 0x075B])
    assert mb.decode_response(out) == mb.ReadResponse(42, (0xCD15, 0x075B))


def test_manual_write_velocities_of_slave_60():
    frame = mb.encode_write_request(60, 2 * 65, [*mb.words_of(409600), *mb.words_of(13)])
    assert frame[:-2] == WRITE_60 and frame == mb.append_crc(WRITE_60)
    req = mb.decode_request(frame)
    assert req == mb.WriteRequest(60, 130, 4, 8, (0x4000, 0x0006, 0x000D, 0x0000))
    dev = mis_device(60)
    out = reply(ModbusBus(dev), frame)
    assert out == mb.append_crc(WRITE_60_REPLY)
    assert out == mb.encode_write_response(60, 130, 4)
    assert dev.values[65] == 409600 and dev.values[66] == 13
    assert dev.writes == [(65, 409600), (66, 13)]


def test_manual_pdo_example():
    """MIS manual §12.6: read P_IST, V_IST, STATUS in one frame, write P_SOLL, V_SOLL in one."""
    dev = mis_device(7, r10=-5, r12=1234, r25=0x10)
    bus = ModbusBus(dev)
    tx, rx, value = 0xF300, 0xF200, 0xF400  # PDO1_TX_SETUP[0], RX_SETUP[0], VALUE[0]
    words = [w for n in (10, 12, 25) for w in mb.words_of(n)]
    assert reply(bus, mb.encode_write_request(7, tx, words)) == mb.encode_write_response(
        7, tx, 6)
    out = mb.decode_response(reply(bus, mb.encode_read_request(7, value, 6)))
    assert out.words == (*mb.words_of(-5), *mb.words_of(1234), *mb.words_of(0x10))
    # the set-up reads back; inactive entries read 0
    assert mb.decode_response(reply(bus, mb.encode_read_request(7, tx, 8))).words == (
        10, 0, 12, 0, 25, 0, 0, 0)
    # VALUE[0..2] cannot be written before RX_SETUP is configured (§12.6.2: invalid address)
    bad = mb.encode_write_request(7, value, list(mb.words_of(99)))
    assert exception_of(reply(bus, bad)) == EC.ILLEGAL_DATA_ADDRESS
    assert reply(bus, mb.encode_write_request(7, rx, [3, 0, 5, 0])) == mb.encode_write_response(
        7, rx, 4)
    w = [*mb.words_of(100000), *mb.words_of(2500)]
    assert reply(bus, mb.encode_write_request(7, value, w)) == mb.encode_write_response(
        7, value, 4)
    assert dev.values[3] == 100000 and dev.values[V_SOLL] == 2500
    # a start other than VALUE[0]; VALUE[1] reads V_IST, VALUE[2] STATUS
    out = mb.decode_response(reply(bus, mb.encode_read_request(7, value + 2, 4)))
    assert out.words == (*mb.words_of(1234), *mb.words_of(0x10))
    # VALUE[2] is not configured for writing; VALUE[3] not for reading
    assert exception_of(reply(bus, mb.encode_write_request(7, value + 4, [1, 0]))) == 2
    assert exception_of(reply(bus, mb.encode_read_request(7, value + 6, 2))) == 2
    # the set-up list must be written from entry 0 (§12.6.1)
    before = dict(dev.values)
    assert exception_of(reply(bus, mb.encode_write_request(7, tx + 2, [1, 0]))) == 2
    assert bus.slaves[0].pdo[1].tx == [10, 12, 25] and dev.values == before
    # PDO2 is independent; power-on forgets the set-up (§12.6.1)
    assert exception_of(reply(bus, mb.encode_read_request(7, 0xF700, 2))) == 2
    bus.power_on()
    assert exception_of(reply(bus, mb.encode_read_request(7, value, 2))) == 2


# ----------------------------------------------------------------------------- addressing
@pytest.mark.parametrize("reading", ["register", "word"])
def test_alternative_window(reading):
    amap = mb.AddressMap(alt_reading=reading)
    dev = mis_device(3, r10=123456789, r11=-2)
    bus = ModbusBus(dev, address_map=amap)
    start = amap.index_of(P_IST, alt=True)
    assert start == (40010 if reading == "register" else 40020)
    out = mb.decode_response(reply(bus, mb.encode_read_request(3, start, 4)))
    assert out.words == (0xCD15, 0x075B, *mb.words_of(-2))
    w = [*mb.words_of(409600), *mb.words_of(13)]
    assert reply(bus, mb.encode_write_request(3, amap.index_of(65, alt=True), w))[1] == 0x10
    assert dev.values[65] == 409600 and dev.values[66] == 13
    # the same register through both windows
    a = reply(bus, mb.encode_read_request(3, 2 * 65, 2))
    b = reply(bus, mb.encode_read_request(3, amap.index_of(65, alt=True), 2))
    assert a == b


def test_resolve_windows():
    amap = mb.AddressMap()
    assert amap.resolve(20, 3) == [mb.WordRef(mb.Area.REGISTER, 10, False),
                                   mb.WordRef(mb.Area.REGISTER, 10, True),
                                   mb.WordRef(mb.Area.REGISTER, 11, False)]
    assert amap.resolve(21, 1) == [mb.WordRef(mb.Area.REGISTER, 10, True)]
    assert amap.resolve(40010, 2) == [mb.WordRef(mb.Area.REGISTER, 10, False),
                                      mb.WordRef(mb.Area.REGISTER, 10, True)]
    assert amap.resolve(0xF40E, 2)[1] == mb.WordRef(mb.Area.VALUE, 7, True, 1)
    assert amap.resolve(0xF600, 1)[0] == mb.WordRef(mb.Area.TX_SETUP, 0, False, 2)
    for index, count in [(39998, 4), (0xF40E, 4), (0xF1FE, 4), (0xFFFF, 2)]:
        with pytest.raises(mb.ModbusError) as e:
            amap.resolve(index, count)
        assert e.value.code == EC.ILLEGAL_DATA_ADDRESS


def test_read_single_words_and_odd_start():
    """Reads may start at the high word and cover half a register (MIS manual §12.3)."""
    bus = ModbusBus(mis_device(5, r10=123456789, r11=7))
    assert mb.decode_response(reply(bus, mb.encode_read_request(5, 21, 1))).words == (0x075B,)
    assert mb.decode_response(reply(bus, mb.encode_read_request(5, 21, 3))).words == (
        0x075B, 7, 0)


# ----------------------------------------------------------------------------- exceptions
@pytest.mark.parametrize("function", [0x01, 0x02, 0x04, 0x05, 0x06, 0x0F, 0x17, 0x2B, 0x4A,
                                      0x4B, 0x7F, 0x00])
def test_unsupported_function_gets_exception_1(function):
    dev = mis_device(42)
    before = dict(dev.values)
    frame = mb.append_crc(bytes((42, function, 0x00, 0x14, 0x00, 0x02)))
    out = reply(ModbusBus(dev), frame)
    assert out == mb.encode_exception(42, function, 1)
    assert out == mb.append_crc(bytes((42, function | 0x80, 0x01)))
    assert dev.values == before


@pytest.mark.parametrize("frame, code", [
    (mb.encode_read_request(42, 2 * 99, 2), EC.ILLEGAL_DATA_ADDRESS),  # no register 99
    (mb.encode_read_request(42, 2 * 150, 4), EC.ILLEGAL_DATA_ADDRESS),  # 151 does not exist
    (mb.encode_read_request(42, 0, 17), EC.ILLEGAL_DATA_VALUE),  # more than 16 words
    (mb.encode_read_request(42, 20, 0), EC.ILLEGAL_DATA_VALUE),
    (mb.encode_read_request(42, 0xFFF0, 16), EC.ILLEGAL_DATA_ADDRESS),
    (mb.encode_write_request(42, 130, [0] * 18), EC.ILLEGAL_DATA_VALUE),
    (mb.encode_write_request(42, 130, [0] * 4, count=2), EC.ILLEGAL_DATA_VALUE),  # byte count
    (mb.encode_write_request(42, 2 * 99, [1, 0]), EC.ILLEGAL_DATA_ADDRESS),
    (mb.encode_write_request(42, 2 * 25, [1, 0]), EC.ILLEGAL_DATA_ADDRESS),  # read-only
    (mb.encode_write_request(42, 2 * 5, list(mb.words_of(400_000))), EC.ILLEGAL_DATA_VALUE),
    (mb.append_crc(bytes.fromhex("2a 03 00 14 00")), EC.ILLEGAL_DATA_VALUE),  # short read
    (mb.append_crc(bytes.fromhex("2a 10 00 14 00 02 04 00 01")), EC.ILLEGAL_DATA_VALUE),
])
def test_exception_codes(frame, code):
    dev = mis_device(42)
    before = dict(dev.values)
    out = reply(ModbusBus(dev), frame)
    assert exception_of(out) == code
    assert mb.decode_response(out).function == frame[1]
    assert dev.values == before and dev.writes == []


@pytest.mark.parametrize("index, words", [
    (2 * 65 + 1, [1, 2]),  # odd start
    (2 * 65, [1]),  # one word: half a register
    (2 * 65, [1, 2, 3]),  # odd count
    (2 * 65 + 1, [1, 2, 3, 4]),
    (40065, [1, 2, 3]),  # odd count in the alternative window
    (0xF201, [3, 0]),  # odd start in a PDO block
])
def test_unaligned_or_partial_writes_are_refused(index, words):
    dev = mis_device(42)
    before = dict(dev.values)
    out = reply(ModbusBus(dev), mb.encode_write_request(42, index, words))
    assert exception_of(out) == EC.ILLEGAL_DATA_ADDRESS
    assert dev.values == before and dev.writes == []


def test_refused_register_in_a_multi_register_write_changes_nothing():
    """V_SOLL accepts 2500, MODE_REG refuses 99: V_SOLL is not stored either (MIS manual §12.5)."""
    dev = mis_device(42)
    before = dict(dev.values)
    frame = mb.encode_write_request(42, 2 * 5, [*mb.words_of(2500), 0, 0])  # registers 5 and 6
    out = reply(ModbusBus(dev), frame)
    assert exception_of(out) == EC.ILLEGAL_DATA_ADDRESS  # register 6 does not exist
    assert dev.values == before and dev.writes == []
    dev = mis_device(42, r4=0)
    frame = mb.encode_write_request(42, 2 * 4, [*mb.words_of(1), *mb.words_of(999_999)])
    out = reply(ModbusBus(dev), frame)
    assert exception_of(out) == EC.ILLEGAL_DATA_VALUE
    assert dev.values[4] == 0 and dev.values[V_SOLL] == 10000
    assert dev.writes == []  # checked as a whole before the first is stored


def test_refusal_with_own_exception_code():
    class Refusing(RegisterFile):
        def write_many(self, values):
            err = ValueError("busy")
            err.modbus_exception = 6  # SERVER DEVICE BUSY
            raise err

    dev = Refusing(1, {3: 0})
    out = reply(ModbusBus(dev), mb.encode_write_request(1, 6, [1, 0]))
    assert mb.decode_response(out) == mb.ExceptionResponse(1, 0x10, 6)


def test_exception_code_mapping():
    from jvl_gym.registers import RegisterError

    assert exception_code(KeyError(5)) == EC.ILLEGAL_DATA_ADDRESS
    assert exception_code(RegisterError("mode")) == EC.SERVER_DEVICE_FAILURE
    assert exception_code(ValueError("other")) == EC.SERVER_DEVICE_FAILURE


# ----------------------------------------------------------------------------- broadcast, bus
def test_broadcast_write_is_carried_out_by_all_and_not_answered():
    a, b = mis_device(1), mis_device(2)
    bus = ModbusBus([a, b])
    frame = mb.encode_write_request(0, 2 * 65, [*mb.words_of(-7)])
    assert reply(bus, frame) == b""
    assert a.values[65] == b.values[65] == -7
    # a broadcast read is not valid (MIS manual §12.4): nothing, no reply
    assert reply(bus, mb.encode_read_request(0, 20, 2)) == b""
    # a refused broadcast is not answered either, and changes nothing
    assert reply(bus, mb.encode_write_request(0, 2 * 65 + 1, [1, 2])) == b""
    assert a.values[65] == b.values[65] == -7
    assert reply(bus, mb.append_crc(bytes((0, 0x06, 0, 1, 0, 1)))) == b""


def test_other_slaves_and_bad_frames_are_ignored():
    a, b = mis_device(1, r10=11), mis_device(2, r10=22)
    bus = ModbusBus([a, b])
    assert mb.decode_response(reply(bus, mb.encode_read_request(2, 20, 2))).words == (22, 0)
    assert reply(bus, mb.encode_read_request(3, 20, 2)) == b""
    assert bus.stats["ignored"] == 1
    bad = bytearray(mb.encode_write_request(1, 130, [5, 0]))
    bad[7] ^= 0x01
    assert reply(bus, bytes(bad)) == b""
    assert a.values[65] == 0 and bus.stats["errors"] == 1
    # the slave address follows node_id (MIS manual §12.1: register 150)
    a.node_id = 9
    assert mb.decode_response(reply(bus, mb.encode_read_request(9, 20, 2))).slave == 9


def test_protocol_is_satisfied_by_register_file():
    assert isinstance(mis_device(), RegisterAccess)


# ----------------------------------------------------------------------------- timeout, delay
@pytest.mark.parametrize("action, register, expected", [
    (1, V_SOLL, 0),  # max velocity set to zero
    (2, MODE_REG, 0),  # passive mode
])
def test_timeout_action(action, register, expected):
    dev = mis_device(42, r199=100, r200=action)
    bus = ModbusBus(dev, MIS_REGISTERS)
    slave = bus.slaves[0]
    bus.poll(10.0)
    assert slave.stats["timeout"] == 0  # the timer starts with the first message
    reply(bus, mb.encode_read_request(42, 20, 2), now=1.0)
    bus.poll(1.05)
    assert dev.values[V_SOLL] == 10000 and dev.values[MODE_REG] == 2
    bus.poll(1.2)
    assert dev.values[register] == expected and slave.timed_out
    assert slave.stats["timeout"] == 1 and len(slave.events) == 1
    # fires once; the next message re-arms it
    dev.values[register] = 5
    bus.poll(2.0)
    assert dev.values[register] == 5
    reply(bus, mb.encode_read_request(42, 20, 2), now=3.0)
    bus.poll(3.5)
    assert dev.values[register] == expected and slave.stats["timeout"] == 2


def test_timeout_event_only_and_disabled():
    dev = mis_device(42, r199=100, r200=0)
    bus = ModbusBus(dev, MIS_REGISTERS)
    reply(bus, mb.encode_read_request(42, 20, 2), now=0.0)
    bus.poll(1.0)
    assert bus.slaves[0].stats["timeout"] == 1 and dev.writes == []
    dev = mis_device(42, r199=0, r200=1)
    bus = ModbusBus(dev, MIS_REGISTERS)
    reply(bus, mb.encode_read_request(42, 20, 2), now=0.0)
    bus.poll(1e6)
    assert bus.slaves[0].stats["timeout"] == 0 and dev.values[V_SOLL] == 10000


def test_register_numbers_come_from_the_mapping():
    """Nothing MIS-specific in the slave: another mapping, other registers."""
    regs = ModbusRegisters(timeout=1000, timeout_action=1001, max_velocity=7)
    dev = RegisterFile(1, {7: 500, 1000: 20, 1001: 1, 199: 0, 200: 0})
    bus = ModbusBus(dev, regs)
    reply(bus, mb.encode_read_request(1, 14, 2), now=0.0)
    bus.poll(0.05)
    assert dev.values[7] == 0 and dev.writes == [(7, 0)]
    assert ModbusSlave(dev).serial_format() == mb.SerialFormat(19200, "N", 1)


def test_serial_format_and_reply_delay():
    dev = mis_device(42, r146=4, r121=0b10_1001)  # 115200 baud, even parity, 2 stop bits
    slave = ModbusSlave(dev, MIS_REGISTERS)
    fmt = slave.serial_format()
    assert fmt == mb.SerialFormat(115200, "E", 2) and fmt.bits == 12
    assert slave.reply_delay() == pytest.approx(2.5 * 12 / 115200)
    dev.values[201] = 5
    assert slave.reply_delay() == pytest.approx(5e-3)
    dev.values[146] = 99
    assert slave.serial_format().baud == 19200
    assert mb.decode_setup(0x101) == mb.ModbusSetup(True, True, "N", 1)
    assert mb.decode_setup(0b0100) == mb.ModbusSetup(False, False, "O", 1)


def test_silence_lengths():
    assert mb.silence(mb.SerialFormat(9600, "E", 1)) == pytest.approx(3.5 * 11 / 9600)
    assert mb.silence(mb.SerialFormat(19200, "N", 1)) == pytest.approx(3.5 * 10 / 19200)
    assert mb.silence(mb.SerialFormat(115200)) == pytest.approx(1.75e-3)
    assert mb.silence(mb.SerialFormat(460800), 1.5) == pytest.approx(0.75e-3)


# ----------------------------------------------------------------------------- RTU framing
def test_framer_splits_by_silence_and_length():
    fmt = mb.SerialFormat(9600)
    t35 = mb.silence(fmt)
    read = mb.encode_read_request(42, 20, 2)
    write = mb.encode_write_request(60, 130, [1, 2, 3, 4])
    f = mb.RtuFramer(fmt)
    # two frames back to back in one chunk: split by their lengths
    assert f.feed(read + write, 0.0) == [read, write]
    # a frame in pieces with short gaps is one frame
    assert f.feed(write[:5], 1.0) == []
    assert f.feed(write[5:9], 1.0 + 0.5 * t35) == []
    assert f.feed(write[9:], 1.0 + 0.9 * t35) == [write]
    # a gap of 3.5 characters ends the frame: both halves are bad frames
    assert f.feed(read[:4], 2.0) == []
    out = f.feed(read[4:], 2.0 + 1.01 * t35)
    assert [type(x) for x in out] == [FrameError] and out[0].code == "bad_crc"
    out = f.flush()
    assert [x.code for x in out] == ["bad_crc"] and f.pending == b""
    # a request of another function ends when its CRC is complete
    other = mb.append_crc(bytes((1, 0x06, 0, 1, 0, 3)))
    assert f.feed(other, 3.0) == [other]
    # garbage is dropped at the next silence
    assert f.feed(b"\x01\x02\x03\x04\x05", 4.0) == []
    out = f.feed(read, 5.0)
    assert isinstance(out[0], FrameError) and out[0].code == "bad_crc" and out[1] == read
    # more than 256 bytes without a frame
    out = f.feed(bytes(300), 6.0)
    assert [x.code for x in out if isinstance(x, FrameError)] == ["too_long"]


def test_decode_errors():
    with pytest.raises(FrameError) as e:
        mb.decode_request(b"\x01\x03")
    assert e.value.code == "too_short"
    with pytest.raises(FrameError) as e:
        mb.decode_request(mb.encode_read_request(1, 0, 2)[:-1] + b"\x00")
    assert e.value.code == "bad_crc"
    with pytest.raises(FrameError):
        mb.decode_response(mb.append_crc(b"\x01\x03\x03\x00\x01\x02"))
    with pytest.raises(ValueError):
        mb.encode_read_request(256, 0, 1)
    with pytest.raises(ValueError):
        mb.encode_write_request(1, 0, [0x10000])


# ----------------------------------------------------------------------------- MacTalk → Modbus
class FakeClock:
    def __init__(self) -> None:
        self.t = 0.0

    def __call__(self) -> float:
        return self.t


class Recorder:
    def __init__(self, name: str) -> None:
        self.name = name
        self.got: list[bytes] = []
        self.flushes = 0

    def feed(self, chunk: bytes) -> bytes:
        self.got.append(chunk)
        return self.name.encode()

    def flush(self) -> bytes:
        self.flushes += 1
        return b""


def test_protocol_switch_state_machine():
    enabled = [False]
    sw = ProtocolSwitch(lambda: enabled[0], now=0.0)
    assert sw.on_bytes(0.5) == ActiveProtocol.MACTALK
    assert sw.poll(5.0) == ActiveProtocol.MACTALK  # not enabled: MacTalk for ever
    assert sw.on_bytes(5.0) == ActiveProtocol.MACTALK
    enabled[0] = True
    assert sw.on_bytes(5.9) == ActiveProtocol.MACTALK  # 0.9 s after the last byte
    assert sw.on_bytes(6.8) == ActiveProtocol.MACTALK
    assert sw.poll(7.7) == ActiveProtocol.MACTALK
    assert sw.poll(7.8) == ActiveProtocol.MODBUS  # one second of silence
    enabled[0] = False
    assert sw.on_bytes(7.9) == ActiveProtocol.MODBUS  # stays until power-on
    sw.power_on(10.0)
    assert sw.state == ActiveProtocol.MACTALK
    enabled[0] = True
    assert sw.on_bytes(10.5) == ActiveProtocol.MACTALK  # MacTalk in the first second
    assert sw.on_bytes(11.6) == ActiveProtocol.MODBUS


def test_switching_session_routes_bytes():
    clock = FakeClock()
    dev = mis_device(42, r121=1)
    sw = ProtocolSwitch.for_device(dev, MIS_REGISTERS.setup, now=0.0)
    mactalk = Recorder("mactalk")
    modbus = ModbusSession(ModbusBus(dev, MIS_REGISTERS), clock=clock, sleep=None)
    s = SwitchingSession(mactalk, modbus, sw, clock)
    clock.t = 0.2
    assert s.feed(b"\x50\x50\x50") == b"mactalk"
    clock.t = 1.0
    assert s.feed(mb.encode_read_request(42, 20, 2)) == b"mactalk"  # still MacTalk
    clock.t = 2.1
    dev.values[10] = 123456789
    assert s.feed(mb.encode_read_request(42, 20, 2)) == mb.append_crc(READ_42_REPLY)
    assert s.active == ActiveProtocol.MODBUS and mactalk.flushes == 1
    # disabled in register 121: MacTalk stays
    dev = mis_device(42, r121=0)
    s = SwitchingSession(Recorder("mactalk"), ModbusSession(ModbusBus(dev), clock=clock),
                         ProtocolSwitch.for_device(dev, 121, now=clock.t), clock)
    clock.t += 5
    assert s.flush() == b"" and s.feed(b"x") == b"mactalk"


def test_switching_session_served_over_tcp():
    """MacTalk first; after a silence (shortened to 0.2 s here) Modbus on the same stream."""
    import socket

    dev = mis_device(42, r10=123456789, r121=1)
    bus = ModbusBus(dev, MIS_REGISTERS)

    def make():
        switch = ProtocolSwitch.for_device(dev, 121, now=time.monotonic(), quiet=0.2)
        return SwitchingSession(Recorder("mactalk"), ModbusSession(bus), switch)

    with ModbusServer(bus=bus, tcp=("127.0.0.1", 0), make_session=make) as srv, \
            socket.create_connection(("127.0.0.1", srv.endpoint("modbus", "tcp").port),
                                     timeout=2) as conn:
        conn.sendall(b"\x50\x50\x50")
        assert conn.recv(64) == b"mactalk"
        session = srv.sessions[0]
        deadline = time.monotonic() + 5
        while session.active != ActiveProtocol.MODBUS and time.monotonic() < deadline:
            time.sleep(0.05)  # the server's receive timeouts poll the switch
        assert session.active == ActiveProtocol.MODBUS
        conn.sendall(mb.append_crc(READ_42))
        got = b""
        while len(got) < 9:
            got += conn.recv(64)
        assert got == mb.append_crc(READ_42_REPLY)


# ----------------------------------------------------------------------------- fuzzing
def valid_frames() -> st.SearchStrategy[bytes]:
    slave = st.sampled_from([0, 42, 43])
    index = st.one_of(st.integers(0, 320), st.integers(40000, 40160),
                      st.integers(0xF200, 0xF710), st.integers(0, 0xFFFF))
    words = st.lists(st.integers(0, 0xFFFF), min_size=0, max_size=20)
    return st.one_of(
        st.builds(mb.encode_read_request, slave, index, st.integers(0, 20)),
        st.builds(mb.encode_write_request, slave, index, words),
        st.builds(lambda s, f, d: mb.append_crc(bytes((s, f)) + d), slave,
                  st.integers(0, 255), st.binary(max_size=20)),
    )


@st.composite
def burst_corrupted(draw) -> bytes:
    """A valid frame with a burst error of at most 16 bits: CRC-16 detects every one."""
    data = bytearray(draw(valid_frames()))
    start = draw(st.integers(0, 8 * len(data) - 1))
    length = draw(st.integers(1, min(16, 8 * len(data) - start)))
    pattern = draw(st.integers(0, 2 ** (length - 1) - 1)) << 1 | 1 if length > 1 else 1
    pattern |= 1 << (length - 1)
    for b in range(length):
        if pattern >> b & 1:
            bit = start + b
            data[bit // 8] ^= 0x80 >> (bit % 8)
    return bytes(data)


def fuzz_bus() -> tuple[ModbusBus, RegisterFile, FakeClock, ModbusSession]:
    dev = mis_device(42, r10=123456789, r199=1000, r200=2)
    bus = ModbusBus(dev, MIS_REGISTERS)
    clock = FakeClock()
    return bus, dev, clock, ModbusSession(bus, clock=clock, sleep=None)


@FUZZ
@given(st.lists(burst_corrupted(), min_size=1, max_size=4))
def test_fuzz_corrupted_frames_change_nothing(frames):
    bus, dev, clock, session = fuzz_bus()
    before = dict(dev.values)
    for f in frames:
        clock.t += 1.0  # a silence between frames
        assert session.feed(f) == b""
    session.flush()
    assert dev.values == before and dev.writes == []
    assert bus.stats["errors"] == len(frames)


@FUZZ
@given(st.lists(st.one_of(st.binary(max_size=300), valid_frames()), min_size=1, max_size=6),
       st.lists(st.floats(0, 0.01), min_size=6, max_size=6))
def test_fuzz_random_streams_never_crash(chunks, gaps):
    bus, dev, clock, session = fuzz_bus()
    before = dict(dev.values)
    for chunk, gap in zip(chunks, gaps):
        clock.t += gap
        out = session.feed(chunk)
        k = 0
        while k < len(out):  # every reply is a well-formed response frame of slave 42
            n = 5 if out[k + 1] & 0x80 else (5 + out[k + 2] if out[k + 1] == 3 else 8)
            r = mb.decode_response(out[k:k + n])
            assert r.slave == 42
            k += n
    session.flush()
    if bus.slaves[0].stats["write"] == 0:
        assert dev.values == before
    else:  # only accepted writes change registers, and only writable ones
        assert dev.values[12] == before[12] and dev.values[25] == before[25]


# ----------------------------------------------------------------------------- pymodbus
def _unit(fn) -> str:
    params = inspect.signature(fn).parameters
    return "device_id" if "device_id" in params else "slave"


@pytest.fixture
def served():
    pytest.importorskip("pymodbus")
    a = mis_device(42, r10=123456789, r11=-1234)
    b = mis_device(60)
    with ModbusServer(bus=ModbusBus([a, b], MIS_REGISTERS), tcp=("127.0.0.1", 0),
                      pty=HAVE_PTY) as srv:
        yield srv, a, b


def _framer_rtu():
    import pymodbus

    framer = getattr(pymodbus, "FramerType", None) or pymodbus.Framer  # 3.6 names it Framer
    return framer.RTU


def _int32(client, registers) -> int:
    """pymodbus's own conversion (low word first) where it has one."""
    conv = getattr(client, "convert_from_registers", None)
    if conv is None:
        lo, hi = registers
        return mb.value_of(lo, hi)
    return conv(list(registers), client.DATATYPE.INT32, word_order="little")


def _words(client, value: int) -> list[int]:
    conv = getattr(client, "convert_to_registers", None)
    if conv is None:
        return list(mb.words_of(value))
    return conv(value, client.DATATYPE.INT32, word_order="little")


def test_pymodbus_client_over_tcp_rtu(served):
    from pymodbus.client import ModbusTcpClient

    srv, a, b = served
    port = srv.endpoint("modbus", "tcp").port
    client = ModbusTcpClient("127.0.0.1", port=port, framer=_framer_rtu(), timeout=2, retries=1)
    assert client.connect()
    try:
        u = _unit(client.read_holding_registers)
        # the manual's read: P_IST of slave 42 at 2n, low word first
        r = client.read_holding_registers(2 * P_IST, count=2, **{u: 42})
        assert not r.isError() and r.registers == [0xCD15, 0x075B]
        assert _int32(client, r.registers) == 123456789
        # the same register at 40 000 + n; two registers in one request
        r = client.read_holding_registers(40000 + P_IST, count=4, **{u: 42})
        assert _int32(client, r.registers[:2]) == 123456789
        assert _int32(client, r.registers[2:]) == -1234
        # the manual's write: V1, V2 of slave 60 at 2n
        w = client.write_registers(2 * 65, _words(client, 409600) + _words(client, 13),
                                   **{u: 60})
        assert not w.isError() and (w.address, w.count) == (130, 4)
        assert b.values[65] == 409600 and b.values[66] == 13
        # a write at 40 000 + n, negative value, read back at 2n
        w = client.write_registers(40000 + 67, _words(client, -5), **{u: 60})
        assert not w.isError() and b.values[67] == -5
        r = client.read_holding_registers(2 * 67, count=2, **{u: 60})
        assert _int32(client, r.registers) == -5
        # refusals: unsupported function, too many words, unaligned write, unknown register
        r = client.write_register(2 * 65, 1, **{u: 60})
        assert r.isError() and r.exception_code == 1
        r = client.read_holding_registers(0, count=17, **{u: 42})
        assert r.isError() and r.exception_code == 3
        r = client.write_registers(2 * 65 + 1, [1, 2], **{u: 60})
        assert r.isError() and r.exception_code == 2
        r = client.read_holding_registers(2 * 99, count=2, **{u: 42})
        assert r.isError() and r.exception_code == 2
        assert b.values[65] == 409600 and b.values[66] == 13
        # a broadcast write: carried out by both, not answered
        if "no_response_expected" in inspect.signature(client.write_registers).parameters:
            client.write_registers(2 * 66, [7, 0], no_response_expected=True, **{u: 0})
            deadline = time.monotonic() + 2
            while (a.values[66], b.values[66]) != (7, 7) and time.monotonic() < deadline:
                time.sleep(0.01)
            assert a.values[66] == b.values[66] == 7
    finally:
        client.close()


def _pty_available() -> bool:
    try:
        fd1, fd2 = os.openpty()
    except OSError:
        return False
    os.close(fd1)
    os.close(fd2)
    return True


HAVE_PTY = _pty_available()


@pytest.mark.skipif(not HAVE_PTY, reason="pseudo-terminals are unavailable")
def test_manual_frames_over_a_pty(served):
    serial = pytest.importorskip("serial")
    srv, a, b = served
    with serial.Serial(srv.endpoint("modbus", "pty").path, 19200, timeout=2) as port:
        port.write(mb.append_crc(READ_42))
        assert port.read(9) == mb.append_crc(READ_42_REPLY)
        port.write(mb.append_crc(WRITE_60))
        assert port.read(8) == mb.append_crc(WRITE_60_REPLY)
    assert b.values[65] == 409600 and b.values[66] == 13
