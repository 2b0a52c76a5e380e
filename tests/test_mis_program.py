"""MIS stored programs: every §9.7 command run on the simulated motor (MIS manual chapter 9),
the program status of §18.2.10, flash and power-on (§9.1, §9.5, §8.2.68), stop/pause/step."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from jvl_gym import MotorArray
from jvl_gym.families.mis import constants as c
from jvl_gym.families.mis.program import SPECS, ProgramError, parse_program
from jvl_gym.families.mis.program.binary import encode_command
from jvl_gym.registers import RegisterError

REV = 409600


def _run(program: str, ms: int = 0, n: int = 1, **params: float) -> MotorArray:
    m = MotorArray("MIS232", n=n, seed=0, **params)
    m.write_many({"A_SOLL": 20000, "IN_POSITION_COUNT": 0})
    m.write("MODE_REG", 2)
    m.store_program(program)
    m.program_start()
    m.step(ms)
    return m


def _reg(m: MotorArray, name: str) -> int:
    return int(m.read_raw(name)[0])


def _until(m: MotorArray, cond, limit_ms: int = 5000) -> int:
    """Step 1 ms at a time until ``cond(m)``; the ms it took."""
    for k in range(limit_ms):
        if cond(m):
            return k
        m.step(1)
    raise AssertionError("condition never met")


def _end(program: str) -> str:
    """The program followed by a line that holds it (so it does not run off its end)."""
    n = program.count("\n") + 1
    return program + f"jump line={n}\n"


# --- §9.7.1 remark, program pointer, §18.2.10 states -------------------------------------
@pytest.mark.statements("mis:9.7.1:1")
def test_remark_does_nothing_and_running_off_the_end_is_a_program_overflow() -> None:
    m = MotorArray("MIS232", seed=0)
    before = m.read_raw("V_SOLL").copy()
    m.store_program('remark text="nothing here"\nremark\n')
    m.program_start()
    m.step(2)
    s = m.program_status()
    assert (s.state, s.name, s.error, s.line) == (5, "program overflow", True, 3)
    assert np.array_equal(m.read_raw("V_SOLL"), before)


# --- §9.7.2 set mode ---------------------------------------------------------------------
@pytest.mark.parametrize(("mode", "code"), [("passive", 0), ("velocity", 1), ("gear", 3)])
@pytest.mark.statements("mis:9.7.2:1")
def test_set_mode(mode: str, code: int) -> None:
    m = _run(_end(f"mode mode={mode}\n"), 2)
    assert _reg(m, "MODE_REG") == code


@pytest.mark.statements("mis:8.2.31:24", "mis:9.7.2:2")
def test_set_mode_refused_with_errors_keeps_the_mode_and_goes_on() -> None:
    """§8.2.31: an active mode is refused while ERR_BITS ≠ 0; the program continues."""
    m = MotorArray("MIS232", seed=0)
    m.write("ERR_BITS", 1)
    m.store_program(_end("mode mode=velocity\nset_output output=2 state=high\n"))
    m.program_start()
    m.step(2)
    assert _reg(m, "MODE_REG") == 0 and _reg(m, "OUTPUTS") == 2
    assert "ERR_BITS" in m.program_refusals()[0]


# --- §9.7.4 move relative ----------------------------------------------------------------
@pytest.mark.statements("mis:9.7.4:1", "mis:9.7.4:2")
def test_move_relative_waits_for_in_position_and_overwrites_v_a_p1() -> None:
    m = _run(_end("move_relative distance=204800 velocity=300 acceleration=30000\n"
                  "set_output output=1 state=high\n"), 1)
    assert _reg(m, "V_SOLL") == 30000 and _reg(m, "A_SOLL") == 30000
    assert _reg(m, "P1") == 204800 and _reg(m, "P_SOLL") == 204800
    took = _until(m, lambda m: _reg(m, "OUTPUTS") == 1)
    # the output follows the in-position bit: set one outer sample after the arrival
    assert _reg(m, "P_IST") == 204800 and _reg(m, "STATUSBITS") & c.ST_IN_POSITION
    assert took > 100  # 0.5 rev at 300 RPM is 100 ms at least


@pytest.mark.statements("mis:9.7.4:1", "mis:9.7.4:2")
def test_move_relative_without_wait_goes_on_at_once_and_zero_keeps_v_soll() -> None:
    m = _run(_end("move_relative distance=-102400 wait=no\nset_output output=1 state=high\n"),
             1)
    assert _reg(m, "OUTPUTS") == 1 and _reg(m, "V_SOLL") == 10000  # the ROM default
    m.step(500)
    assert _reg(m, "P_IST") == -102400


@pytest.mark.statements("mis:9.7.4:1")
def test_move_relative_is_relative_to_p_ist_and_takes_a_user_register() -> None:
    m = MotorArray("MIS232", seed=0)
    m.write_many({"P2": 40960, "A_SOLL": 20000})
    m.write("MODE_REG", 2)
    m.store_program(_end("move_relative distance=register2 velocity=600\n"
                         "move_relative distance=register2 velocity=600\n"))
    m.program_start()
    m.step(600)
    assert _reg(m, "P_IST") == 81920 and _reg(m, "P1") == 40960


# --- §9.7.5 move relative + velocity change at a distance ----------------------------------
@pytest.mark.statements("mis:9.7.5:1")
def test_move_relative_velocity_change_at_distance() -> None:
    """§9.7.5: V_SOLL becomes the new velocity when the distance left reaches the change
    distance (tested every pass: in the first outer sample it is reached); always waits."""
    m = _run(_end("move_relative_change distance=409600 velocity=300 acceleration=5000 "
                  "change_distance=102400 new_velocity=60\nset_output output=1 state=high\n"))
    rows = []
    while _reg(m, "OUTPUTS") == 0:
        rows.append((409600 - _reg(m, "P_IST"), _reg(m, "V_SOLL"), abs(_reg(m, "V_IST"))))
        m.step(1)
    change = next(k for k, r in enumerate(rows) if r[1] == 6000)
    # the row before the change is the outer sample that reached the change distance
    assert rows[change - 1][0] <= 102400 < rows[change - 2][0]
    assert all(r[1] == 30000 for r in rows[1:change]) and max(r[2] for r in rows) == 30000
    assert rows[-1][2] <= 6000 and _reg(m, "P_IST") == 409600


# --- §9.7.6 move relative + set outputs -----------------------------------------------------
@pytest.mark.statements("mis:9.7.6:1")
def test_move_relative_sets_outputs_when_done() -> None:
    m = _run(_end("set_outputs outputs=4:high\n"
                  "move_relative_outputs distance=40960 velocity=300 outputs=1:high,4:low\n"), 20)
    assert _reg(m, "OUTPUTS") == 8 and _reg(m, "P_IST") < 40960
    _until(m, lambda m: _reg(m, "OUTPUTS") == 1)
    assert _reg(m, "P_IST") == 40960


# --- §9.7.7 move absolute ---------------------------------------------------------------------
@pytest.mark.statements("mis:9.7.7:1")
def test_move_absolute_to_a_saved_position() -> None:
    m = MotorArray("MIS232", seed=0)
    m.write_many({"P3": -81920, "A_SOLL": 20000})
    m.write("MODE_REG", 2)
    m.store_program(_end("move_absolute position=register3 velocity=300\n"
                         "move_absolute position=1000 wait=no\nset_output output=2 state=high\n"))
    m.program_start()
    _until(m, lambda m: _reg(m, "OUTPUTS") == 2)
    # the 2nd move did not wait: the output came in the sample after the arrival at P3
    assert _reg(m, "P_SOLL") == 1000 and abs(_reg(m, "P_IST") + 81920) < 200
    assert _reg(m, "P1") == 0  # an absolute move leaves P1 alone


# --- §9.7.8 move sensor ----------------------------------------------------------------------
@pytest.mark.statements("mis:9.7.8:1")
def test_move_sensor_stops_distance_after_the_input() -> None:
    m = _run(_end("move_sensor distance=20480 velocity=300 safety_distance=409600 input=3 "
                  "condition=high\nset_output output=1 state=high\n"), 150)
    assert _reg(m, "OUTPUTS") == 0
    m.set_input(digital_inputs=0b100)
    m.step(1)  # the firmware reads the input in this sample, the program in the next pass
    at = _reg(m, "P_IST")
    _until(m, lambda m: _reg(m, "OUTPUTS") == 1)
    assert _reg(m, "P_IST") == at + 20480 and _reg(m, "P1") == 20480


@pytest.mark.statements("mis:9.7.8:1")
def test_move_sensor_never_passes_the_safety_distance() -> None:
    m = _run(_end("move_sensor distance=-20480 velocity=600 safety_distance=81920 input=3 "
                  "condition=high\nset_output output=1 state=high\n"))
    _until(m, lambda m: _reg(m, "OUTPUTS") == 1)
    assert _reg(m, "P_IST") == -81920


# --- §9.7.9 set outputs --------------------------------------------------------------------
@pytest.mark.statements("mis:9.7.9:1")
def test_set_output_single_levels_and_pulse() -> None:
    m = _run(_end("set_output output=3 state=high\nset_output output=3 state=low\n"
                  "set_output output=5 state=high_pulse pulse_ms=50\n"), 1)
    assert _reg(m, "OUTPUTS") == 16
    m.step(49)
    assert _reg(m, "OUTPUTS") == 16
    m.step(1)
    assert _reg(m, "OUTPUTS") == 0


@pytest.mark.statements("mis:9.7.9:1")
def test_low_pulse_and_multiple_outputs_leave_dont_care_alone() -> None:
    m = MotorArray("MIS232", seed=0)
    m.write("OUTPUTS", 0b10000001)
    m.store_program(_end("set_outputs outputs=2:high,8:low\n"
                         "set_output output=1 state=low_pulse pulse_ms=10\n"))
    m.program_start()
    m.step(1)
    assert _reg(m, "OUTPUTS") == 0b00000010
    m.step(10)
    assert _reg(m, "OUTPUTS") == 0b00000011


# --- §9.7.10 – §9.7.12 jumps ------------------------------------------------------------------
@pytest.mark.statements("mis:9.7.10:1")
def test_unconditional_jump() -> None:
    m = _run("jump line=3\nset_output output=1 state=high\nset_output output=2 state=high\n"
             "jump line=4\n", 1)
    assert _reg(m, "OUTPUTS") == 2


@pytest.mark.parametrize(("inputs", "condition", "taken"),
                         [(0b100, "high", True), (0, "high", False), (0, "low", True)])
@pytest.mark.statements("mis:9.7.11:1")
def test_jump_single_input_level(inputs: int, condition: str, taken: bool) -> None:
    m = MotorArray("MIS232", seed=0)
    m.set_input(digital_inputs=inputs)
    m.step(1)
    m.store_program(f"jump_input input=3 condition={condition} line=3\n"
                    "set_output output=1 state=high\njump line=3\n")
    m.program_start()
    m.step(1)
    assert _reg(m, "OUTPUTS") == (0 if taken else 1)


def _edges(m: MotorArray, n: int) -> None:
    for _ in range(n):
        m.set_input(digital_inputs=1)
        m.step(3)
        m.set_input(digital_inputs=0)
        m.step(4)


@pytest.mark.statements("mis:9.7.11:1")
def test_edges_a_jump_sees_only_in_the_pass_after_them_a_wait_sees_all() -> None:
    """§9.7.11: a jump sees a transition "during the last 30 microseconds" (the pass after the
    outer sample that brought it), §9.7.14: a wait tests every pass, so it sees every edge."""
    poll = _run("jump_input input=1 condition=rising line=3\njump line=1\n"
                "calculate register=P2 expression=P2+1\njump line=1\n", 5)
    wait = _run("wait_input input=1 condition=rising\n"
                "calculate register=P2 expression=P2+1\njump line=1\n", 5)
    for m in (poll, wait):
        _edges(m, 40)
    assert _reg(wait, "P2") == 40
    assert 0 < _reg(poll, "P2") < 40


def test_jump_sees_the_filtered_input() -> None:
    """§2.2.6: a filtered input changes after INPUT_FILTER_CNT ms; the program reads INPUTS."""
    m = MotorArray("MIS232", seed=0)
    m.write_many({"INPUT_FILTER_MASK": 1, "INPUT_FILTER_CNT": 20})
    m.store_program("jump_input input=1 condition=high line=3\njump line=1\n"
                    "set_output output=1 state=high\njump line=4\n")
    m.program_start()
    m.set_input(digital_inputs=1)
    took = _until(m, lambda m: _reg(m, "OUTPUTS") == 1)
    assert 20 <= took <= 22


@pytest.mark.parametrize(("operand", "pattern", "taken"),
                         [("and", "1:high,2:low", True), ("and", "1:high,2:high", False),
                          ("or", "1:low,2:high", False), ("or", "1:low,in_position:high", True),
                          ("and", "error:low,in_position:high", True)])
@pytest.mark.statements("mis:9.7.12:1")
def test_jump_multiple_inputs(operand: str, pattern: str, taken: bool) -> None:
    m = MotorArray("MIS232", seed=0)
    m.write("MODE_REG", 2)
    m.set_input(digital_inputs=1)
    m.step(2)
    m.store_program(f"jump_inputs operand={operand} inputs={pattern} line=3\n"
                    "set_output output=1 state=high\njump line=3\n")
    m.program_start()
    m.step(1)
    assert _reg(m, "OUTPUTS") == (0 if taken else 1)


# --- §9.7.13 – §9.7.15 waits ----------------------------------------------------------------
@pytest.mark.statements("mis:9.7.13:1")
def test_wait_ms() -> None:
    m = _run(_end("set_output output=1 state=high\nwait_ms time=100\n"
                  "set_output output=1 state=low\n"), 1)
    took = _until(m, lambda m: _reg(m, "OUTPUTS") == 0)
    assert took == 100
    assert _run(_end("wait_ms time=0\nset_output output=1 state=high\n"), 1).read_raw(
        "OUTPUTS")[0] == 1


@pytest.mark.parametrize(("condition", "levels"), [("falling", (1, 0)), ("rising", (0, 1)),
                                                   ("low", (1, 0)), ("high", (0, 1))])
@pytest.mark.statements("mis:9.7.14:1")
def test_wait_single_input(condition: str, levels: tuple[int, int]) -> None:
    m = MotorArray("MIS232", seed=0)
    m.set_input(digital_inputs=levels[0] << 6)
    m.step(1)
    m.store_program(_end(f"wait_input input=7 condition={condition}\n"
                         "set_output output=1 state=high\n"))
    m.program_start()
    m.step(30)
    assert _reg(m, "OUTPUTS") == 0
    m.set_input(digital_inputs=levels[1] << 6)
    m.step(2)
    assert _reg(m, "OUTPUTS") == 1


@pytest.mark.statements("mis:9.7.15:1")
def test_wait_multiple_inputs_and_or() -> None:
    m = _run(_end("wait_inputs operand=and inputs=1:high,2:high\n"
                  "set_output output=1 state=high\n"
                  "wait_inputs operand=or inputs=1:low,2:low\nset_output output=2 state=high\n"),
             5)
    m.set_input(digital_inputs=1)
    m.step(3)
    assert _reg(m, "OUTPUTS") == 0
    m.set_input(digital_inputs=3)
    m.step(2)
    assert _reg(m, "OUTPUTS") == 1
    m.set_input(digital_inputs=2)
    m.step(2)
    assert _reg(m, "OUTPUTS") == 3


# --- §9.7.16 – §9.7.18 registers ----------------------------------------------------------
@pytest.mark.statements("mis:9.7.16:1")
def test_set_register_native_and_engineering_units() -> None:
    m = _run(_end("set_register register=V_SOLL value=123.45rpm\n"
                  "set_register register=P4 value=1.5rev\nset_register register=65 value=777\n"),
             1)
    assert _reg(m, "V_SOLL") == 12345 and _reg(m, "P4") == 614400 and _reg(m, "V1") == 777


@pytest.mark.parametrize(("op", "value", "taken"), [("=", 5, True), ("!=", 5, False),
                                                    ("<", 6, True), (">", 5, False),
                                                    ("<=", 5, True), (">=", 6, False)])
@pytest.mark.statements("mis:9.7.17:1")
def test_jump_register(op: str, value: int, taken: bool) -> None:
    m = MotorArray("MIS232", seed=0)
    m.write("P2", 5)
    m.store_program(f"jump_register register=P2 operator={op} value={value} line=3\n"
                    "set_output output=1 state=high\njump line=3\n")
    m.program_start()
    m.step(1)
    assert _reg(m, "OUTPUTS") == (0 if taken else 1)


@pytest.mark.statements("mis:9.7.18:1")
def test_wait_register_sees_it_as_the_firmware_updates_it() -> None:
    m = _run(_end("move_relative distance=409600 velocity=300 wait=no\n"
                  "wait_register register=P_IST operator=>= value=204800\n"
                  "set_output output=1 state=high\n"))
    p = []
    while _reg(m, "OUTPUTS") == 0:
        p.append(_reg(m, "P_IST"))
        m.step(1)
    assert p[-1] >= 204800 > p[-2]  # the first outer sample where P_IST got there


# --- §9.7.19 – §9.7.21 positions and zero search ------------------------------------------
@pytest.mark.statements("mis:9.7.19:1", "mis:9.7.20:1")
def test_save_and_set_position() -> None:
    m = _run(_end("move_relative distance=40960 velocity=600\nsave_position register=register2\n"
                  "set_position position=12345\n"))
    _until(m, lambda m: _reg(m, "P_IST") == 12345)
    assert _reg(m, "P2") == 40960 and _reg(m, "P_SOLL") == 12345
    m.step(100)
    assert _reg(m, "P_IST") == 12345  # no move: P_SOLL was set with it
    m = _run(_end("set_register register=P3 value=-5\nset_position position=register3\n"), 2)
    assert _reg(m, "P_IST") == -5 and _reg(m, "P_SOLL") == -5


@pytest.mark.statements("mis:9.7.21:1")
def test_zero_search_waits_until_done() -> None:
    home = -0.5
    m = MotorArray("MIS232", seed=0, home_position=home)
    m.write_many({"HOME_MASK": 1, "V_HOME": -3000, "P_HOME": 0, "STARTMODE": 2,
                  "IN_POSITION_COUNT": 0})
    m.store_program(_end("zero_search mode=sensor1\nset_output output=1 state=high\n"))
    m.program_start()
    m.step(2)
    assert _reg(m, "MODE_REG") == 13 and _reg(m, "OUTPUTS") == 0
    _until(m, lambda m: _reg(m, "OUTPUTS") == 1, 8000)
    assert _reg(m, "MODE_REG") == 2 and _reg(m, "STATUSBITS") & c.ST_ZERO_SEARCH_DONE


# --- §9.7.22 – §9.7.24 FastMAC and binary ---------------------------------------------------
@pytest.mark.statements("mis:9.7.22:1")
def test_fastmac_change_mode_and_activate_register() -> None:
    """§9.7.22: "the value in register no. 65 (V1) will be written to register no. 5"."""
    m = MotorArray("MIS232", seed=0)
    m.write_many({"V1": 4321, "T2": 300, "P8": 999, "A4": 5555})
    m.store_program(_end("fastmac mode=velocity register=velocity number=1\n"
                         "fastmac mode=passive register=torque number=2\n"
                         "fastmac mode=passive register=acceleration number=4\n"
                         "fastmac mode=position register=position number=8\n"))
    m.program_start()
    m.step(1)
    assert _reg(m, "V_SOLL") == 4321 and _reg(m, "RUN_CURRENT") == 300
    assert _reg(m, "A_SOLL") == 5555 and _reg(m, "P_SOLL") == 999
    assert _reg(m, "MODE_REG") == 2


@pytest.mark.statements("mis:8.2.21:3", "mis:9.7.23:1")
def test_fastmac_macro_command() -> None:
    """FastMac 3 (COMMAND 99, §8.2.21): P_IST = 0; FastMac 1: errors cleared."""
    m = MotorArray("MIS232", seed=0)
    m.write_many({"P_IST": 5000, "ERR_BITS": 8})
    m.store_program(_end("fastmac_command command=3\nfastmac_command command=1\n"))
    m.program_start()
    m.step(1)
    assert _reg(m, "P_IST") == 0 and _reg(m, "ERR_BITS") == 0 and _reg(m, "COMMAND") == 0


@pytest.mark.statements("mis:9.7.24:1")
def test_binary_command_runs_its_instruction() -> None:
    code = encode_command(parse_program("set_output output=6 state=high\n")[0]).hex()
    m = _run(_end(f"binary code={code}\n"), 1)
    assert _reg(m, "OUTPUTS") == 32


# --- §9.7.25 – §9.7.27 calculator and comparison ----------------------------------------------
@pytest.mark.statements("mis:9.7.25:1")
def test_calculator_left_to_right_in_32_bits() -> None:
    m = MotorArray("MIS232", seed=0)
    m.write_many({"V_SOLL": 100, "P2": 2147483647, "P3": -7})
    m.store_program(_end("calculate register=V_SOLL expression=V_SOLL+100*2\n"
                         "calculate register=P2 expression=P2+1\n"
                         "calculate register=P3 expression=P3/2\n"
                         "calculate register=P4 expression=P3*0-9/0\n"
                         "calculate register=A_SOLL expression=1000000\n"))
    m.program_start()
    m.step(1)
    assert _reg(m, "V_SOLL") == 400  # (100 + 100) * 2, not 100 + 200
    assert _reg(m, "P2") == -(2**31)  # "it will therefore become negative"
    assert _reg(m, "P3") == -3 and _reg(m, "P4") == 0
    assert _reg(m, "A_SOLL") == 500000  # stored within the register's range (§8.2.6)


@pytest.mark.parametrize(("op", "taken"), [(">=", True), ("<", False), ("=", False)])
@pytest.mark.statements("mis:9.7.27:1")
def test_jump_according_to_a_comparison(op: str, taken: bool) -> None:
    """§9.7.27's example: register 3 (P_SOLL) >= register 51 (P2)."""
    m = MotorArray("MIS232", seed=0)
    m.write_many({"P_SOLL": 10, "P2": 5})
    m.store_program(f"jump_compare register=3 operator={op} register2=51 line=3\n"
                    "set_output output=1 state=high\njump line=3\n")
    m.program_start()
    m.step(1)
    assert _reg(m, "OUTPUTS") == (0 if taken else 1)


