"""Every operating mode against its manual formula."""

from __future__ import annotations

import numpy as np
import pytest

from jvl_gym import ModeError, MotorArray
from jvl_gym.families.mac050_141 import constants as c
from jvl_gym.registers import RegisterError
from jvl_gym.world import AnalogInput, PulseInput, SpeedProfile, SupplyEvents, World


def _gear_run(mode: int, stop_at: int = 600, total_steps: int = 900):
    """500-pulse/rev master at 5 rev/s, GEARF1/GEARF2 = 1024/125 (manual 4.4.4)."""
    m = MotorArray("MAC140", n=1, seed=0, load_inertia=10e-6)
    m.write("KVOUT", 27.3 / 17.3)
    m.write("GEARF1", 1024)
    m.write("GEARF2", 125)
    m.write("V_SOLL", 8000)
    m.write("A_SOLL", 100)
    m.write("MODE_REG", mode)
    acc = total = 0.0
    lag, pos, vel, fnc = [], [], [], []
    for k in range(total_steps):
        p = 0.0
        if k < stop_at:
            acc += 2500 * c.OUTER_DT
            p = np.floor(acc) - total
        total += p
        m.set_input(pulse_counts=p)
        m.step()
        if 400 < k < stop_at:
            lag.append(total * 1024 / 125 - m.read("P_IST")[0])
            vel.append(m.read("V_IST")[0])
        pos.append(m.read("P_IST")[0])
        fnc.append(m.read("P_FNC")[0] / 16)
    m.fnc_trace = np.array(fnc)
    return m, total * 1024 / 125, np.array(lag), np.array(pos), np.array(vel)


@pytest.mark.statements("mac050_141:3.2.2:13", "mac050_141:3.2.14:1", "mac050_141:4.1.12:1",
                        "mac050_141:4.1.12:3", "mac050_141:4.4.4:3", "mac050_141:4.4.4:7")
def test_gp_follows_500_pulse_master_exactly_and_stops_without_overshoot():
    m, final, lag, pos, vel = _gear_run(c.GP_MODE)
    # steady state: the speed is the master's exactly (5 rev/s · 4096 counts per outer sample)
    assert np.mean(vel) == pytest.approx(5 * 4096 * c.OUTER_DT, rel=1e-3)
    # constant lag (the braking distance of the profile), ±1 pulse of the uneven pulse train
    assert np.ptp(lag) < 12
    assert abs(pos[-1] - final) <= 2  # the gear position is fractional; ±1 count of standstill
    assert m.fnc_trace.max() <= final + 1  # the profile stops without overshoot (4.1.12)
    assert int(m.read("ERR_STAT")[0]) & c.IN_POS


@pytest.mark.statements("mac050_141:3.2.2:34", "mac050_141:4.1.3:1", "mac050_141:4.4.25:1")
def test_gf_has_smaller_follow_error_and_overshoots():
    _, final_gp, lag_gp, _, _ = _gear_run(c.GP_MODE)
    m, final, lag_gf, pos, _ = _gear_run(c.GF_MODE)
    assert np.mean(np.abs(lag_gf)) < 0.1 * np.mean(np.abs(lag_gp))
    assert m.fnc_trace.max() > final + 20  # the profile overshoots when the pulses stop (4.1.3)
    assert abs(pos[-1] - final) <= 2


@pytest.mark.statements("mac050_141:3.2.2:26", "mac050_141:4.1.6:1", "mac050_141:4.4.17:1")
def test_avz_dead_band_and_scale():
    m = MotorArray("MAC140", n=5, seed=0)
    m.write("V_SOLL", 2000)
    m.write("A_SOLL", 1000)
    volts = np.array([0.5, -0.6, 10.0, -10.0, 3.0])
    m.set_input(analog_volts=volts)
    m.write("MODE_REG", c.AVZ_MODE)
    m.step(10)
    aninp = np.round(volts * 102.3)
    expected = np.where(aninp > 64, (aninp - 64) * 0.0010416 * 2000,
                        np.where(aninp <= -64, (aninp + 64) * 0.0010416 * 2000, 0)).astype(int)
    np.testing.assert_array_equal(m.read("FNC_OUT"), expected)
    assert expected[0] == expected[1] == 0


