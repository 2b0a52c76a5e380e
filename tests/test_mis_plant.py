"""The MIS step motor plant: the torque–angle relation, step loss beyond the pull-out torque,
back-EMF limiting the current at speed, standby current, and the equivalences of the engine
(one array = one-motor arrays, threads = serial, determinism)."""

from __future__ import annotations

import numpy as np
import pytest

from jvl_gym import MotorArray
from jvl_gym.families.mis import constants as c


def _running(rpm: float, load: float, n: int = 1, **kw) -> MotorArray:
    m = MotorArray("MIS232", n=n, seed=0, **kw)
    m.set_input(load_torque=load)
    m.write_many({"V_START": 1000, "A_SOLL": 1000, "V_SOLL": int(rpm * 100),
                  "FLWERRMAX": 20000, "MODE_REG": 1})
    return m


@pytest.mark.parametrize("rpm", [60.0, 300.0, 1200.0])
def test_below_the_pull_out_torque_no_step_is_lost_in_100_revolutions(rpm: float) -> None:
    m = _running(rpm, 0.0)
    load = 0.8 * m.pull_out_torque(rpm)[0]
    m.set_input(load_torque=load)
    m.run(100 / rpm * 60 + 2.0)
    assert m.rotor_counts[0] > 100 * 409600
    assert m.lost_steps[0] == 0
    assert m.read("ERR_BITS")[0] == 0
    assert abs(m.read("FLWERR")[0]) < 2 * c.COUNTS_PER_FULL_STEP


@pytest.mark.parametrize("rpm", [60.0, 300.0, 1200.0])
@pytest.mark.statements("mis:8.2.19:2")
def test_above_the_pull_out_torque_steps_are_lost_and_flwerrmax_trips(rpm: float) -> None:
    m = _running(rpm, 0.0)
    m.run(1.5)  # at speed first
    m.set_input(load_torque=1.2 * m.pull_out_torque(rpm)[0])
    tr = m.trace(["FLWERR", "ERR_BITS", "MODE_REG"], 1000)
    assert m.lost_steps[0] >= 4
    assert np.abs(tr["FLWERR"][:, 0]).max() > 20000  # the follow error grows
    tripped = np.flatnonzero(tr["ERR_BITS"][:, 0] & c.ERR_FOLLOW)
    assert tripped.size and tr["ERR_BITS"][tripped[0], 0] & c.ERR_GENERAL
    assert tr["MODE_REG"][-1, 0] == c.PASSIVE  # after the emergency stop
    assert abs(tr["FLWERR"][tripped[0] - 1, 0]) <= 20000  # tripped as it passed FLWERRMAX


@pytest.mark.statements("mis:5.8.1:3")
def test_lost_steps_come_in_whole_electrical_turns_and_the_encoder_sees_them() -> None:
    m = _running(300.0, 0.0)
    m.write("FLWERRMAX", 0)
    m.run(1.0)
    m.set_input(load_torque=1.3 * m.pull_out_torque(300.0)[0])
    m.run(0.05)
    m.set_input(load_torque=0.0)
    m.run(1.0)
    lost = m.lost_steps[0]
    assert lost > 0 and lost % 4 == 0
    flw = m.read("FLWERR")[0]
    assert flw == pytest.approx(lost * c.COUNTS_PER_FULL_STEP, abs=c.COUNTS_PER_FULL_STEP)


def test_holding_torque_is_the_torque_angle_peak_at_standstill() -> None:
    m = MotorArray("MIS232", n=1, seed=0)
    m.write_many({"RUN_CURRENT": 1022, "MODE_REG": 2})
    assert m.pull_out_torque(0.0)[0] == pytest.approx(1.9, rel=1e-3)  # §5.1.3: 1.9 N·m at 6 A
    m.set_input(load_torque=1.5)
    m.run(0.3)
    assert m.lost_steps[0] == 0
    assert m.torque[0] == pytest.approx(1.5, rel=0.02)
    m.write("RUN_CURRENT", 511)  # §5.1.6: half the current, about half the torque
    m.run(0.3)
    assert m.lost_steps[0] != 0


@pytest.mark.statements("mis:5.1.6:3")
def test_back_emf_limits_the_current_at_speed() -> None:
    m = _running(2500.0, 0.0)
    m.write("A_SOLL", 5000)
    m.run(0.1)
    low = m.current_amplitude[0]
    m.run(1.0)
    high = m.current_amplitude[0]
    ref = np.sqrt(2) * 511 * 5.87e-3
    assert low == pytest.approx(ref, rel=0.02)
    assert high < 0.8 * ref
    assert m.pull_out_torque(2500.0)[0] < m.pull_out_torque(100.0)[0]


