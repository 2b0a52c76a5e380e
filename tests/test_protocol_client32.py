"""The master's side of the 32-bit MacTalk (MAC800 serial quick guide §1.3, MIS manual §18.2):
the client sends the manuals' request bytes and reads their replies, types values by the
register table, refuses before sending, and the dialect of a unit is told from its reply to a
read (protocol.probe). The other end is a twin session in-process (no port, no physics:
``protocol_fakes.RegisterArray`` on the families' tables)."""

from __future__ import annotations

from collections.abc import Callable

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from jvl_gym.families import family, mis
from jvl_gym.protocol.errors import NoAnswerError, RefusedError
from jvl_gym.protocol.mactalk import codec32 as m32
from jvl_gym.protocol.mactalk.client16 import MacTalkClient
from jvl_gym.protocol.mactalk.client32 import MacTalk32Client
from jvl_gym.protocol.mactalk.dialect import MACTALK16, MACTALK32, client_class
from jvl_gym.protocol.mactalk.line import Bus
from jvl_gym.protocol.mactalk.probe import PROBE_REGISTER, DialectProbe
from jvl_gym.protocol.mactalk.twin16 import Twin
from jvl_gym.registers import ReadOnlyRegisterError, RegisterError, to_raw
from protocol_fakes import SAFE_MODE, RegisterArray
from test_protocol_mactalk32 import READ_EXAMPLES, WRITE_EXAMPLES, h


class LoopSerial:
    """A pyserial stand-in: each written request is answered by ``answer(request)``."""

    def __init__(self, answer: Callable[[bytes], bytes]) -> None:
        self.answer = answer
        self.sent: list[bytes] = []
        self.pending = b""
        self.timeout = 0.0

    def write(self, data: bytes) -> None:
        self.sent.append(bytes(data))
        self.pending += self.answer(bytes(data))

    def read(self, n: int) -> bytes:
        out, self.pending = self.pending[:n], self.pending[n:]
        return out

    def flush(self) -> None:
        pass

    def reset_input_buffer(self) -> None:
        self.pending = b""

    def close(self) -> None:
        pass


def on_twin(twin: Twin | Bus, address: int = 7) -> tuple[MacTalk32Client, LoopSerial]:
    session = twin.session()
    ser = LoopSerial(lambda raw: session.feed(raw) + session.flush())
    return MacTalk32Client("loop://", address, table=mis.REGISTERS, timeout=0.05, retries=0,
                           serial=ser), ser


def mis_twin(n: int = 1) -> tuple[Twin, RegisterArray]:
    m = RegisterArray(mis.REGISTERS, n, dialect=MACTALK32)
    return Twin(m, list(range(7, 7 + n)), dialect=MACTALK32), m


# ------------------------------------------------------------ the manuals' frames
@pytest.mark.parametrize("frame, address, register, value", WRITE_EXAMPLES)
def test_the_client_sends_the_quick_guides_writes(frame, address, register, value) -> None:
    ser = LoopSerial(lambda raw: m32.ACCEPT)
    c = MacTalk32Client("loop://", address, table=mis.REGISTERS, serial=ser)
    c.write_value(register, value)
    assert ser.sent == [frame]


@pytest.mark.parametrize("request_, reply, address, register, value", READ_EXAMPLES)
def test_the_client_reads_the_manuals_replies(request_, reply, address, register,
                                              value) -> None:
    ser = LoopSerial(lambda raw: reply)
    c = MacTalk32Client("loop://", address, table=mis.REGISTERS, serial=ser)
    assert c.read_value(register) == value
    assert ser.sent == [request_]


def test_a_reply_naming_another_register_is_passed_over() -> None:
    """Quick guide §1.3.3 example 2 as printed: a read of register 3 answered with register 5,
    which "will always be the same as requested": not the answer (a late one to an earlier
    read); the reply naming register 3 that follows is."""
    printed = h("52h,52h,52h - 00h,FFh - 05h,FAh - 04h,FBh - 70h,8Fh,82h,7Dh,03h,FCh,00h,FFh"
                " - AAh,AAh")
    right = printed[:5] + h("03h,FCh") + printed[7:]
    c = MacTalk32Client("loop://", 8, table=mis.REGISTERS, timeout=0.05, retries=0,
                        serial=LoopSerial(lambda r: printed))
    with pytest.raises(NoAnswerError):
        c.read_value(3)
    c.ser = LoopSerial(lambda r: printed + right)
    assert c.read_value(3) == 230_000


