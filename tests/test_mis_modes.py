"""MIS modes and functions beyond the profile: gear mode, turn table, zero search, COMMAND,
STATUSBITS, errors, limits, under-voltage, the sample buffer and the write rules (MIS manual
§5.9, §5.10, §5.12, §6.4, §6.5, §8.2)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from jvl_gym import MotorArray
from jvl_gym.families.mis import constants as c
from jvl_gym.motor.array import ModeError
from jvl_gym.registers import RegisterError


def _motor(**regs: int) -> MotorArray:
    m = MotorArray("MIS232", n=1, seed=0)
    m.write_many(regs)
    return m


# --- gear mode (§8.2.3, §8.2.13) --------------------------------------------------------
@pytest.mark.statements("mis:8.2.3:7", "mis:8.2.13:3", "mis:6.4.1:2")
def test_gear_one_input_step_moves_200_counts() -> None:
    """§8.2.13: GEAR1 = 409600, GEAR2 = 2048: one step applied moves the motor 200 counts;
    2048 counts one revolution."""
    m = _motor(GEAR1=409600, GEAR2=2048, V_SOLL=100000, A_SOLL=100000)
    m.write("MODE_REG", 3)
    m.set_input(pulse_counts=1)
    m.step(1)
    m.set_input(pulse_counts=0)
    m.step(20)
    assert m.read("P_SOLL")[0] == 200 and m.read("P_IST")[0] == 200
    m.set_input(pulse_counts=8)
    m.step(256)  # 2048 input counts in all
    m.set_input(pulse_counts=0)
    m.step(300)
    assert m.read("P_IST")[0] == 409600 + 200
    assert m.read("EXT_ENCODER")[0] == 2049


@given(st.lists(st.integers(-50, 50), min_size=1, max_size=40),
       st.integers(1, 10**6), st.integers(-5000, 5000).filter(lambda g: g != 0))
@settings(max_examples=25, deadline=None)
@pytest.mark.statements("mis:8.2.3:7", "mis:8.2.13:2", "mis:8.2.14:1", "mis:6.4.1:1")
def test_gear_carries_the_remainder(pulses: list[int], g1: int, g2: int) -> None:
    """§8.2.3: input × GEAR1/GEAR2 is added to P_SOLL; any remainder is used next time: over
    any pulse sequence P_SOLL = floor(total × GEAR1 / GEAR2)."""
    m = _motor(GEAR1=g1, GEAR2=g2, V_SOLL=0)
    m.write("MODE_REG", 3)
    for k in pulses:
        m.set_input(pulse_counts=k)
        m.step(1)
    total = sum(pulses)
    expected = (total * g1) // g2
    assert m.read("P_SOLL")[0] == ((expected + 2**31) % 2**32) - 2**31


# --- turn table (§5.12) -----------------------------------------------------------------
def _table(mode: int, **regs: int) -> MotorArray:
    return _motor(TURNTABLE_MODE=mode, MIN_P_IST=0, MAX_P_IST=409599, V_SOLL=300000,
                  A_SOLL=100000, IN_POSITION_COUNT=0, **regs)


@pytest.mark.statements(
    "mis:8.2.27:3", "mis:8.2.70:2", "mis:5.12.5:2", "mis:5.12.1:1", "mis:5.12.1:6",
    "mis:5.12.5:3", "mis:5.12.6:4")
def test_turn_table_multiturn_cw_example() -> None:
    """§5.12.1, mode 4: start 0, target 970000: P_SOLL = 150800 (the remainder of
    970000/409600) after a CW move of 970000 counts; P_IST stays in range and TURNTAB_COUNT
    counts the wraps."""
    m = _table(c.TT_MULTI_CW)
    m.write("MODE_REG", 2)
    m.write("P_SOLL", 970000)
    assert m.read("P_SOLL")[0] == 150800
    tr = m.trace(["P_IST"], 1500)
    assert tr["P_IST"].min() >= 0 and tr["P_IST"].max() <= 409599
    assert m.read("P_IST")[0] == 150800
    assert m.read("TURNTAB_COUNT")[0] == 2
    # within the detent's microstep error at the standby current
    assert m.rotor_counts[0] == pytest.approx(970000, abs=600)


@pytest.mark.statements(
    "mis:8.2.26:3", "mis:8.2.27:3", "mis:8.2.70:1", "mis:8.2.70:2", "mis:5.12.5:2",
    "mis:5.12.1:1", "mis:5.12.1:2", "mis:5.12.1:3", "mis:5.12.1:5", "mis:5.12.1:7", "mis:5.12.3:2")
def test_turn_table_directions_and_limits() -> None:
    m = _table(c.TT_CW, P_SOLL=250000)
    m.write("MODE_REG", 2)
    m.step(400)
    m.write("P_SOLL", 150000)  # always CW: round through MAX, 309600 counts
    m.step(600)
    assert m.read("P_IST")[0] == 150000
    assert m.rotor_counts[0] == pytest.approx(250000 + 309600, abs=600)
    m.write("P_SOLL", -1000)  # limited to the range (modes 1–3)
    assert m.read("P_SOLL")[0] == 0
    s = _table(c.TT_SHORTEST)
    s.write("MODE_REG", 2)
    s.write("P_SOLL", 250000)  # shorter CCW: 159600 counts back
    s.step(600)
    assert s.read("P_IST")[0] == 250000
    assert s.rotor_counts[0] == pytest.approx(-159600, abs=600)
    assert s.read("TURNTAB_COUNT")[0] == -1
    w = _table(c.TT_MULTI_CCW)
    w.write("P_SOLL", 12345678)  # §5.12.1 mode 5: above the range → MAX
    assert w.read("P_SOLL")[0] == 409599
    with pytest.raises(RegisterError, match="TURNTABLE_MODE"):
        w.write("TURNTABLE_MODE", 6)


# --- zero search (§6.5) -----------------------------------------------------------------
@pytest.mark.parametrize("mode", [13, 14])
@pytest.mark.statements(
    "mis:8.2.3:10", "mis:8.2.3:11", "mis:8.2.24:8", "mis:8.2.33:3", "mis:8.2.35:2", "mis:6.5.1:1")
def test_zero_search_finds_the_sensor_and_goes_to_startmode(mode: int) -> None:
    home = -0.5  # rad: the home input is active at or below it
    m = MotorArray("MIS232", n=1, seed=0, home_position=home)
    m.write_many({"HOME_MASK": 1, "V_HOME": -3000, "P_HOME": 0, "STARTMODE": 2,
                  "IN_POSITION_COUNT": 0})
    m.write("MODE_REG", mode)
    for _ in range(80):  # the home_position sensor drives the HOME_MASK input
        m.step(100)
        if m.read("MODE_REG")[0] != mode:
            break
    assert m.read("MODE_REG")[0] == 2
    assert m.read("STATUSBITS")[0] & c.ST_ZERO_SEARCH_DONE
    zero = m.rotor_counts[0] - m.read("P_IST")[0]  # where P_IST = 0 is on the shaft
    assert zero == pytest.approx(home * 409600 / (2 * np.pi), abs=600)
    assert m.read("ERR_BITS")[0] == 0


@pytest.mark.statements(
    "mis:8.2.3:13", "mis:8.2.33:3", "mis:8.2.74:2", "mis:6.5.2:2", "mis:6.5.8:2", "mis:2.2.2:2")
def test_zero_search_on_an_external_input() -> None:
    m = _motor(HOME_MASK=0b100, V_HOME=3000, STARTMODE=1, V_SOLL=0, IN_POSITION_COUNT=0)
    m.write("MODE_REG", 13)
    m.step(300)
    assert m.read("MODE_REG")[0] == 13
    m.set_input(digital_inputs=0b100)
    m.step(300)
    assert m.read("MODE_REG")[0] == 1 and m.read("STATUSBITS")[0] & c.ST_ZERO_SEARCH_DONE


def test_zero_search_times_out() -> None:
    m = _motor(HOME_MASK=1, V_HOME=-3000, V_HOME_TIMEOUT=200, STARTMODE=1)
    m.write("MODE_REG", 13)
    m.step(400)
    assert m.read("ERR_BITS")[0] & c.ERR_ZERO_SEARCH_TIMEOUT
    assert m.read("MODE_REG")[0] == c.PASSIVE


# --- COMMAND (§8.2.21) ------------------------------------------------------------------
def test_fastmac_commands() -> None:
    m = _motor(P1=5000, V1=12345, A1=777, T1=300, P7=-2000, P_NEW=42)
    m.write("COMMAND", 108)
    assert m.read("P_SOLL")[0] == 5000 and m.read("V_SOLL")[0] == 12345
    assert m.read("A_SOLL")[0] == 777 and m.read("RUN_CURRENT")[0] == 300
    m.write("P_IST", 100)
    m.write("COMMAND", 113)  # P_SOLL = P_IST + P7
    assert m.read("P_SOLL")[0] == -1900
    m.write("COMMAND", 119)  # P_IST = P_SOLL = encoder = P_NEW
    assert m.read("P_IST")[0] == m.read("P_SOLL")[0] == m.read("ENCODER_POS")[0] == 42
    m.write("COMMAND", 120)
    assert m.read("P_IST")[0] == m.read("P_SOLL")[0] == 84
    m.write("COMMAND", 99)
    assert m.read("P_IST")[0] == 0 and m.read("COMMAND")[0] == 0
    m.write("COMMAND", 101)
    assert m.read("V_SOLL")[0] == 0
    m.step(3)
    assert m.read("ENCODER_POS")[0] == 84  # the encoder keeps its new zero


@pytest.mark.statements(
    "mis:8.2.3:1", "mis:8.2.21:1", "mis:8.2.31:4", "mis:8.2.31:24", "mis:7.2.4:1", "mis:7.2.4:2")
def test_clear_errors_command_and_modes_refused_while_in_error() -> None:
    m = _motor(FLWERRMAX=1000, P_SOLL=4_000_000, V_SOLL=100000, A_SOLL=1000)
    m.set_input(load_torque=5.0)
    m.write("MODE_REG", 2)
    m.step(200)
    assert m.read("ERR_BITS")[0] & c.ERR_FOLLOW
    assert m.read("MODE_REG")[0] == 0
    with pytest.raises(ModeError, match="ERR_BITS"):
        m.write("MODE_REG", 2)
    m.write("COMMAND", 97)
    assert m.read("ERR_BITS")[0] == 0
    m.set_input(load_torque=0.0)
    m.write("MODE_REG", 2)  # accepted again
    with pytest.raises(ModeError, match="safe mode"):
        m.write("MODE_REG", 15)
    with pytest.raises(ModeError):
        m.write("MODE_REG", 5)
    assert m.read("MODE_REG")[0] == 2


# --- status bits (§8.2.24) --------------------------------------------------------------
@pytest.mark.statements(
    "mis:8.2.24:3", "mis:8.2.24:4", "mis:8.2.24:5", "mis:8.2.24:6", "mis:8.2.24:7",
    "mis:8.2.24:20", "mis:8.2.24:22")
def test_status_bits_during_a_move() -> None:
    m = _motor(P_SOLL=409600, V_SOLL=30000, A_SOLL=3000, D_SOLL=0)
    m.write("MODE_REG", 2)
    st = m.trace(["STATUSBITS"], 1500)["STATUSBITS"][:, 0]
    acc = np.flatnonzero(st & c.ST_ACCELERATING)
    dec = np.flatnonzero(st & c.ST_DECELERATING)
    at = np.flatnonzero(st & c.ST_AT_VELOCITY)
    assert acc.size and at.size and dec.size
    assert acc.max() <= at.min() <= at.max() < dec.min()
    assert st[-1] & c.ST_IN_POSITION and st[-1] & c.ST_IN_PHYSICAL_POSITION
    assert st[-1] & c.ST_IN_TARGET_POSITION and st[-1] & c.ST_ENCODER_OK
    assert not st[-1] & c.ST_GENERAL_ERROR


# --- limits and under-voltage (§5.9, §5.10) ---------------------------------------------
@pytest.mark.statements(
    "mis:8.2.31:6", "mis:5.9.3:2", "mis:5.9.4:1", "mis:5.9.4:2", "mis:6.6:1", "mis:7.2.6:1")
def test_software_position_limit_stops_with_an_error() -> None:
    m = _motor(MAX_P_IST=100000, MIN_P_IST=-100000, V_SOLL=20000, ACC_EMERG=50000)
    m.write("MODE_REG", 1)
    m.step(500)
    assert m.read("ERR_BITS")[0] & c.ERR_POSITION_LIMIT
    assert m.read("WARN_BITS")[0] & c.WARN_POS_LIMIT_SEEN
    assert m.read("MODE_REG")[0] == 0
    assert m.read("P_IST")[0] < 100000 + 20000


@pytest.mark.statements(
    "mis:8.2.31:7", "mis:8.2.32:6", "mis:8.2.47:1", "mis:8.2.47:2", "mis:8.2.48:2",
    "mis:8.2.68:16", "mis:8.2.68:17", "mis:5.10:1", "mis:5.10:2", "mis:6.6:1", "mis:7.2.7:1")
def test_low_bus_voltage_actions() -> None:
    m = _motor(V_SOLL=10000, SETUP_BITS=(1 << 21) | (1 << 22))
    m.write("MODE_REG", 1)
    m.step(50)
    m.set_input(supply_volts=10.0)  # below MIN_BUSVOL = 565 (15 V)
    m.step(200)
    assert m.read("WARN_BITS")[0] & c.WARN_LOW_BUS
    assert m.read("ERR_BITS")[0] & c.ERR_LOW_BUS
    assert m.read("MODE_REG")[0] == 0
    assert m.read("BUSVOL")[0] == round(10.0 / 26.525e-3)


# --- sample buffer (§8.2.60–63) ---------------------------------------------------------
@pytest.mark.statements(
    "mis:8.2.60:1", "mis:8.2.60:2", "mis:8.2.60:3", "mis:8.2.61:2", "mis:8.2.63:2")
def test_sample_buffer_records_registers() -> None:
    m = _motor(SAMPLE1=10, SAMPLE2=12, SAMPLE3=0, REC_CNT=50, S_TIME=2, V_SOLL=5000,
               V_START=10000)
    m.write("MODE_REG", 1)
    m.write("S_CONTROL", 2)
    m.step(150)
    assert m.read("S_CONTROL")[0] == 0
    buf = m.sample_buffer()
    assert buf["P_IST"].shape == (1, 50)
    assert np.all(np.diff(buf["P_IST"][0]) > 0)
    assert np.all(buf["V_IST"][0] == 5000)
    assert np.all(buf["SAMPLE3"] == 0)


# --- write rules ------------------------------------------------------------------------
def test_bad_writes_change_nothing() -> None:
    m = _motor(V_SOLL=1000)
    with pytest.raises(RegisterError):
        m.write_many({"V_SOLL": 2000, "STARTMODE": 11})
    assert m.read("V_SOLL")[0] == 1000
    with pytest.raises(RegisterError):
        m.write("V_SOLL", 300001)
    with pytest.raises(RegisterError):
        m.write("V_IST", 5)
    with pytest.raises(ValueError, match="encoder_type"):
        MotorArray("MIS232", n=1, encoder_type=7)
    with pytest.raises(ValueError, match="digital_inputs"):
        m.set_input(digital_inputs=300)
    assert m.read("V_SOLL")[0] == 1000


# --- power-on, safe mode, flash (§8.2.3, §8.2.33, §8.2.37) --------------------------------
@pytest.mark.statements("mis:8.2.3:12", "mis:8.2.33:1", "mis:8.2.33:2")
def test_startmode_from_a_setup_and_flash_in_safe_mode() -> None:
    m = MotorArray("MIS232", n=1, setup={"STARTMODE": 1, "V_SOLL": 5000, "V_START": 10000})
    assert m.read("MODE_REG")[0] == 1
    m.step(10)
    assert m.read("V_IST")[0] == 5000
    with pytest.raises(RegisterError, match="STARTMODE"):
        MotorArray("MIS232", n=1, setup={"STARTMODE": 11})
    m.write("V_SOLL", 7000)
    with pytest.raises(ModeError, match="safe mode"):
        m.write_flash()
    m.enter_safe_mode()
    with pytest.raises(ModeError, match="by command only"):
        m.write("MODE_REG", 1)
    m.write_flash()  # saved, then reset: STARTMODE 1 at V_SOLL 70 RPM
    assert m.read("MODE_REG")[0] == 1 and m.read("V_SOLL")[0] == 7000
    assert m.read("P_IST")[0] == 0


@pytest.mark.statements("mis:8.2.37:2", "mis:6.5.2:1")
def test_homemode_starts_a_zero_search_at_power_on() -> None:
    m = MotorArray("MIS232", n=1, setup={"HOMEMODE": 13, "STARTMODE": 2})
    assert m.read("MODE_REG")[0] == 13


@pytest.mark.statements(
    "mis:8.2.32:2", "mis:8.2.32:4", "mis:8.2.68:13", "mis:8.2.73:2", "mis:5.9.2:1", "mis:5.9.2:2",
    "mis:5.9.4:1", "mis:5.9.5:1", "mis:6.6:4")
def test_hardware_limit_input_and_its_warning_bits() -> None:
    m = _motor(PL_MASK=0b100, V_SOLL=5000, V_START=10000, SETUP_BITS=1 << 17)
    m.write("MODE_REG", 1)
    m.step(20)
    m.set_input(digital_inputs=0b100)
    m.step(5)
    warn = m.read("WARN_BITS")[0]
    assert warn & c.WARN_POS_LIMIT and warn & c.WARN_POS_LIMIT_SEEN
    assert m.read("ERR_BITS")[0] == 0  # SETUP_BITS bit 17: no error, the motor stops
    held = m.read("P_IST")[0]
    m.step(20)  # and does not move on into the limit
    assert m.read("V_IST")[0] == 0 and m.read("MODE_REG")[0] == 1
    assert m.read("P_IST")[0] == held
    m.write("V_SOLL", -5000)  # away from it
    m.step(5)
    assert m.read("V_IST")[0] == -5000
    m.set_input(digital_inputs=0)
    m.step(2)
    warn = m.read("WARN_BITS")[0]
    assert not warn & c.WARN_POS_LIMIT and warn & c.WARN_POS_LIMIT_SEEN


@pytest.mark.statements(
    "mis:8.2.38:1", "mis:8.2.38:2", "mis:8.2.38:3", "mis:8.2.49:2", "mis:5.8.1:1")
def test_absolute_encoder_register() -> None:
    m = MotorArray("MIS232", n=2, encoder_type=np.array([3, 4]))
    m.write_many({"V_SOLL": 100000, "A_SOLL": 10000, "MODE_REG": 1})
    m.run(0.6)  # beyond one revolution
    absolute = m.read("ABSENCODER")
    assert 0 <= absolute[0] < 409600 < absolute[1]
    assert absolute[1] - absolute[0] == pytest.approx(409600 * (absolute[1] // 409600), abs=100)
    assert m.read("ENCODER_TYPE").tolist() == [3, 4]


@pytest.mark.statements("mis:8.2.34:2", "mis:8.2.36:2", "mis:6.5.1:3")
def test_torque_zero_search_against_an_end_stop() -> None:
    """§6.5.7: with closed loop and current control the search runs into a mechanical stop
    until the current reaches T_HOME; that point is P_HOME; then to position 0 and STARTMODE
    (the simulator's reading: a search 13 with HOME_MASK = 0, module ``firmware.homing``)."""
    wall = -1.0  # rad
    m = MotorArray("MIS232", n=1, seed=0, end_stop_low=wall)
    m.write_many({"SETUP_BITS": c.SETUP_CLOSED_LOOP | c.SETUP_CURRENT_CONTROL,
                  "V_HOME": -3000, "T_HOME": 1024, "P_HOME": -20000, "STARTMODE": 2,
                  "IN_POSITION_COUNT": 0})
    m.write("MODE_REG", 13)
    for _ in range(100):
        m.step(100)
        if m.read("MODE_REG")[0] != 13:
            break
    m.step(500)
    assert m.read("MODE_REG")[0] == 2 and m.read("STATUSBITS")[0] & c.ST_ZERO_SEARCH_DONE
    assert m.read("P_IST")[0] == 0
    wall_counts = wall * 409600 / (2 * np.pi)
    assert m.rotor_counts[0] == pytest.approx(wall_counts + 20000, abs=1000)
    assert m.read("ERR_BITS")[0] == 0


@given(st.dictionaries(st.sampled_from(["V_SOLL", "A_SOLL", "P_SOLL", "V_START", "D_SOLL",
                                        "RUN_CURRENT", "STARTMODE", "TURNTABLE_MODE",
                                        "MODE_REG", "COMMAND", "GEAR2"]),
                       st.integers(-(2**33), 2**33), min_size=1, max_size=6))
@settings(max_examples=60, deadline=None)
def test_a_write_is_all_or_nothing(values: dict[str, int]) -> None:
    """Any set of register values: either every one is stored (as the rules store it) or a
    RegisterError leaves every register and the state as they were."""
    m = _motor(V_SOLL=1234)
    regs, state = m.regs.copy(), m.state.copy()
    try:
        m.write_many(values)
    except RegisterError:
        np.testing.assert_array_equal(m.regs, regs)
        np.testing.assert_array_equal(m.state, state)
        return
    for name, value in values.items():
        if name not in ("COMMAND", "MODE_REG"):
            assert m.read(name)[0] == value or name == "P_SOLL"


def test_user_commands_reset_save_and_emergency_stops() -> None:
    m = _motor(V_SOLL=20000, V_START=1000, A_SOLL=1000, ACC_EMERG=2000)
    m.write("MODE_REG", 1)
    m.step(300)
    with pytest.raises(RegisterError, match="passive or safe"):
        m.write("COMMAND", 268)
    m.write("COMMAND", 398)  # emergency stop with ACC_EMERG, then passive
    v = m.trace(["V_IST", "MODE_REG"], 150)
    assert np.diff(v["V_IST"][:50, 0]).tolist() == [-200] * 49
    assert v["MODE_REG"][-1, 0] == 0
    m.write_many({"MODE_REG": 1, "V_SOLL": 5000})
    m.step(50)
    m.write("COMMAND", 399)  # without deceleration
    assert m.read("MODE_REG")[0] == 0
    angle = m.position_rad[0]
    m.write("STARTMODE", 2)
    m.write("COMMAND", 268)  # save, reset: registers from flash, the rotor where it was
    assert m.read("MODE_REG")[0] == 2 and m.read("V_SOLL")[0] == 5000
    assert m.read("P_IST")[0] == 0 and m.position_rad[0] == angle
    m.step(200)
    assert abs(m.position_rad[0] - angle) < 0.01  # no jump of the field at the reset
