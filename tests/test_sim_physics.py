"""Closed-loop physics of the simulator."""

from __future__ import annotations

import math

import numpy as np
import pytest

from jvl_gym import MotorArray
from jvl_gym.families.mac050_141 import constants as c


@pytest.mark.statements("mac050_141:3.2.2:11", "mac050_141:3.2.5:1", "mac050_141:3.2.12:1",
                        "mac050_141:4.4.2:1")
def test_velocity_mode_settles_at_v_soll():
    m = MotorArray("MAC140", n=1, seed=0)
    m.write("V_SOLL", 1600)
    m.write("MODE_REG", 1)
    m.run(0.4)
    assert m.speed_rpm[0] == pytest.approx(762.9, rel=0.01)
    assert m.read("V_IST")[0] == pytest.approx(100, abs=1)


@pytest.mark.statements("mac050_141:3.2.6:1", "mac050_141:3.2.117:1", "mac050_141:4.1.1:1",
                        "mac050_141:4.1.1:3")
def test_profile_steps_by_exactly_a_soll():
    m = MotorArray("MAC140", n=1, seed=0)
    m.write("A_SOLL", 160)
    m.write("V_SOLL", 3200)
    m.write("MODE_REG", 1)
    fnc = []
    for _ in range(25):
        m.step()
        fnc.append(int(m.read("FNC_OUT")[0]))
    steps = np.diff([0, *fnc])
    assert np.all(steps[:20] == 160)
    assert fnc[-1] == 3200


def test_shaft_follows_a_slow_ramp_within_3_percent():
    m = MotorArray("MAC140", n=1, seed=0)
    m.write("A_SOLL", 2)  # 2·248.3 = 497 rpm/s
    m.write("V_SOLL", 6400)  # 3052 rpm
    m.write("MODE_REG", 1)
    errs = []
    for k in range(1500):
        m.step()
        target = c.v_soll_to_rpm(float(m.read("FNC_OUT")[0]))
        if k > 200 and target > 500:
            errs.append(abs(m.speed_rpm[0] - target) / target)
    assert max(errs) < 0.03


@pytest.mark.statements("mac050_141:3.2.2:12", "mac050_141:3.2.3:2", "mac050_141:3.2.8:8",
                        "mac050_141:3.2.26:3", "mac050_141:3.2.33:7", "mac050_141:3.2.35:13",
                        "mac050_141:4.1.2:1", "mac050_141:4.4.3:1")
def test_position_move_ends_in_position():
    m = MotorArray("MAC140", n=1, seed=0)
    m.write("V_SOLL", 4000)
    m.write("A_SOLL", 100)
    m.write("P_SOLL", 100000)
    m.write("MODE_REG", 2)
    m.run(2.0)
    assert abs(int(m.read("P_IST")[0]) - 100000) < int(m.read("INPOSWIN")[0])
    assert int(m.read("ERR_STAT")[0]) & c.IN_POS
    assert int(m.read("P_FNC")[0]) == 1600000
    assert int(m.read("FNCERR")[0]) == 0


@pytest.mark.statements("mac050_141:3.2.2:14", "mac050_141:4.1.4:1")
def test_at_mode_torque_gives_t_over_j():
    jl = 100e-6  # keeps the speed below 1000 rpm, where the current loop has voltage headroom
    m = MotorArray("MAC140", n=1, seed=0, load_inertia=jl)
    cfg = m.motor_configs[0]
    m.write("T_SOLL", 400)
    m.set_input(analog_volts=5.0)
    m.write("MODE_REG", 4)
    m.step(5)
    w0, t0 = m.speed_rad_s[0], m.time[0]
    m.step(20)
    acc = (m.speed_rad_s[0] - w0) / (m.time[0] - t0)
    torque = 200.0 * cfg.torque_per_vf  # 5 V = half of T_SOLL = 400 → VF_OUT = 200
    assert acc == pytest.approx(torque / (cfg.rotor_inertia + jl), rel=0.02)


@pytest.mark.statements("mac050_141:3.2.2:10", "mac050_141:4.4.1:1", "mac050_141:4.4.1:9")
def test_init_short_circuit_braking_energy_balance():
    m = MotorArray("MAC140", n=1, seed=0, initial_speed=300.0, viscous_friction=1e-6)
    e0 = m.energy["kinetic"][0]
    m.run(1.0)
    e = m.energy
    assert abs(m.speed_rad_s[0]) < 1.0
    dissipated = e["copper"][0] + e["friction"][0]
    assert dissipated == pytest.approx(e0 - e["kinetic"][0], rel=0.01)
    assert e["copper"][0] > 0.5 * e0  # the short-circuit current did the braking
    assert abs(e["electrical"][0]) < 1e-3 * e0  # equal phase voltages deliver no energy