@pytest.mark.statements("mis:8.2.7:3", "mis:8.2.8:2", "mis:8.2.8:3", "mis:8.2.24:18", "mis:5.1:1")
def test_standby_current_after_standby_time() -> None:
    m = MotorArray("MIS232", n=1, seed=0)
    m.write_many({"STANDBY_TIME": 200, "STANDBY_CURRENT": 100, "P_SOLL": 10000, "MODE_REG": 2})
    tr = m.trace(["STATUSBITS"], 600)
    amps = np.sqrt(2) * 5.87e-3
    assert m.current_amplitude[0] == pytest.approx(100 * amps, rel=0.02)
    standby = tr["STATUSBITS"][:, 0] & c.ST_STANDBY_CURRENT
    assert not standby[:150].any() and standby[-1]
    m.write("P_SOLL", 0)  # a move: running current without delay
    m.step(2)
    assert m.current_amplitude[0] == pytest.approx(511 * amps, rel=0.02)


@pytest.mark.statements("mis:8.2.3:2", "mis:6.1.1:1")
def test_passive_mode_has_no_current_and_the_encoder_follows_a_turned_shaft() -> None:
    m = MotorArray("MIS232", n=1, seed=0)
    m.set_input(load_torque=-0.5)  # turns the free shaft forward
    m.run(0.2)
    assert m.current_amplitude[0] == 0.0
    assert m.read("ENCODER_POS")[0] > 10000
    assert m.read("P_IST")[0] == 0


def _mixed(n: int, seed: int) -> MotorArray:
    m = MotorArray(["MIS232", "MIS176", "MIS342", "SMC85"] * (n // 4), n=n, seed=seed,
                   load_inertia=np.linspace(0.0, 2e-4, n))
    m.set_input(load_torque=np.linspace(-0.1, 0.3, n))
    m.write_many({"V_SOLL": np.linspace(-60000, 90000, n).round(), "A_SOLL": 3000,
                  "P_SOLL": np.linspace(-400000, 900000, n).round(),
                  "MODE_REG": np.where(np.arange(n) % 2 == 0, 1, 2)})
    return m


def test_one_array_equals_one_motor_arrays_bit_for_bit() -> None:
    big = _mixed(12, 3)
    big.step(300)
    for i in (0, 5, 11):
        one = MotorArray(big.motor_configs[i].name, n=1, seed=[int(big.keys[i])],
                         load_inertia=big.parameters["load_inertia"][i])
        one.set_input(load_torque=big.inputs[i, 0])
        one.write_many({"V_SOLL": int(big.read("V_SOLL")[i]), "A_SOLL": 3000,
                        "P_SOLL": int(big.read("P_SOLL")[i]),
                        "MODE_REG": 1 if i % 2 == 0 else 2})
        one.step(300)
        np.testing.assert_array_equal(one.state[0], big.state[i])
        np.testing.assert_array_equal(one.regs[0], big.regs[i])


def test_threads_equal_serial_and_a_seed_repeats() -> None:
    from jvl_gym.motor.array import driver

    a, b = _mixed(64, 7), _mixed(64, 7)
    a.step(200)  # 64 motors ≥ PARALLEL_MIN: threads
    drv = driver("mis")
    drv.serial(*b.engine_view(), 200)
    np.testing.assert_array_equal(a.state, b.state)
    np.testing.assert_array_equal(a.regs, b.regs)
    again = _mixed(64, 7)
    again.step(200)
    np.testing.assert_array_equal(again.state, a.state)


@pytest.mark.statements("mis:8.2.18:3")
def test_without_an_encoder_steps_are_lost_unseen() -> None:
    """§8.2.18: FLWERR needs the encoder option; without it the lost steps are invisible to
    the firmware (no follow error, no error bit) but not to the truth."""
    m = _running(300.0, 0.0, encoder_type=0)
    m.run(1.0)
    m.set_input(load_torque=1.3 * m.pull_out_torque(300.0)[0])
    m.run(0.2)
    assert m.lost_steps[0] > 0
    assert m.read("FLWERR")[0] == 0 and m.read("ERR_BITS")[0] == 0
    assert m.read("ENCODER_TYPE")[0] == 0
    assert not m.read("STATUSBITS")[0] & c.ST_ENCODER_OK


def test_an_acceleration_beyond_the_pull_out_torque_loses_steps() -> None:
    """J·α above the pull-out torque slips poles as a load torque does: a heavy load inertia
    (20 × the rotor's) accelerated at 50 000 RPM/s needs about 5 N·m; at 500 RPM/s 0.05 N·m."""
    m = MotorArray("MIS232", n=2, seed=0, load_inertia=1e-3)
    m.write_many({"A_SOLL": np.array([50000, 500]), "V_START": 1000, "V_SOLL": 30000,
                  "MODE_REG": 1})
    m.run(1.5)
    lost = m.lost_steps
    assert lost[0] > 0 and lost[1] == 0