@pytest.mark.statements("mac050_141:3.2.2:15", "mac050_141:3.2.122:4", "mac050_141:4.1.5:1",
                        "mac050_141:4.4.6:1", "mac050_141:4.4.18:1")
def test_av_and_vat():
    m = MotorArray("MAC140", n=2, seed=0)
    m.write("V_SOLL", 1600)
    m.write("T_SOLL", 800)
    m.set_input(analog_volts=[5.0, -2.5])
    m.write("MODE_REG", c.AV_MODE, index=[0])
    m.write("MODE_REG", c.VAT_MODE, index=[1])
    m.step(20)
    assert int(m.read("FNC_OUT")[0]) == int(512 * 1600 / 1023)
    m.run(0.3)
    assert abs(int(m.read("VF_OUT")[1])) <= abs(-256 * 800 / 1024) + 1


@pytest.mark.statements("mac050_141:3.2.2:28", "mac050_141:4.1.9:1", "mac050_141:4.1.9:2",
                        "mac050_141:4.4.19:1")
def test_ag_factor_limits_and_stationary_master():
    m = MotorArray("MAC140", n=3, seed=0)
    m.write("GEARF1", 1)
    m.write("GEARF2", 1)
    m.write("V_SOLL", 20000)
    m.write("A_SOLL", 400)
    m.set_input(analog_volts=[10.0, -10.0, 0.0], pulse_counts=40)
    m.write("MODE_REG", c.AG_MODE)
    m.run(0.5)
    v = []
    for _ in range(100):
        m.step()
        v.append(m.read("V_IST").copy())
    ratio = np.mean(v, axis=0) / 40
    assert ratio[0] == pytest.approx(1.01 + 0.14, rel=2e-3)  # +10 V ↔ 1.15
    assert ratio[1] == pytest.approx(1.01 - 0.14, rel=2e-3)  # −10 V ↔ 0.87
    m.set_input(pulse_counts=0)
    m.run(0.5)
    assert np.all(np.abs(m.speed_rpm) < 1)  # master at rest: motor at rest whatever the voltage


@pytest.mark.statements("mac050_141:3.2.2:16", "mac050_141:3.2.122:4", "mac050_141:4.1.7:2",
                        "mac050_141:4.4.7:1")
def test_avg_bias_is_300_rpm_at_10_volts():
    m = MotorArray("MAC140", n=1, seed=0)
    m.write("V_SOLL", 10000)
    m.write("A_SOLL", 200)
    m.set_input(analog_volts=10.0, pulse_counts=0)
    m.write("MODE_REG", c.AVG_MODE)
    m.run(0.5)
    assert c.v_soll_to_rpm(float(m.read("FNC_OUT")[0])) == pytest.approx(300, abs=0.5)


COIL = dict(P1=10000, P2=12000, P3=58000, P4=60000, P5=12000, P6=1)


