"""An independent sample of MAC50-141 manual statements, each checked through the public interface.

The sample was drawn before reading the project's tests or statement files: the candidate lines
are those of the MAC50, MAC95, MAC140, MAC141 technical manual's register chapter (3.x), function
blocks (4.1), modes (4.4) and monitoring functions (4.5) in the manual's text edition; 15 line
numbers were drawn with ``random.Random(1206050)`` (``choice`` over those lines) and for each the
nearest sentence stating a checkable behaviour was taken. Each test quotes its statement in the
project's own words and cites the manual section.

Candidate lines: 170-1571, 1591-1901, 1949-2649, 2650-2756.
Drawn line -> statement line (section): 1299 -> 1299 (3.2.126), 2348 -> 2348 (4.4.13),
232 -> 234 (3.2.1), 2143 -> 2143 (4.4.6), 1496 -> 1497 (3.2.153), 1865 -> 1865 (4.1.12),
1711 -> 1710-1713 (4.1.3), 1725 -> 1730 (4.1.4), 1270 -> 1267 (3.2.123), 1443 -> 1439
(3.2.143), 842 -> 839 (3.2.40), 2162 -> 2161 (4.4.6), 1982 -> 1983 (4.4), 1553 -> 1555-1562
(3.2.163), 203 -> 204 (3.1). Skipped as stating nothing checkable: 10 lines (headings, running
headers, cross-references).
"""

from __future__ import annotations

import numpy as np
import pytest

from jvl_gym import MotorArray

OUTER_HZ = 7812.5 / 15
COUNTS_PER_REV = 4096  # V_IST: 1 count/sample = 7.629 rpm (manual 3.2.12)
POLE_PAIRS = 2  # "the motor contains two pole-pairs" (manual 3.2.36, bit 11)


def _motor(**regs: float) -> MotorArray:
    m = MotorArray("MAC140", seed=0)
    for name, value in regs.items():
        m.write(name, value)
    return m


def _dominant_hz(signal: np.ndarray) -> float:
    x = signal.astype(float) - signal.mean()
    spectrum = np.abs(np.fft.rfft(x))
    return float(np.fft.rfftfreq(len(x), 1 / OUTER_HZ)[spectrum.argmax()])


def test_phase_currents_sinusoidal_with_frequency_set_by_speed() -> None:
    """MAC50-141 manual §3.2.126: when the motor rotates the three phase currents are sinusoidal
    with a frequency that depends on the rate of rotation (electrical frequency = pole pairs x
    revolutions per second)."""
    for v_soll in (160, 320):  # 10 and 20 counts/sample
        m = _motor(V_SOLL=v_soll, MODE_REG=1)
        m.set_input(load_torque=0.3)
        m.run(0.5)
        tr = m.trace(["IA_SOLL"], 1042)
        expected = v_soll / 16 * OUTER_HZ / COUNTS_PER_REV * POLE_PAIRS
        assert _dominant_hz(tr["IA_SOLL"][:, 0]) == pytest.approx(expected, abs=0.5)


@pytest.mark.statements("mac050_141:4.4.13:10")
def test_home1_runs_at_v_home() -> None:
    """MAC50-141 manual §4.4.13: in HOME1_MODE the velocity function block is given
    V_SOLL = V_HOME."""
    m = _motor(V_HOME=-320, T_HOME=300, MODE_REG=12)
    m.run(0.3)
    assert m.mode_name() == "HOME1_MODE"
    assert int(m.read("V_SOLL")[0]) == -320
    assert int(m.read("V_IST")[0]) == pytest.approx(-320 / 16, abs=1)


@pytest.mark.statements("mac050_141:3.2.1:2")
def test_prog_version_is_a_word() -> None:
    """MAC50-141 manual §3.2.1: PROG_VERSION has data format Word (16 bit unsigned,
    0..65535, manual §3.1)."""
    m = _motor()
    m.write("PROG_VERSION", 65535)
    assert int(m.read_raw("PROG_VERSION")[0]) == 65535
    with pytest.raises(ValueError):
        m.write("PROG_VERSION", -1)
    with pytest.raises(ValueError):
        m.write("PROG_VERSION", 65536)
    assert int(m.read_raw("PROG_VERSION")[0]) == 65535


