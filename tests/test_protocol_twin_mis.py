"""The twin serving simulated MIS step motors (``MotorArray("MIS231")``) over the 32-bit MacTalk
of MIS manual §18.2, alone and on one line with a MAC140."""

from __future__ import annotations

from jvl_gym import MotorArray
from jvl_gym.families.mis import constants as c
from jvl_gym.protocol.mactalk import codec16 as mt
from jvl_gym.protocol.mactalk import codec32 as m32
from jvl_gym.protocol.mactalk.line import Bus
from jvl_gym.protocol.mactalk.twin16 import Twin


def ask(twin: Twin | Bus, raw: bytes) -> bytes:
    s = twin.session()
    return s.feed(raw) + s.flush()


def read(twin: Twin | Bus, address: int, register: int) -> int:
    reply = m32.decode(ask(twin, m32.encode_read(address, register)))
    return int.from_bytes(reply.data, "little", signed=True)


def test_a_simulated_mis_is_read_and_written_and_moves() -> None:
    """The manual's read example (register 5 of unit 7 holding 1000) answered by the simulator;
    a velocity written over the line is the speed the motor runs at."""
    m = MotorArray("MIS231", seed=0)
    twin = Twin(m, [7])
    assert ask(twin, m32.encode_write_value(7, 5, 1000)) == m32.ACCEPT
    assert ask(twin, m32.encode_read(7, 5)) == bytes.fromhex(
        "52 52 52 00 ff 05 fa 04 fb e8 17 03 fc 00 ff 00 ff aa aa")
    assert ask(twin, m32.encode_write_value(7, 5, 25000)) == m32.ACCEPT  # 250 RPM (§8.2.5)
    assert ask(twin, m32.encode_write_value(7, 2, c.VELOCITY)) == m32.ACCEPT
    m.step(500)
    assert read(twin, 7, 12) == 25000  # V_IST
    assert ask(twin, m32.encode_write_value(7, 5, 400000)) == b""  # out of range: refused
    assert m.read_raw("V_SOLL")[0] == 25000


def test_a_simulated_mis_keeps_what_is_flashed_over_a_reset() -> None:
    """§18.2.5–§18.2.8: write flash in safe mode saves and resets; a reset powers on from it."""
    m = MotorArray("MIS231", seed=0)
    twin = Twin(m, [7])
    assert ask(twin, m32.encode_write_value(7, 6, 4321)) == m32.ACCEPT  # A_SOLL
    assert ask(twin, m32.encode_enter_safe_mode(7)) == m32.ACCEPT
    assert ask(twin, m32.encode_write_flash(7)) == b""
    assert ask(twin, m32.encode_write_value(7, 6, 1000)) == m32.ACCEPT
    assert ask(twin, m32.encode_reset(7)) == b""
    assert read(twin, 7, 6) == 4321


def test_mis_and_mac_on_one_line_each_in_its_own_framing() -> None:
    mac = MotorArray("MAC140", seed=0)
    mis = MotorArray("MIS232", seed=0)
    bus = Bus([Twin(mac, [19]), Twin(mis, [5])])
    assert ask(bus, mt.encode_write_word(19, 5, 1600)) == mt.ACCEPT
    assert ask(bus, m32.encode_write_value(5, 5, 25000)) == m32.ACCEPT
    assert mac.read("V_SOLL")[0] == 1600 and mis.read("V_SOLL")[0] == 25000
    assert read(bus, 5, 5) == 25000
    assert mt.decode(ask(bus, mt.encode_read(19, 5))).data[:2] == (1600).to_bytes(2, "little")