@pytest.mark.statements("mac050_141:3.2.2:29", "mac050_141:4.4.20:1", "mac050_141:4.4.20:3")
def test_coil_example_traverses_dwells_and_returns_to_p5():
    m = MotorArray("MAC140", n=1, seed=0, load_inertia=10e-6)
    for k, v in COIL.items():
        m.write(k, v)
    m.write("V_SOLL", 20000)
    m.write("A_SOLL", 400)
    m.write("GEARF1", 4)
    m.write("GEARF2", 1)
    m.set_input(analog_volts=10.0)  # start-position command
    m.write("MODE_REG", c.COIL_MODE)
    m.run(1.0)
    assert abs(int(m.read("P_IST")[0]) - 12000) < 10
    m.set_input(analog_volts=0.0, pulse_counts=20)  # spindle turning
    fnc = []
    for _ in range(3000):
        m.step()
        fnc.append(int(m.read("P_FNC")[0]) / 16)
    fnc = np.array(fnc)
    assert fnc.min() >= 12000 - 1 and fnc.max() <= 58000 + 1  # profile limited to P2..P3
    # dwell while the virtual traverse runs P3→P4→P3 (and P2→P1→P2): 2·2000 counts at 80/sample
    for stop in (58000, 12000):
        at = np.abs(fnc - stop) < 1
        edges = np.flatnonzero(np.diff(at.astype(int)))
        runs = np.diff(edges)[::2] if at[0] == 0 else np.diff(edges)[1::2]
        assert runs.size >= 1 and np.all(np.abs(runs - 50) <= 2)
    m.set_input(analog_volts=10.0)
    m.run(2.0)
    assert abs(int(m.read("P_IST")[0]) - 12000) < 10


@pytest.mark.statements("mac050_141:4.4.20:4")
def test_coil_rules_are_enforced():
    m = MotorArray("MAC140", n=1, seed=0)
    for k, v in {**COIL, "P2": 9000}.items():
        m.write(k, v)
    before = m.regs.copy()
    with pytest.raises(ModeError, match="P1 ≤ P2"):
        m.write("MODE_REG", c.COIL_MODE)
    np.testing.assert_array_equal(m.regs, before)
    m.write("P2", 12000)
    m.write("MODE_REG", c.COIL_MODE)
    with pytest.raises(RegisterError, match="COIL"):
        m.write("P6", 2)
    with pytest.raises(RegisterError, match="COIL"):
        m.write("P3", 61000)


@pytest.mark.statements("mac050_141:3.2.42:5")
def test_gearf2_zero_and_home_mode_values_refused():
    m = MotorArray("MAC140", n=1, seed=0)
    m.write("GEARF2", 0)
    with pytest.raises(ModeError, match="GEARF2"):
        m.write("MODE_REG", c.GP_MODE)
    m.write("GEARF2", 5)
    m.write("MODE_REG", c.GP_MODE)
    with pytest.raises(RegisterError, match="GEARF2"):
        m.write("GEARF2", 0)
    with pytest.raises(RegisterError, match="HOME_MODE"):
        m.write("HOME_MODE", 11)
    m.write("HOME_MODE", 13 | (12 << 8))


@pytest.mark.statements("mac050_141:3.2.2:22", "mac050_141:3.2.42:6", "mac050_141:4.4.13:1",
                        "mac050_141:4.4.13:6")
def test_home1_finds_mechanical_stop():
    m = MotorArray("MAC140", n=1, seed=0, end_stop_low=-3.0, end_stop_high=3.0)
    m.write("V_HOME", -800)
    m.write("T_HOME", 300)
    m.write("P_HOME", -1000)
    m.write("MODE_REG", c.HOME1_MODE)
    for _ in range(3000):
        m.step()
        if m.mode_name() != "HOME1_MODE":
            break
    assert m.mode_name() in ("STOP_MODE", "INIT_MODE")
    assert m.position_rad[0] == pytest.approx(-3.0, abs=0.02)
    assert abs(int(m.read("P_IST")[0]) - (-1000)) <= 2
    assert int(m.read("P_SOLL")[0]) == 0
    assert int(m.read("P_FNC")[0]) == -16000 + 16 * (int(m.read("P_IST")[0]) + 1000)


