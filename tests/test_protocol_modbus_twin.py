"""Modbus RTU of the twin's MIS motors (MIS manual §12): the served twin answers the
manual's example frames byte for byte, pymodbus reads and writes it at 2n and 40 000 + n, the
refusals are exception replies that change nothing, the time-out action acts on the motor, and
``jvl-gym serve --modbus`` wires it up.

The MIS motors are ``MotorArray("MIS231")`` once the MIS family is registered, until then
``protocol_fakes.RegisterArray`` on the MIS register table (the table's validation, no physics).
"""

from __future__ import annotations

import inspect
import os
import time

import numpy as np
import pytest

from jvl_gym import MotorArray
from jvl_gym.families import families, mis
from jvl_gym.protocol.mactalk.dialect import MACTALK32
from jvl_gym.protocol.mactalk.twin16 import Twin
from jvl_gym.protocol.modbus import codec as mb
from jvl_gym.protocol.modbus.server import MIS_REGISTERS, ModbusServer
from jvl_gym.protocol.modbus.twin import MotorRegisters, modbus_bus, modbus_registers
from jvl_gym.registers import ReadOnlyRegisterError, RegisterRangeError, UnknownRegisterError
from protocol_fakes import RegisterArray

EC = mb.ExceptionCode
P_IST, V_SOLL, MODE_REG, V1, V2, V3 = 10, 5, 2, 65, 66, 67

# MIS manual §12.4: "Read actual position (register 10) from motor with slave address 42"
READ_42 = bytes((0x2A, 0x03, 0x00, 0x14, 0x00, 0x02))
READ_42_REPLY = bytes((0x2A, 0x03, 0x04, 0xCD, 0x15, 0x07, 0x5B))
# MIS manual §12.5: Velocity 1 (65) = 409600 and Velocity 2 (66) = 13 on slave 60
WRITE_60 = bytes((0x3C, 0x10, 0x00, 0x82, 0x00, 0x04, 0x08, 0x40, 0x00, 0x00, 0x06, 0x00, 0x0D,
                  0x00, 0x00))
WRITE_60_REPLY = bytes((0x3C, 0x10, 0x00, 0x82, 0x00, 0x04))


def mis_motors(n: int):
    """``n`` MIS231 motors: the simulator when the MIS family is registered, else the fake."""
    if "mis" in families():
        return MotorArray("MIS231", n=n, seed=0)
    return RegisterArray(mis.REGISTERS, n)


def mis_twin(addresses=(42, 60)) -> Twin:
    return Twin(mis_motors(len(addresses)), list(addresses), dialect=MACTALK32)


def handle(twin: Twin, frame: bytes) -> bytes:
    return modbus_bus(twin).handle(frame, now=0.0)[0]


def exception_of(frame: bytes) -> int:
    r = mb.decode_response(frame)
    assert isinstance(r, mb.ExceptionResponse), r
    return r.code


# ----------------------------------------------------------------------------- the adapter
def test_the_slave_registers_are_found_by_name_in_the_mis_table() -> None:
    """MIS manual §12.1: set-up 121, baud rate 146, time-out 199, response 200, delay 201."""
    assert modbus_registers(mis.REGISTERS, mis.FAMILY.twin.passive_mode) == MIS_REGISTERS


def test_adapter_reads_and_writes_by_number_and_refuses_as_the_simulator() -> None:
    twin = mis_twin()
    dev = MotorRegisters(twin, 1)
    assert dev.node_id == 60
    dev.write(P_IST, -123_456)
    assert dev.read(P_IST) == -123_456 == twin.m.read_raw(P_IST)[1]
    assert twin.m.read_raw(P_IST)[0] != -123_456
    dev.write(202, -1)  # TICKS, Word32: the 32 bits unsigned
    assert dev.read(202) == 2**32 - 1
    with pytest.raises(UnknownRegisterError):
        dev.read(254)
    with pytest.raises(ReadOnlyRegisterError):
        dev.write(12, 1)  # V_IST
    with pytest.raises(RegisterRangeError):
        dev.write(V_SOLL, 300_001)
    assert dev.read(V_SOLL) == twin.m.read_raw(V_SOLL)[1]
    dev.write(150, 61)  # MY_ADDR: the slave address follows at once
    assert dev.node_id == 61


def test_a_16_bit_family_is_not_served_over_modbus() -> None:
    with pytest.raises(ValueError, match="32-bit"):
        modbus_bus(Twin(MotorArray("MAC140", n=1, seed=0), [42]))


