"""The digital twin: MacTalk rules on a MotorArray, and client ↔ twin over a real pty and TCP.

Integration tests run over both transports; the pty ones are skipped only if pseudo-terminals
are unavailable.
"""

from __future__ import annotations

import importlib.util
import os
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from jvl_gym import MotorArray
from jvl_gym.families.mac050_141.table import TABLE as MAC050_141
from jvl_gym.protocol import MacTalkClient, NoAnswerError
from jvl_gym.protocol.mactalk import codec16 as mt
from jvl_gym.protocol.mactalk import fastmac as fm
from jvl_gym.protocol.mactalk import flexmac as fx
from jvl_gym.protocol.mactalk.twin16 import Twin
from jvl_gym.protocol.serving.transport import TwinServer
from jvl_gym.registers import Access, Format, ReadOnlyRegisterError, RegisterError

try:
    _fd1, _fd2 = os.openpty()
    os.close(_fd1)
    os.close(_fd2)
    HAVE_PTY = True
except (AttributeError, OSError):
    HAVE_PTY = False

needs_pty = pytest.mark.skipif(not HAVE_PTY, reason="pseudo-terminals are unavailable")


def make_twin(n: int = 1, addresses: list[int] | None = None, **kw) -> Twin:
    return Twin(MotorArray("MAC140", n=n, seed=0), addresses or list(range(19, 19 + n)), **kw)


def ask(twin: Twin, raw: bytes) -> bytes:
    s = twin.session()
    return s.feed(raw) + s.flush()


# ---------------------------------------------------------------- MacTalk rules (no transport)
def test_manual_read_example_shape_and_longint_rule() -> None:
    twin = make_twin()
    twin.m.write("T_SOLL", 0x3FF)
    reply = mt.decode(ask(twin, mt.encode_read(19, 7)))
    assert isinstance(reply, mt.DataReply) and len(reply.data) == 4
    assert mt.bytes_to_words(reply.data) == [0x3FF, int(twin.m.read_raw(8)[0]) & 0xFFFF]
    twin.m.write("P_SOLL", -100_000)
    reply = mt.decode(ask(twin, mt.encode_read(19, 3)))
    assert mt.bytes_to_long(reply.data) == -100_000


def test_manual_write_example_shape() -> None:
    twin = make_twin(addresses=[0x10])
    # the manual's example writes 3322h to register 8 (P_FNC low word): accepted
    assert ask(twin, bytes.fromhex("52 52 52 10 EF 08 F7 02 FD 22 DD 33 CC AA AA")) == mt.ACCEPT
    assert int(twin.m.read_raw(8)[0]) & 0xFFFF == 0x3322


@pytest.mark.statements("mac050_141:3.2.156:1")
def test_multidrop_by_myaddr_and_broadcast() -> None:
    twin = make_twin(3, [5, 6, 7])
    assert ask(twin, mt.encode_write_word(6, 65, 1234)) == mt.ACCEPT
    assert list(twin.m.read_raw(65)) == [0, 1234, 0]
    assert ask(twin, mt.encode_read(9, 65)) == b""  # nobody there
    assert ask(twin, mt.encode_write_word(mt.BROADCAST, 66, 77)) == b""  # all do it, silently
    assert list(twin.m.read_raw(66)) == [77, 77, 77]
    # changing MYADDR moves the unit
    assert ask(twin, mt.encode_write_word(7, 156, 30)) == mt.ACCEPT
    assert ask(twin, mt.encode_read(30, 156))[7:9] == bytes((30, 0xFF ^ 30))
    # a single motor answers a broadcast (point-to-point link)
    solo = make_twin()
    assert mt.decode(ask(solo, mt.encode_read(mt.BROADCAST, 156))).data[:2] == b"\x13\x00"


def test_refused_write_gets_no_accept_and_changes_nothing() -> None:
    twin = make_twin()
    before = twin.m.regs.copy()
    for raw in (mt.encode_write_word(19, 12, 5),  # V_IST is read-only
                mt.encode_write_word(19, 7, 2000),  # T_SOLL > 1023
                mt.encode_write_word(19, 2, 15),  # SAFE_MODE cannot be written (4.4.16)
                mt.encode_write_long(19, 4, 1),  # 32 bits into a LongInt's high word
                mt.encode_write_long(19, 5, 40000),  # V_SOLL is a 16-bit Integer
                mt.encode_write_word(19, 200, 1)):  # no such register
        assert ask(twin, raw) == b""
    assert twin.stats["refused"] == 6
    np.testing.assert_array_equal(twin.m.regs, before)