# --- timing (§9.8) -----------------------------------------------------------------------------
@pytest.mark.statements("mis:9.8:2")
def test_lines_share_the_main_loop_time_between_outer_samples() -> None:
    """A counting loop of 2 lines (calculator of two operands 120 µs, jump 30 µs) runs
    1000/150 times per outer sample on average."""
    m = _run("calculate register=P2 expression=P2+1\njump line=1\n", 30)
    assert abs(_reg(m, "P2") - 30 * 1000 / 150) <= 1


# --- flash, power-on, control -------------------------------------------------------------------
@pytest.mark.statements("mis:9.1:1", "mis:9.1:2")
def test_program_survives_reset_and_starts_at_power_on_in_position_mode() -> None:
    m = MotorArray("MIS232", seed=0)
    m.write("STARTMODE", 1)
    m.store_program(_end("set_output output=2 state=high\n"))
    m.write("COMMAND", 267)  # reset the CPU (§8.2.22)
    assert _reg(m, "MODE_REG") == 2  # §9.1: always starts up in position mode
    assert m.program_status().name == "starting program"
    m.step(1)
    assert _reg(m, "OUTPUTS") == 2 and m.program_status().name == "running"
    m.reset()
    assert m.program_text() is not None and m.program_status().state == 9


@pytest.mark.statements("mis:8.2.68:3", "mis:9.1:3")
def test_setup_bit_1_keeps_the_program_from_starting() -> None:
    m = MotorArray("MIS232", seed=0)
    m.write_many({"SETUP_BITS": 2, "STARTMODE": 1})
    m.store_program(_end("set_output output=2 state=high\n"))
    m.write("COMMAND", 268)  # save in flash, then reset (§8.2.22)
    m.step(5)
    assert m.program_status().name == "stopped" and _reg(m, "OUTPUTS") == 0
    assert _reg(m, "MODE_REG") == 1