# ----------------------------------------------------------------------------- frames
def test_manual_read_actual_position_of_slave_42() -> None:
    twin = mis_twin()
    twin.m.write_raw(P_IST, 123456789, index=0)
    assert handle(twin, mb.append_crc(READ_42)) == mb.append_crc(READ_42_REPLY)


def test_manual_write_v1_v2_of_slave_60() -> None:
    """The manual's frame writes V1 = 409600 and V2 = 13 and shows the motor's accepting reply
    (MIS manual §12.5): the twin gives that reply byte for byte and stores both values (the
    worked example decides over the ±300000 of the tables, §8.2.42)."""
    twin = mis_twin()
    assert handle(twin, mb.append_crc(WRITE_60)) == mb.append_crc(WRITE_60_REPLY)
    assert twin.m.read_raw(V1)[1] == 409_600 and twin.m.read_raw(V2)[1] == 13


@pytest.mark.parametrize("function", [0x01, 0x04, 0x06, 0x0F, 0x17, 0x2B])
def test_unsupported_function_gets_exception_1(function: int) -> None:
    twin = mis_twin()
    before = twin.m.read_raw(P_IST).copy()
    frame = mb.append_crc(bytes((42, function, 0x00, 0x14, 0x00, 0x02)))
    assert handle(twin, frame) == mb.append_crc(bytes((42, function | 0x80, 0x01)))
    np.testing.assert_array_equal(twin.m.read_raw(P_IST), before)


@pytest.mark.parametrize("index, words, code", [
    (2 * V1 + 1, [1, 0], EC.ILLEGAL_DATA_ADDRESS),  # odd start
    (2 * V1, [1], EC.ILLEGAL_DATA_ADDRESS),  # half a register
    (2 * V1, [1, 0, 2], EC.ILLEGAL_DATA_ADDRESS),  # odd count
    (40000 + V1, [1, 0, 2], EC.ILLEGAL_DATA_ADDRESS),
    (2 * 12, [1, 0], EC.ILLEGAL_DATA_ADDRESS),  # V_IST is read-only
    (2 * 254, [1, 0], EC.ILLEGAL_DATA_ADDRESS),  # no register 254
    (2 * V_SOLL, list(mb.words_of(400_000)), EC.ILLEGAL_DATA_VALUE),
    (2 * (V1 + 7), [*mb.words_of(100), *mb.words_of(0)], EC.ILLEGAL_DATA_VALUE),  # A1 ≥ 1
    (2 * V1, [0] * 18, EC.ILLEGAL_DATA_VALUE),  # more than 16 words
])
def test_refused_writes_are_exceptions_and_change_nothing(index, words, code) -> None:
    twin = mis_twin()
    before = {n: twin.m.read_raw(n).copy() for n in (V_SOLL, V1, V2, V3, V1 + 7, 12)}
    out = handle(twin, mb.encode_write_request(42, index, words))
    assert exception_of(out) == code
    for n, v in before.items():
        np.testing.assert_array_equal(twin.m.read_raw(n), v)


def test_timeout_action_sets_the_motor_passive() -> None:
    """MIS manual §12.1: after MODBUS_TIMEOUT ms without a message, response 2 = passive."""
    twin = mis_twin()
    bus = modbus_bus(twin)
    for reg, value in ((MODE_REG, 1), (199, 50), (200, 2)):
        frame = mb.encode_write_request(42, 2 * reg, list(mb.words_of(value)))
        assert mb.decode_response(bus.handle(frame, now=0.0)[0]) == mb.WriteResponse(
            42, 2 * reg, 2)
    bus.poll(0.049)
    assert twin.m.read_raw(MODE_REG)[0] == 1
    bus.poll(0.051)
    assert twin.m.read_raw(MODE_REG)[0] == 0
    assert bus.slaves[0].timed_out and not bus.slaves[1].timed_out


# ----------------------------------------------------------------------------- served
def _pty_available() -> bool:
    try:
        fd1, fd2 = os.openpty()
    except OSError:
        return False
    os.close(fd1)
    os.close(fd2)
    return True


HAVE_PTY = _pty_available()


@pytest.fixture
def served():
    pytest.importorskip("pymodbus")
    from jvl_gym.cli.serve import _modbus_server

    twin = mis_twin()
    twin.m.write_raw(P_IST, 123456789, index=0)
    server = _modbus_server(twin, ("127.0.0.1", 0), HAVE_PTY, speed=1.0)
    server.run_clock = False
    with server:
        yield server, twin


