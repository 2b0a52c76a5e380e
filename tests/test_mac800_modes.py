"""MAC800 modes (register 2) beyond velocity: position, gear, zero searches, analogue modes,
START_MODE, CNTRL_BITS and the sample buffer; the default filter's step response."""

from __future__ import annotations

import numpy as np
import pytest

from jvl_gym import MotorArray
from jvl_gym.families.mac800 import constants as c
from jvl_gym.families.mac800 import units as u


@pytest.mark.parametrize("motor", ["MAC800", "MAC400"])
def test_default_filter_is_well_damped(motor: str) -> None:
    """The default main filter on the default motor: the closed loop of the sampled model
    (speed measured as the mean over a sample) has its poles well inside the unit circle and
    damped (ζ > 0.7); in the simulator a V_SOLL step at the default A_SOLL overshoots by at
    most 5 % at every speed up to 1000 RPM and settles within ±10 RPM in 0.2 s."""
    m = MotorArray(motor, n=1, seed=0)
    cfg = m.motor_configs[0]
    b = (cfg.peak_torque / 1023 / cfg.rotor_inertia / u.SAMPLE_HZ**2 * u.COUNTS_PER_REV
         / (2 * np.pi) * 16)
    x6, x5, y5 = (m.read(k)[0] for k in ("KVFX6", "KVFX5", "KVFY5"))
    vb4, vb3 = m.read("KVB4")[0], m.read("KVB3")[0]
    kff = m.read("KFF5")[0]
    assert (kff, y5) == (1.0, 1.0) and vb4 + vb3 == 1.0  # unit DC gains: no speed offset
    # (z − 1)²·z² + b·(z + 1)/2·(x6·z + x5)·(vb4·z + vb3) = 0
    poles = np.roots(np.polyadd(np.polymul([1, -2, 1], [1, 0, 0]),
                                b * np.polymul([0.5, 0.5],
                                               np.polymul([x6, x5], [vb4, vb3]))))
    assert np.abs(poles).max() < 0.9
    zeta = [-np.log(abs(z)) / np.hypot(np.log(abs(z)), np.angle(z)) for z in poles if z != 0]
    assert min(zeta) > 0.7
    for target in (100.0, 300.0, 500.0, 1000.0):
        m = MotorArray(motor, n=1, seed=0)
        m.write_many({"V_SOLL": round(u.rpm_to_v_soll(target)), "MODE_REG": 1})
        rpm = m.trace(["speed_rpm"], 300)["speed_rpm"][:, 0]
        assert rpm.max() <= 1.05 * target
        assert np.all(np.abs(rpm[154:] - target) < 10.0)


@pytest.mark.statements("mac800:reg2:4", "mac800:reg3:1", "mac800:reg8:1")
def test_position_mode_reaches_p_soll() -> None:
    m = MotorArray("MAC800", n=1, seed=0, load_inertia=2e-4)
    m.write_many({"V_SOLL": 5541, "A_SOLL": 360, "P_SOLL": 100000, "MODE_REG": 2})
    m.run(2.0)
    assert abs(m.read("P_IST")[0] - 100000) <= 2
    assert m.read("P_FUNC")[0] == 100000


@pytest.mark.statements("mac800:reg2:5", "mac800:reg8:1", "mac800:reg14:1", "mac800:reg14:2",
                        "mac800:reg15:1", "mac800:reg39:1", "mac800:reg39:8", "mac800:reg163:1")
def test_gear_mode_follows_the_pulse_input() -> None:
    m = MotorArray("MAC800", n=1, seed=0)
    m.write_many({"GEARF_1": 3, "GEARF_2": 2, "P_SOLL": 0, "MODE_REG": 3})
    m.set_input(pulse_counts=10)
    m.step(770)
    m.set_input(pulse_counts=0)
    m.run(0.5)
    assert m.read("P_FUNC")[0] == 770 * 10 * 3 // 2
    assert abs(m.read("P_IST")[0] - 11550) <= 10
    m.write("HW_SETUP", c.INVXDIR)
    m.set_input(pulse_counts=10)
    m.step(10)
    assert m.read("V_EXT")[0] == -10


@pytest.mark.statements("mac800:reg2:1", "mac800:reg2:11", "mac800:reg38:1", "mac800:reg41:1",
                        "mac800:reg42:2")
def test_torque_zero_search_then_start_mode() -> None:
    m = MotorArray("MAC800", n=1, seed=0, end_stop_low=-0.5, end_stop_high=100.0)
    m.write_many({"V_HOME": -300, "T_HOME": 200, "P_HOME": 1000, "START_MODE": 2,
                  "MODE_REG": 12})
    m.run(3.0)
    assert m.read("HOME_MODE")[0] & c.HOME_DONE
    assert m.read("MODE_REG")[0] == 2
    assert abs(m.read("P_IST")[0] - 1000) < 20
    assert m.position_rad[0] < -0.49


@pytest.mark.parametrize("mode", [13, 14])
@pytest.mark.statements("mac800:reg2:12", "mac800:reg2:13", "mac800:reg42:2")
def test_sensor_zero_search(mode: int) -> None:
    m = MotorArray("MAC800", n=1, seed=0, home_position=2.0, coulomb_friction=0.2)
    m.write_many({"V_HOME": 600, "T_HOME": 100, "P_HOME": 0, "MODE_REG": mode})
    m.run(4.0)
    assert m.read("HOME_MODE")[0] & c.HOME_DONE
    assert m.read("MODE_REG")[0] == 0 and m.speed_rpm[0] == 0.0  # START_MODE 0: passive
    # the zero is at the sensor: P_IST counts from there; sensor type 1 meets the edge at
    # V_HOME (within two samples' travel), type 2 leaves it at V_HOME/64
    zero_rad = m.position_rad[0] - m.read("P_IST")[0] * c.RAD_PER_COUNT
    travel = 600 / 16 * c.RAD_PER_COUNT
    assert zero_rad == pytest.approx(2.0, abs=2 * travel if mode == 13 else travel / 16)