def test_malformed_program_is_refused_and_nothing_changes() -> None:
    m = MotorArray("MIS232", seed=0)
    good = _end("set_output output=2 state=high\n")
    m.store_program(good)
    regs = m.regs.copy()
    with pytest.raises(ProgramError, match=r"line 2, field velocity") as err:
        m.store_program("mode mode=position\nmove_relative distance=1 velocity=fast\n")
    assert (err.value.line, err.value.field) == (2, "velocity")
    with pytest.raises(ProgramError, match=r"line 1, field line"):
        m.store_program("jump line=7\n")
    assert m.program_text() == good and np.array_equal(m.regs, regs)


def test_stop_pause_step_restart() -> None:
    m = _run("set_register register=P2 value=1\nset_register register=P2 value=2\n"
             "set_register register=P2 value=3\nwait_ms time=10000\n")
    m.program_step()
    m.step(1)
    assert _reg(m, "P2") == 1 and m.program_status().name == "paused"
    m.program_step()
    m.step(1)
    assert _reg(m, "P2") == 2 and m.program_status().line == 3
    m.program_start()  # resumes
    m.step(1)
    assert _reg(m, "P2") == 3 and m.program_status().line == 4
    m.program_stop()
    m.write("P2", 0)
    m.step(3)
    assert _reg(m, "P2") == 0 and m.program_status().name == "stopped"
    m.program_restart()
    m.step(1)
    assert _reg(m, "P2") == 3