def _framer_rtu():
    import pymodbus

    framer = getattr(pymodbus, "FramerType", None) or pymodbus.Framer
    return framer.RTU


def _unit(fn) -> str:
    params = inspect.signature(fn).parameters
    return "device_id" if "device_id" in params else "slave"


def _int32(client, registers) -> int:
    return client.convert_from_registers(list(registers), client.DATATYPE.INT32,
                                         word_order="little")


def _words(client, value: int) -> list[int]:
    return client.convert_to_registers(value, client.DATATYPE.INT32, word_order="little")


def test_pymodbus_reads_and_writes_the_served_twin(served) -> None:
    from pymodbus.client import ModbusTcpClient

    server, twin = served
    assert isinstance(server, ModbusServer)
    port = server.endpoint("modbus", "tcp").port
    client = ModbusTcpClient("127.0.0.1", port=port, framer=_framer_rtu(), timeout=2, retries=1)
    assert client.connect()
    try:
        u = _unit(client.read_holding_registers)
        r = client.read_holding_registers(2 * P_IST, count=2, **{u: 42})
        assert not r.isError() and r.registers == [0xCD15, 0x075B]  # low word first
        assert _int32(client, r.registers) == 123456789
        r = client.read_holding_registers(40000 + P_IST, count=2, **{u: 42})
        assert _int32(client, r.registers) == 123456789
        # V1 and V2 of slave 60 in one write at 2n, read back at 40 000 + n
        w = client.write_registers(2 * V1, _words(client, -250_000) + _words(client, 1234),
                                   **{u: 60})
        assert not w.isError() and (w.address, w.count) == (2 * V1, 4)
        assert twin.m.read_raw(V1)[1] == -250_000 and twin.m.read_raw(V2)[1] == 1234
        r = client.read_holding_registers(40000 + V1, count=4, **{u: 60})
        assert _int32(client, r.registers[:2]) == -250_000
        assert _int32(client, r.registers[2:]) == 1234
        w = client.write_registers(40000 + V_SOLL, _words(client, 12_345), **{u: 60})
        assert not w.isError() and twin.m.read_raw(V_SOLL)[1] == 12_345
        r = client.read_holding_registers(2 * V_SOLL, count=2, **{u: 60})
        assert _int32(client, r.registers) == 12_345
        # refusals
        r = client.write_register(2 * V1, 1, **{u: 60})  # function 06h
        assert r.isError() and r.exception_code == 1
        r = client.write_registers(2 * V1 + 1, [1, 0], **{u: 60})  # unaligned
        assert r.isError() and r.exception_code == 2
        r = client.write_registers(2 * V_SOLL, _words(client, 300_001), **{u: 60})
        assert r.isError() and r.exception_code == 3
        assert twin.m.read_raw(V_SOLL)[1] == 12_345
        r = client.read_holding_registers(0, count=17, **{u: 42})
        assert r.isError() and r.exception_code == 3
        # broadcast: both motors write, no reply
        client.write_registers(2 * V3, _words(client, 777), no_response_expected=True, **{u: 0})
        deadline = time.monotonic() + 2
        while list(twin.m.read_raw(V3)) != [777, 777] and time.monotonic() < deadline:
            time.sleep(0.01)
        assert list(twin.m.read_raw(V3)) == [777, 777]
    finally:
        client.close()


@pytest.mark.skipif(not HAVE_PTY, reason="pseudo-terminals are unavailable")
def test_manual_frames_over_a_pty(served) -> None:
    serial = pytest.importorskip("serial")
    server, twin = served
    ok_60 = mb.encode_write_request(60, 2 * V1, [*mb.words_of(250_000), *mb.words_of(13)])
    with serial.Serial(server.endpoint("modbus", "pty").path, 19200, timeout=2) as port:
        port.write(mb.append_crc(READ_42))
        assert port.read(9) == mb.append_crc(READ_42_REPLY)
        port.write(ok_60)
        assert port.read(8) == mb.append_crc(WRITE_60_REPLY)
        port.write(mb.append_crc(WRITE_60))  # V1 = 409600, the manual's frame
        assert port.read(8) == mb.append_crc(WRITE_60_REPLY)
    assert twin.m.read_raw(V1)[1] == 409_600 and twin.m.read_raw(V2)[1] == 13


