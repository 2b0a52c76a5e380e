"""MIS monitoring registers as the register descriptions state them (MIS manual §8.2):
ACTUAL_TORQUE in passive and active mode (§8.2.112), TICKS counting on from a written value
(§8.2.107), EXT_ENCODER counting the external encoder input in every mode (§8.2.101) and
EXT_ENCODER_VEL its velocity (§8.2.102), FILTERSTATUS (§8.2.56), the position-limit error of a
motor standing at its limit (§7.2.6), the in-physical-position output (§5.6.3), the standby
current's ceiling per motor type (§5.1.4), S_CONTROL = 1 initialising the sample system
(§8.2.63) and the under-voltage count LOWBUSCVI_CNT (§8.2.130)."""

from __future__ import annotations

import numpy as np
import pytest

from jvl_gym import MotorArray
from jvl_gym.families.mis import constants as c


def _motor(**regs: int) -> MotorArray:
    m = MotorArray("MIS232", n=1, seed=0)
    m.write_many(regs)
    return m


@pytest.mark.statements("mis:8.2.112:1", "mis:8.2.112:2")
def test_actual_torque_reads_zero_in_passive_mode_and_full_when_active() -> None:
    """§8.2.112: "In passive mode = 0%"; "In active mode without current control enabled =
    100 %" (2047), with the closed loop on."""
    m = _motor(SETUP_BITS=c.SETUP_CLOSED_LOOP)
    assert m.read("ACTUAL_TORQUE")[0] == 0  # at power-on
    m.step(5)
    assert m.read("MODE_REG")[0] == c.PASSIVE
    assert m.read("ACTUAL_TORQUE")[0] == 0  # and after the first milliseconds
    m.write_many({"V_SOLL": 0, "MODE_REG": c.VELOCITY})
    m.step(5)
    assert m.read("ACTUAL_TORQUE")[0] == 2047
    m.write("MODE_REG", c.PASSIVE)
    m.step(5)
    assert m.read("ACTUAL_TORQUE")[0] == 0


@pytest.mark.statements("mis:8.2.107:1", "mis:8.2.107:2")
def test_ticks_count_one_per_millisecond_on_from_a_written_value() -> None:
    """§8.2.107: TICKS (R/W) increments by one count per millisecond from zero at power-on; a
    written value is where the count goes on from, and it wraps at 2³²."""
    m = _motor()
    m.step(7)
    assert m.read("TICKS")[0] == 7
    m.write("TICKS", 1_000_000)
    m.step(5)
    assert m.read("TICKS")[0] == 1_000_005
    m.write("TICKS", 2**32 - 2)
    m.step(3)
    assert m.read("TICKS")[0] == 1


@pytest.mark.statements("mis:8.2.101:1")
@pytest.mark.parametrize("mode", [c.PASSIVE, c.VELOCITY, c.POSITION, c.GEAR])
def test_ext_encoder_counts_the_external_input_in_every_mode(mode: int) -> None:
    """§8.2.101: EXT_ENCODER "counts the external encoder input" (no mode named); outside gear
    mode the input moves nothing."""
    m = _motor(GEAR1=1, GEAR2=1, V_SOLL=0, EXT_ENCODER=100)
    m.write("MODE_REG", mode)
    m.set_input(pulse_counts=7)
    m.step(10)
    assert m.read("EXT_ENCODER")[0] == 170
    if mode != c.GEAR:
        assert m.read("P_SOLL")[0] == 0
    else:
        assert m.read("P_SOLL")[0] == 70