def test_motors_without_a_program_step_as_before() -> None:
    a = MotorArray("MIS232", n=2, seed=3)
    b = MotorArray("MIS232", n=2, seed=3)
    for m in (a, b):
        m.write("V_SOLL", 20000)
        m.write("MODE_REG", 1)
    b.store_program("mode mode=velocity\njump line=2\n", index=1)
    b.program_start(index=1)
    a.step(300)
    b.step(300)
    assert np.array_equal(a.regs, b.regs) and np.array_equal(a.state, b.state)


@pytest.mark.statements("mis:9.7.5:2")
def test_a_fatal_error_holds_the_program_at_its_move() -> None:
    """§9.7.5: after a fatal error the program stays at the move until the motor is reset."""
    m = _run(_end("move_relative distance=409600 velocity=300\nset_output output=1 "
                  "state=high\n"), 20)
    m.write("ERR_BITS", 1 << 6)  # temperature error: the motor stops and goes passive
    m.step(500)
    assert _reg(m, "MODE_REG") == 0 and m.program_status().line == 1
    assert _reg(m, "OUTPUTS") == 0


def _summed(data: bytes) -> bytes:
    return data + (sum(data) & 0xFFFF).to_bytes(2, "little")


def test_program_image_round_trip_and_flash_errors() -> None:
    """§18.2.10 states 10 (program data corrupted), 11 (checksum incorrect) and 6 (invalid
    instruction) of flash images; a good image runs."""
    m = MotorArray("MIS232", seed=0)
    m.store_program(_end("set_output output=3 state=high\n"))
    image = m.program_image()
    other = MotorArray("MIS232", seed=0)
    other.load_program_image(0, image)
    assert other.program_text() == m.program_text()
    other.program_start()
    other.step(1)
    assert _reg(other, "OUTPUTS") == 4
    bad_sum = image[:-2] + ((int.from_bytes(image[-2:], "little") + 1) & 0xFFFF).to_bytes(
        2, "little")
    garbage = b"\x01\x00\xee"  # one line of an unknown instruction code
    # one line: a binary command whose code (FFh) is no instruction
    binary = bytes([1, 0, list(SPECS).index("binary"), 1, 0xFF])
    for data, state in ((bad_sum, 11), (_summed(garbage), 10), (_summed(binary), 6)):
        other.load_program_image(0, data)
        other.program_start()
        other.step(1)
        assert other.program_status().state == state and other.program_status().error
    with pytest.raises(ValueError, match="4 … 3074 bytes"):
        other.load_program_image(0, b"\x00")
    with pytest.raises(ValueError, match="no stored program"):
        MotorArray("MIS232").program_start()


