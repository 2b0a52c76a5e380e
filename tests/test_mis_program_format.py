"""The MIS program text format and flash bytes: every §9.7 command read and written back,
errors naming line and field, random text refused cleanly or round-tripped."""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from jvl_gym.families.mis.program import SPECS, ProgramError, parse_program, print_program
from jvl_gym.families.mis.program.binary import (
    FLASH_BYTES,
    decode_program,
    encode_program,
)
from jvl_gym.families.mis.program.commands import cost_us
from jvl_gym.families.mis.program.format import parse_line, print_line

#: one line of every command type (§9.7.1 … §9.7.27)
EVERY = (Path(__file__).parent / "fixtures" / "mis_program_every.txt").read_text()


def test_every_command_type_has_a_line_and_round_trips() -> None:
    cmds = parse_program(EVERY)
    assert {c.keyword for c in cmds} == set(SPECS)
    assert len(SPECS) == 26  # §9.7.1–9.7.27 without 9.7.3 (the move family's heading)
    assert print_program(cmds) == EVERY
    assert decode_program(encode_program(cmds)) == cmds
    assert cmds[0]["text"] == 'pick & place: "fast"'
    assert cmds[3]["velocity"] == 1050 and cmds[3]["new_velocity"] == 225


def test_defaults_and_engineering_units() -> None:
    cmds = parse_program("move_relative distance=1\nset_register register=P2 value=-0.5rev\n"
                         "set_register register=V1 value=12.34rpm\n")
    assert cmds[0].values == {"distance": 1, "acceleration": 0, "velocity": 0, "wait": "yes"}
    assert cmds[1]["value"] == -204800 and cmds[2]["value"] == 1234


@pytest.mark.parametrize(("text", "line", "field"), [
    ("mode mode=position\nmove_relative distance=1 velocity=fast\n", 2, "velocity"),
    ("mode mode=turbo\n", 1, "mode"),
    ("jump line=3\n", 1, "line"),
    ("jump\n", 1, "line"),
    ("mode\n", 1, "mode"),
    ("dance step=1\n", 1, None),
    ("mode mode=passive\n\nmode mode=passive\n", 2, None),
    ("set_register register=P_IST value=1\nset_register register=V_IST value=1\n", 2,
     "register"),
    ("set_register register=NOPE value=1\n", 1, "register"),
    ("set_output output=1 state=high pulse_ms=10\n", 1, "pulse_ms"),
    ("set_output output=1 state=high_pulse\n", 1, "pulse_ms"),
    ("fastmac mode=position register=torque number=5\n", 1, "number"),
    ("fastmac_command command=4\n", 1, "command"),
    ("binary code=ff\n", 1, "code"),
    ("binary code=xyz\n", 1, "code"),
    ("calculate register=P2 expression=P2+ precision=32\n", 1, "expression"),
    ("calculate register=P2 expression=P2 precision=16\n", 1, "precision"),
    ("wait_ms time=32768\n", 1, "time"),
    ("wait_inputs operand=and inputs=1:high,1:low\n", 1, "inputs"),
    ("move_relative distance=register4\n", 1, "distance"),
    ("move_absolute position=1 velocity=3000.01\n", 1, "velocity"),
    ('remark text="open\n', 1, "text"),
    ("mode mode=position mode=passive\n", 1, "mode"),
    ("mode speed=1\n", 1, "speed"),
])
def test_malformed_lines_name_line_and_field(text: str, line: int, field: str | None) -> None:
    with pytest.raises(ProgramError) as err:
        parse_program(text)
    assert (err.value.line, err.value.field) == (line, field)
    assert str(err.value).startswith(f"line {line}")


def test_a_program_bigger_than_the_program_flash_is_refused() -> None:
    from jvl_gym import MotorArray

    m = MotorArray("MIS232")
    line = 'remark text="' + "x" * 200 + '"\n'
    with pytest.raises(ProgramError, match="3072-byte program flash") as err:
        m.store_program(line * 20)
    # 2 bytes of line count, 202 bytes a remark (code, length, text): line 16 does not fit
    assert err.value.line == (FLASH_BYTES - 2) // 202 + 1 == 16
    assert m.program_text() is None