@pytest.mark.statements("mac050_141:4.4.6:1")
def test_av_mode_speed_regulator_active() -> None:
    """MAC50-141 manual §4.4.6: in AV_MODE the speed regulator is active: the motor's speed
    follows the AV block's velocity (+/-10 V = +/-V_SOLL) and a load is met with torque."""
    m = _motor(V_SOLL=1600)
    m.set_input(analog_volts=5.0, load_torque=0.2)
    m.write("MODE_REG", 5)
    m.run(1.0)
    assert int(m.read("FNC_OUT")[0]) == pytest.approx(800, abs=2)
    assert int(m.read("V_IST")[0]) == pytest.approx(50, abs=2)
    assert int(m.read("VF_OUT")[0]) > 0


@pytest.mark.statements("mac050_141:3.2.153:1")
def test_motor_type_indicates_the_motor_type() -> None:
    """MAC50-141 manual §3.2.153: MOTOR_TYPE indicates the motor type (a distinct value for
    each of MAC50, MAC95, MAC140, MAC141)."""
    codes = [int(MotorArray(t).read("MOTOR_TYPE")[0]) for t in ("MAC050", "MAC095", "MAC140",
                                                                 "MAC141")]
    assert len(set(codes)) == 4


def test_gear_position_block_velocity_from_v_ext_and_gear_factor() -> None:
    """MAC50-141 manual §4.1.12: the gear position block makes its velocity profile from the
    measured external velocity V_EXT and the gear factor GEARF1/GEARF2, and stops at the geared
    position."""
    m = _motor(GEARF1=3, GEARF2=2, V_SOLL=2000, A_SOLL=50, MODE_REG=3)
    m.set_input(pulse_counts=10)
    m.run(0.5)
    assert int(m.read("V_EXT")[0]) == 10
    assert int(m.read("FNC_OUT")[0]) == 10 * 3 // 2 * 16
    m.set_input(pulse_counts=0)
    m.run(0.5)
    assert int(m.read("FNC_OUT")[0]) == 0


@pytest.mark.statements("mac050_141:4.1.3:3", "mac050_141:4.1.3:4")
def test_gear_follow_limits_velocity_to_v_soll_and_steps_to_a_soll() -> None:
    """MAC50-141 manual §4.1.3: the gear follow block follows V_EXT*GEARF1/GEARF2 but limits the
    velocity to +/-V_SOLL and each change to +/-A_SOLL."""
    m = _motor(GEARF1=3, GEARF2=2, V_SOLL=800, A_SOLL=50, MODE_REG=24)
    m.set_input(pulse_counts=100)  # 150 counts/sample wanted, 50 allowed
    fnc = m.trace(["FNC_OUT"], 60)["FNC_OUT"][:, 0].astype(int)
    assert np.abs(fnc).max() == 800
    assert np.abs(np.diff(np.concatenate([[0], fnc]))).max() <= 50
    m = _motor(GEARF1=3, GEARF2=2, V_SOLL=800, A_SOLL=50, MODE_REG=24)
    m.set_input(pulse_counts=10)
    m.run(0.5)
    assert int(m.read("FNC_OUT")[0]) == 10 * 3 * 16 // 2


@pytest.mark.statements("mac050_141:4.1.4:1")
def test_torque_block_ten_volts_is_t_soll() -> None:
    """MAC50-141 manual §4.1.4: the torque block converts the analogue input so that +/-10 V is
    +/-T_SOLL, written to VF_OUT."""
    for volts in (5.0, -10.0):
        m = _motor(T_SOLL=400)
        m.set_input(analog_volts=volts, load_torque=0.1 * np.sign(volts))
        m.write("MODE_REG", 4)
        m.run(0.05)
        assert int(m.read("VF_OUT")[0]) == pytest.approx(400 * volts / 10, abs=1)


@pytest.mark.statements("mac050_141:3.2.123:1", "mac050_141:3.2.122:3")
def test_aninp_offset_compensates_the_analogue_input() -> None:
    """MAC50-141 manual §3.2.123 (with §3.2.122): ANINP_OFFSET compensates an offset of the
    analogue input; ANINP is the measured voltage (+/-10 V = +/-1023) plus ANINP_OFFSET."""
    m = _motor(ANINP_OFFSET=100)
    m.run(0.02)
    assert int(m.read("ANINP")[0]) == 100
    m.set_input(analog_volts=-5.0)
    m.run(0.02)
    assert int(m.read("ANINP")[0]) == pytest.approx(-512 + 100, abs=1)