# --- user command 342 (§8.2.22: "Clear all flash sectors in the RXP area") ----------------
_KEPT = _end("set_register register=P2 value=1\n")


def _stored(n: int = 2, running: bool = True) -> MotorArray:
    m = MotorArray("MIS232", n=n, seed=0)
    m.store_program(_KEPT)
    if running:
        m.program_start()
        m.step(2)
    return m


def _program_of(m: MotorArray, i: int = 0) -> tuple[str | None, tuple]:
    s = m.program_status(i)
    return m.program_text(i), (s.state, s.line, s.error, s.checksum)


@pytest.mark.statements("mis:8.2.22:11")
def test_command_342_erases_the_stored_program() -> None:
    """Writing COMMAND 342 erases the program of the motors written (it stops, a reset no
    longer starts it); COMMAND reads 0 and the other motors keep theirs."""
    m = _stored()
    kept = _program_of(m, 1)
    m.write("COMMAND", 342, index=0)
    assert m.program_text(0) is None and m.program_status(0).name == "passive"
    assert m.program_image(0) == b"" and _reg(m, "COMMAND") == 0
    assert _program_of(m, 1) == kept
    m.write("MODE_REG", 0)
    m.write("COMMAND", c.CMD_RESET, index=0)
    assert m.program_text(0) is None and _reg(m, "MODE_REG") != c.POSITION


