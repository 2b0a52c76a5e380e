"""An independent sample of MAC800 overview statements, each checked through the public interface.

The sample was drawn before reading the project's tests or statement files: the candidate lines
are all lines of the MAC800 overview manual's text edition (data formats, register overview,
serial communication); 15 line numbers were drawn with ``random.Random(1206800)`` (``choice``
over those lines) and for each the nearest sentence (table row) stating a checkable behaviour was
taken. Bus statements are checked on a ``jvl-gym serve`` twin over TCP with raw MacTalk bytes.

Candidate lines: 1-733.
Drawn line -> statement line (section): 164 -> 165-166 (T_SOLL), 388 -> 388 (POS3), 351 -> 351
(V_HOME), 95 -> 95 (MODE_REG), 630 -> 627-631 (1.3 write example 1), 137 -> 138 (V_SOLL),
717 -> 717 (1.3 application example), 9 -> 13 (1.1), 667 -> 667-668 (1.3 read), 208 -> 208-212
(V_IST), 292 -> 292 (ERR_STAT), 512 -> 512 (V_EXT), 473 -> 473 (KVFX3), 53 -> 56-69 (PROG_VER),
731 -> 726-733 (1.3 application example). Skipped as stating nothing checkable: 3 lines.
"""

from __future__ import annotations

import os
import socket
import subprocess
import sys
from collections.abc import Iterator

import numpy as np
import pytest

from jvl_gym import MotorArray


def _motor(**regs: float) -> MotorArray:
    m = MotorArray("MAC800", seed=0)
    for name, value in regs.items():
        m.write(name, value)
    return m


class _Line:
    """A raw byte connection to a served MAC800 twin."""

    def __init__(self, port: int) -> None:
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=20)

    def transact(self, frame: list[int], reply_len: int) -> bytes:
        self.sock.sendall(bytes(frame))
        reply = b""
        while len(reply) < reply_len:
            chunk = self.sock.recv(256)
            if not chunk:
                break
            reply += chunk
        return reply