# ----------------------------------------------------------------------------- the CLI
def test_serve_modbus_refuses_what_it_cannot_serve(capsys) -> None:
    from jvl_gym.cli.main import app

    with pytest.raises(SystemExit) as info:
        app(["serve", "--motor", "MAC140", "--address", "42", "--modbus", "--tcp",
             "127.0.0.1:0"])
    assert info.value.code == 2
    assert "32-bit" in capsys.readouterr().err


def test_modbus_server_refuses_addresses_modbus_has_not() -> None:
    import typer

    from jvl_gym.cli.serve import _modbus_server

    with pytest.raises(typer.BadParameter, match="1..247"):
        _modbus_server(mis_twin((42, 250)), ("127.0.0.1", 0), False, 1.0)


def _recv(sock, n: int, timeout: float = 2.0) -> bytes:

    sock.settimeout(timeout)
    out = b""
    try:
        while len(out) < n:
            chunk = sock.recv(256)
            if not chunk:
                break
            out += chunk
    except TimeoutError:
        pass
    return out


@pytest.mark.parametrize("enable", [1, 0])
def test_serve_modbus_switch_follows_register_121(enable: int) -> None:
    """MIS manual §12.2.1: MacTalk after power-on; Modbus after 1 s of silence if bit 0 of
    register 121 is set then, else MacTalk goes on."""
    import socket

    from jvl_gym.cli.serve import _modbus_server
    from jvl_gym.protocol.mactalk import codec32 as m32

    twin = mis_twin()
    twin.m.write_raw(P_IST, 123456789, index=0)
    server = _modbus_server(twin, ("127.0.0.1", 0), False, 1.0, switch=True)
    server.run_clock = False
    with server, socket.create_connection(
            ("127.0.0.1", server.endpoint("modbus", "tcp").port), timeout=2) as s:
        s.sendall(m32.encode_write_value(42, 121, enable))  # in the first second: MacTalk
        assert _recv(s, 3) == m32.ACCEPT
        time.sleep(1.2)
        s.sendall(mb.append_crc(READ_42))
        if enable:
            assert _recv(s, 9) == mb.append_crc(READ_42_REPLY)
            s.sendall(m32.encode_read(42, P_IST))  # MacTalk cannot switch it back
            assert _recv(s, 19, timeout=0.5) == b""
        else:
            assert _recv(s, 9, timeout=0.5) == b""
            time.sleep(0.1)
            s.sendall(m32.encode_read(42, P_IST))
            reply = m32.decode(_recv(s, 19))
            assert m32.data_value(reply.data) == 123456789


@pytest.mark.skipif("mis" not in families(), reason="the MIS family is not registered")
def test_jvl_gym_serve_modbus_end_to_end() -> None:
    """``jvl-gym serve --motor MIS231 --address 42 --modbus --tcp``: pymodbus writes MODE_REG and
    P_IST and reads P_IST back at 40 000 + n; Ctrl-C stops the server."""
    import signal
    import subprocess
    import sys

    pytest.importorskip("pymodbus")
    from pymodbus.client import ModbusTcpClient

    proc = subprocess.Popen([sys.executable, "-m", "jvl_gym.cli_serve", "--motor", "MIS231",
                             "--address", "42", "--modbus", "--tcp", "127.0.0.1:0"],
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        lines: list[str] = []
        for line in proc.stdout:  # up to the ready line, after any first-use compile notice
            if not line.startswith("jvl_gym: compil"):
                lines.append(line)
            if line.startswith("running") or not line:
                break
        assert lines[0].strip() == "motor 0: MIS231 at address 42", lines
        port = int(lines[1].strip().rsplit(":", 1)[1])
        # serve is ready once it says so (its motors' step is compiled): a first request took
        # at most 17 ms at a load average of 12 on two cores; 10 s is the margin
        client = ModbusTcpClient("127.0.0.1", port=port, framer=_framer_rtu(), timeout=10,
                                 retries=0)
        assert client.connect()
        u = _unit(client.read_holding_registers)
        assert not client.write_registers(2 * P_IST, _words(client, -4711), **{u: 42}).isError()
        r = client.read_holding_registers(40000 + P_IST, count=2, **{u: 42})
        assert _int32(client, r.registers) == -4711  # passive: the position stays
        client.close()
    finally:
        proc.send_signal(signal.SIGINT)
        out, _ = proc.communicate(timeout=20)
    assert proc.returncode == 0 and "stopped" in out