def test_command_342_refused_as_a_whole_keeps_the_program() -> None:
    """A transaction whose later register the firmware refuses (an active mode while ERR_BITS
    ≠ 0, §8.2.31) leaves the program stored and running as it was."""
    m = _stored()
    m.write("ERR_BITS", 1)
    before = _program_of(m, 0), m.regs.copy()
    for write in (m.write_many, m.write_raw_many):
        with pytest.raises(RegisterError):
            write({"COMMAND": 342, "MODE_REG": 2})
        assert _program_of(m, 0) == before[0] and np.array_equal(m.regs, before[1])
    m.step(1)  # the kept program still runs
    assert m.program_status(0).name == "running"


@settings(max_examples=30, deadline=None)
@given(command=st.sampled_from([0, 97, 267, 268, 269, 342, 399, 500]),
       mode=st.sampled_from([None, 0, 1, 2]), errors=st.booleans(), running=st.booleans())
def test_command_342_in_a_transaction_erases_all_or_nothing(command: int, mode: int | None,
                                                             errors: bool,
                                                             running: bool) -> None:
    """A transaction of a command and a mode request either goes through, and the program is
    gone exactly when the command was 342, or is refused and the program and the registers
    are as they were."""
    m = _stored(n=1, running=running)
    if errors:
        m.write("ERR_BITS", 1)
    before, regs = _program_of(m), m.regs.copy()
    values = {"COMMAND": command} if mode is None else {"COMMAND": command, "MODE_REG": mode}
    try:
        m.write_many(values)
    except RegisterError:
        assert _program_of(m) == before and np.array_equal(m.regs, regs)
        return
    assert (m.program_text() is None) == (command == 342)