@pytest.mark.statements("mis:8.2.78:1", "mis:5.6.1:1")
def test_error_output_is_set_while_an_error_is_present() -> None:
    """The decision between §5.6.1 (the error output active in normal operation, passive on
    an error) and §8.2.78 ("The Error Output will be set when any error is set"): §8.2.78 —
    the ERROR_MASK pin (an output by IOSETUP bits 8–15) is set while ERR_BITS ≠ 0."""
    m = _motor(IOSETUP=1 << 8, ERROR_MASK=1)
    m.step(2)
    assert m.read("OUTPUTS")[0] & 1 == 0
    m.write("ERR_BITS", c.ERR_GENERAL | c.ERR_FOLLOW)
    m.step(2)
    assert m.read("OUTPUTS")[0] & 1 == 1
    m.write("COMMAND", c.CMD_CLEAR_ERRORS)
    m.step(2)
    assert m.read("OUTPUTS")[0] & 1 == 0


@pytest.mark.statements("mis:8.2.102:2")
def test_ext_encoder_vel_is_the_count_of_the_last_16_ms() -> None:
    """§8.2.102: EXT_ENCODER_VEL, in counts per 16 ms, "measured every 16ms"."""
    m = _motor()
    m.set_input(pulse_counts=5)
    m.step(32)
    assert m.read("EXT_ENCODER_VEL")[0] == 80
    m.set_input(pulse_counts=-3)
    m.step(15)
    assert m.read("EXT_ENCODER_VEL")[0] == 80  # not measured again yet
    m.step(1)
    assert m.read("EXT_ENCODER_VEL")[0] == -48
    m.set_input(pulse_counts=0)
    m.step(16)
    assert m.read("EXT_ENCODER_VEL")[0] == 0


@pytest.mark.statements("mis:8.2.56:2")
def test_filter_status_tells_confidence_and_slope_errors_each_second() -> None:
    """§8.2.56: each second, bit k when more than half the samples of the last second of input
    k + 1 fell outside the confidence limits, bit 8 + k when more than half were slope
    limited."""
    m = _motor(AFZUP_CONFMAX=2000, AFZUP_MAXSLOPE=10,  # 2.44 V; 12 mV per 10 ms sample
               AFZUP_WRITEBITS=255)  # to every input (§8.2.50)
    m.set_input(analog1=4.0, analog2=2.0)  # IO1 outside confidence; IO2 climbs slope-limited
    m.step(999)
    assert m.read("FILTERSTATUS")[0] == 0  # not updated before the second is over
    m.step(1)
    assert m.read("FILTERSTATUS")[0] == 0b1 | (0b10 << 8)
    m.set_input(analog1=0.0, analog2=0.0)  # IO1 where its filter stayed; IO2 falls, limited
    m.step(1000)
    assert m.read("FILTERSTATUS")[0] == 0b10 << 8
    m.step(1000)  # IO2 reached 0 after the first second
    assert m.read("FILTERSTATUS")[0] == 0


@pytest.mark.statements("mis:7.2.6:2")
@pytest.mark.parametrize("case", ["input, position mode", "software limit, velocity mode"])
def test_a_motor_at_its_limit_asked_towards_it_gets_the_position_limit_error(case: str) -> None:
    """§7.2.6: the error is set when a limit sensor is active or P_IST is at MIN_P_IST /
    MAX_P_IST: a motor standing at its limit that is sent on towards it stops with the error
    and is made passive; sent the other way, it moves."""
    if case.startswith("input"):
        m = MotorArray("MIS232", n=2, seed=0)
        m.write_many({"PL_MASK": 1, "P_SOLL": np.array([20000, -20000])})
        m.set_input(digital_inputs=1)  # the positive limit input active
        m.write("MODE_REG", c.POSITION)
    else:
        m = MotorArray("MIS232", n=2, seed=0)
        m.write_many({"MIN_P_IST": 0, "MAX_P_IST": 100000,  # P_IST = 0 is at MIN_P_IST
                      "V_SOLL": np.array([-2000, 2000])})
        m.write("MODE_REG", c.VELOCITY)
    m.step(50)
    assert m.read("ERR_BITS")[0] & c.ERR_POSITION_LIMIT
    assert m.read("MODE_REG")[0] == c.PASSIVE and m.read("P_IST")[0] == 0
    assert m.read("ERR_BITS")[1] == 0 and m.read("P_IST")[1] != 0