@pytest.fixture(scope="module")
def line() -> Iterator[_Line]:
    probe = socket.socket()
    probe.bind(("127.0.0.1", 0))
    port = probe.getsockname()[1]
    probe.close()
    proc = subprocess.Popen(
        [sys.executable, "-m", "jvl_gym.cli", "serve", "--motor", "MAC800", "--address", "8",
         "--tcp", f"127.0.0.1:{port}"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=os.environ)
    try:
        assert proc.stdout is not None
        for text in proc.stdout:  # the banner ends with the TCP line
            if "tcp" in text:
                break
        else:
            pytest.fail(proc.stderr.read() if proc.stderr else "serve ended")
        conn = _Line(port)
        yield conn
        conn.sock.close()
    finally:
        proc.terminate()
        proc.wait(20)


def _protected(*values: int) -> list[int]:
    return [b for v in values for b in (v, 0xFF - v)]


def _write_frame(address: int, reg: int, value: int) -> list[int]:
    data = list(value.to_bytes(4, "little", signed=True))
    return [0x52] * 3 + _protected(address, reg, 4, *data) + [0xAA, 0xAA]


def _read_frame(address: int, reg: int) -> list[int]:
    return [0x50] * 3 + _protected(address, reg) + [0xAA, 0xAA]


@pytest.mark.statements("mac800:reg7:1", "mac800:reg7:2", "mac800:reg7:3")
def test_t_soll_range_and_1023_is_300_percent() -> None:
    """MAC800 overview §1.2 (T_SOLL, register 7): the maximum allowed torque, 0-1023, where 1023
    is 300 % of nominal (the full peak torque): VF_OUT never passes T_SOLL and VF_OUT/1023 of
    three times the rated torque is the motor's torque."""
    m = _motor()
    with pytest.raises(ValueError):
        m.write("T_SOLL", 1024)
    rated = m.motor_configs[0].rated_torque
    m = _motor(T_SOLL=341, P_SOLL=0, MODE_REG=2)
    m.run(0.1)
    m.set_input(load_torque=3.0 * rated / 3 * 1.25)  # more than T_SOLL = 100 % gives
    vf = m.trace(["VF_OUT"], 40)["VF_OUT"][:, 0]
    assert vf.max() == 341
    m = _motor(T_SOLL=1023, P_SOLL=0, MODE_REG=2)
    m.run(0.1)
    m.set_input(load_torque=2.0)
    m.run(0.5)
    vf_out = float(m.read("VF_OUT")[0])
    assert vf_out / 1023 * 3 * rated == pytest.approx(2.0, rel=0.03)


@pytest.mark.statements("mac800:reg49:1")
def test_pos3_is_position_register_p4() -> None:
    """MAC800 overview §1.2 (register 55 POS3): position register P4 in encoder counts, a Long
    Int, the fourth of the position registers that feed P_SOLL."""
    m = _motor()
    m.write(55, 245_000)
    assert int(m.read("POS3")[0]) == 245_000
    m.write("P_REG_P", 4)
    m.step(2)
    assert int(m.read("P_SOLL")[0]) == 245_000


@pytest.mark.statements("mac800:reg40:1")
def test_v_home_has_the_unit_of_v_soll() -> None:
    """MAC800 overview §1.2 (V_HOME, register 40): the speed used during a zero search, in the
    unit of register 5 (V_SOLL, counts/sample/16)."""
    m = _motor(V_HOME=-1600, T_HOME=800, MODE_REG=12)
    m.run(0.5)
    assert m.mode_name() == "Torque zero search"
    v = m.trace(["V_IST"], 50)["V_IST"][:, 0]
    assert v.mean() == pytest.approx(-100, abs=2)


@pytest.mark.statements("mac800:reg2:11")
def test_mode_12_is_a_torque_zero_search() -> None:
    """MAC800 overview §1.2 (MODE_REG, register 2): mode 12 is the torque zero search: the motor
    runs at V_HOME until the torque passes T_HOME, and that point is the zero (P_HOME), with
    Home_Done (HOME_MODE bit 16) set."""
    m = _motor(P_HOME=1000, T_HOME=200, V_HOME=-139, MODE_REG=12)
    m.run(0.3)
    assert int(m.read("P_IST")[0]) < -1000
    m.set_input(load_torque=-1.6)  # a blockage the search's torque limit cannot pass
    tr = m.trace(["MODE_REG", "P_IST", "HOME_MODE"], 300)
    left = int(np.argmax(tr["MODE_REG"][:, 0] != 12))
    assert left > 0
    assert int(tr["P_IST"][left, 0]) == pytest.approx(1000, abs=30)
    assert int(tr["HOME_MODE"][left, 0]) & (1 << 16)


@pytest.mark.statements("mac800:1.3.2:1", "mac800:1.3.2:3")
def test_write_example_writes_600_to_register_5(line: _Line) -> None:
    """MAC800 overview §1.3 (write example 1): 52h x3, address 8, register 5, length 4, data
    58h 02h 00h 00h (each byte followed by its complement), AAh AAh writes 600 to V_SOLL and the
    motor accepts with 11h 11h 11h."""
    frame = [0x52, 0x52, 0x52, 0x08, 0xF7, 0x05, 0xFA, 0x04, 0xFB, 0x58, 0xA7, 0x02, 0xFD,
             0x00, 0xFF, 0x00, 0xFF, 0xAA, 0xAA]
    assert line.transact(frame, 3) == bytes([0x11, 0x11, 0x11])
    reply = line.transact(_read_frame(8, 5), 19)
    assert reply[9:17:2] == (600).to_bytes(4, "little")


@pytest.mark.statements("mac800:reg5:1")
def test_v_soll_unit_is_counts_per_sample_over_16() -> None:
    """MAC800 overview §1.2 (V_SOLL, register 5): the desired velocity in counts/sample/16;
    1 RPM = 2.77056."""
    m = _motor(V_SOLL=1600, MODE_REG=1)
    m.run(1.0)
    tr = m.trace(["V_IST", "speed_rpm"], 50)
    assert tr["V_IST"][:, 0].mean() == pytest.approx(100, abs=1)
    assert tr["speed_rpm"][:, 0].mean() == pytest.approx(1600 / 2.77056, rel=0.01)


def test_1000_rpm_is_v_soll_2771() -> None:
    """MAC800 overview §1.3 (application example "setting the maximum speed"): 1000 RPM is
    V_SOLL = 2771."""
    m = _motor(V_SOLL=2771, MODE_REG=1)
    m.run(1.5)
    assert float(m.speed_rpm[0]) == pytest.approx(1000, rel=0.01)


@pytest.mark.statements("mac800:1.1:2")
def test_long_int_is_32_bit_signed() -> None:
    """MAC800 overview §1.1: Long Int is 32 bit signed, range -2.147E9..+2.147E9."""
    m = _motor()
    m.write("P_SOLL", 2**31 - 1)
    assert int(m.read("P_SOLL")[0]) == 2**31 - 1
    m.write("P_SOLL", -(2**31))
    assert int(m.read("P_SOLL")[0]) == -(2**31)
    with pytest.raises(ValueError):
        m.write("P_SOLL", 2**31)


@pytest.mark.statements("mac800:1.3.3:1")
def test_read_reply_data_first_byte_lsb(line: _Line) -> None:
    """MAC800 overview §1.3 (read command): the reply carries address 0, the register number,
    length 4 and the register's data, first byte the LSB, each byte followed by its
    complement (register 5 = 600 reads 58h 02h 00h 00h)."""
    line.transact(_write_frame(8, 5, 600), 3)
    reply = line.transact(_read_frame(8, 5), 19)
    assert reply == bytes([0x52, 0x52, 0x52, 0x00, 0xFF, 0x05, 0xFA, 0x04, 0xFB, 0x58, 0xA7,
                           0x02, 0xFD, 0x00, 0xFF, 0x00, 0xFF, 0xAA, 0xAA])


@pytest.mark.statements("mac800:reg12:1")
def test_v_ist_counts_per_sample_and_rpm() -> None:
    """MAC800 overview §1.2 (V_IST, register 12): the actual velocity, a Long Int in
    counts/sample, 1 RPM = 0.17316 counts/sample."""
    m = _motor(V_SOLL=2771, MODE_REG=1)
    m.run(1.5)
    tr = m.trace(["V_IST", "speed_rpm"], 100)
    assert tr["V_IST"][:, 0].mean() == pytest.approx(0.17316 * tr["speed_rpm"][:, 0].mean(),
                                                     rel=0.01)


@pytest.mark.statements("mac800:reg35:4", "mac800:reg26:1")
def test_fnc_err_bit_2_when_function_error_passes_fncerrmax() -> None:
    """MAC800 overview §1.2 (ERR_STAT bit 2 FNC_ERR, FNCERRMAX register 26): when the function
    error passes FNCERRMAX the motor is stopped and FNC_ERR (ERR_STAT bit 2) is set."""
    m = _motor(FNCERRMAX=5000, P_SOLL=0, T_SOLL=300, MODE_REG=2)
    m.run(0.1)
    m.set_input(load_torque=4.0)
    tr = m.trace(["FNCERR", "ERR_STAT", "V_IST"], 300)
    set_at = int(np.argmax(tr["ERR_STAT"][:, 0] & 4))
    assert set_at > 0
    assert abs(int(tr["FNCERR"][set_at, 0])) > 5000
    assert abs(int(tr["FNCERR"][set_at - 1, 0])) <= 5000
    m.set_input(load_torque=0.0)  # the stop ramp can act once the load no longer overpowers
    m.run(1.0)
    assert abs(int(m.read("V_IST")[0])) <= 1
    assert m.mode_name() == "Passive"
    assert int(m.read("ERR_STAT")[0]) & 4


@pytest.mark.statements("mac800:reg163:1")
def test_v_ext_is_the_pulse_input_speed() -> None:
    """MAC800 overview §1.2 (V_EXT, register 163): the speed at the external pulse input."""
    m = _motor()
    m.set_input(pulse_counts=37)
    m.run(0.05)
    assert int(m.read(163)[0]) == 37


@pytest.mark.statements("mac800:1.1:3")
def test_kvfx3_is_fixed16() -> None:
    """MAC800 overview §1.2 (KVFX3, register 130) and §1.1: a Fixed16 coefficient, 16 bit
    signed fixed point in units of 1/65536, range -32768.0..+32767.9999847."""
    m = _motor()
    m.write(130, 1.5)
    assert int(m.read_raw("KVFX3")[0]) == int(1.5 * 65536)
    m.write("KVFX3", -32768.0)
    assert float(m.read("KVFX3")[0]) == -32768.0
    with pytest.raises(ValueError):
        m.write("KVFX3", 32768.0)


@pytest.mark.statements("mac800:reg1:2")
def test_prog_ver_is_long_with_bit_15_for_mac800(line: _Line) -> None:
    """MAC800 overview §1.2 (PROG_VER, register 1): a Long Int with the firmware version
    (bits 0-5 minor, 6-12 major) and bit 15 set on a MAC400 or MAC800."""
    reply = line.transact(_read_frame(8, 1), 19)
    assert reply[7] == 4  # Len: a 32-bit register
    value = int.from_bytes(reply[9:17:2], "little")
    assert value & (1 << 15)
    assert int(_motor().read("PROG_VERSION")[0]) == value


@pytest.mark.statements("mac800:1.3.4:5")
def test_read_p_ist_example_245000(line: _Line) -> None:
    """MAC800 overview §1.3 (application example "reading the actual position"): P_IST =
    245 000 counts (3BD08h) reads as 08h F7h BDh 42h 03h FCh 00h FFh."""
    assert line.transact(_write_frame(8, 10, 245_000), 3) == bytes([0x11] * 3)
    reply = line.transact([0x50, 0x50, 0x50, 0x08, 0xF7, 0x0A, 0xF5, 0xAA, 0xAA], 19)
    assert reply == bytes([0x52, 0x52, 0x52, 0x00, 0xFF, 0x0A, 0xF5, 0x04, 0xFB, 0x08, 0xF7,
                           0xBD, 0x42, 0x03, 0xFC, 0x00, 0xFF, 0xAA, 0xAA])
