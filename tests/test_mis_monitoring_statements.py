"""MIS monitoring registers as the register descriptions state them (MIS manual §8.2):
ACTUAL_TORQUE in passive and active mode (§8.2.112), TICKS counting on from a written value
(§8.2.107), EXT_ENCODER counting the external encoder input in every mode (§8.2.101)."""

from __future__ import annotations

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