@pytest.mark.statements("mis:9.8:1")
def test_costs_follow_the_timing_table() -> None:
    """§9.8: move relative 90/150/210 µs, absolute 60/120/180, set a register 60, jump 30."""
    cmds = parse_program("move_relative distance=1\nmove_relative distance=1 velocity=1\n"
                         "move_relative distance=1 velocity=1 acceleration=1\n"
                         "move_absolute position=1\nmove_absolute position=1 velocity=1 "
                         "acceleration=1\nset_register register=P2 value=1\njump line=1\n"
                         "set_outputs outputs=1:high,2:low,3:low\n")
    assert [cost_us(c) for c in cmds] == [90, 150, 210, 60, 180, 60, 30, 90]


_WORDS = st.sampled_from([*SPECS, "line=1", "distance=1", "input=1", "condition=high",
                          "operator=>=", "register=P2", "value=3", "text=hi", "mode=position",
                          "velocity=1.5", "outputs=1:high", "inputs=error:low", "operand=or",
                          "code=00", "expression=P2*2", "=", '"', "x=\"a b\"", "time=5"])


_LINES = EVERY.splitlines()


@st.composite
def _mutated(draw: st.DrawFn) -> str:
    """Lines of :data:`EVERY` (jump targets may fall outside), one character maybe changed."""
    text = "\n".join(draw(st.lists(st.sampled_from(_LINES), min_size=1, max_size=6)))
    if draw(st.booleans()):
        k = draw(st.integers(0, len(text) - 1))
        text = text[:k] + draw(st.characters(codec="utf-8")) + text[k + 1:]
    return text


@settings(max_examples=400, deadline=None)
@given(st.one_of(st.text(max_size=80), _mutated(),
                 st.lists(st.lists(_WORDS, min_size=1, max_size=6).map(" ".join),
                          min_size=1, max_size=4).map("\n".join)))
def test_random_text_is_refused_cleanly_or_round_trips(text: str) -> None:
    try:
        cmds = parse_program(text)
    except ProgramError as exc:
        assert exc.line >= 1 and str(exc).startswith(f"line {exc.line}")
        return
    again = parse_program(print_program(cmds))
    assert again == cmds
    assert decode_program(encode_program(cmds)) == cmds


@pytest.mark.parametrize("text", ["wait_ms time=" + "9" * 1000,
                                  "set_register register=P2 value=" + "9" * 300 + "rev",
                                  "move_relative distance=1 velocity=" + "9" * 200,
                                  "calculate register=P2 expression=" + "9" * 200])
def test_huge_numbers_are_refused_cleanly(text: str) -> None:
    with pytest.raises(ProgramError, match="line 1, field"):
        parse_program(text)


def test_a_text_above_what_the_flash_holds_is_refused_by_its_size() -> None:
    from jvl_gym.families.mis.program.binary import FLASH_BYTES, encode_command
    from jvl_gym.families.mis.program.format import (
        MAX_LINE_BYTES,
        MAX_TEXT_BYTES,
        MIN_INSTRUCTION_BYTES,
        parse_line,
    )

    assert len(encode_command(parse_line("remark"))) == MIN_INSTRUCTION_BYTES
    assert MAX_TEXT_BYTES == (FLASH_BYTES - 2) // MIN_INSTRUCTION_BYTES * (MAX_LINE_BYTES + 2)
    with pytest.raises(ProgramError, match="cannot be a program") as info:
        parse_program("\0" * 4 * 2**20)  # 4 MB of NULs
    assert len(str(info.value)) < 300


def test_errors_show_a_short_piece_of_the_text() -> None:
    for text in ("\0" * 1000, "x" * 1000, "mode " + "y" * 900 + "=1", "mode mode=" + "z" * 399):
        with pytest.raises(ProgramError) as info:
            parse_program(text + "\n")
        assert len(str(info.value)) < 700, str(info.value)[:200]
    longest = print_line(parse_line('remark text="' + '\\"' * 255 + '"'))
    assert len(longest.encode()) <= 1024  # the longest canonical line fits a line