@pytest.mark.statements("mac050_141:3.2.2:18", "mac050_141:3.2.130:1", "mac050_141:4.4.9:1",
                        "mac050_141:4.4.9:2", "mac050_141:4.4.9:3")
def test_testu_record_is_the_rl_step():
    # A free rotor turns under the test current and its back-EMF bends the step; the classical
    # procedure holds the rotor (here: a large load inertia) so the record is the pure RL step.
    m = MotorArray("MAC140", n=1, seed=0, load_inertia=1e-2)
    cfg = m.motor_configs[0]
    m.write("UMEAS", 60)
    m.write("MODE_REG", 8)
    m.step(2)
    assert m.mode_name() == "INIT_MODE"
    buf = m.sample_buffer()
    ua, ic = buf["UA_VAL"][0], buf["IC_IST"][0]
    assert len(ic) == 11 and np.all(ua == 60)
    a = math.exp(-c.INNER_DT * cfg.phase_resistance / cfg.phase_inductance)
    g = (cfg.supply_voltage / 2 / 1023) / (cfg.phase_resistance * cfg.amps_per_count)
    k = np.arange(11)
    d = cfg.pwm_delay_samples
    expected = -60 * g * (1 - a ** np.clip(k - d, 0, None))
    assert np.all(np.abs(ic - expected) <= 1.0 + 0.01 * np.abs(expected))
    assert ic[0] == 0 and ic[d] == 0 and ic[d + 1] < 0


@pytest.mark.statements("mac050_141:3.2.2:19", "mac050_141:3.2.2:20", "mac050_141:3.2.7:7",
                        "mac050_141:4.4.10:1", "mac050_141:4.4.11:1")
def test_testa_record_is_the_torque_ramp_then_break_and_init():
    jl = 100e-6
    m = MotorArray("MAC140", n=1, seed=0, load_inertia=jl)
    cfg = m.motor_configs[0]
    m.write("T_SOLL", 100)
    m.set_record_length(40)
    m.write("MODE_REG", 9)
    m.step(40)
    buf = m.sample_buffer()
    v = buf["V_IST"][0].astype(float)
    assert np.all(buf["T_SOLL"][0] == 100)
    acc = 100 * cfg.torque_per_vf / (cfg.rotor_inertia + jl)  # rad/s²
    counts_per_sample2 = acc * c.OUTER_DT**2 * c.COUNTS_PER_REV / (2 * math.pi)
    slope = np.polyfit(np.arange(10, 40), v[10:], 1)[0]
    assert slope == pytest.approx(counts_per_sample2, rel=0.02)
    assert m.mode_name() == "BREAK_MODE"
    m.run(0.5)
    assert m.mode_name() == "INIT_MODE"
    assert abs(m.speed_rpm[0]) < 100


@pytest.mark.parametrize("case", ["inertia", "blocked"])
@pytest.mark.statements("mac050_141:3.2.24:1", "mac050_141:4.1.2:7", "mac050_141:4.2.1:6",
                        "mac050_141:4.4.3:1", "mac050_141:4.5.5:2")
def test_overload_bounded_torque_fncerr_trip_stop_init(case):
    kw = {"load_inertia": 300e-6} if case == "inertia" else {"coulomb_friction": 2.0}
    m = MotorArray("MAC140", n=1, seed=0, **kw)
    m.write("T_SOLL", 300)
    m.write("A_SOLL", 400)
    m.write("V_SOLL", 8000)
    m.write("FNCERRMAX", 50000)
    m.write("P_SOLL", 2000000)
    m.write("MODE_REG", 2)
    seen_stop = False
    fncerr = []
    for _ in range(3000):
        m.step()
        assert abs(int(m.read("VF_OUT")[0])) <= 300
        fncerr.append(int(m.read("FNCERR")[0]))
        seen_stop |= m.mode_name() == "STOP_MODE"
        if m.mode_name() == "INIT_MODE":
            break
    assert int(m.read("ERR_STAT")[0]) & c.FNC_ERR
    assert m.mode_name() == "INIT_MODE"
    assert seen_stop or case == "blocked"
    assert max(abs(x) for x in fncerr) > 50000


