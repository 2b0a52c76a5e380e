"""Program status and command (61h, MIS manual §18.2.10) served by the twin for a simulated MIS
with a stored program."""

from __future__ import annotations

import pytest

from jvl_gym import MotorArray
from jvl_gym.protocol.mactalk import codec32 as m32
from jvl_gym.protocol.mactalk.twin16 import Twin

PROGRAM = ("set_register register=P2 value=1\nset_register register=P2 value=2\n"
           "set_register register=P2 value=3\njump line=4\n")


def ask(twin: Twin, raw: bytes) -> bytes:
    s = twin.session()
    return s.feed(raw) + s.flush()


def _twin() -> tuple[MotorArray, Twin]:
    m = MotorArray("MIS231", seed=0)
    m.store_program(PROGRAM)
    return m, Twin(m, [7])


def test_the_manuals_start_example_byte_for_byte() -> None:
    """§18.2.10: "61h,61h,61h 07h,F8h 01h,FEh 01h,FEh AAh,AAh" (start, unit 7) is answered
    with program state 9 (starting), pointer 0, stack 0, checksum 0 (computed when the program
    starts), inputs 80h, outputs 0."""
    m, twin = _twin()
    m.set_input(digital_inputs=0x80)
    m.step(1)
    request = bytes.fromhex("61 61 61 07 f8 01 fe 01 fe aa aa")
    assert m32.encode_program(7, 1) == request
    assert m32.decode(request) == m32.Request(m32.Command.PROGRAM, 7, None, b"\x01")
    assert ask(twin, request) == bytes.fromhex(
        "61 61 61 00 ff 08 f7 09 f6 00 ff 00 ff 00 ff 00 ff 00 ff 80 7f 00 ff aa aa")
    m.step(1)
    reply = m32.decode(ask(twin, m32.encode_program(7, 0)))
    assert isinstance(reply, m32.ProgramReply) and m32.decode(m32.encode(reply)) == reply
    state, pointer, stack = reply.data[0], int.from_bytes(reply.data[1:3], "little"), reply.data[3]
    assert (state, pointer, stack) == (1, 3, 0)  # running, at line 4 (index 3)
    assert int.from_bytes(reply.data[4:6], "little") == sum(
        m._runners[0].flash) & 0xFFFF  # type: ignore[index]


def test_stop_pause_run_area_and_outputs_over_the_line() -> None:
    m, twin = _twin()
    ask(twin, m32.encode_program(7, 4, (0).to_bytes(2, "little") + (1).to_bytes(2, "little")))
    m.step(1)
    assert m.read_raw("P2")[0] == 2 and m.program_status().name == "paused"
    ask(twin, m32.encode_program(7, 1))  # resume
    m.step(1)
    assert m.read_raw("P2")[0] == 3
    reply = m32.decode(ask(twin, m32.encode_program(7, 2)))
    assert reply.data[0] == 7  # stopped
    reply = m32.decode(ask(twin, m32.encode_program(7, 5, bytes([0x06, 0x01]))))
    assert reply.data[7] == 0x06  # §18.2.10's example: "sets output 2+3 and clears output 1"
    ask(twin, m32.encode_program(7, 7, (100).to_bytes(2, "little")))
    assert m.program_text() is None


@pytest.mark.parametrize("raw", [m32.encode_program(7, 9), m32.encode_program(7, 4, b"\x00")])
def test_a_bad_program_command_gets_no_reply_and_changes_nothing(raw: bytes) -> None:
    m, twin = _twin()
    regs = m.regs.copy()
    assert ask(twin, raw) == b""
    assert (m.regs == regs).all() and m.program_status().name == "stopped"