@pytest.mark.statements("mac050_141:3.2.37:3", "mac050_141:4.4.13:8")
def test_home1_hands_over_to_p_mode_which_reaches_p_soll():
    """At the zero the function position is the motor position and STARTMODE starts (manual
    4.4.13): the follow error and the speed loop's history from pushing against the stop do
    not carry into P_MODE, which moves to P_SOLL = 0 and reports IN_POS."""
    m = MotorArray("MAC140", n=1, seed=0, end_stop_low=-3.0, end_stop_high=3.0)
    m.write_many({"V_HOME": -800, "T_HOME": 300, "P_HOME": -1000, "STARTMODE": c.P_MODE,
                  "V_SOLL": 1000, "INPOSWIN": 10, "INPOSCNT": 5})
    m.write("MODE_REG", c.HOME1_MODE)
    for _ in range(3000):
        m.step()
        if m.mode_name() != "HOME1_MODE":
            break
    assert m.mode_name() == "P_MODE"
    m.run(1.5)
    assert abs(int(m.read("P_IST")[0])) <= 10
    assert int(m.read("ERR_STAT")[0]) & c.IN_POS


@pytest.mark.parametrize("mode", [c.HOME2_MODE, c.HOME3_MODE])
@pytest.mark.parametrize("start", [0.0, 2.0])
@pytest.mark.statements("mac050_141:3.2.2:23", "mac050_141:3.2.2:24", "mac050_141:3.2.37:3",
                        "mac050_141:3.2.38:1", "mac050_141:3.2.41:3", "mac050_141:3.2.122:4",
                        "mac050_141:4.4.14:1", "mac050_141:4.4.14:3", "mac050_141:4.4.15:3")
def test_home2_home3_find_the_sensor_edge(mode, start):
    edge = 1.0
    m = MotorArray("MAC140", n=1, seed=0, home_position=edge, initial_angle=start)
    m.write("V_HOME", 400)  # the sensor is active above the edge: the search goes up
    m.write("T_HOME", 1)  # active high
    m.write("P_HOME", 500)
    m.write("STARTMODE", c.P_MODE)
    m.write("MODE_REG", mode)
    for _ in range(5000):
        m.step()
        if m.mode_name() in ("P_MODE",):
            break
    assert m.mode_name() == "P_MODE"
    counts_past_edge = (m.position_rad[0] - edge) * c.COUNTS_PER_REV / (2 * np.pi)
    # P_IST was set to P_HOME within one sample of travel of the edge
    assert abs(int(m.read("P_IST")[0]) - 500 - counts_past_edge) < 60


@pytest.mark.statements("mac050_141:3.2.8:10")
def test_flying_saw_returns_to_start_through_p_fnc():
    m = MotorArray("MAC140", n=1, seed=0)
    m.write("P_SOLL", 0)
    m.write("V_SOLL", 6000)
    m.write("A_SOLL", 200)
    m.write("MODE_REG", c.P_MODE)
    m.run(0.2)
    m.write("MODE_REG", c.GP_MODE)  # synchronise with the object
    m.set_input(pulse_counts=30)
    m.run(0.5)
    assert int(m.read("P_IST")[0]) > 5000
    m.set_input(pulse_counts=0)
    m.write("MODE_REG", c.P_MODE)  # back to the start position
    m.run(1.5)
    assert abs(int(m.read("P_IST")[0])) < 10
    assert int(m.read("ERR_STAT")[0]) & c.IN_POS


@pytest.mark.statements("mac050_141:3.2.2:30", "mac050_141:4.1.10:1", "mac050_141:4.1.10:2",
                        "mac050_141:4.1.10:3", "mac050_141:4.1.10:5", "mac050_141:4.4.21:1")
def test_a2pos_hysteresis_absolute_and_relative():
    m = MotorArray("MAC140", n=1, seed=0)
    m.write("P1", 1000)
    m.write("P2", 5000)
    m.write("V_SOLL", 4000)
    m.write("MODE_REG", c.A2POS_MODE)
    assert int(m.read("P_SOLL")[0]) == 1000
    for volts, expect in ((5.0, 1000), (5.5, 5000), (4.8, 5000), (4.3, 1000)):
        m.set_input(analog_volts=volts)
        m.step()
        assert int(m.read("P_SOLL")[0]) == expect
    m.write("ERR_STAT", c.RELPOSPSOLL)
    m.set_input(analog_volts=6.0)
    m.step()
    assert int(m.read("P_SOLL")[0]) == 6000


