"""Bounded errors: an error that repeats bad input repeats a short prefix and the length
(``registers.errors.echo``), whatever the input's size; capability errors name the motors once."""

from __future__ import annotations

import pytest

from jvl_gym import MotorArray
from jvl_gym.families import UnsupportedOperation
from jvl_gym.families.mis.program.format import ProgramError, parse_program
from jvl_gym.protocol.mactalk import codec16 as mt
from jvl_gym.protocol.mactalk.dialect import check_dialect
from jvl_gym.registers import RegisterError
from jvl_gym.registers.errors import ECHO_LIMIT, echo, echo_hex

BOUND = 400  # characters an error message may take, whatever the input


def test_echo_cuts_long_input_to_a_prefix_and_its_length() -> None:
    assert echo("KVOUT") == "'KVOUT'" and echo(b"\x01") == "b'\\x01'"
    text = echo("\0" * 4_000_000)
    assert text.endswith("… (4000000 characters)") and len(text) < BOUND
    assert echo(b"x" * 10**6) == f"{b'x' * ECHO_LIMIT!r}… (1000000 bytes)"
    assert echo(list(range(10**5))).endswith("(100000 items)")
    assert echo_hex(bytes(10**6)).endswith("… (1000000 bytes)")
    assert len(echo_hex(bytes(10**6))) < BOUND


@pytest.mark.parametrize("text", [
    "\0" * 4_000_000,  # a program of NULs
    "remark " + "x" * 1_000_000 + "=1",  # a field name of a million characters
    "mode " + "y" * 1_000_000,  # a word that is no key=value
])
def test_a_huge_bad_program_gives_a_short_error(text: str) -> None:
    with pytest.raises(ProgramError) as info:
        parse_program(text)
    message = str(info.value)
    assert message.startswith("line 1") and "characters" in message  # its length, not it
    assert len(message.split(";")[0]) < BOUND


def test_a_huge_register_name_gives_a_short_error() -> None:
    m = MotorArray("MAC140")
    with pytest.raises(RegisterError) as info:
        m.read("Q" * 1_000_000)
    assert len(str(info.value)) < BOUND and "1000000 characters" in str(info.value)


def test_huge_protocol_arguments_give_short_errors() -> None:
    with pytest.raises(ValueError) as info:
        check_dialect("d" * 100_000)
    assert len(str(info.value)) < BOUND
    with pytest.raises(ValueError) as info:
        mt.encode_write_word(19, 2, 10**100_0)
    assert len(str(info.value)) < BOUND


def test_a_capability_error_names_the_motors_once() -> None:
    with pytest.raises(UnsupportedOperation) as info:
        MotorArray("MAC800").enter_safe_mode()
    message = str(info.value)
    assert message.startswith("MAC800 integrated servo motors have no safe mode")
    assert "motors motors" not in message
