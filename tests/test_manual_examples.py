"""The manual's worked examples (docs/model.md §3) as tests."""

from __future__ import annotations

import numpy as np
import pytest

from jvl_gym.families.mac050_141 import constants as c
from jvl_gym.families.mac050_141.table import TABLE as MAC050_141
from jvl_gym.registers import RegisterRangeError
from jvl_gym.registers.formats import from_raw, to_raw


@pytest.mark.statements("mac050_141:3.2.5:1", "mac050_141:3.2.5:2")
def test_v_soll_1600_is_762_9_rpm():  # manual 3.2.5
    assert c.v_soll_to_rpm(1600) == pytest.approx(762.9, abs=0.05)


@pytest.mark.statements("mac050_141:3.2.6:1", "mac050_141:3.2.6:2")
def test_a_soll_160_is_39731_rpm_per_s():  # manual 3.2.6 (the manual rounds 520.8 Hz)
    assert c.a_soll_to_rpm_per_s(160) == pytest.approx(39731, rel=2e-4)


@pytest.mark.statements("mac050_141:3.2.12:1", "mac050_141:3.2.12:4")
def test_v_ist_100_is_762_9_rpm():  # manual 3.2.12
    assert c.v_ist_to_rpm(100) == pytest.approx(762.9, abs=0.05)
    assert c.v_ist_to_rpm(1) == pytest.approx(7.629, abs=1e-3)  # the register's unit


@pytest.mark.statements("mac050_141:3.2.13:1")
def test_kvout_example_3_9():  # manual 3.2.13
    kvout = (17.3e-6 + 50e-6) / 17.3e-6
    reg = MAC050_141.lookup("KVOUT")
    stored = float(from_raw(reg, to_raw(reg, kvout)))
    assert stored == pytest.approx(3.9, abs=0.01)
    assert abs(stored - kvout) <= 0.5 / 256


@pytest.mark.statements("mac050_141:3.2.3:1", "mac050_141:4.1.2:8")
def test_670_relative_moves_before_p_soll_leaves_range():  # manual 4.1.2
    reg = MAC050_141.lookup("P_SOLL")
    to_raw(reg, 670 * 100000)  # still inside ±67E6
    with pytest.raises(RegisterRangeError):
        to_raw(reg, 671 * 100000)
    # P_FNC after 670 such moves: 670·1600000 = 1.072E9, inside the LongInt range
    assert 670 * 100000 * 16 < 2**31 - 1


@pytest.mark.statements("mac050_141:4.1.8:2")
def test_stop_speed_is_300_rpm():  # manual 4.1.8
    assert c.v_ist_to_rpm(c.STOP_SPEED_COUNTS) == pytest.approx(300.0)


@pytest.mark.parametrize(("a_soll", "direction"), [(10, 1), (10, -1), (25, 1)])
@pytest.mark.statements("mac050_141:3.2.24:1", "mac050_141:3.2.24:3", "mac050_141:4.4.3:4",
                        "mac050_141:4.5.5:1")
def test_held_motor_fncerr_grows_by_the_profile_velocity_each_sample(a_soll, direction):
    """Manual 3.2.24: a motor held away from its position in P_MODE while the function
    generator asks for a velocity of 10 has its profile corrected by −10 at each sample, so
    |FNCERR| grows by 10 per sample although the position error stays constant.

    The shaft is held by a Coulomb friction far above the torque limit T_SOLL; from standstill
    the function block asks for one A_SOLL step of velocity per sample, and the speed
    regulator's correction (docs/model.md §8) takes exactly that back."""
    from jvl_gym import MotorArray

    motor = MotorArray("MAC140", coulomb_friction=50.0)
    motor.write_many({"T_SOLL": 300, "V_SOLL": 1000, "A_SOLL": a_soll,
                      "P_SOLL": direction * 200000})
    motor.write("MODE_REG", c.P_MODE)
    motor.step(300)
    fncerr = []
    for _ in range(20):
        motor.step(1)
        fncerr.append(int(motor.read("FNCERR")[0]))
    assert int(motor.read("P_IST")[0]) == 0  # held: the position error is constant
    assert set(map(int, (fncerr[1:] - np.asarray(fncerr[:-1])))) == {-direction * a_soll}
