"""The twin in the 32-bit MacTalk (MAC800 quick guide §1.3, MIS manual §18.2), and motors of
several families on one line, each in its own framing (protocol.bus).

Until ``MotorArray("MIS231")`` and the MAC800 array exist, the 32-bit motors are
``protocol_fakes.RegisterArray`` on the families' register tables (validation by the table, no
physics)."""

from __future__ import annotations

import socket
import threading

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from jvl_gym import MotorArray
from jvl_gym.families import mac800, mis
from jvl_gym.protocol.mactalk import codec16 as mt
from jvl_gym.protocol.mactalk import codec32 as m32
from jvl_gym.protocol.mactalk.dialect import MACTALK16, MACTALK32, dialect_of
from jvl_gym.protocol.mactalk.line import Bus
from jvl_gym.protocol.mactalk.twin16 import Twin
from jvl_gym.protocol.serving.transport import TwinServer
from protocol_fakes import SAFE_MODE, RegisterArray
from test_protocol_mactalk32 import READ_EXAMPLES, WRITE_EXAMPLES, h

C = m32.Command


def mis_twin(n: int = 1, addresses: list[int] | None = None) -> tuple[Twin, RegisterArray]:
    m = RegisterArray(mis.REGISTERS, n)
    return Twin(m, addresses or list(range(7, 7 + n)), dialect=MACTALK32), m


def mac800_twin(addresses: list[int]) -> tuple[Twin, RegisterArray]:
    m = RegisterArray(mac800.REGISTERS, len(addresses))
    return Twin(m, addresses, dialect=MACTALK32), m


def ask(twin: Twin | Bus, raw: bytes) -> bytes:
    s = twin.session()
    return s.feed(raw) + s.flush()


# ------------------------------------------------------------ the manuals' examples, served
@pytest.mark.parametrize("frame, address, register, value", WRITE_EXAMPLES)
def test_quick_guide_writes_are_carried_out_and_accepted(frame, address, register,
                                                         value) -> None:
    twin, m = mac800_twin([7, 8])
    assert ask(twin, frame) == m32.ACCEPT
    i = [7, 8].index(address)
    assert m.read_raw(register)[i] == value
    assert m.read_raw(register)[1 - i] == m.rom[register]  # the other unit is untouched


@pytest.mark.parametrize("request_, reply, address, register, value", READ_EXAMPLES)
def test_read_examples_answered_byte_for_byte(request_, reply, address, register,
                                              value) -> None:
    """Quick guide §1.3.3/§1.3.4 (MAC800, address 8) and MIS §18.2.2 (address 7)."""
    twin, m = mac800_twin([address]) if address == 8 else mis_twin(1, [address])
    m.regs[0, register] = value  # P_IST, ERR_STAT …: what the motor would hold
    assert ask(twin, request_) == reply


def test_mis_len_2_write_then_read_gives_the_manuals_reply() -> None:
    """MIS §18.2.4 writes 1000 with Len = 2; §18.2.2 reads it back as E8h,17h,03h,FCh,00h …"""
    twin, m = mis_twin(1, [7])
    m.regs[0, 5] = 123_456  # a high word the short write must not keep
    write = h("52h,52h,52h - 07h,F8h - 05h,FAh - 02h,FDh - E8h,17h,03h,FCh - AAh,AAh")
    assert ask(twin, write) == m32.ACCEPT
    assert m.read_raw("V_SOLL")[0] == 1000
    assert ask(twin, h("50 50 50 07 f8 05 fa aa aa")) == READ_EXAMPLES[-1][1]


@pytest.mark.parametrize("register, data, stored", [
    (3, "ff ff", -1),  # P_SOLL, Int32: sign extension
    (3, "00 80", -32768),
    (202, "ff ff", 65535),  # TICKS, Word32: zero extension
    (202, "ff ff ff ff", 2**32 - 1),
    (3, "ff ff ff 7f", 2**31 - 1),
])
def test_short_and_long_writes_extend_as_the_register_format(register, data, stored) -> None:
    twin, m = mis_twin()
    assert ask(twin, m32.encode_write(7, register, bytes.fromhex(data))) == m32.ACCEPT
    assert m.read_raw(register)[0] == stored
    reply = m32.decode(ask(twin, m32.encode_read(7, register)))
    assert m32.data_value(reply.data, signed=register != 202) == stored