@pytest.mark.statements("mac050_141:3.2.124:3", "mac050_141:3.2.143:1")
def test_hall_synchronisation_of_the_electrical_angle():
    """hall_start = 1: ELDEG_IST starts at the hall sector centre (30° off at angle 0, torque
    ·cos 30°) and is exact after the first zero transition (ELDEGP_OFFSET = 0 matches)."""
    m = MotorArray("MAC140", n=2, seed=0, hall_start=[0, 1], load_inertia=100e-6)
    assert int(m.read("ELDEG_IST")[1]) == 170  # centre of sector 0: 30° = 170.7 units
    m.write("T_SOLL", 400)
    m.set_input(analog_volts=5.0)
    m.write("MODE_REG", c.AT_MODE)
    m.step(3)
    assert m.torque[1] / m.torque[0] == pytest.approx(math.cos(math.radians(30)), abs=0.02)
    for _ in range(60):  # past θ_mech = π, i.e. θ_e = 2π: the zero transition
        m.step()
    theta_e = (2 * m.position_rad[1]) % (2 * math.pi)
    true_eldeg = theta_e * 2048 / (2 * math.pi)
    lag = abs(m.read("V_ELDEG")[1])  # ELDEG_IST is sampled at the start of the last inner sample
    assert abs(int(m.read("ELDEG_IST")[1]) - true_eldeg) <= lag + 1
    assert (int(m.read("CNTRL_BITS")[1]) >> 13) in (1, 2, 3, 4, 5, 6)


def _eldeg_error(m: MotorArray, offset: np.ndarray) -> np.ndarray:
    """How far ELDEG_IST is from the rotor's true electrical angle plus ``offset`` [1/2048
    electrical turn, wrapped], beyond what its sampling allows (≤ 0: within): the reading is
    taken at the start of the last inner sample, so it lags by up to V_ELDEG, and each side
    rounds by up to one count."""
    true_eldeg = ((2 * m.position_rad) % (2 * math.pi)) * 2048 / (2 * math.pi)
    error = (m.read("ELDEG_IST").astype(float) - true_eldeg - offset + 1024) % 2048 - 1024
    return np.abs(error) - (np.abs(m.read("V_ELDEG")) + 2)


def _turn(m: MotorArray, direction: int, steps: int) -> None:
    """AT_MODE at 40 % torque in ``direction`` for ``steps`` outer samples."""
    m.write("T_SOLL", 400)
    m.set_input(analog_volts=5.0 * direction)
    m.write("MODE_REG", c.AT_MODE)
    m.step(steps)


@pytest.mark.parametrize("direction", [1, -1])
@pytest.mark.statements("mac050_141:3.2.124:1")
def test_the_hall_offset_of_the_direction_is_written_to_eldeg_ist(direction):
    """3.2.124/125: at the hall zero transition the firmware writes ELDEGP_OFFSET to
    ELDEG_IST when the rotor turns positive and ELDEGN_OFFSET when it turns negative; the
    register of the other direction has no effect. Motors that start from their hall sector
    (hall_start = 1), offsets 0 / 300 in the register of the direction / 300 in the other."""
    m = MotorArray("MAC140", n=3, seed=0, hall_start=1, load_inertia=100e-6)
    this, other = ("ELDEGP_OFFSET", "ELDEGN_OFFSET")[::direction]
    m.write(this, [0, 300, 0])
    m.write(other, [0, 0, 300])
    _turn(m, direction, 63)  # past one electrical turn from angle 0: a zero transition
    assert np.all(np.sign(m.speed_rpm) == direction)
    assert np.all(_eldeg_error(m, np.array([0.0, 300.0, 0.0])) <= 0)
    assert np.all(_eldeg_error(m, np.array([300.0, 0.0, 300.0])) > 0)


@pytest.mark.statements("mac050_141:3.2.36:9")
def test_hall_int_keeps_the_hall_correction_after_the_first():
    """CNTRL_BITS HALL_INT (3.2.36 bit 5): the first hall zero transition after power-on
    corrects ELDEG_IST; later ones only while HALL_INT is set, so a new ELDEGN_OFFSET takes
    effect at the next transition with HALL_INT and never without it."""
    m = MotorArray("MAC140", n=2, seed=0, hall_start=1, load_inertia=100e-6)
    m.write("CNTRL_BITS", m.read("CNTRL_BITS") | np.array([0, c.HALL_INT]))
    _turn(m, -1, 10)  # the first transition, at once below angle 0: ELDEGN_OFFSET = 0
    assert np.all(_eldeg_error(m, np.zeros(2)) <= 0)
    m.write("ELDEGN_OFFSET", 300)
    m.step(63)  # a further electrical turn, so another zero transition
    assert np.all(np.sign(m.speed_rpm) == -1)
    assert _eldeg_error(m, np.zeros(2))[0] <= 0 < _eldeg_error(m, np.full(2, 300.0))[0]
    assert _eldeg_error(m, np.full(2, 300.0))[1] <= 0 < _eldeg_error(m, np.zeros(2))[1]