def test_word_and_long_writes_of_a_longint() -> None:
    twin = make_twin()
    assert ask(twin, mt.encode_write_long(19, 49, -2)) == mt.ACCEPT
    assert int(twin.m.read_raw(49)[0]) == -2
    assert ask(twin, mt.encode_write_word(19, 49, 0x0005)) == mt.ACCEPT  # low word only
    assert int(twin.m.read_raw(49)[0]) == -65536 + 5
    assert ask(twin, mt.encode_write_word(19, 50, 0x0001)) == mt.ACCEPT  # high word only
    assert int(twin.m.read_raw(49)[0]) == 0x10005


def test_read_block_returns_16_words() -> None:
    twin = make_twin()
    reply = mt.decode(ask(twin, mt.encode_read_block(19, 65)))
    assert len(reply.data) == 32
    twin.m.write("V3", -7)
    assert mt.bytes_to_words(mt.decode(ask(twin, mt.encode_read_block(19, 65))).data)[2] == \
        0xFFF9


@pytest.mark.statements("mac050_141:4.4.16:7")
def test_safe_mode_flash_and_reset_rules(tmp_path: Path) -> None:
    twin = make_twin(flash_dir=tmp_path)
    twin.m.write("KVOUT", 2.5)
    assert ask(twin, mt.encode_write_flash(19)) == b""  # not in SAFE_MODE: refused
    assert not (tmp_path / "flash_0.json").exists()
    twin.m.write("MODE_REG", 1)
    assert ask(twin, mt.encode_reset(19)) == b""  # not in INIT/SAFE: refused
    assert twin.mode(0) == 1
    assert ask(twin, mt.encode_go_safe_mode(19)) == mt.ACCEPT
    twin.m.step(300)
    assert twin.mode(0) == 15
    assert ask(twin, mt.encode_write_word(19, 2, 0)) == b""  # MODE_REG cannot leave SAFE_MODE
    assert ask(twin, mt.encode_write_flash(19)) == b""  # no accept after write flash (5.1)
    assert (tmp_path / "flash_0.json").exists()
    assert twin.mode(0) == 0  # reset: power-on mode
    twin.m.write("KVOUT", 1.0)
    assert ask(twin, mt.encode_reset(19)) == b""
    assert float(twin.m.read("KVOUT")[0]) == 2.5  # registers from flash
    # a new twin (power cycle) reads the flash file
    twin.close()
    again = make_twin(flash_dir=tmp_path)
    assert float(again.m.read("KVOUT")[0]) == 2.5 and again.addresses() == [19]
    # go init mode leaves SAFE_MODE
    assert ask(again, mt.encode_go_safe_mode(19)) == mt.ACCEPT
    assert ask(again, mt.encode_go_init_mode(19)) == mt.ACCEPT
    assert again.mode(0) == 0


def test_sample_buffer_readout_after_testu() -> None:
    twin = make_twin()
    twin.m.set_record_length(20)
    assert ask(twin, mt.encode_write_word(19, 130, 100)) == mt.ACCEPT  # UMEAS
    assert ask(twin, mt.encode_write_word(19, 2, 8)) == mt.ACCEPT  # TESTU
    twin.m.step(5)
    ref = twin.m.sample_buffer_raw(0)
    assert ref.shape == (20, 4)
    rows = []
    while True:
        data = mt.decode(ask(twin, mt.encode_read_sample_buffer(19))).data
        if not data:
            break
        rows.append([mt.bytes_to_long(data[4 * k:4 * k + 4]) for k in range(4)])
    np.testing.assert_array_equal(np.array(rows), ref)
    # after the end marker the read-out starts again at sample 0
    first = mt.decode(ask(twin, mt.encode_read_sample_buffer(19))).data
    assert mt.bytes_to_long(first[:4]) == ref[0, 0]


# ---------------------------------------------------------------- over a real pty and TCP
@pytest.fixture(scope="module")
def server():
    twin = make_twin(2, [19, 20])
    with TwinServer(twin, speed=4.0, tcp=("127.0.0.1", 0), pty=HAVE_PTY) as srv:
        yield srv