@pytest.mark.parametrize("frame", [
    m32.encode_write_value(7, 5, 300_001),  # V_SOLL beyond its range (MIS §8.2.5)
    m32.encode_write_value(7, 149, 3),  # GROUP_SEQ is read-only
    m32.encode_write_value(7, 4, 3),  # reserved
    m32.encode_write_value(7, 254, 3),  # no such register
    m32.encode_write_value(7, 2, 16),  # MODE_REG out of range
    m32.encode_write_value(7, 5, -1, length=2)[:-5] + b"\xaa\xaa",  # truncated data
    h("52 52 52 07 f8 05 fa 04 fb e8 17 03 fc 00 ff 00 fe aa aa"),  # bad complement
    h("52 52 52 07 f8 05 fa 03 fc e8 17 03 fc 00 ff aa aa"),  # Len 3
    h("53 53 53 07 f8 aa aa"),  # a sample buffer the fake's family does not declare
])
def test_refused_or_malformed_frames_get_no_reply_and_change_nothing(frame: bytes) -> None:
    twin, m = mis_twin()
    before = m.regs.copy()
    assert ask(twin, frame) == b""
    np.testing.assert_array_equal(m.regs, before)


def test_read_block_returns_32_registers() -> None:
    twin, m = mis_twin()
    m.regs[0, 5:37] = np.arange(100, 132)
    reply = m32.decode(ask(twin, m32.encode_read_block(7, 5)))
    assert reply.register == 5 and len(reply.data) == 128
    values = [m32.data_value(reply.data[k:k + 4]) for k in range(0, 128, 4)]
    reserved = [mis.REGISTERS.lookup(n).access.value == "reserved" for n in range(5, 37)]
    assert values == [0 if r else v for r, v in zip(reserved, range(100, 132))]
    assert any(reserved) and not all(reserved)
    end = m32.decode(ask(twin, m32.encode_read_block(7, 250)))  # past 255: zeros
    assert len(end.data) == 128 and end.data[4 * 6:] == bytes(128 - 24)


def test_safe_mode_flash_and_reset() -> None:
    """MIS §18.2.5 – §18.2.8."""
    twin, m = mis_twin()
    assert ask(twin, m32.encode_write_value(7, 3, 4711)) == m32.ACCEPT
    # write flash outside safe mode fails: the only case with a response (an accept)
    assert ask(twin, m32.encode_write_flash(7)) == m32.ACCEPT
    assert 3 not in m.flash[0]
    assert ask(twin, m32.encode_enter_safe_mode(7)) == m32.ACCEPT
    assert m.read_raw("MODE_REG")[0] == SAFE_MODE
    assert ask(twin, m32.encode_write_value(7, 2, 15)) == b""  # not by a write
    assert ask(twin, m32.encode_write_flash(7)) == b""  # carried out, reset, no response
    assert m.flash[0][3] == 4711 and m.resets[0] == 1
    assert ask(twin, m32.encode_enter_safe_mode(7)) == m32.ACCEPT
    assert ask(twin, m32.encode_exit_safe_mode(7)) == m32.ACCEPT
    assert m.read_raw("MODE_REG")[0] == 0
    assert ask(twin, m32.encode_exit_safe_mode(7)) == m32.ACCEPT  # not in safe mode: nothing
    assert ask(twin, m32.encode_write_value(7, 3, 1)) == m32.ACCEPT
    assert ask(twin, m32.encode_reset(7)) == b""  # §18.2.8: no response
    assert m.resets[0] == 2 and m.read_raw("P_SOLL")[0] == 4711  # back to the flash


def test_write_flash_is_kept_in_the_flash_file(tmp_path) -> None:
    m = RegisterArray(mis.REGISTERS, 1)
    twin = Twin(m, [7], dialect=MACTALK32, flash_dir=tmp_path)
    ask(twin, m32.encode_write_value(7, 3, -99))
    ask(twin, m32.encode_enter_safe_mode(7))
    assert ask(twin, m32.encode_write_flash(7)) == b""
    again = RegisterArray(mis.REGISTERS, 1)
    twin.close()
    Twin(again, [7], dialect=MACTALK32, flash_dir=tmp_path)
    assert again.read_raw("P_SOLL")[0] == -99 and again.read_raw("MY_ADDR")[0] == 7