@pytest.mark.statements("mac050_141:3.2.2:31", "mac050_141:4.1.11:1", "mac050_141:4.4.22:1")
def test_apos_dead_band():
    m = MotorArray("MAC140", n=1, seed=0)
    m.write("P1", 100)
    m.write("P2", 160)  # 10 counts per ANINP count
    m.write("P3", 50)
    m.write("V_SOLL", 4000)
    m.write("MODE_REG", c.APOS_MODE)
    m.set_input(analog_volts=1.0)  # ANINP 102 → P_NEW = 1120
    m.step()
    assert int(m.read("P_SOLL")[0]) == 1120 - 50
    m.set_input(analog_volts=1.03)  # ANINP 105 → 1150: P_SOLL trails by the dead band
    m.step()
    assert int(m.read("P_SOLL")[0]) == 1100
    m.set_input(analog_volts=1.0)  # back to 1120: inside the dead band, no change
    m.step()
    assert int(m.read("P_SOLL")[0]) == 1100


@pytest.mark.statements("mac050_141:3.2.3:3", "mac050_141:3.2.13:4", "mac050_141:3.2.35:5",
                        "mac050_141:3.2.35:6", "mac050_141:3.2.43:1", "mac050_141:3.2.43:3",
                        "mac050_141:3.2.44:1", "mac050_141:3.2.45:1", "mac050_141:3.2.46:1",
                        "mac050_141:3.2.47:1", "mac050_141:3.2.48:1")
def test_register_mode_pointers():
    m = MotorArray("MAC140", n=2, seed=0)
    m.write("P3", 4000)
    m.write("V2", 777)
    m.write("T4", 500)
    m.write("L1", 2.5)
    m.write("P_REG_P", 3)
    m.write("V_REG_P", 2)
    m.write("T_REG_P", 4)
    m.write("L_REG_P", 1)
    assert int(m.read("P_SOLL")[0]) == 4000 and int(m.read("P_REG_P")[0]) == 0
    assert int(m.read("V_SOLL")[1]) == 777 and int(m.read("T_SOLL")[0]) == 500
    assert m.read("KVOUT")[0] == 2.5
    m.write("ERR_STAT", c.RELPOSPSOLL)
    m.write("P_REG_P", 3)
    assert int(m.read("P_SOLL")[0]) == 8000
    m.write("ERR_STAT", c.RELPOSPFNC)
    p_fnc = int(m.read("P_FNC")[0])
    m.write("P_REG_P", 3)
    assert int(m.read("P_FNC")[0]) == p_fnc - 16 * 4000


@pytest.mark.statements("mac050_141:3.2.36:2", "mac050_141:3.2.36:3", "mac050_141:3.2.163:1")
def test_resynchronisation_bits():
    m = MotorArray("MAC140", n=1, seed=0)
    m.write("P_NEW", 1234)
    m.write("CNTRL_BITS", c.MAN_RESYNC)
    m.step()
    assert int(m.read("P_IST")[0]) == 1234 and int(m.read("P_FNC")[0]) == 16 * 1234
    assert not int(m.read("CNTRL_BITS")[0]) & c.MAN_RESYNC
    m.write("CNTRL_BITS", c.MAN_RESYNC | c.REL_RESYNC)
    m.step()
    assert int(m.read("P_IST")[0]) == 2468 and int(m.read("P_SOLL")[0]) == 2468


@pytest.mark.statements("mac050_141:3.2.35:2", "mac050_141:3.2.35:3", "mac050_141:3.2.152:1",
                        "mac050_141:3.2.160:1", "mac050_141:3.2.160:3", "mac050_141:4.5.6:2",
                        "mac050_141:4.5.6:3")