TRANSPORTS = ["tcp", pytest.param("pty", marks=needs_pty)]


@pytest.fixture(params=TRANSPORTS)
def client(request, server):
    url = server.endpoint("mactalk", request.param).url
    with MacTalkClient(url, address=20, timeout=1.0) as c:
        yield c


def _test_value(reg) -> float:
    """A legal value different from the default, avoiding values with side effects."""
    special = {"MODE_REG": None, "MYADDR": 20, "HOME_MODE": 12 | (13 << 8), "CNTRL_BITS": 0x10,
               "ERR_STAT": 1 << 9, "REC_CNT": 0, "P_REG_P": 0, "V_REG_P": 0, "A_REG_P": 0,
               "T_REG_P": 0, "L_REG_P": 0, "Z_REG_P": 0, "STARTMODE": 0, "P_IST": 0,
               "MIN_P_IST": -1_000_000, "MAX_P_IST": 1_000_000,
               "P_FNC": 0, "U_MIN_SUP": 0, "UV_HANDLE": 0}  # P_FNC follows 16·P_IST in INIT_MODE
    if reg.name in special:
        return special[reg.name]
    lo, hi = reg.minimum, reg.maximum
    v = lo + (hi - lo) * 0.37
    return round(v * reg.scale) / reg.scale if reg.scale != 1 else int(v)


WRITABLE = [r for r in MAC050_141 if r.access == Access.RW and r.format != Format.LONGINT_HIGH]


def test_read_write_every_writable_register(client) -> None:
    written = {}
    for reg in WRITABLE:
        value = _test_value(reg)
        if value is None:
            continue
        client.write(reg.name, value)
        written[reg.name] = value
    # read everything back afterwards; status bits the firmware owns are masked out:
    # CNTRL_BITS 15..13 hall state (3.2.36), ERR_STAT flags other than RELPOSPSOLL (3.2.35)
    mask = {"CNTRL_BITS": 0x1FFF, "ERR_STAT": 1 << 9}
    bad = {}
    for n, v in written.items():
        got = client.read(n)
        if n in mask:
            got, v = int(got) & mask[n], int(v) & mask[n]
        if not np.isclose(got, v, atol=0.5 / MAC050_141.lookup(n).scale):
            bad[n] = (v, got)
    assert not bad
    assert len(written) == len(WRITABLE) - 1


def test_longint_high_words_and_typed_errors(client) -> None:
    client.write("P8", 0)
    client.write_word(64, 0x0002)  # P8_HI
    assert client.read("P8") == 0x20000
    with pytest.raises(ReadOnlyRegisterError):
        client.write("V_IST", 3)
    with pytest.raises(RegisterError):
        client.write("T_SOLL", 5000)


def test_no_answer_is_a_clear_error(server) -> None:
    url = server.endpoint("mactalk", "tcp").url
    with MacTalkClient(url, address=99, timeout=0.1, retries=1) as c:
        with pytest.raises(NoAnswerError, match="address 99.*MYADDR"):
            c.read("P_IST")
        assert c.retried == 1


@pytest.mark.parametrize("kind", TRANSPORTS)
def test_testu_through_the_protocol(server, kind) -> None:
    with MacTalkClient(server.endpoint("mactalk", kind).url, address=19, timeout=1.0) as c:
        buf = c.run_test(8, {"UMEAS": 100}, timeout=5.0)
    assert set(buf) >= {"UA_VAL", "IC_IST"}
    assert len(buf["UA_VAL"]) == 11 and np.all(buf["UA_VAL"] == 100)
    ic = buf["IC_IST"]
    assert ic[-1] < -50 and np.all(np.diff(ic[2:]) <= 0)  # current builds up against UC


def test_load_concurrent_clients_small(server) -> None:
    spec = importlib.util.spec_from_file_location(
        "bench_protocol", Path(__file__).resolve().parents[1] / "benchmarks" / "bench_protocol.py")
    bench = importlib.util.module_from_spec(spec)
    sys.modules["bench_protocol"] = bench
    spec.loader.exec_module(bench)
    url = server.endpoint("mactalk", "tcp").url
    total, wall = bench.run_load(url, [19, 20], 500)  # one client per motor address
    assert total.requests == 1000 and total.writes > 100
    assert total.lost == 0 and total.corrupted == 0, total.errors