@pytest.mark.statements("mac050_141:3.2.143:1")
def test_eldeg_ist_unit_is_360_over_2048_electrical_degrees() -> None:
    """MAC50-141 manual §3.2.143: ELDEG_IST is the rotor's electrical angle in units of
    360/2048 electrical degrees (2048 per electrical turn, two pole pairs per revolution)."""
    m = _motor(V_SOLL=160, MODE_REG=1)
    m.run(0.3)
    tr = m.trace(["ELDEG_IST", "P_IST"], 500)
    eldeg = tr["ELDEG_IST"][:, 0].astype(float)
    assert eldeg.min() >= 0 and eldeg.max() <= 2047
    turns = np.unwrap(eldeg * 2 * np.pi / 2048) / (2 * np.pi)
    counts = tr["P_IST"][:, 0].astype(float)
    per_rev = (turns[-1] - turns[0]) / ((counts[-1] - counts[0]) / COUNTS_PER_REV)
    assert per_rev == pytest.approx(POLE_PAIRS, rel=0.01)


@pytest.mark.statements("mac050_141:3.2.40:2")
@pytest.mark.parametrize("v_home", [320, -320])
def test_sign_of_v_home_is_the_search_direction(v_home: int) -> None:
    """MAC50-141 manual §3.2.40: the sign of V_HOME gives the direction of the home search."""
    m = _motor(V_HOME=v_home, T_HOME=300, MODE_REG=12)
    m.run(0.3)
    assert np.sign(int(m.read("P_IST")[0])) == np.sign(v_home)


@pytest.mark.statements("mac050_141:4.4.6:5")
def test_av_mode_to_init_goes_via_stop_mode() -> None:
    """MAC50-141 manual §4.4.6: from AV_MODE a change to INIT_MODE always passes through
    STOP_MODE."""
    m = _motor(V_SOLL=1600)
    m.set_input(analog_volts=5.0)
    m.write("MODE_REG", 5)
    m.run(0.5)
    m.write("MODE_REG", 0)
    m.step(1)
    assert m.mode_name() == "STOP_MODE"
    m.run(1.0)
    assert m.mode_name() == "INIT_MODE"


@pytest.mark.statements("mac050_141:4.4:1")
@pytest.mark.parametrize("mode", [1, 2, 4])
def test_i2t_updated_in_all_modes(mode: int) -> None:
    """MAC50-141 manual §4.4 (and §3.2.16): I2T, the calculated coil load, is updated in all
    modes of operation."""
    m = _motor(V_SOLL=800, T_SOLL=600, P_SOLL=0)
    m.set_input(load_torque=0.5, analog_volts=5.0)
    m.write("MODE_REG", mode)
    m.run(0.5)
    assert int(m.read("I2T")[0]) > 0


@pytest.mark.statements("mac050_141:3.2.163:1", "mac050_141:3.2.163:2", "mac050_141:3.2.36:2",
                         "mac050_141:3.2.36:3")
def test_man_resync_sets_positions_to_p_new() -> None:
    """MAC50-141 manual §3.2.163: MAN_RESYNC without REL_RESYNC sets P_SOLL = P_IST = P_NEW and
    P_FNC = 16*P_NEW; with REL_RESYNC P_NEW is added; the bit resets itself."""
    m = _motor(P_NEW=12345, CNTRL_BITS=1 << 10)
    m.step(2)
    assert int(m.read("P_IST")[0]) == 12345
    assert int(m.read("P_SOLL")[0]) == 12345
    assert int(m.read("P_FNC")[0]) == 16 * 12345
    assert not int(m.read("CNTRL_BITS")[0]) & (1 << 10)
    m.write("P_NEW", 100)
    m.write("CNTRL_BITS", (1 << 10) | (1 << 12))
    m.step(2)
    assert int(m.read("P_IST")[0]) == 12445
    assert int(m.read("P_SOLL")[0]) == 12445
    assert int(m.read("P_FNC")[0]) == 16 * 12445


@pytest.mark.statements("mac050_141:3.1:2")
def test_fixed4_unit_is_one_4096th() -> None:
    """MAC50-141 manual §3.1: Fixed4 is 16-bit signed fixed point with unit 1/4096 (range
    -7.999756..+7.999756)."""
    m = _motor()
    m.write("KVFX4", 1.0)
    assert int(m.read_raw("KVFX4")[0]) == 4096
    m.write("KVFX4", -7.999756)
    assert int(m.read_raw("KVFX4")[0]) == -32767
    with pytest.raises(ValueError):
        m.write("KVFX4", 8.0)
