"""Injected hardware faults of the MIS (world input ``faults``, ERR_BITS positions) and the
consequences the manual gives each (MIS manual §7.2.5, §7.2.10–13, §7.2.17, §7.2.21, §8.2.24,
§8.2.31–32): the error bit, the motor passive, and the way back."""

from __future__ import annotations

import pytest

from jvl_gym import MotorArray
from jvl_gym.families.mis import constants as c

_RESET_ONLY = [(c.ERR_OUTPUT_DRIVER, "MIS232", 3), (c.ERR_INTERNAL, "MIS232", 3),
               (c.ERR_SINGLE_TURN_ENCODER, "MIS232", 3), (c.ERR_DRIVER_OVERLOAD, "MIS340", 3)]
_CLEARABLE = [(c.ERR_ENCODER_LOST_POSITION, "MIS232", 2), (c.ERR_ENCODER_REED, "MIS232", 4),
              (c.ERR_H4_ENCODER, "MIS232", 4), (c.ERR_STO_ALARM, "MIS232", 3)]


def _running(motor: str, encoder: int) -> MotorArray:
    m = MotorArray(motor, n=1, seed=0, encoder_type=encoder)
    m.write_many({"V_SOLL": 30000, "A_SOLL": 10000, "ACC_EMERG": 20000})
    m.write("MODE_REG", c.VELOCITY)
    m.step(100)
    return m


def _err(m: MotorArray) -> int:
    return int(m.read("ERR_BITS")[0])


def _fault_stops_the_motor(m: MotorArray, bit: int) -> None:
    m.set_input(faults=bit)
    m.step(1)
    assert _err(m) == bit | c.ERR_GENERAL
    m.step(30)  # the error stop with ACC_EMERG, then passive
    assert m.read("MODE_REG")[0] == c.PASSIVE and m.read("V_IST")[0] == 0
    with pytest.raises(Exception, match="ERR_BITS"):
        m.write("MODE_REG", c.VELOCITY)


@pytest.mark.statements("mis:8.2.31:5", "mis:7.2.5:1", "mis:8.2.31:10", "mis:7.2.10:1",
                        "mis:8.2.31:17", "mis:7.2.17:1", "mis:8.2.31:21", "mis:7.2.21:1",
                        "mis:8.2.32:9")
@pytest.mark.parametrize(("bit", "motor", "encoder"), _RESET_ONLY)
def test_faults_that_only_a_reset_clears(bit: int, motor: str, encoder: int) -> None:
    """§7.2.5 output driver (bit 2), §7.2.10 internal error (bit 7), §7.2.17 single turn encoder
    error (bit 14), §7.2.21 motor driver overload (bit 18, with WARN_BITS bit 8 "Driver
    overload"): "Motor is set in Passive mode", back only by a reset or power cycle."""
    m = _running(motor, encoder)
    _fault_stops_the_motor(m, bit)
    if bit == c.ERR_DRIVER_OVERLOAD:
        assert int(m.read("WARN_BITS")[0]) & c.WARN_DRIVER_OVERLOAD
    m.set_input(faults=0)
    m.write("ERR_BITS", 0)
    m.write("COMMAND", c.CMD_CLEAR_ERRORS)
    m.step(1)
    assert _err(m) == bit | c.ERR_GENERAL  # neither clears it
    m.write("COMMAND", c.CMD_RESET)
    m.step(1)
    assert _err(m) == 0
    m.write("MODE_REG", c.VELOCITY)


@pytest.mark.statements("mis:8.2.31:11", "mis:7.2.11:1", "mis:8.2.31:12", "mis:7.2.12:1",
                        "mis:8.2.31:18", "mis:8.2.31:22", "mis:8.2.24:9")
@pytest.mark.parametrize(("bit", "motor", "encoder"), _CLEARABLE)
def test_faults_that_clearing_the_error_bits_clears(bit: int, motor: str, encoder: int) -> None:
    """§7.2.11 encoder lost position (bit 8), §7.2.12 reed error (bit 9) of the H3/H4, §8.2.31
    bit 15 H4 internal encoder error, bit 27 STO alarm: passive; "clear the error bit(s) in
    register 35" once the fault is gone (a fault still present sets it again). §8.2.24 bit 9
    "Internal encoder error" with an encoder error."""
    m = _running(motor, encoder)
    _fault_stops_the_motor(m, bit)
    status = int(m.read("STATUSBITS")[0])
    encoder_error = bool(bit & c.ERR_ENCODER_ANY)
    assert bool(status & c.ST_ENCODER_ERROR) == encoder_error
    assert bool(status & c.ST_ENCODER_OK) == (not encoder_error)
    m.write("ERR_BITS", 0)
    m.step(1)
    assert _err(m) == bit | c.ERR_GENERAL  # the fault still there
    m.set_input(faults=0)
    m.write("ERR_BITS", 0)
    m.step(1)
    assert _err(m) == 0
    assert int(m.read("STATUSBITS")[0]) & c.ST_ENCODER_ERROR == 0
    m.write("MODE_REG", c.VELOCITY)