# ---------------------------------------------------------------- FastMAC / FlexMAC user interface
def _user_twin() -> Twin:
    twin = make_twin()
    m = twin.m
    m.write("CNTRL_BITS", 3)  # USERINTF = 11: FastMAC/FlexMAC (3.2.36), acts after a reset
    m.enter_safe_mode()
    m.write_flash()  # → reset: latched
    assert int(m.interface_bits[0]) & 3 == 3
    for name, v in {"P5": -3000, "P6": 4096, "P7": 10000, "V3": 800, "V4": 1600, "A4": 200,
                    "A2": 100, "T2": 1023, "Z1": 10}.items():
        m.write(name, v)
    return twin


def _wait_in_pos(sock, byte: int, timeout: float = 10.0) -> int:
    """Repeat ``byte`` (same toggle: no new command) and read status bytes until IN_POS."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        sock.sendall(bytes((byte,)))
        st = fm.decode_status(sock.recv(1)[0])
        if st.in_pos:
            return st.toggle
        time.sleep(0.01)
    raise TimeoutError("IN_POS not reached")


def test_fastmac_example_sequence_drives_to_p6_p7_p5() -> None:
    import socket

    twin = _user_twin()
    with TwinServer(twin, speed=4.0, user_tcp=0) as srv:
        e = srv.endpoint("user0", "tcp")
        with socket.create_connection((e.host, e.port), timeout=2.0) as s:
            def send(b: int) -> fm.Status:
                s.sendall(bytes((b,)))
                return fm.decode_status(s.recv(1)[0])

            reached = []
            for byte, comment in fm.EXAMPLE_SEQUENCE:
                st = send(byte)
                assert st.toggle == byte >> 7, comment
                if "IN_POS = 0" in comment:
                    _wait_in_pos(s, byte)
                    time.sleep(0.05)
                    reached.append(int(twin.m.read("P_IST")[0]))
            assert twin.mode(0) == 2
            assert int(twin.m.read("V_SOLL")[0]) == 800  # V3 activated last
    assert [abs(p - t) <= 10 for p, t in zip(reached, (4096, 10000, -3000))] == [True] * 3


@pytest.mark.statements("mac050_141:3.2.36:14", "mac050_141:4.4.16:1")
def test_flexmac_on_the_user_interface_and_safe_mode() -> None:
    twin = _user_twin()
    u = twin.user[0]
    assert u.feed(bytes((fm.encode_command(fm.FastCommand.USE_FLEXMAC, 1),))) != b""
    assert u.flexmac and fm.decode_status(u.status()).flexmac
    st = u.feed(fx.encode_write(-1234, index=3))  # V_SOLL by index
    assert len(st) == 1 and int(twin.m.read("V_SOLL")[0]) == -1234
    u.feed(fx.encode_write(0x0547, address=fx.flex_address(5)))
    assert int(twin.m.read("V_SOLL")[0]) == 0x0547
    twin.m.write("P_IST", 123456)
    reply = u.feed(fx.encode_read(long=True, index=3))
    assert fx.decode_read_reply(reply, long=True)[1] == mt.long_to_bytes(123456)
    reply = u.feed(fx.encode_read(long=True, number=fx.flex_number(10)))
    assert fx.decode_read_reply(reply, long=True)[1] == mt.long_to_bytes(123456)
    # malformed FlexMAC changes nothing
    before = twin.m.regs.copy()
    u.feed(bytes.fromhex("63 63 63 47 B9 05 FA"))
    np.testing.assert_array_equal(twin.m.regs, before)
    # SAFE_MODE: writes are refused, status still sent, MacTalk takes the motor out (4.4.16)
    twin.m.enter_safe_mode()
    twin.m.step(100)
    u.feed(fx.encode_write(2, index=3))
    assert int(twin.m.read("V_SOLL")[0]) == 0x0547
    assert u.feed(fx.encode_write(0, long=False, number=fx.flex_number(2))) != b""
    assert twin.mode(0) == 15
    # back to FastMAC with the manual's 07FH x3
    assert u.feed(fx.encode_use_fastmac()) != b"" and not u.flexmac


@pytest.mark.statements("mac050_141:3.2.36:12")
def test_user_interface_inactive_without_userintf() -> None:
    twin = make_twin()
    assert twin.user[0].feed(bytes((0xE0, 0x62))) == b""