def test_group_write_by_group_id_and_sequence() -> None:
    """MIS §18.2.9: the units of the group write, a repeated sequence is not written again,
    GROUP_SEQ holds the last one; never answered."""
    twin, m = mis_twin(3)
    for i, group in enumerate([4, 4, 5]):
        assert ask(twin, m32.encode_write_value(7 + i, 148, group)) == m32.ACCEPT
    gw = m32.encode_group_write(4, 1, 5, m32.value_bytes(1000, 2))
    assert ask(twin, gw) == b""
    assert m.read_raw("V_SOLL").tolist() == [1000, 1000, 10_000]
    seq = [m32.data_value(m32.decode(ask(twin, m32.encode_read(a, 149))).data) for a in (7, 8, 9)]
    assert seq == [1, 1, 0]
    m.regs[:, 5] = 0
    assert ask(twin, gw) == b""  # the same sequence again: already received
    assert m.read_raw("V_SOLL").tolist() == [0, 0, 0]
    assert ask(twin, m32.encode_group_write(4, 2, 5, m32.value_bytes(-5))) == b""
    assert m.read_raw("V_SOLL").tolist() == [-5, -5, 0]
    ask(twin, m32.encode_reset(7))  # a reset forgets the last sequence
    assert m32.data_value(m32.decode(ask(twin, m32.encode_read(7, 149))).data) == 0


def test_group_write_to_a_family_without_groups_is_ignored() -> None:
    twin, m = mac800_twin([7])
    before = m.regs.copy()
    assert ask(twin, m32.encode_group_write(0, 1, 5, m32.value_bytes(3))) == b""
    np.testing.assert_array_equal(m.regs, before)


def test_broadcast_is_carried_out_by_all_and_answered_only_point_to_point() -> None:
    twin, m = mis_twin(2)
    assert ask(twin, m32.encode_write_value(255, 3, 42)) == b""
    assert m.read_raw("P_SOLL").tolist() == [42, 42]
    one, m1 = mis_twin(1)
    assert ask(one, m32.encode_write_value(255, 3, 43)) == m32.ACCEPT


SLOW = settings(max_examples=150, deadline=None, derandomize=True,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])


@SLOW
@given(st.integers(1, 255), st.integers(-(2**31), 2**31 - 1), st.data())
def test_fuzz_corrupted_writes_never_change_a_register(register: int, value: int,
                                                       data: st.DataObject) -> None:
    twin, m = mis_twin()
    raw = bytearray(m32.encode_write_value(7, register, value))
    k = data.draw(st.integers(3, len(raw) - 1))
    raw[k] ^= data.draw(st.integers(1, 255))
    before = m.regs.copy()
    reply = ask(twin, bytes(raw))
    assert reply == b""
    np.testing.assert_array_equal(m.regs, before)


# ------------------------------------------------------------ dialects of the families
#: the MacTalk each family speaks (MAC050–141 manual 5.1; MAC800 quick guide §1.3; MIS §18.2)
FAMILY_DIALECTS = {"mac050_141": ("MAC140", MACTALK16), "mis": ("MIS231", MACTALK32),
                   "mac800": ("MAC800", MACTALK32)}


@pytest.mark.parametrize("key", sorted(FAMILY_DIALECTS))
def test_each_family_declares_its_dialect(key: str) -> None:
    """The first of the family contract's dialects (checked for the registered families)."""
    from jvl_gym.families import families

    if key not in families():
        pytest.skip(f"the {key} family is not registered")
    motor, dialect = FAMILY_DIALECTS[key]
    assert dialect_of(MotorArray(motor, n=1, seed=0)) == dialect


def test_a_backend_speaks_the_dialect_its_family_declares() -> None:
    assert dialect_of(RegisterArray(mis.REGISTERS)) == MACTALK16
    assert dialect_of(RegisterArray(mis.REGISTERS, dialect=MACTALK32)) == MACTALK32
    assert Twin(RegisterArray(mis.REGISTERS, dialect=MACTALK32), [7]).dialect == MACTALK32
    with pytest.raises(ValueError, match="unknown MacTalk dialect"):
        Twin(RegisterArray(mis.REGISTERS), [7], dialect="mactalk64")