@pytest.mark.statements("mis:5.6.3:1")
def test_in_position_output_shows_physical_position_with_inpos_mask_bit_8() -> None:
    """§5.6.3: INPOS_MASK bit 8 puts the in-physical-position flag (the encoder within
    IN_POSITION_WINDOW of P_SOLL) on the in-position output instead of the in-position flag."""
    m = MotorArray("MIS232", n=2, seed=0)
    m.write_many({"IOSETUP": 1 << 8, "INPOS_MASK": np.array([0x001, 0x101]), "P_SOLL": 20000,
                  "IN_POSITION_WINDOW": 100, "IN_POSITION_COUNT": 0, "STANDBY_TIME": 65535})
    m.write("MODE_REG", c.POSITION)
    m.step(300)
    assert (m.read("OUTPUTS") & 1).tolist() == [1, 1]  # in position, physically too
    m.set_input(load_torque=0.6 * m.pull_out_torque(1.0)[0])  # pushes the rotor aside
    m.step(200)
    assert (np.abs(m.read("ENCODER_POS") - 20000) > 100).all()
    assert (m.read("OUTPUTS") & 1).tolist() == [1, 0]


@pytest.mark.statements("mis:5.1.4:1")
def test_standby_current_of_an_mis34x_tops_out_at_6_amperes() -> None:
    """§5.1.4: an MIS34x runs on up to 9000 mA, but its standby current goes to 6000 mA only
    (1022 units of 5.87 mA); an MIS23x's standby current goes as far as its running current."""
    peak = np.sqrt(2.0) * 5.87e-3
    for motor, largest in (("MIS340", 1022), ("MIS232", 1022)):
        m = MotorArray(motor, n=1, seed=0)
        m.write_many({"STANDBY_CURRENT": 1533, "STANDBY_TIME": 10, "RUN_CURRENT": 1533})
        m.write("MODE_REG", c.POSITION)
        m.step(50)
        assert m.read("STATUSBITS")[0] & c.ST_STANDBY_CURRENT
        assert m.current_amplitude[0] == pytest.approx(largest * peak, rel=1e-3), motor


@pytest.mark.statements("mis:8.2.63:3")
def test_s_control_1_initialises_the_sample_system() -> None:
    """§8.2.63: "A value of one will initialize the sample system": a recording under way
    stops and its samples are dropped; 2 then starts a new sequence from an empty buffer."""
    m = _motor(SAMPLE1=10, REC_CNT=100, S_TIME=1)
    m.write("S_CONTROL", 2)
    m.step(20)
    assert m.sample_buffer()["P_IST"].shape == (1, 20)
    m.write("S_CONTROL", 1)
    m.step(20)
    assert m.sample_buffer()["P_IST"].shape == (1, 0)
    assert m.read("S_CONTROL")[0] == 1
    m.write("S_CONTROL", 2)
    m.step(10)
    assert m.sample_buffer()["P_IST"].shape == (1, 10)


@pytest.mark.statements("mis:8.2.130:2")
def test_low_bus_error_waits_for_lowbuscvi_cnt_measurements_in_a_row() -> None:
    """§8.2.130: LOWBUSCVI_CNT is the "Number of times in a row the voltage can be too low
    before error is set", one measurement per 50 µs: with 100, a dip of 5 ms (100
    measurements) gives the warning only, a sixth millisecond the error (SETUP_BITS bit 21)."""
    m = _motor(SETUP_BITS=1 << 21, LOWBUSCVI_CNT=100)
    m.set_input(supply_volts=10.0)  # below MIN_BUSVOL (15 V)
    m.step(5)
    assert m.read("WARN_BITS")[0] & c.WARN_LOW_BUS and m.read("ERR_BITS")[0] == 0
    m.set_input(supply_volts=48.0)
    m.step(1)  # the count starts again
    m.set_input(supply_volts=10.0)
    m.step(5)
    assert m.read("ERR_BITS")[0] == 0
    m.step(1)
    assert m.read("ERR_BITS")[0] & c.ERR_LOW_BUS
