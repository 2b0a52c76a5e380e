"""The zero-search time-out of the MIS (MIS manual §7.2.19, §6.5.9, §8.2.126): the error is set
and the motor is set back in the mode it was in before the search started, where it stays
(docs/families/mis-sim.md, "Zero search time-out": the decision between the two readings)."""

from __future__ import annotations

import pytest

from jvl_gym import MotorArray
from jvl_gym.families.mis import constants as c


@pytest.mark.statements("mis:7.2.19:1", "mis:7.2.19:2", "mis:8.2.31:1", "mis:6.5.9:1")
@pytest.mark.parametrize("startmode", [c.PASSIVE, c.VELOCITY])
def test_time_out_sets_the_motor_back_in_the_mode_before_the_search(startmode: int) -> None:
    """A search started in position mode times out after V_HOME_TIMEOUT ms: ERR_BITS bit 16
    (and bit 0), and the motor is in position mode again, whatever STARTMODE says; it stays
    there (no error stop to passive) and does not move until the error is cleared (§8.2.31),
    then it goes back to P_SOLL."""
    m = MotorArray("MIS232", n=1, seed=0)
    m.write_many({"HOME_MASK": 1, "V_HOME": -3000, "V_HOME_TIMEOUT": 200,
                  "STARTMODE": startmode, "IN_POSITION_COUNT": 0, "MODE_REG": c.POSITION})
    m.step(50)
    m.write("MODE_REG", c.ZERO_SEARCH_1)
    m.step(150)
    assert m.read("MODE_REG")[0] == c.ZERO_SEARCH_1
    m.step(100)
    err = m.read("ERR_BITS")[0]
    assert err & c.ERR_ZERO_SEARCH_TIMEOUT and err & c.ERR_GENERAL
    assert m.read("MODE_REG")[0] == c.POSITION
    m.step(100)
    held = m.read("P_IST")[0]
    assert held < -1000  # where the search's run ended
    m.step(400)
    assert m.read("MODE_REG")[0] == c.POSITION and m.read("P_IST")[0] == held
    assert m.read("ERR_BITS")[0] & c.ERR_ZERO_SEARCH_TIMEOUT
    m.write("COMMAND", c.CMD_CLEAR_ERRORS)
    m.step(500)
    assert m.read("MODE_REG")[0] == c.POSITION and m.read("P_IST")[0] == 0


@pytest.mark.statements("mis:6.5.9:1", "mis:7.2.19:1")
def test_a_power_on_search_that_times_out_goes_on_in_startmode() -> None:
    """§6.5.9: "If the time out is passed the motor will return to startup mode" — the search
    of HOMEMODE at power-on has STARTMODE as its previous mode; the motor stays in it."""
    m = MotorArray("MIS232", n=1, seed=0)
    m.write_many({"HOME_MASK": 1, "V_HOME": -3000, "V_HOME_TIMEOUT": 200, "V_SOLL": 5000,
                  "HOMEMODE": c.ZERO_SEARCH_1, "STARTMODE": c.VELOCITY})
    m.write("COMMAND", c.CMD_SAVE_RESET)  # HOMEMODE and STARTMODE act from power-on
    assert m.read("MODE_REG")[0] == c.ZERO_SEARCH_1
    m.step(300)
    assert m.read("ERR_BITS")[0] & c.ERR_ZERO_SEARCH_TIMEOUT
    assert m.read("MODE_REG")[0] == c.VELOCITY
    m.step(500)
    assert m.read("MODE_REG")[0] == c.VELOCITY and m.read("V_IST")[0] == 0
    m.write("COMMAND", c.CMD_CLEAR_ERRORS)
    m.step(500)
    assert m.read("V_IST")[0] == 5000


@pytest.mark.statements("mis:8.2.31:1")
def test_other_errors_still_stop_the_motor_and_make_it_passive() -> None:
    """Only the time-out sets the motor back; a follow error (ERR_BITS bit 1) stops the motor
    with ACC_EMERG and makes it passive (§8.2.28, §8.2.31)."""
    m = MotorArray("MIS232", n=1, seed=0)
    m.write_many({"FLWERRMAX": 1000, "P_SOLL": 4_000_000, "V_SOLL": 100000, "A_SOLL": 1000})
    m.set_input(load_torque=5.0)
    m.write("MODE_REG", c.POSITION)
    m.step(300)
    assert m.read("ERR_BITS")[0] & c.ERR_FOLLOW
    assert m.read("MODE_REG")[0] == c.PASSIVE
