"""FastMAC codec (manual 5.2.1): the 5.2.1.5 example bytes in both directions, the 32 commands,
the toggle bit, the safe (two identical bytes) variant and the status byte."""

from __future__ import annotations

import pytest

from jvl_gym.protocol import FrameError
from jvl_gym.protocol.mactalk import fastmac as fm

# the example of manual 5.2.1.5: byte → (mode, register or command, toggle)
EXAMPLE = [
    (0xE0, fm.Mode.COMMAND, fm.FastCommand.NOP, 1),
    (0x62, fm.Mode.COMMAND, fm.FastCommand.P_SOLL_ZERO, 0),  # commented "Set P_IST = 0"
    (0x81, fm.Mode.INIT, "A2", 1),  # commented "Activate T2": fits no code with 003H
    (0x03, fm.Mode.INIT, "A4", 0),
    (0x93, fm.Mode.INIT, "V4", 1),
    (0x5D, fm.Mode.POSITION, "P6", 0),
    (0xDE, fm.Mode.POSITION, "P7", 1),
    (0x52, fm.Mode.POSITION, "V3", 0),
    (0xDC, fm.Mode.POSITION, "P5", 1),
]


@pytest.mark.parametrize("byte, mode, what, toggle", EXAMPLE)
def test_example_5_2_1_5_both_directions(byte, mode, what, toggle) -> None:
    got = fm.decode_byte(byte)
    assert got.mode == mode and got.toggle == toggle
    if isinstance(what, fm.FastCommand):
        assert got.command == what
        assert fm.encode_command(what, toggle) == byte
    else:
        assert got.register == what
        assert fm.encode_activate(mode, what, toggle) == byte


def test_example_comments_match_except_the_two_documented_bytes() -> None:
    for (byte, comment), (_, _, what, _) in zip(fm.EXAMPLE_SEQUENCE, EXAMPLE):
        if isinstance(what, str):
            assert (what in comment) == (byte != 0x81), comment
    assert fm.encode_activate(fm.Mode.INIT, "T2", 1) == 0x85


def test_table_code_of_the_text() -> None:
    code = fm.TABLE_CODE
    assert fm.encode_activate(fm.Mode.INIT, "P1", 0, code) == 0b000_00000
    assert fm.encode_activate(fm.Mode.INIT, "V8", 0, code) == 0b000_01111
    assert fm.encode_activate(fm.Mode.VELOCITY, "A1", 0, code) == 0b001_10000
    assert fm.encode_activate(fm.Mode.POSITION, "T4", 1, code) == 0b110_10111
    assert fm.encode_activate(fm.Mode.INIT, "L2", 0, code) == 0b000_11001
    assert fm.encode_activate(fm.Mode.INIT, "Z3", 0, code) == 0b000_11110
    assert fm.decode_byte(0x5D, code).register == "Z2"


@pytest.mark.parametrize("code", [fm.TABLE_CODE, fm.EXAMPLE_CODE])
def test_every_byte_decodes_and_reencodes(code) -> None:
    seen = set()
    for byte in range(256):
        c = fm.decode_byte(byte, code)
        if c.command is not None:
            again = fm.encode_command(c.command, c.toggle)
        else:
            again = fm.encode_activate(c.mode, c.register, c.toggle, code)
            seen.add((c.mode, c.register))
        assert again == byte
    assert len(seen) == 3 * 32  # every register of every group in three modes


def test_32_commands() -> None:
    assert len(fm.FastCommand) == 32
    assert fm.encode_command(fm.FastCommand.USE_FLEXMAC, 0) == 0x7F
    assert fm.encode_command(fm.FastCommand.TRANSMIT_MYADDR, 1) == 0xFD


def test_bad_arguments() -> None:
    with pytest.raises(ValueError):
        fm.encode_activate(fm.Mode.INIT, "P9", 0)
    with pytest.raises(ValueError):
        fm.encode_activate(fm.Mode.COMMAND, "P1", 0)
    with pytest.raises(ValueError):
        fm.encode_command(1, 2)


def test_toggle_bit_separates_commands() -> None:
    rx = fm.FastMacReceiver()
    got = [rx.feed(b) for b in (0xE0, 0xE0, 0x62, 0x62, 0x62, 0x81)]
    assert [g.command if g and g.command is not None else g for g in got[:5]] == [
        fm.FastCommand.NOP, None, fm.FastCommand.P_SOLL_ZERO, None, None]
    assert got[5].register == "A2"


def test_safe_communication_needs_two_identical_bytes() -> None:
    rx = fm.FastMacReceiver()
    assert rx.feed(fm.encode_command(fm.FastCommand.SAFE_COMM, 1)).command == \
        fm.FastCommand.SAFE_COMM
    assert rx.safe
    assert rx.feed(0x5D) is None  # first of the pair
    assert rx.feed(0x5D).register == "P6"
    assert rx.feed(0xDE) is None
    err = rx.feed(0xDC)  # differs: rejected, 0xDC starts a new pair
    assert isinstance(err, FrameError) and err.code == "bad_safe_pair"
    assert "DEh then DCh" in err.reason
    assert rx.feed(0xDC).register == "P5"
    rapid = fm.encode_command(fm.FastCommand.RAPID_COMM, 0)
    assert rx.feed(rapid) is None and rx.feed(rapid).command == fm.FastCommand.RAPID_COMM
    assert not rx.safe


def test_status_byte() -> None:
    s = fm.Status(toggle=1, dec_flag=False, acc_flag=True, in_pos=True, flexmac=True,
                  framing_error=False, error=True)
    b = fm.encode_status(s)
    assert b == 0b1011_1001
    assert fm.decode_status(b) == s
    for byte in range(256):
        if byte & 0x60 == 0x60:
            with pytest.raises(FrameError, match="FlexMAC header"):
                fm.decode_status(byte)
        else:
            assert fm.encode_status(fm.decode_status(byte) ) == byte & ~0x02
    with pytest.raises(ValueError):
        fm.encode_status(fm.Status(dec_flag=True, acc_flag=True))
