"""The MAC800 register overview's unit examples (§1.2, registers 5, 6, 12) in the simulator."""

from __future__ import annotations

import numpy as np
import pytest

from jvl_gym import MotorArray
from jvl_gym.families.mac800 import units as u
from jvl_gym.families.mac800.motors import Mac800MotorArray


@pytest.fixture(scope="module")
def motor() -> MotorArray:
    return MotorArray("MAC800", n=1, seed=0)


def test_motor_array_of_the_family() -> None:
    m = MotorArray("MAC800", n=1)
    assert isinstance(m, Mac800MotorArray)
    assert isinstance(MotorArray("MAC400", n=1), Mac800MotorArray)


@pytest.mark.statements("mac800:reg2:3", "mac800:reg5:1", "mac800:reg5:2")
def test_v_soll_277_is_100_rpm_at_the_shaft() -> None:
    """Register 5: "To obtain 100 RPM, V_SOLL must be set to 277"."""
    m = MotorArray("MAC800", n=1, seed=0)
    m.write_many({"V_SOLL": 277, "MODE_REG": 1})
    m.run(0.4)
    rpm = m.trace(["speed_rpm"], 770)["speed_rpm"][:, 0]  # one second
    assert rpm.mean() == pytest.approx(100.0, rel=0.01)
    assert np.all(np.abs(rpm - 100.0) < 5.0)


@pytest.mark.statements("mac800:reg2:3", "mac800:reg6:1", "mac800:reg6:2")
def test_a_soll_360_ramps_the_profile_at_100000_rpm_per_s() -> None:
    """Register 6: "To obtain 100000 RPM/s, A_SOLL must be set to 360"; the velocity function
    block's output FNC_OUT ramps by A_SOLL per sample."""
    m = MotorArray("MAC800", n=1, seed=0)
    m.write_many({"A_SOLL": 360, "V_SOLL": round(u.rpm_to_v_soll(3000)), "MODE_REG": 1})
    f = m.trace(["FNC_OUT"], 20)["FNC_OUT"][:, 0]
    slope = np.diff(f)  # count/sample per sample (FNC_OUT is Fixed16 in counts/sample)
    rpm_per_s = slope * u.SAMPLE_HZ**2 * 60.0 / u.COUNTS_PER_REV
    assert np.all(rpm_per_s == pytest.approx(100000.0, rel=0.01))


@pytest.mark.statements("mac800:reg12:1")
def test_v_ist_reads_0_17316_counts_per_sample_per_rpm() -> None:
    """Register 12: "1RPM=0.17316 counts/sample"."""
    m = MotorArray("MAC800", n=1, seed=0)
    m.write_many({"V_SOLL": round(u.rpm_to_v_soll(1000)), "MODE_REG": 1})
    m.run(0.5)
    tr = m.trace(["V_IST", "speed_rpm"], 770)
    ratio = tr["V_IST"][:, 0].mean() / tr["speed_rpm"][:, 0].mean()
    assert ratio == pytest.approx(u.V_IST_COUNTS_PER_RPM, rel=0.002)


@pytest.mark.statements("mac800:reg11:1")
def test_v_ist16_is_the_sum_of_16_samples() -> None:
    """Register 11: V_IST measured over 16 samples, in V_SOLL's unit."""
    m = MotorArray("MAC800", n=1, seed=0)
    m.write_many({"V_SOLL": 2771, "MODE_REG": 1})
    m.run(0.5)
    tr = m.trace(["V_IST", "V_IST16"], 40)
    assert tr["V_IST16"][-1, 0] == tr["V_IST"][-16:, 0].sum()


@pytest.mark.statements("mac800:reg198:1", "mac800:reg198:2")
def test_u_bus_reads_the_bus_voltage(motor: MotorArray) -> None:
    """Register 198: U_BUS = 366 is 325 V."""
    assert motor.read("U_BUS")[0] == 366
    assert motor.read("U_24V")[0] == round(24.0 / u.U_24V_VOLTS_PER_UNIT)