# ------------------------------------------------------------ several families on one line
def mixed_bus() -> tuple[Bus, MotorArray, RegisterArray, RegisterArray]:
    mac = MotorArray("MAC140", n=2, seed=0)
    mis_m = RegisterArray(mis.REGISTERS, 1)
    m800 = RegisterArray(mac800.REGISTERS, 1)
    bus = Bus([Twin(mac, [19, 20]), Twin(mis_m, [7], dialect=MACTALK32),
               Twin(m800, [8], dialect=MACTALK32)])
    return bus, mac, mis_m, m800


def test_each_motor_answers_in_its_own_framing() -> None:
    bus, mac, mis_m, m800 = mixed_bus()
    # a MAC050–141 read reply: no register number, words N and N+1
    mac.write_raw("V_SOLL", 1234, index=1)
    reply = mt.decode(ask(bus, mt.encode_read(20, 5)))
    assert reply == mt.DataReply(mt.words_to_bytes([1234, int(mac.read_raw(6)[1]) & 0xFFFF]))
    # MIS and MAC800 read replies name the register
    mis_m.regs[0, 5] = 1000
    assert ask(bus, m32.encode_read(7, 5)) == READ_EXAMPLES[-1][1]
    assert ask(bus, WRITE_EXAMPLES[0][0]) == m32.ACCEPT  # quick guide: 600 to reg 5 of unit 8
    assert m800.read_raw(5)[0] == 600
    assert mis_m.read_raw(5)[0] == 1000 and mac.read_raw("V_SOLL").tolist() == [0, 1234]
    # the same bytes (a write is one grammar) reach only the unit at the address
    assert ask(bus, m32.encode_write_value(19, 5, 77)) == mt.ACCEPT
    assert mac.read_raw("V_SOLL").tolist() == [77, 1234]


def test_frames_of_another_dialect_change_nothing() -> None:
    bus, mac, mis_m, m800 = mixed_bus()
    regs = (mac.read_raw("V_SOLL").copy(), mis_m.regs.copy(), m800.regs.copy())
    # the sample-buffer read of the MAC050–141 to the MIS unit: not a 32-bit command
    assert ask(bus, mt.encode_read_sample_buffer(7)) == b""
    # a group write (32-bit only) reaches no MAC050–141, and the MIS's group is 0
    assert ask(bus, m32.encode_group_write(3, 1, 5, m32.value_bytes(9))) == b""
    np.testing.assert_array_equal(mac.read_raw("V_SOLL"), regs[0])
    np.testing.assert_array_equal(mis_m.regs, regs[1])
    np.testing.assert_array_equal(m800.regs, regs[2])
    assert bus.twins[0].stats["errors"] >= 1  # the MACs could not parse the 59h frame
    # a broadcast on a line of several units is carried out by all, answered by none
    assert ask(bus, m32.encode_write_value(255, 3, 5)) == b""
    assert mis_m.read_raw(3)[0] == 5 and m800.read_raw(3)[0] == 5
    assert mac.read_raw("P_SOLL").tolist() == [5, 5]


def test_a_bus_refuses_an_address_used_twice() -> None:
    with pytest.raises(ValueError, match="address 7"):
        Bus([mis_twin(1, [7])[0], mac800_twin([7])[0]])


def test_bus_advances_each_family_at_its_own_rate() -> None:
    bus, mac, mis_m, m800 = mixed_bus()
    t0 = float(mac.time[0])
    bus.advance(0.0105)
    bus.advance(0.0105)
    assert mis_m.steps == int(0.021 / 0.001) == 21  # 1 kHz, the remainder carried over
    assert float(mac.time[0]) - t0 == pytest.approx(10 / mac.OUTER_HZ)


def _exchange(sock: socket.socket, frame: bytes, n: int) -> bytes:
    sock.sendall(frame)
    out = b""
    while len(out) < n:
        chunk = sock.recv(4096)
        if not chunk:
            break
        out += chunk
    return out


#: MIS registers of the full 32-bit range (P_SOLL, P_IST, GEAR1, GEAR2; MIS §8.2)
REGS = (3, 10, 14, 15)