def test_commands_are_the_mis_frames() -> None:
    """MIS §18.2.5 – §18.2.8, §8.2.63 (53h)."""
    ser = LoopSerial(lambda raw: m32.ACCEPT if raw[0] in (0x54, 0x55) else b"")
    c = MacTalk32Client("loop://", 7, table=mis.REGISTERS, timeout=0.05, serial=ser)
    c.go_safe_mode()
    c.go_init_mode()
    c.write_flash(settle=0.05)
    c.reset(settle=0)
    assert ser.sent == [h("54 54 54 07 f8 aa aa"), h("55 55 55 07 f8 aa aa"),
                        h("56 56 56 07 f8 aa aa"), h("57 57 57 07 f8 aa aa")]


# ------------------------------------------------------------ typed access on a twin
def test_typed_read_write_and_refusals_change_nothing() -> None:
    twin, m = mis_twin()
    c, ser = on_twin(twin)
    c.write("V_SOLL", 5000)  # MIS §8.2.6, 0.01 RPM units
    assert m.read_raw("V_SOLL")[0] == 5000 and c.read("V_SOLL") == 5000
    c.write("P_SOLL", -230_000)
    assert c.read_raw("P_SOLL") == -230_000
    before, sent = m.regs.copy(), len(ser.sent)
    with pytest.raises(RegisterError, match="range"):
        c.write("V_SOLL", 10**9)
    with pytest.raises(ReadOnlyRegisterError):
        c.write("V_IST", 0)
    assert len(ser.sent) == sent and (m.regs == before).all()  # refused before sending
    with pytest.raises(NoAnswerError, match="no accept"):  # refused by the unit: no accept
        c.write_value(m.table.lookup("GROUP_SEQ").number, 1)
    assert (m.regs == before).all()


def test_write_flash_outside_safe_mode_is_reported_refused() -> None:
    """MIS §18.2.7: "The response will only be transmitted if the command failed"."""
    twin, m = mis_twin()
    c, _ = on_twin(twin)
    c.write("P_SOLL", 4711)
    with pytest.raises(RefusedError, match="safe mode"):
        c.write_flash(settle=0.05)
    assert m.table.lookup("P_SOLL").number not in m.flash[0]
    c.go_safe_mode()
    assert m.read_raw("MODE_REG")[0] == SAFE_MODE
    c.write_flash(settle=0.05)
    assert m.flash[0][m.table.lookup("P_SOLL").number] == 4711


def test_read_raws_by_blocks_equal_single_reads() -> None:
    twin, m = mis_twin()
    c, ser = on_twin(twin)
    c.write("P_SOLL", -5)
    numbers = [r.number for r in m.table if r.access.value != "reserved"]
    sent = len(ser.sent)
    many = c.read_raws(numbers)
    blocks = len(ser.sent) - sent
    assert blocks <= -(-len(numbers) // m32.BLOCK_REGISTERS) + 8 and blocks < len(numbers) / 4
    assert many == {n: c.read_raw(n) for n in numbers}


@settings(max_examples=60, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.data())
def test_any_value_in_range_reads_back_as_written(data) -> None:
    twin, m = mis_twin()
    c, _ = on_twin(twin)
    names = [r.name for r in m.table if r.access.value == "rw" and r.name != "MODE_REG"
             and r.name not in ("MY_ADDR", "GROUP_ID")]
    reg = m.table.lookup(data.draw(st.sampled_from(names)))
    raw = data.draw(st.integers(int(to_raw(reg, reg.minimum)), int(to_raw(reg, reg.maximum))))
    c.write(reg.name, raw / reg.scale)
    assert c.read_raw(reg.name) == raw == int(m.read_raw(reg.name)[0])


# ------------------------------------------------------------ the dialect of a unit
def test_probe_tells_the_dialects_apart_on_one_line() -> None:
    """A read has the same bytes in both dialects; the replies differ after 00h FFh: the
    16-bit datalength 04h (MAC050–141 manual 5.1), the 32-bit register number (quick guide
    §1.3.3)."""
    mac = Twin(RegisterArray(family("mac050_141").table, 1), [19])
    mis_, _ = mis_twin()
    session = Bus([mac, mis_]).session()
    ser = LoopSerial(lambda raw: session.feed(raw) + session.flush())
    probe = DialectProbe("loop://", 1, timeout=0.05, retries=0, serial=ser)
    assert PROBE_REGISTER != 4
    assert [probe.dialect(a) for a in (19, 7, 8)] == [MACTALK16, MACTALK32, None]
    assert client_class(MACTALK16) is MacTalkClient
    assert client_class(MACTALK32) is MacTalk32Client