def test_undervoltage_detection_and_timer():
    m = MotorArray("MAC140", n=1, seed=0, viscous_friction=1e-3)  # draws ≈ 100 W at 3000 rpm
    m.write("U_MIN_SUP", round(35 / 0.0537))
    m.write("UV_HANDLE", c.SET_UV_ERR | c.UV_SOLL0)
    m.write("V_SOLL", 6000)
    m.write("MODE_REG", c.V_MODE)
    m.run(0.3)
    assert not int(m.read("ERR_STAT")[0]) & c.UV_DETECT
    # the source sags to 20 V; the bus capacitor discharges into the motor below 35 V
    m.world = World(supply=SupplyEvents([(0.0, 0.3, 20.0)], nominal=48.0, n=1))
    m.run(0.25)
    st = int(m.read("ERR_STAT")[0])
    assert st & c.UV_DETECT and st & c.UV_ERR and int(m.read("V_SOLL")[0]) == 0
    m.run(0.5)
    assert int(m.read("ERR_STAT")[0]) & c.UV_DETECT  # the 1 s timer holds it
    m.run(1.0)
    assert not int(m.read("ERR_STAT")[0]) & c.UV_DETECT


def test_pulse_input_decoding_semantics():
    prof = SpeedProfile.constant(2.0, n=1)
    quad = PulseInput(prof, lines=500, signal="quadrature")
    pdir = PulseInput(SpeedProfile.constant(2.0, n=1), lines=500, signal="pulse_dir")
    n = 521
    q = sum(quad.advance(c.OUTER_DT, np.array([False]), np.array([False]))[0] for _ in range(n))
    p = sum(pdir.advance(c.OUTER_DT, np.array([True]), np.array([False]))[0] for _ in range(n))
    assert q == pytest.approx(4 * 500 * 2.0 * n * c.OUTER_DT, abs=1)
    assert p == pytest.approx(500 * 2.0 * n * c.OUTER_DT, abs=1)
    neg = PulseInput(SpeedProfile.constant(2.0, n=1), lines=500, signal="pulse_dir")
    assert neg.advance(c.OUTER_DT, np.array([True]), np.array([True]))[0] <= 0


@pytest.mark.statements("mac050_141:4.1.3:3")
def test_world_drives_gear_mode_through_the_kernel():
    m = MotorArray("MAC140", n=2, seed=0)
    m.write("V_SOLL", 20000)
    m.write("A_SOLL", 400)
    m.world = World(pulse=PulseInput(SpeedProfile.ramp([2.0, 4.0], 0.2, n=2), lines=1024),
                    analog=AnalogInput(0.0, n=2, noise_std=0.01, seed=1))
    m.write("MODE_REG", c.GF_MODE)
    m.run(1.0)
    np.testing.assert_allclose(m.speed_rpm, [120.0, 240.0], rtol=0.01)


@pytest.mark.statements("mac050_141:3.2.26:1", "mac050_141:4.2.1:6", "mac050_141:4.4.4:1")
def test_overload_in_gear_mode_bounds_torque_and_trips():
    m = MotorArray("MAC140", n=1, seed=0, coulomb_friction=2.0)  # rotor blocked
    m.write("T_SOLL", 300)
    m.write("FNCERRMAX", 20000)
    m.write("V_SOLL", 8000)
    m.set_input(pulse_counts=20)
    m.write("MODE_REG", c.GP_MODE)
    for _ in range(500):
        m.step()
        assert abs(int(m.read("VF_OUT")[0])) <= 300
        if m.mode_name() == "INIT_MODE":
            break
    assert int(m.read("ERR_STAT")[0]) & c.FNC_ERR and m.mode_name() == "INIT_MODE"


ALL_MODES = [c.V_MODE, c.P_MODE, c.GP_MODE, c.AT_MODE, c.AV_MODE, c.AVG_MODE, c.MANI_MODE,
             c.HOME1_MODE, c.HOME2_MODE, c.AVZ_MODE, c.VAT_MODE, c.AG_MODE, c.COIL_MODE,
             c.A2POS_MODE, c.APOS_MODE, c.TESTTQ_MODE, c.GF_MODE]