@pytest.mark.statements("mac800:reg9:1", "mac800:reg36:10")
def test_index_home() -> None:
    m = MotorArray("MAC800", n=1, seed=0, home_position=2.0, index_angle=0.3,
                   coulomb_friction=0.2)
    m.write_many({"V_HOME": 600, "T_HOME": 100, "P_HOME": 0, "CNTRL_BITS": c.INDEX_HOME,
                  "MODE_REG": 13})
    m.run(4.0)
    zero_rad = m.position_rad[0] - m.read("P_IST")[0] * c.RAD_PER_COUNT
    assert zero_rad == pytest.approx(0.3, abs=0.002)  # the index nearest to the sensor
    assert m.read("INDEX_OFFSET")[0] == pytest.approx((2.0 - 0.3) / c.RAD_PER_COUNT, abs=80)


@pytest.mark.statements("mac800:reg37:1", "mac800:reg42:1")
def test_power_on_zero_search_and_start_mode() -> None:
    m = MotorArray("MAC800", n=1, seed=0, home_position=1.0,
                   setup={"HOME_MODE": 13, "START_MODE": 1, "V_HOME": 600, "V_SOLL": 277,
                          "KFF5": 1.0, "KVB4": 1.0, "KVFX6": 0.1073, "KVFX5": -0.0998,
                          "KVFY5": 1.0, "KIFX2": 3.621, "KIFX1": -3.057, "KIFY1": 1.0,
                          "KIB1": 1.0, "AMPLITUDE": 776})
    assert m.read("MODE_REG")[0] == 13
    m.run(3.0)
    assert m.read("MODE_REG")[0] == 1
    assert m.speed_rpm[0] == pytest.approx(100.0, rel=0.05)


@pytest.mark.statements("mac800:reg2:6", "mac800:reg2:7")
def test_analog_torque_and_velocity_modes() -> None:
    m = MotorArray("MAC800", n=2, seed=0)
    m.set_input(analog_volts=[5.0, -5.0])
    m.write_many({"T_SOLL": 400, "MODE_REG": 4}, 0)
    m.write_many({"V_SOLL": 2771, "MODE_REG": 5}, 1)
    m.step(5)
    assert m.read("VF_OUT")[0] == round(1024 * 400 / 2047)
    m.run(0.5)
    assert m.speed_rpm[1] == pytest.approx(-500.0 * 1024 / 2047 * 2, rel=0.02)


@pytest.mark.statements("mac800:reg2:14", "mac800:reg2:15")
def test_dead_band_and_velocity_torque_limit() -> None:
    m = MotorArray("MAC800", n=2, seed=0)
    m.set_input(analog_volts=[0.5, 2.0])
    m.write_many({"V_SOLL": 2771, "MODE_REG": 16}, 0)
    m.write_many({"V_SOLL": 2771, "T_SOLL": 1000, "MODE_REG": 17}, 1)
    m.set_input(1, load_torque=5.0)
    m.run(0.5)
    assert abs(m.speed_rpm[0]) < 1.0  # inside the dead band
    assert abs(m.read("VF_OUT")[1]) <= round(1000 * 410 / 2047) + 1


@pytest.mark.statements("mac800:reg2:20")
def test_analog_to_position() -> None:
    m = MotorArray("MAC800", n=1, seed=0)
    m.write_many({"POS0": 0, "POS1": 20000, "V_SOLL": 2771, "MODE_REG": 21})
    m.run(0.5)
    assert m.read("P_SOLL")[0] == 0
    m.set_input(analog_volts=8.0)
    m.run(1.5)
    assert m.read("P_SOLL")[0] == 20000 and abs(m.read("P_IST")[0] - 20000) < 10


@pytest.mark.statements("mac800:reg36:1", "mac800:reg36:2", "mac800:reg36:3", "mac800:reg36:4",
                        "mac800:reg158:1")
def test_sample_buffer_and_rewind() -> None:
    m = MotorArray("MAC800", n=1, seed=0)
    m.write_many({"SAMPLE1": 10, "SAMPLE2": 12, "V_SOLL": 277, "MODE_REG": 1})
    m.write("CNTRL_BITS", c.RECORDBIT)
    m.step(20)
    assert m.read("REC_CNT")[0] == 20
    buf = m.sample_buffer(0)
    assert buf["P_IST"].shape == (20,) and buf["P_IST"][-1] == m.read("P_IST")[0]
    m.write("CNTRL_BITS", c.REWINDBIT | c.RECINNERBIT | c.RECORDBIT)
    m.step(3)
    assert m.read("REC_CNT")[0] == 3 * c.INNER_PER_OUTER


@pytest.mark.statements("mac800:reg4:1", "mac800:reg36:1", "mac800:reg36:8")
def test_syncposman_and_syncposauto() -> None:
    m = MotorArray("MAC800", n=1, seed=0)
    m.write_many({"P_NEW": 5000, "CNTRL_BITS": c.SYNCPOSMAN})
    m.step()
    assert m.read("P_IST")[0] == 5000 and m.read("P_SOLL")[0] == 5000
    assert m.read("CNTRL_BITS")[0] & c.SYNCPOSMAN == 0
    m.write("MODE_REG", 2)
    m.run(0.2)
    assert abs(m.read("P_IST")[0] - 5000) < 3
