"""The MAC800 follow error in its velocity modes (register overview, registers 20 and 22): a
blocked rotor makes FLWERR grow while the profile runs on, and FLWERRMAX stops the motor (as
the MAC050–141 does in its velocity modes, its manual 3.2.20: the follow error there detects
"abnormal loading of the motor or blockages")."""

from __future__ import annotations

import pytest

from jvl_gym import MotorArray
from jvl_gym.families.mac800 import constants as c
from jvl_gym.families.mac800 import units as u

#: the velocity modes: velocity, analogue velocity, analogue velocity with dead band, velocity
#: with analogue torque limit
VELOCITY_MODES = [c.VELOCITY_MODE, c.ANALOG_VELOCITY_MODE, c.ANALOG_VELOCITY_DEADBAND_MODE,
                  c.VELOCITY_ANALOG_TORQUE_MODE]


@pytest.mark.statements("mac800:1.2:20", "mac800:1.2:21")
@pytest.mark.parametrize("mode", VELOCITY_MODES)
def test_flwerrmax_stops_a_blocked_rotor_in_the_velocity_modes(mode: int) -> None:
    """The rotor held within ±0.01 rad by end stops: FLWERR grows with the profile's run, and
    when it passes FLWERRMAX (12 000 counts) ERR_STAT bit 1 (FLW_ERR) is set and the motor is
    stopped (passive)."""
    m = MotorArray("MAC800", n=1, seed=0, end_stop_low=-0.01, end_stop_high=0.01)
    m.set_input(analog_volts=10.0)
    m.write_many({"FLWERRMAX": 12000, "V_SOLL": round(u.rpm_to_v_soll(300)), "MODE_REG": mode})
    m.run(0.05)
    assert 0 < m.read("FLWERR")[0] <= 12000
    assert not m.read("ERR_STAT")[0] & c.FLW_ERR
    m.run(1.0)
    assert m.read("ERR_STAT")[0] & c.FLW_ERR
    assert m.read("MODE_REG")[0] == c.PASSIVE_MODE


@pytest.mark.statements("mac800:1.2:20")
def test_follow_error_of_a_free_motor_in_velocity_mode_stays_small() -> None:
    """A free motor at constant speed follows its profile: the follow error is the lag the
    velocity loop built up while accelerating and does not grow; FLWERRMAX does not trip."""
    m = MotorArray("MAC800", n=1, seed=0)
    m.write_many({"FLWERRMAX": 12000, "V_SOLL": round(u.rpm_to_v_soll(1000)), "MODE_REG": 1})
    m.run(0.5)
    lag = m.read("FLWERR")[0]
    assert 0 < lag < 12000
    m.run(1.0)
    assert abs(m.read("FLWERR")[0] - lag) <= 2
    assert not m.read("ERR_STAT")[0] & c.FLW_ERR
    assert m.read("MODE_REG")[0] == c.VELOCITY_MODE