def test_mixed_bus_served_over_tcp_to_concurrent_clients() -> None:
    bus, mac, mis_m, m800 = mixed_bus()
    errors: list[str] = []
    with TwinServer(bus, tcp=("127.0.0.1", 0), run_clock=False) as server:
        port = server.endpoint("mactalk", "tcp").port

        def client(k: int) -> None:
            with socket.create_connection(("127.0.0.1", port), timeout=5) as s:
                for j in range(20):
                    v = 1000 * k + j
                    if _exchange(s, m32.encode_write_value(7, REGS[k], v), 3) != m32.ACCEPT:
                        errors.append(f"write {k} {j}")
                    r = m32.decode(_exchange(s, m32.encode_read(7, REGS[k]), 19))
                    if m32.data_value(r.data) != v:
                        errors.append(f"read {k} {j}")
                    word = mt.decode(_exchange(s, mt.encode_read(19 + k % 2, 1), 17))
                    if not isinstance(word, mt.DataReply):
                        errors.append(f"mac {k} {j}")

        threads = [threading.Thread(target=client, args=(k,)) for k in range(4)]
        for t in threads:
            t.start()
        for t in threads:
            t.join(30)
    assert errors == []
    assert [int(mis_m.read_raw(REGS[k])[0]) for k in range(4)] == [19, 1019, 2019, 3019]


def test_mixed_bus_over_a_pty() -> None:
    import os

    bus, mac, mis_m, m800 = mixed_bus()
    m800.regs[0, 10] = 245_000
    with TwinServer(bus, pty=True, run_clock=False) as server:
        fd = os.open(server.endpoint("mactalk", "pty").path, os.O_RDWR | os.O_NOCTTY)
        try:
            os.write(fd, h("50h,50h,50h - 08h,F7h - 0Ah,F5h - AAh,AAh"))
            out = b""
            while len(out) < 19:
                out += os.read(fd, 64)
        finally:
            os.close(fd)
    assert out == READ_EXAMPLES[3][1]  # quick guide §1.3.4: P_IST = 245,000


@pytest.fixture
def toy_family():
    import sys
    from pathlib import Path

    from jvl_gym.families import register_family

    fixtures = str(Path(__file__).resolve().parent / "fixtures")
    sys.path.insert(0, fixtures)
    register_family("toy", "toy_family")
    yield
    sys.path.remove(fixtures)


def test_serve_builds_one_twin_per_family_on_one_line(toy_family, tmp_path) -> None:
    from jvl_gym.cli.serve import banner, build_line

    types, addresses = ["MAC140", "TOY1", "MAC140"], [19, 5, 20]
    line, order = build_line(types, addresses, seed=0, flash_dir=tmp_path)
    assert isinstance(line, Bus) and order == [0, 2, 1]
    assert line.addresses() == [19, 20, 5]
    assert [t.flash_dir for t in line.twins] == [tmp_path / "mac050_141", tmp_path / "toy"]
    assert banner([types[k] for k in order], line) == [
        "motor 0: MAC140 at address 19", "motor 1: MAC140 at address 20",
        "motor 2: TOY1 at address 5"]
    # the toy family declares no dialect: it speaks the MAC050–141 MacTalk
    assert [t.dialect for t in line.twins] == [MACTALK16, MACTALK16]
    assert ask(line, mt.encode_write(5, 3, mt.words_to_bytes([250]))) == mt.ACCEPT
    assert line.twins[1].m.read("V_SOLL").tolist() == [250]
    one, order = build_line(["MAC140"], [19])
    assert isinstance(one, Twin) and order == [0]


@pytest.fixture(scope="module")
def fuzz_bus():
    return mixed_bus()


@SLOW
@given(chunks=st.lists(st.binary(max_size=60), max_size=6))
def test_fuzz_random_bytes_on_a_mixed_line_change_nothing(fuzz_bus, chunks: list[bytes]) -> None:
    """Random bytes (no valid write among them) change no register of any family's motor."""
    bus, mac, mis_m, m800 = fuzz_bus
    before = (mac.regs.copy(), mis_m.regs.copy(), m800.regs.copy())
    s = bus.session()
    for c in chunks:
        s.feed(c)
    s.flush()
    np.testing.assert_array_equal(mac.regs, before[0])
    np.testing.assert_array_equal(mis_m.regs, before[1])
    np.testing.assert_array_equal(m800.regs, before[2])