def _setup_for(m: MotorArray, mode: int, index) -> None:
    for k, v in {**COIL, "V_SOLL": 1500, "P_SOLL": 3000, "V_HOME": 300, "T_HOME": 200,
                 "MAN_I_NOM": 300, "MAN_ALPHA": 100}.items():
        m.write(k, v, index=index)
    m.set_input(index=index, analog_volts=3.0, pulse_counts=7)
    m.write("MODE_REG", mode, index=index)


def test_every_mode_in_a_mixed_array_equals_separate_runs():
    from jvl_gym.motor.noise import motor_keys

    n = len(ALL_MODES)
    keys = motor_keys(3, n)
    big = MotorArray("MAC140", n=n, seed=3, current_noise=1.0, home_position=0.5)
    for k, mode in enumerate(ALL_MODES):
        _setup_for(big, mode, [k])
    big.step(150)
    for k, mode in enumerate(ALL_MODES):
        one = MotorArray("MAC140", n=1, seed=[keys[k]], current_noise=1.0, home_position=0.5)
        _setup_for(one, mode, None)
        one.step(150)
        np.testing.assert_array_equal(one.regs[0], big.regs[k], err_msg=c.MODE_NAMES[mode])
        np.testing.assert_array_equal(one.state[0], big.state[k], err_msg=c.MODE_NAMES[mode])


@pytest.mark.statements("mac050_141:3.2.2:33", "mac050_141:4.4.24:1")
def test_testtq_measures_friction():
    m = MotorArray("MAC140", n=1, seed=0, coulomb_friction=0.05)
    m.write("V_SOLL", 400)
    m.write("MODE_REG", c.TESTTQ_MODE)
    m.run(2.0)
    assert m.mode_name() == "INIT_MODE"
    buf = m.sample_buffer()
    vf = buf["VF_OUT"][0]
    half = c.REC_CNT_MAX // 2
    t_plus, t_minus = vf[half - 150:half].mean(), vf[-150:].mean()
    friction = (t_plus - t_minus) / 2 * m.motor_configs[0].torque_per_vf
    assert friction == pytest.approx(0.05, rel=0.1)


@pytest.mark.statements("mac050_141:3.2.2:1")
def test_mode_table_names_real_registers_and_every_mode():
    from jvl_gym.families.mac050_141.firmware.mode_table import MODES, markdown_mode_table
    from jvl_gym.families.mac050_141.table import TABLE as MAC050_141

    assert [m.number for m in MODES] == list(range(25))
    assert all(m.name == c.MODE_NAMES[m.number] for m in MODES)
    for m in MODES:
        for reg in m.parameters:
            MAC050_141.lookup(reg)
    assert "COIL_MODE" in markdown_mode_table()