@pytest.mark.statements("mis:7.2.11:1", "mis:7.2.12:1")
def test_preset_command_354_clears_the_lost_position_and_reed_errors() -> None:
    """§7.2.11/§7.2.12: "Reset the position (special command 354 in register 24)"."""
    m = _running("MIS232", 4)
    m.set_input(faults=c.ERR_ENCODER_LOST_POSITION | c.ERR_ENCODER_REED)
    m.step(50)
    m.set_input(faults=0)
    m.write("P_NEW", 1000)
    m.write("COMMAND", c.CMD_PRESET_POSITION)
    assert _err(m) == 0 and m.read("P_IST")[0] == 1000


@pytest.mark.statements("mis:8.2.31:13", "mis:7.2.13:1", "mis:8.2.31:16", "mis:7.2.16:1")
@pytest.mark.parametrize(("bit", "encoder"), [(c.ERR_ENCODER_COM, 2),
                                              (c.ERR_EXTERNAL_MEMORY, 3)])
def test_errors_found_only_at_start_up_can_be_cleared(bit: int, encoder: int) -> None:
    """§7.2.13 encoder COM error (bit 10, H3/H4), §7.2.16 external memory (bit 13): "This error
    will only be set during startup and can be cleared afterwards. Then the motor operation
    will be the same"."""
    m = _running("MIS232", encoder)
    m.set_input(faults=bit)
    m.step(20)
    assert _err(m) == 0 and m.read("V_IST")[0] == 30000  # not while running
    m.write("MODE_REG", c.PASSIVE)
    m.step(400)
    m.write("COMMAND", c.CMD_RESET)
    assert _err(m) == bit | c.ERR_GENERAL
    m.step(5)
    m.write("ERR_BITS", 0)
    m.step(5)
    assert _err(m) == 0  # the fault still there, the error stays cleared
    m.write_many({"V_SOLL": 30000, "A_SOLL": 10000, "MODE_REG": c.VELOCITY})
    m.step(100)
    assert m.read("V_IST")[0] == 30000


@pytest.mark.statements("mis:8.2.31:15", "mis:7.2.15:1")
def test_closed_loop_fault_sets_its_error_when_the_closed_loop_is_activated() -> None:
    """§7.2.15: "The error only occurs when activating the closed loop"; passive; back after a
    calibration and a reset ("the motor can be reset by writing 267 to register 24")."""
    m = _running("MIS232", 3)
    m.set_input(faults=c.ERR_CLOSED_LOOP)
    m.step(20)
    assert _err(m) == 0  # open loop: no error
    m.write("SETUP_BITS", c.SETUP_CLOSED_LOOP)
    m.step(1)
    assert _err(m) == c.ERR_CLOSED_LOOP | c.ERR_GENERAL
    m.step(30)
    assert m.read("MODE_REG")[0] == c.PASSIVE
    m.set_input(faults=0)
    m.write("ERR_BITS", 0)
    assert _err(m) == c.ERR_CLOSED_LOOP | c.ERR_GENERAL
    m.write("COMMAND", c.CMD_RESET)
    assert _err(m) == 0


def test_faults_the_motor_cannot_have_are_refused_and_change_nothing() -> None:
    """An encoder fault needs its encoder option (§7.2.11–13: H3/H4, §7.2.17: H2/H4, §8.2.31 bit
    15: H4), the driver overload an SMC85/MIS34x/MIS43x (§8.2.31 bit 18); other bits are no
    injectable fault."""
    m = MotorArray(["MIS232", "MIS340"], n=2, seed=0)  # both with the H2 (code 3)
    before = m.inputs.copy()
    for bad, index, why in [(c.ERR_ENCODER_LOST_POSITION, None, "encoder option"),
                            (c.ERR_H4_ENCODER, 1, "encoder option"),
                            (c.ERR_DRIVER_OVERLOAD, 0, "SMC85"),
                            (c.ERR_FOLLOW, None, "injectable"),
                            (c.ERR_STO, None, "within")]:
        with pytest.raises(ValueError, match=why):
            m.set_input(index=index, faults=bad)
        with pytest.raises(ValueError, match=why):
            m.set_input(index=index, faults=bad, supply_volts=30.0)
    assert (m.inputs == before).all()
    m.set_input(index=1, faults=c.ERR_DRIVER_OVERLOAD | c.ERR_SINGLE_TURN_ENCODER)