@pytest.mark.parametrize("gear_mode", [c.GP_MODE, c.GF_MODE])
@pytest.mark.statements("mac050_141:3.2.24:5")
def test_gear_to_p_mode_hand_over_starts_fncerr_from_zero(gear_mode):
    """Manual 3.2.24: in GP/GF FNCERR is the gear position error, in P_MODE the sum of the
    profile corrections. A motor switched from following pulses to P_MODE starts its FNCERR
    at 0, so an FNCERRMAX below the gear error does not trip in P_MODE, which reaches P_SOLL."""
    m = MotorArray("MAC140")
    m.write_many({"V_SOLL": 1000, "A_SOLL": 20, "T_SOLL": 200, "GEARF1": 1, "GEARF2": 1})
    m.write("MODE_REG", gear_mode)
    m.set_input(pulse_counts=20)
    m.step(200)
    gear_error = int(m.read("FNCERR")[0])
    assert abs(gear_error) > 100  # the follow lag of a 20 counts/sample pulse train
    m.set_input(pulse_counts=0)
    target = int(m.read("P_IST")[0]) + 5000
    m.write_many({"FNCERRMAX": abs(gear_error) // 2, "P_SOLL": target})
    m.write("MODE_REG", c.P_MODE)
    m.step(1)
    assert int(m.read("FNCERR")[0]) == 0
    m.step(1500)
    assert int(m.read("MODE_REG")[0]) == c.P_MODE
    assert int(m.read("ERR_STAT")[0]) & c.FNC_ERR == 0
    assert abs(int(m.read("P_IST")[0]) - target) <= 10


#: regulated modes a user switches between while the motor moves (manual 4.4)
_MOVING_MODES = [c.V_MODE, c.P_MODE, c.GP_MODE, c.AV_MODE, c.AVG_MODE, c.AVZ_MODE, c.VAT_MODE,
                 c.AG_MODE, c.A2POS_MODE, c.APOS_MODE, c.GF_MODE]


@pytest.mark.parametrize("first", _MOVING_MODES)
def test_every_hand_over_between_moving_modes_is_bumpless_and_error_free(first):
    """Switching from one regulated mode to another while moving (docs/model.md §9): the
    profile continues from the present velocity (FNC_OUT moves by at most one A_SOLL step at
    the switch), no error bit is set and the new mode stays active."""
    for second in _MOVING_MODES:
        if second == first:
            continue
        m = MotorArray("MAC140")
        m.write_many({"V_SOLL": 800, "A_SOLL": 20, "T_SOLL": 600, "GEARF1": 1, "GEARF2": 1,
                      "P_SOLL": 30000})
        m.set_input(pulse_counts=10, analog_volts=3.0)
        m.write("MODE_REG", first)
        m.step(200)
        before = int(m.read("FNC_OUT")[0])
        m.write("MODE_REG", second)
        m.step(1)
        after = int(m.read("FNC_OUT")[0])
        assert abs(after - before) <= 20 + 1, (first, second, before, after)
        m.step(1000)
        errors = c.I2T_ERR | c.FLW_ERR | c.FNC_ERR | c.UIT_ERR | c.PLIM_ERR
        assert int(m.read("ERR_STAT")[0]) & errors == 0, (first, second)
        assert int(m.read("MODE_REG")[0]) == second, (first, second)


@pytest.mark.parametrize("edge", [1.0, 2.0])
@pytest.mark.statements("mac050_141:3.2.36:5", "mac050_141:4.4.14:3")
def test_index_home_puts_the_zero_on_the_nearest_index_marker(edge):
    """CNTRL_BITS INDEX_HOME (3.2.36 bit 11): in a homing mode the home position is rounded to
    the nearest index marker, the hall transition at the electrical zero (two per revolution:
    θ = 0 and π rad with two pole pairs). HOME2 on a sensor edge at ``edge`` rad, without the
    bit (motor 0: the zero at the edge) and with it (motor 1: at the marker nearest the edge)."""
    m = MotorArray("MAC140", n=2, seed=0, home_position=edge)
    m.write_many({"V_HOME": 400, "T_HOME": 1, "P_HOME": 0, "STARTMODE": c.P_MODE})
    m.write("CNTRL_BITS", m.read("CNTRL_BITS") | np.array([0, c.INDEX_HOME]))
    m.write("MODE_REG", c.HOME2_MODE)
    for _ in range(5000):
        m.step()
        if (m.read("MODE_REG") == c.P_MODE).all():
            break
    zero_rad = m.position_rad - m.read("P_IST") * c.RAD_PER_COUNT
    marker = round(edge / np.pi) * np.pi
    one_sample = 400 / 16 * c.RAD_PER_COUNT * 2  # V_HOME's travel in two outer samples
    assert zero_rad[0] == pytest.approx(edge, abs=one_sample)
    assert zero_rad[1] == pytest.approx(marker, abs=one_sample)
