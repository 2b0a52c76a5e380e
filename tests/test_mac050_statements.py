"""Statements of the MAC050–141 manual (register chapter 3.2, function blocks 4.1, regulators
4.2–4.3, modes 4.4, monitoring 4.5), each test asserting the manual's words; the statement ids
(``statements.yaml`` beside the family's conformance file) are in each test's marker."""

from __future__ import annotations

import numpy as np
import pytest

from jvl_gym import ModeError, MotorArray
from jvl_gym.families.mac050_141 import constants as c

#: a coil set-up obeying the rules of manual 4.4.20 (its typical set-up)
COIL = {"P1": 10000, "P2": 12000, "P3": 58000, "P4": 60000, "P5": 12000, "P6": 1}


def _motor(n: int = 1, **kw) -> MotorArray:
    return MotorArray("MAC140", n=n, seed=0, **kw)


def _steps_until(m: MotorArray, leave: str, limit: int = 5000) -> int:
    """Step until the (one) motor is no longer in mode ``leave``; the number of steps."""
    for k in range(limit):
        m.step()
        if m.mode_name() != leave:
            return k + 1
    raise AssertionError(f"still in {leave} after {limit} samples")


# ------------------------------------------------------------------ 3.2.1 PROG_VERSION


@pytest.mark.statements("mac050_141:3.2.1:1", "mac050_141:3.2.1:2", "mac050_141:3.2.1:3")
def test_prog_version_reads_78_is_writable_and_not_kept_in_flash() -> None:
    m = _motor()
    assert int(m.read("PROG_VERSION")[0]) == 78  # 4Eh: version 4.14
    m.write("PROG_VERSION", 80)
    assert int(m.read("PROG_VERSION")[0]) == 80
    m.enter_safe_mode()
    m.write_flash()  # saves and restarts: the program version is the program's again
    assert int(m.read("PROG_VERSION")[0]) == 78


# ------------------------------------------------------------------ 3.2.2 MODE_REG, 4.4.16 SAFE


@pytest.mark.statements("mac050_141:3:1", "mac050_141:3.2.2:4", "mac050_141:4.4.16:5")
def test_256_in_safe_mode_restores_the_defaults_saves_them_and_resets() -> None:
    m = _motor()
    m.write("KVOUT", 3.0)
    m.enter_safe_mode()
    m.write_flash()
    assert m.read("KVOUT")[0] == 3.0  # the user set-up is in flash
    m.enter_safe_mode()
    m.write("MODE_REG", 256)
    assert m.read("KVOUT")[0] == 1.0 and m.mode_name() == "INIT_MODE"  # defaults, reset
    m.write("KVOUT", 2.0)
    m.enter_safe_mode()
    m.write("MODE_REG", 258)  # the last saved parameters are now the defaults
    assert m.read("KVOUT")[0] == 1.0


@pytest.mark.statements("mac050_141:3.2.2:2")
def test_mode_values_outside_0_to_24_and_256_to_258_are_refused() -> None:
    m = _motor()
    for bad in (25, 100, 255):
        before = m.regs.copy()
        with pytest.raises(ModeError):
            m.write("MODE_REG", bad)
        np.testing.assert_array_equal(m.regs, before)


# ------------------------------------------------------------------ 3.2.5 V_SOLL, 3.2.6 A_SOLL


def _set_up_mode(m: MotorArray, mode: int, *, v_soll: int = 1000, a_soll: int = 20,
                 t_soll: int = 1023, volts: float = 10.0, pulses: int = 200) -> None:
    """``mode`` set up to ask for more speed than V_SOLL: a far target, a fast pulse train, a
    full analogue input."""
    m.write_many({"V_SOLL": v_soll, "A_SOLL": a_soll, "T_SOLL": t_soll, "GEARF1": 1,
                  "GEARF2": 1, "FNCERRMAX": 0, "P_SOLL": 2000000, **COIL})
    if mode == c.A2POS_MODE:
        m.write_many({"P1": 0, "P2": 2000000})
    if mode == c.APOS_MODE:
        m.write_many({"P1": 2000000, "P2": 0, "P3": 0})
    if mode == c.COIL_MODE:
        m.write_many({"P5": 58000})  # start-position command: travel to P5 = 58000
    m.set_input(analog_volts=volts, pulse_counts=pulses)
    m.write("MODE_REG", mode)


_V_SOLL_MODES = [c.V_MODE, c.P_MODE, c.GP_MODE, c.AV_MODE, c.AVG_MODE, c.VAT_MODE, c.AG_MODE,
                 c.COIL_MODE, c.A2POS_MODE, c.APOS_MODE, c.GF_MODE]


@pytest.mark.statements("mac050_141:3.2.5:3", "mac050_141:3.2.5:4", "mac050_141:3.2.5:5",
                        "mac050_141:3.2.5:6", "mac050_141:3.2.5:7", "mac050_141:3.2.5:8",
                        "mac050_141:3.2.5:9", "mac050_141:3.2.5:10", "mac050_141:3.2.5:11",
                        "mac050_141:3.2.5:12", "mac050_141:3.2.5:13", "mac050_141:4.1.3:4",
                        "mac050_141:4.1.7:3", "mac050_141:4.1.12:2")
@pytest.mark.parametrize("mode", _V_SOLL_MODES, ids=[c.MODE_NAMES[x] for x in _V_SOLL_MODES])
def test_v_soll_is_the_speed_limit_of_every_velocity_using_mode(mode: int) -> None:
    """Manual 3.2.5: V_SOLL is the required, maximum or full-scale velocity of each mode: asked
    for more, the profile (FNC_OUT) reaches V_SOLL and never exceeds it."""
    m = _motor()
    _set_up_mode(m, mode)
    f = m.trace(["FNC_OUT"], 300)["FNC_OUT"][:, 0]
    assert np.abs(f).max() == 1000
    assert f[-1] == 1000


_A_SOLL_MODES = [c.V_MODE, c.P_MODE, c.GP_MODE, c.AV_MODE, c.AVG_MODE, c.HOME1_MODE,
                 c.HOME2_MODE, c.HOME3_MODE, c.VAT_MODE, c.AG_MODE, c.COIL_MODE, c.A2POS_MODE,
                 c.APOS_MODE, c.GF_MODE]


@pytest.mark.statements("mac050_141:3.2.6:3", "mac050_141:3.2.6:4", "mac050_141:3.2.6:5",
                        "mac050_141:3.2.6:6", "mac050_141:3.2.6:7", "mac050_141:3.2.6:8",
                        "mac050_141:3.2.6:9", "mac050_141:3.2.6:10", "mac050_141:3.2.6:11",
                        "mac050_141:3.2.6:12", "mac050_141:3.2.6:13", "mac050_141:3.2.6:14",
                        "mac050_141:4.1.5:2", "mac050_141:4.1.12:2")
@pytest.mark.parametrize("mode", _A_SOLL_MODES, ids=[c.MODE_NAMES[x] for x in _A_SOLL_MODES])
def test_a_soll_is_the_acceleration_limit_of_every_profile_mode(mode: int) -> None:
    """Manual 3.2.6: A_SOLL is the maximum acceleration/deceleration: the profile changes by
    A_SOLL per sample while it accelerates and never by more."""
    homing = mode in (c.HOME2_MODE, c.HOME3_MODE)  # the sensor (on the analogue input) far away
    m = _motor(home_position=10.0) if homing else _motor()
    m.write_many({"V_HOME": 1000, "T_HOME": 800})
    _set_up_mode(m, mode)
    f = m.trace(["FNC_OUT"], 120)["FNC_OUT"][:, 0]
    steps = np.abs(np.diff([0, *f]))
    assert steps.max() == 20
    assert np.all(steps[:10] == 20)


_T_SOLL_MODES = [c.V_MODE, c.P_MODE, c.GP_MODE, c.AV_MODE, c.AVG_MODE, c.HOME2_MODE,
                 c.HOME3_MODE, c.VAT_MODE, c.AG_MODE, c.COIL_MODE, c.A2POS_MODE, c.APOS_MODE,
                 c.GF_MODE]


@pytest.mark.statements("mac050_141:3.2.7:2", "mac050_141:3.2.7:3", "mac050_141:3.2.7:4",
                        "mac050_141:3.2.7:5", "mac050_141:3.2.7:6", "mac050_141:3.2.7:8",
                        "mac050_141:3.2.7:9", "mac050_141:3.2.7:10", "mac050_141:3.2.7:11",
                        "mac050_141:3.2.7:12", "mac050_141:3.2.7:13", "mac050_141:3.2.7:14",
                        "mac050_141:3.2.7:15", "mac050_141:3.2.41:5", "mac050_141:4.4.2:2",
                        "mac050_141:4.4.14:2", "mac050_141:4.4.15:2")
@pytest.mark.parametrize("mode", _T_SOLL_MODES, ids=[c.MODE_NAMES[x] for x in _T_SOLL_MODES])
def test_t_soll_bounds_the_torque_of_a_blocked_motor(mode: int) -> None:
    """Manual 3.2.7: T_SOLL is the maximum torque: a blocked rotor gets VF_OUT up to T_SOLL
    and no more (VAT: |ANINP·T_SOLL/1024| at the full 10 V is T_SOLL within one unit)."""
    homing = mode in (c.HOME2_MODE, c.HOME3_MODE)  # the sensor (on the analogue input) far away
    m = _motor(coulomb_friction=5.0, **({"home_position": 10.0} if homing else {}))
    m.write_many({"V_HOME": 1000, "T_HOME": 800})
    _set_up_mode(m, mode, t_soll=300, a_soll=50)
    vf = np.abs(m.trace(["VF_OUT"], 150)["VF_OUT"][:, 0])
    assert vf.max() <= 300 and vf.max() >= 299


@pytest.mark.statements("mac050_141:3.2.7:16", "mac050_141:3.2.121:2")
def test_full_torque_is_1023() -> None:
    m = _motor(coulomb_friction=50.0)
    m.write_many({"T_SOLL": 1023, "V_SOLL": 3000, "A_SOLL": 1000})
    m.write("MODE_REG", c.V_MODE)
    vf = m.trace(["VF_OUT"], 60)["VF_OUT"][:, 0]
    assert vf.max() == 1023


# ------------------------------------------------------------------ 3.2.8 P_FNC, 3.2.10 P_IST


_P_FNC_MODES = [c.V_MODE, c.P_MODE, c.AV_MODE, c.GP_MODE, c.AVG_MODE, c.AG_MODE, c.COIL_MODE]


@pytest.mark.statements("mac050_141:3.2.8:1", "mac050_141:3.2.8:2", "mac050_141:3.2.8:3",
                        "mac050_141:3.2.8:4", "mac050_141:3.2.8:5", "mac050_141:3.2.8:6",
                        "mac050_141:3.2.8:7", "mac050_141:4.1.2:6")
@pytest.mark.parametrize("mode", _P_FNC_MODES, ids=[c.MODE_NAMES[x] for x in _P_FNC_MODES])
def test_p_fnc_accumulates_the_profile_in_the_function_generator_modes(mode: int) -> None:
    """Manual 3.2.8, 4.1.2: the function generator adds each sample's FNC_OUT (1/16
    count/sample) to P_FNC (1/16 counts)."""
    m = _motor()
    _set_up_mode(m, mode, pulses=10, volts=3.0)
    m.step(20)
    for _ in range(20):
        before = int(m.read("P_FNC")[0])
        m.step()
        assert int(m.read("P_FNC")[0]) - before == int(m.read("FNC_OUT")[0]) != 0


@pytest.mark.statements("mac050_141:3.2.8:9", "mac050_141:4.1.2:9", "mac050_141:4.1.2:10")
def test_subtracting_from_p_fnc_is_a_relative_move() -> None:
    """Manual 3.2.8, 4.1.2: subtracting 1600000 (1/16 counts) from P_FNC moves the motor a
    further 100000 counts in P_MODE, and P_FNC ends at the same value again; repeatable."""
    m = _motor()
    m.write_many({"P_SOLL": 0, "V_SOLL": 4000, "A_SOLL": 100})
    m.write("MODE_REG", c.P_MODE)
    for k in (1, 2):
        m.write("P_FNC", int(m.read("P_FNC")[0]) - 1600000)
        m.run(2.0)
        assert int(m.read("P_FNC")[0]) == 0
        assert abs(int(m.read("P_IST")[0]) - k * 100000) < 10


@pytest.mark.statements("mac050_141:3.2.10:1", "mac050_141:3.2.10:2")
def test_p_ist_may_be_overwritten_without_moving_the_motor() -> None:
    """Manual 3.2.10: P_IST, the position in encoder counts, can be overwritten: control does
    not use it, so the motor holding its position in P_MODE stays where it is."""
    m = _motor()
    m.write_many({"P_SOLL": 4096, "V_SOLL": 2000})
    m.write("MODE_REG", c.P_MODE)
    m.run(1.0)
    assert m.position_rad[0] == pytest.approx(2 * np.pi, abs=10 * c.RAD_PER_COUNT)
    where = m.position_rad[0]
    m.write("P_IST", 50000)
    m.run(0.5)
    assert m.position_rad[0] == pytest.approx(where, abs=3 * c.RAD_PER_COUNT)
    assert abs(int(m.read("P_IST")[0]) - 50000) <= 3  # it counts on from the written value


_ALL_MODES_ALIVE = [c.INIT_MODE, c.V_MODE, c.AT_MODE, c.MANI_MODE, c.STOP_MODE]


@pytest.mark.statements("mac050_141:3.2.10:4", "mac050_141:3.2.12:3", "mac050_141:4.2.1:2",
                        "mac050_141:4.2.1:3", "mac050_141:4.4.1:4", "mac050_141:4.5.3:3")
def test_p_ist_and_v_ist_follow_the_shaft_in_init_mode() -> None:
    """Manual 3.2.10/3.2.12, 4.2: V_IST is the encoder's count difference per sample and is added
    to P_IST, in every mode, also INIT_MODE with the motor passive (a coasting rotor)."""
    m = _motor(initial_speed=300.0, load_inertia=1e-3)  # a flywheel: the braking is slow
    assert m.mode_name() == "INIT_MODE"
    m.step()  # the encoder is read at the start of a sample: one sample behind the shaft
    p_start, t_start = int(m.read("P_IST")[0]), m.position_rad[0]
    for _ in range(10):
        p0 = int(m.read("P_IST")[0])
        m.step()
        dp = int(m.read("P_IST")[0]) - p0
        assert dp == int(m.read("V_IST")[0]) > 0
    travel = (m.position_rad[0] - t_start) / c.RAD_PER_COUNT
    assert int(m.read("P_IST")[0]) - p_start == pytest.approx(travel, rel=0.05)


@pytest.mark.statements("mac050_141:3.2.10:4", "mac050_141:3.2.12:3", "mac050_141:4.2.1:3",
                        "mac050_141:4.4.5:3", "mac050_141:4.4.8:3")
@pytest.mark.parametrize("mode", [c.AT_MODE, c.MANI_MODE])
def test_p_ist_and_v_ist_are_updated_in_the_torque_and_manual_modes(mode: int) -> None:
    m = _motor()
    m.write_many({"T_SOLL": 300, "MAN_I_NOM": 300, "MAN_ALPHA": 0})
    m.set_input(analog_volts=3.0)
    m.write("MODE_REG", mode)
    m.step(5)
    m.set_input(load_torque=0.5)  # turns the shaft in both modes
    tr = m.trace(["P_IST", "V_IST"], 100)
    assert np.any(tr["V_IST"][:, 0] != 0)
    np.testing.assert_array_equal(np.diff(tr["P_IST"][:, 0]), tr["V_IST"][1:, 0])


# ------------------------------------------------------------------ 3.2.13 KVOUT


@pytest.mark.statements("mac050_141:3.2.13:3", "mac050_141:4.2.1:5")
def test_the_speed_loop_torque_is_multiplied_by_kvout() -> None:
    """Manual 3.2.13, 4.2: the VF filter's output is multiplied by KVOUT to give VF_OUT."""
    from jvl_gym.families.mac050_141.firmware.speed_loop import speed_regulator

    outs = []
    for kvout in (1.0, 2.0, 4.0):
        m = _motor()
        m.write_many({"KVOUT": kvout, "KFF3": 1.0, "KFF2": 0.0, "KFF1": 0.0, "KFF0": 0.0,
                      "GEARB": 0.0, "KVFX4": 0.5, "KVFX3": 0.0, "KVFX2": 0.0, "KVFX1": 0.0,
                      "KVFY3": 0.0, "KVFY2": 0.0, "KVFY1": 0.0, "KVFY0": 0.0})
        speed_regulator(m.regs[0], m.state[0], 100.0, False, 1023.0)
        outs.append(int(m.read("VF_OUT")[0]))
    assert outs == [50, 100, 200]


# ------------------------------------------------------------------ 3.2.14 GEARF1, GEARF2


@pytest.mark.statements("mac050_141:3.2.14:1", "mac050_141:3.2.14:2", "mac050_141:3.2.14:3",
                        "mac050_141:4.1.3:3", "mac050_141:4.1.7:1", "mac050_141:4.4.4:2",
                        "mac050_141:4.4.7:1")
@pytest.mark.parametrize("mode", [c.GP_MODE, c.GF_MODE, c.AVG_MODE, c.AG_MODE])
def test_the_gear_ratio_is_gearf1_over_gearf2_and_its_sign_reverses(mode: int) -> None:
    """Manual 3.2.14: output/input = GEARF1/GEARF2; a negative GEARF1 reverses the motor; used
    in GP, AVG, AG and GF (0 V on the analogue input: AVG adds nothing, AG's factor is 1.01)."""
    m = _motor(2)
    m.write_many({"GEARF1": np.array([3, -3]), "GEARF2": 2, "V_SOLL": 10000, "A_SOLL": 200,
                  "FNCERRMAX": 0})
    m.set_input(pulse_counts=10, analog_volts=0.0)
    m.write("MODE_REG", mode)
    m.run(0.5)
    v = np.mean(m.trace(["V_IST"], 100)["V_IST"], axis=0)
    expected = 15.0 * (1.01 if mode == c.AG_MODE else 1.0)
    np.testing.assert_allclose(v, [expected, -expected], rtol=3e-3)


# ------------------------------------------------------------------ 3.2.16–19 I2T, UIT; 4.5.1–2


@pytest.mark.statements("mac050_141:3.2.16:3", "mac050_141:3.2.16:4", "mac050_141:3.2.35:17",
                        "mac050_141:4.4:2", "mac050_141:4.5.1:1")
def test_i2t_trip_sets_i2t_err_and_stops_to_init() -> None:
    """Manual 3.2.16, 4.5.1: I2T above I2TLIM sets I2T_ERR and the motor goes to INIT_MODE."""
    m = _motor()
    m.write_many({"I2TLIM": 200, "V_SOLL": 1600})
    m.write("MODE_REG", c.V_MODE)
    m.set_input(load_torque=0.3)
    _steps_until(m, "V_MODE", 2000)
    m.run(0.5)
    assert int(m.read("ERR_STAT")[0]) & c.I2T_ERR
    assert m.mode_name() == "INIT_MODE" and int(m.read("I2T")[0]) > 200


@pytest.mark.statements("mac050_141:3.2.16:2", "mac050_141:3.2.16:5", "mac050_141:4.4:1",
                        "mac050_141:4.5.1:2")
def test_i2t_integrates_the_squared_phase_currents_in_every_mode() -> None:
    """Manual 3.2.16: I2T integrates Ia² + Ib² + Ic², in every mode: in MANI_MODE a stator
    field of twice the current raises I2T four times as fast; a passive motor adds nothing."""
    m = _motor(3, load_inertia=1e-2)  # the field does not turn the rotor much
    m.write("MAN_I_NOM", np.array([0, 200, 400]))
    m.write("MAN_ALPHA", 0)
    m.write("MODE_REG", c.MANI_MODE)
    m.step(200)
    i2t = m.read("I2T").astype(float)
    assert i2t[0] == 0
    assert i2t[2] / i2t[1] == pytest.approx(4.0, rel=0.1)


@pytest.mark.statements("mac050_141:3.2.18:1", "mac050_141:3.2.18:2", "mac050_141:3.2.18:3",
                        "mac050_141:3.2.35:14", "mac050_141:3.2.35:20", "mac050_141:4.5.2:1",
                        "mac050_141:4.5.2:2")
def test_uit_counts_only_regenerated_power_and_trips_above_52_volts() -> None:
    """Manual 3.2.18/19, 4.5.2: UIT integrates the regenerated power (negative power is taken
    as 0: UIT stays 0 while the motor accelerates); above UITLIM with a supply above 52 V, UIT_ERR
    is set and the motor goes to INIT_MODE; at 48 V it keeps running."""
    m = _motor(2)
    m.set_input(supply_volts=[56.0, 48.0])
    m.write_many({"UITLIM": 1, "V_SOLL": 3000, "A_SOLL": 100})
    m.write("MODE_REG", c.V_MODE)
    m.step(25)  # accelerating: power flows into the motor
    np.testing.assert_array_equal(m.read("UIT"), [0, 0])
    modes = m.trace(["MODE_REG"], 275)["MODE_REG"][:, 0]
    m.write("V_SOLL", -3000)  # braking: power flows back
    modes = np.concatenate([modes, m.trace(["MODE_REG"], 300)["MODE_REG"][:, 0]])
    assert c.STOP_MODE in modes  # the error stop brakes first (4.5.2)
    assert np.all(m.read("UIT") > 1)
    err = m.read("ERR_STAT")
    assert err[0] & c.UIT_ERR and not err[1] & c.UIT_ERR
    np.testing.assert_array_equal(m.read("MODE_REG"), [c.INIT_MODE, c.V_MODE])


# ------------------------------------------------------------- 3.2.20–27 FLWERR, FNCERR; 4.5.4–5


_FLWERR_MODES = [c.V_MODE, c.P_MODE, c.GP_MODE, c.AV_MODE, c.AVG_MODE, c.VAT_MODE, c.AG_MODE,
                 c.COIL_MODE, c.A2POS_MODE, c.APOS_MODE, c.GF_MODE, c.AVZ_MODE]


@pytest.mark.statements("mac050_141:3.2.20:1", "mac050_141:3.2.20:3", "mac050_141:3.2.20:4",
                        "mac050_141:3.2.20:8", "mac050_141:4.4.2:3", "mac050_141:4.4.3:3",
                        "mac050_141:4.4.4:4", "mac050_141:4.4.6:3", "mac050_141:4.4.7:3",
                        "mac050_141:4.4.21:3", "mac050_141:4.4.22:3", "mac050_141:4.4.25:3",
                        "mac050_141:4.5.4:1")
@pytest.mark.parametrize("mode", _FLWERR_MODES, ids=[c.MODE_NAMES[x] for x in _FLWERR_MODES])
def test_flwerr_accumulates_the_velocity_error_of_a_blocked_motor(mode: int) -> None:
    """Manual 3.2.20, 4.5.4: in the regulated modes FLWERR accumulates the velocity error (the
    profile minus the measured velocity): a blocked rotor makes it grow, so it detects a
    blockage, even in the velocity modes."""
    m = _motor(coulomb_friction=5.0)
    _set_up_mode(m, mode, t_soll=300, pulses=20)
    tr = m.trace(["FLWERR", "P_FNC"], 100)
    flw, p_fnc = tr["FLWERR"][:, 0], tr["P_FNC"][:, 0]
    assert abs(int(flw[-1])) > 100
    # the motor does not move: FLWERR is the profile's travel, P_FNC/16 (P_FNC's start differs)
    assert int(flw[-1]) - int(flw[0]) == pytest.approx((int(p_fnc[-1]) - int(p_fnc[0])) / 16,
                                                       abs=2)


_NO_FLWERR_MODES = [c.INIT_MODE, c.AT_MODE, c.MANI_MODE]


@pytest.mark.statements("mac050_141:3.2.20:2", "mac050_141:3.2.24:2", "mac050_141:4.4.1:5",
                        "mac050_141:4.4.1:6", "mac050_141:4.4.5:4", "mac050_141:4.4.8:4")
@pytest.mark.parametrize("mode", _NO_FLWERR_MODES, ids=[c.MODE_NAMES[x] for x in _NO_FLWERR_MODES])
def test_flwerr_and_fncerr_are_0_in_the_other_modes(mode: int) -> None:
    """Manual 3.2.20/3.2.24, 4.4.1, 4.4.5, 4.4.8: FLWERR and FNCERR are 0 in INIT, AT and MANI,
    also with the rotor blocked and after a mode that left them non-zero."""
    m = _motor(coulomb_friction=5.0)
    m.write_many({"T_SOLL": 300, "V_SOLL": 1000, "P_SOLL": 100000, "FNCERRMAX": 0,
                  "MAN_I_NOM": 300})
    m.write("MODE_REG", c.P_MODE)
    m.step(100)
    assert m.read("FLWERR")[0] != 0 and m.read("FNCERR")[0] != 0
    m.write("MODE_REG", c.INIT_MODE)  # through STOP_MODE: the blocked motor stops at once
    m.step(2)
    m.set_input(analog_volts=3.0)
    if mode != c.INIT_MODE:
        m.write("MODE_REG", mode)
    tr = m.trace(["FLWERR", "FNCERR"], 50)
    assert not tr["FLWERR"].any() and not tr["FNCERR"].any()


@pytest.mark.statements("mac050_141:3.2.22:1", "mac050_141:3.2.22:2", "mac050_141:3.2.35:15",
                        "mac050_141:3.2.35:20", "mac050_141:4.1.8:3", "mac050_141:4.4.2:5",
                        "mac050_141:4.4.3:9", "mac050_141:4.4.12:3", "mac050_141:4.5.4:2",
                        "mac050_141:4.5.4:3")
def test_flwerrmax_trips_flw_err_through_stop_and_0_disables_it() -> None:
    """Manual 3.2.22, 4.5.4: |FLWERR| > FLWERRMAX sets FLW_ERR and the motor goes to INIT_MODE
    through STOP_MODE; FLWERRMAX = 0 disables the check."""
    m = _motor(2, coulomb_friction=5.0)
    m.write_many({"V_SOLL": 800, "T_SOLL": 300, "FLWERRMAX": np.array([5000, 0])})
    m.write("MODE_REG", c.V_MODE)
    modes = m.trace(["MODE_REG", "FLWERR"], 300)
    seen = modes["MODE_REG"][:, 0]
    assert c.STOP_MODE in seen and seen[-1] == c.INIT_MODE
    first_stop = int(np.argmax(seen == c.STOP_MODE))
    assert abs(modes["FLWERR"][first_stop - 1, 0]) <= 5000 < abs(modes["FLWERR"][first_stop, 0])
    err = m.read("ERR_STAT")
    assert err[0] & c.FLW_ERR and not err[1] & c.FLW_ERR
    assert int(m.read("MODE_REG")[1]) == c.V_MODE and abs(int(m.read("FLWERR")[1])) > 5000


@pytest.mark.statements("mac050_141:3.2.26:1", "mac050_141:3.2.26:2", "mac050_141:3.2.35:16",
                        "mac050_141:3.2.35:20", "mac050_141:4.4.3:6", "mac050_141:4.5.5:2")
def test_fncerrmax_trips_fnc_err_and_0_disables_it() -> None:
    """Manual 3.2.26, 4.5.5: |FNCERR| > FNCERRMAX sets FNC_ERR and the motor goes to INIT_MODE;
    FNCERRMAX = 0 disables the check (a held motor in P_MODE)."""
    m = _motor(2, coulomb_friction=5.0)
    m.write_many({"V_SOLL": 800, "T_SOLL": 300, "P_SOLL": 1000000,
                  "FNCERRMAX": np.array([20000, 0])})
    m.write("MODE_REG", c.P_MODE)
    modes = m.trace(["MODE_REG"], 600)["MODE_REG"][:, 0]
    assert c.STOP_MODE in modes  # through STOP_MODE (4.5.5)
    err = m.read("ERR_STAT")
    assert err[0] & c.FNC_ERR and not err[1] & c.FNC_ERR
    np.testing.assert_array_equal(m.read("MODE_REG"), [c.INIT_MODE, c.P_MODE])
    assert abs(int(m.read("FNCERR")[1])) > 20000


_NO_CORRECTION_MODES = [c.V_MODE, c.AV_MODE, c.AVG_MODE, c.VAT_MODE, c.AVZ_MODE]


@pytest.mark.statements("mac050_141:3.2.24:4", "mac050_141:4.4.2:4", "mac050_141:4.4.2:6",
                        "mac050_141:4.4.6:4", "mac050_141:4.4.7:4")
@pytest.mark.parametrize("mode", _NO_CORRECTION_MODES,
                         ids=[c.MODE_NAMES[x] for x in _NO_CORRECTION_MODES])
def test_without_function_correction_fncerr_stays_0(mode: int) -> None:
    """Manual 4.4.2, 4.4.6, 4.4.7: the velocity modes do not correct the profile (correction of
    function block passive), so FNCERR, the sum of the corrections (3.2.24), stays 0 and the
    profile goes on though the blocked motor cannot follow."""
    m = _motor(coulomb_friction=5.0)
    _set_up_mode(m, mode, t_soll=300, pulses=20, volts=5.0)
    tr = m.trace(["FNCERR", "FNC_OUT"], 200)
    assert not tr["FNCERR"].any()
    assert np.abs(tr["FNC_OUT"][-1, 0]) > 100


@pytest.mark.statements("mac050_141:3.2.24:5", "mac050_141:4.4.4:5", "mac050_141:4.4.25:4")
@pytest.mark.parametrize("mode", [c.GP_MODE, c.GF_MODE])
def test_in_the_gear_modes_fncerr_is_the_position_error(mode: int) -> None:
    """Manual 3.2.24: in GP and GF FNCERR is a positioning error: the lag of the motor's
    function position behind the geared pulse position, in 1/16 counts."""
    m = _motor()
    m.write_many({"GEARF1": 1, "GEARF2": 1, "V_SOLL": 20000, "A_SOLL": 5, "FNCERRMAX": 0})
    m.set_input(pulse_counts=20)
    m.write("MODE_REG", mode)
    p_fnc0 = int(m.read("P_FNC")[0])
    tr = m.trace(["P_FNC", "FNCERR"], 30)
    travelled = tr["P_FNC"][:, 0] - p_fnc0  # the profile's travel since the mode began
    pulses = 16 * 20 * np.arange(1, 31)  # the geared pulse position since the mode began
    np.testing.assert_array_equal(tr["FNCERR"][:, 0], travelled - pulses)
    assert tr["FNCERR"][-1, 0] < -1000  # the profile lags (A_SOLL 5)


# ------------------------------------------------------------------ 3.2.28–30 limits; 4.5.3


@pytest.mark.statements("mac050_141:3.2.10:3", "mac050_141:3.2.28:1", "mac050_141:3.2.28:2",
                        "mac050_141:3.2.28:3", "mac050_141:3.2.35:10", "mac050_141:3.2.35:20",
                        "mac050_141:4.5.3:1", "mac050_141:4.5.3:2")
def test_position_limits_trip_below_min_and_above_max_and_both_0_disable() -> None:
    """Manual 3.2.28/30, 4.5.3: P_IST < MIN_P_IST or P_IST > MAX_P_IST sets PLIM_ERR and the
    motor goes to INIT_MODE through STOP_MODE; the check is on while either limit is non-zero
    (motor 2: MIN_P_IST = 0, MAX_P_IST far: moving below 0 trips), off when both are 0."""
    m = _motor(4)
    m.write_many({"MIN_P_IST": np.array([-2000, -100000, 0, 0]),
                  "MAX_P_IST": np.array([100000, 2000, 100000, 0]),
                  "V_SOLL": np.array([-1000, 1000, -1000, -1000])})
    m.write("MODE_REG", c.V_MODE)
    tr = m.trace(["MODE_REG"], 300)["MODE_REG"]
    err = m.read("ERR_STAT")
    assert [bool(e & c.PLIM_ERR) for e in err] == [True, True, True, False]
    for k in range(3):
        assert c.STOP_MODE in tr[:, k] and tr[-1, k] == c.INIT_MODE
    assert int(m.read("MODE_REG")[3]) == c.V_MODE
    p = m.read("P_IST")
    assert p[0] < -2000 and p[1] > 2000 and p[2] < 0


# ------------------------------------------------------------------ 3.2.32 ACC_EMERG


@pytest.mark.statements("mac050_141:3.2.32:1", "mac050_141:3.2.32:2", "mac050_141:4.1.8:1",
                        "mac050_141:4.4.12:2")
def test_acc_emerg_replaces_a_soll_when_an_error_stops_the_motor() -> None:
    """Manual 3.2.32: after an error the stop decelerates with ACC_EMERG instead of A_SOLL;
    ACC_EMERG = 0 keeps A_SOLL."""
    slopes = []
    for acc_emerg in (0, 5):
        m = _motor()
        m.write_many({"V_SOLL": 3000, "A_SOLL": 100, "ACC_EMERG": acc_emerg, "MIN_P_IST": -1,
                      "MAX_P_IST": 20000})
        m.write("MODE_REG", c.V_MODE)
        tr = m.trace(["MODE_REG", "FNC_OUT"], 400)
        stop = tr["FNC_OUT"][tr["MODE_REG"][:, 0] == c.STOP_MODE, 0]
        assert int(m.read("ERR_STAT")[0]) & c.PLIM_ERR
        slopes.append(set(np.diff(stop[:6]).tolist()))
    assert slopes == [{-100}, {-5}]


# ------------------------------------------------------------------ 3.2.33–34 INPOSWIN, INPOSCNT


@pytest.mark.statements("mac050_141:3.2.33:2", "mac050_141:3.2.33:5", "mac050_141:4.1.1:5")
def test_in_position_needs_less_than_inposwin_not_equal() -> None:
    """Manual 3.2.33: in position only when the deviation is less than INPOSWIN; equal is not in
    position. A motor at rest in V_MODE with INPOSCNT = 0 (|V_IST| = 0): IN_POS with INPOSWIN 1,
    not with INPOSWIN 0."""
    m = _motor(2)
    m.write_many({"V_SOLL": 0, "INPOSCNT": 0, "INPOSWIN": np.array([1, 0])})
    m.write("MODE_REG", c.V_MODE)
    m.step(20)
    np.testing.assert_array_equal(m.read("V_IST"), [0, 0])
    assert [bool(e & c.IN_POS) for e in m.read("ERR_STAT")] == [True, False]


@pytest.mark.statements("mac050_141:3.2.20:8", "mac050_141:3.2.33:3", "mac050_141:3.2.33:4",
                        "mac050_141:4.4.3:5")
def test_inposcnt_is_the_number_of_consecutive_samples_inside_the_window() -> None:
    """Manual 3.2.34: IN_POS comes INPOSCNT consecutive samples after the position is inside
    INPOSWIN (P_MODE: |P_SOLL − P_FNC/16 + FLWERR| < INPOSWIN, manual 4.4.3)."""
    for cnt in (1, 10):
        m = _motor()
        m.write_many({"P_SOLL": 5000, "V_SOLL": 2000, "INPOSWIN": 10, "INPOSCNT": cnt})
        m.write("MODE_REG", c.P_MODE)
        tr = m.trace(["ERR_STAT", "P_FNC", "FLWERR"], 300)
        inside = np.abs(5000 - tr["P_FNC"][:, 0] / 16 + tr["FLWERR"][:, 0]) < 10
        in_pos = (tr["ERR_STAT"][:, 0] & c.IN_POS) != 0
        run = np.zeros(inside.size, dtype=int)  # consecutive samples inside, up to each
        for k, x in enumerate(inside):
            run[k] = (run[k - 1] + 1 if k else 1) if x else 0
        np.testing.assert_array_equal(in_pos, run >= cnt)
        assert not in_pos[0] and in_pos[-1] and (run[in_pos.argmax() - 1] == cnt - 1)


@pytest.mark.statements("mac050_141:3.2.33:6", "mac050_141:4.1.1:6", "mac050_141:4.4.2:8")
def test_in_velocity_mode_with_inposcnt_in_pos_is_the_velocity_error() -> None:
    """Manual 3.2.33/34, 4.1.1: in V_MODE with INPOSCNT > 0, IN_POS when |V_SOLL − 16·V_IST| <
    INPOSWIN: at the required speed, not while accelerating, not when blocked; with
    INPOSCNT = 0 it is the standstill test, not set while running."""
    m = _motor(3, coulomb_friction=np.array([0.0, 5.0, 0.0]))
    m.write_many({"V_SOLL": 1600, "T_SOLL": 300, "INPOSWIN": 40,
                  "INPOSCNT": np.array([3, 3, 0])})
    m.write("MODE_REG", c.V_MODE)
    m.step(10)
    assert not (m.read("ERR_STAT") & c.IN_POS).any()  # accelerating
    m.run(0.5)
    assert np.abs(1600 - 16 * int(m.read("V_IST")[0])) < 40
    assert [bool(e & c.IN_POS) for e in m.read("ERR_STAT")] == [True, False, False]


# ------------------------------------------------------------------ 3.2.35 ERR_STAT


@pytest.mark.statements("mac050_141:3.2.35:18", "mac050_141:4.4.1:7")
def test_an_error_bit_blocks_leaving_init_until_it_is_cleared() -> None:
    """Manual 3.2.35, 4.4.1: after an error stop the motor stays in INIT_MODE until the error
    bit is reset; writing a mode before that is refused and changes nothing."""
    m = _motor(coulomb_friction=5.0)
    m.write_many({"V_SOLL": 800, "T_SOLL": 300, "FLWERRMAX": 1000})
    m.write("MODE_REG", c.V_MODE)
    m.run(0.5)
    assert m.mode_name() == "INIT_MODE" and int(m.read("ERR_STAT")[0]) & c.FLW_ERR
    before = m.regs.copy()
    with pytest.raises(ModeError, match="error bit"):
        m.write("MODE_REG", c.V_MODE)
    np.testing.assert_array_equal(m.regs, before)
    m.write("ERR_STAT", 0)
    m.write("MODE_REG", c.V_MODE)
    assert m.mode_name() == "V_MODE"


@pytest.mark.statements("mac050_141:3.2.35:8")
def test_relative_positioning_by_p_fnc_moves_by_px() -> None:
    """Manual 3.2.35 bit 10 RELPOSPFNC: with the bit set, a position register pointer subtracts
    16·Px from P_FNC; in P_MODE the motor moves a further Px."""
    m = _motor()
    m.write_many({"P3": 3000, "V_SOLL": 3000})
    m.write("MODE_REG", c.P_MODE)
    m.write("ERR_STAT", c.RELPOSPFNC)
    for k in (1, 2):
        m.write("P_REG_P", 3)
        m.run(1.0)
        assert abs(int(m.read("P_IST")[0]) - k * 3000) < 10
    assert int(m.read("P_SOLL")[0]) == 0


@pytest.mark.statements("mac050_141:3.2.35:9", "mac050_141:3.2.43:3")
def test_absolute_positioning_by_the_registers_when_neither_bit_is_set() -> None:
    """Manual 3.2.35 bit 9: with RELPOSPSOLL and RELPOSPFNC reset, P_SOLL = Px."""
    m = _motor()
    m.write_many({"P3": 3000, "P_SOLL": 777})
    m.write("P_REG_P", 3)
    m.write("P_REG_P", 3)
    assert int(m.read("P_SOLL")[0]) == 3000


# ------------------------------------------------------------------ 3.2.36 CNTRL_BITS


@pytest.mark.statements("mac050_141:3.2.36:1")
def test_cntrl_bits_13_to_15_show_the_hall_signals() -> None:
    """Manual 3.2.36 bits 15..13: the hall status: a turning rotor shows the six hall states
    1..6 in turn, each for a sixth of the electrical turn (ELDEG_IST)."""
    m = _motor()
    m.write("V_SOLL", 400)
    m.write("MODE_REG", c.V_MODE)
    tr = m.trace(["CNTRL_BITS", "ELDEG_IST"], 300)
    hall = tr["CNTRL_BITS"][:, 0] >> 13
    assert set(hall.tolist()) == {1, 2, 3, 4, 5, 6}
    changes = np.flatnonzero(np.diff(hall))
    assert changes.size >= 6
    for k in changes:  # a hall change every 2048/6 electrical units
        assert min(int(tr["ELDEG_IST"][k + 1, 0]) % 341, 341 - int(tr["ELDEG_IST"][k + 1, 0])
                   % 341) < 40


@pytest.mark.statements("mac050_141:3.2.36:4", "mac050_141:3.2.163:3")
def test_auto_resync_sets_p_fnc_to_16_p_ist_in_init_mode() -> None:
    """Manual 3.2.36 bit 9, 3.2.163: with AUTO_RESYNC, in INIT_MODE P_FNC = 16·P_IST (a turning
    passive motor); without it P_FNC is left alone."""
    m = _motor(2, initial_speed=50.0)
    cb = int(m.read("CNTRL_BITS")[0])
    m.write("CNTRL_BITS", np.array([cb | c.AUTO_RESYNC, cb & ~c.AUTO_RESYNC]))
    m.step(10)
    p_ist = m.read("P_IST")
    assert p_ist[0] > 0
    np.testing.assert_array_equal(m.read("P_FNC"), [16 * p_ist[0], 0])


@pytest.mark.statements("mac050_141:3.2.36:2", "mac050_141:3.2.36:3", "mac050_141:3.2.163:1",
                        "mac050_141:3.2.163:2")
def test_manual_resynchronisation_absolute_and_relative() -> None:
    """Manual 3.2.163: MAN_RESYNC without REL_RESYNC sets P_SOLL = P_IST = P_NEW and
    P_FNC = 16·P_NEW; with REL_RESYNC it adds P_NEW (16·P_NEW to P_FNC); the bit clears itself."""
    m = _motor()
    m.write_many({"P_NEW": 1234, "P_SOLL": 50})
    cb = int(m.read("CNTRL_BITS")[0]) & ~c.AUTO_RESYNC
    m.write("CNTRL_BITS", cb | c.MAN_RESYNC)
    m.step()
    assert [int(m.read(x)[0]) for x in ("P_SOLL", "P_IST", "P_FNC")] == [1234, 1234, 16 * 1234]
    assert not int(m.read("CNTRL_BITS")[0]) & c.MAN_RESYNC
    m.write("P_NEW", 100)
    m.write("CNTRL_BITS", cb | c.MAN_RESYNC | c.REL_RESYNC)
    m.step()
    assert [int(m.read(x)[0]) for x in ("P_SOLL", "P_IST", "P_FNC")] == [1334, 1334, 16 * 1334]
    assert not int(m.read("CNTRL_BITS")[0]) & c.MAN_RESYNC


@pytest.mark.statements("mac050_141:3.2.36:6", "mac050_141:3.2.116:2")
def test_recinnerbit_records_at_the_inner_rate() -> None:
    """Manual 3.2.36 bit 8: with RECINNERBIT the buffer is written at 7812.5 Hz (15 records per
    outer sample of 520.8 Hz), without it once per outer sample."""
    m = _motor(2)
    cb = int(m.read("CNTRL_BITS")[0]) | c.RECORDBIT
    m.write("CNTRL_BITS", np.array([cb | c.RECINNERBIT, cb]))
    m.step(2)
    np.testing.assert_array_equal(m.read("REC_CNT"), [2 * c.INNER_PER_OUTER, 2])
    assert c.INNER_PER_OUTER == 15 and c.INNER_HZ == pytest.approx(7812.5)


@pytest.mark.statements("mac050_141:3.2.36:10", "mac050_141:3.2.36:11", "mac050_141:3.2.36:12")
def test_pulse_format_and_sign_take_effect_only_after_flash_and_reset() -> None:
    """Manual 3.2.36 bits 2, 3 and 0–1: PULSEDIR (pulse + direction instead of quadrature),
    INPSIGN (count reversed) and USERINTF are read at power-on: a write changes nothing until
    the set-up is saved in flash and the motor restarts."""
    m = _motor()
    assert m.pulse_decoding() == (np.array([False]), np.array([False]))
    latched = int(m.interface_bits[0])
    m.write("CNTRL_BITS", int(m.read("CNTRL_BITS")[0]) | c.PULSEDIR | c.INPSIGN | 0b11)
    dec = m.pulse_decoding()
    assert not dec[0][0] and not dec[1][0] and int(m.interface_bits[0]) == latched
    m.enter_safe_mode()
    m.write_flash()
    dec = m.pulse_decoding()
    assert dec[0][0] and dec[1][0] and int(m.interface_bits[0]) & 0b11 == 0b11


# ------------------------------------------------------------------ 3.2.37–42 power-on and homing


@pytest.mark.statements("mac050_141:3.2.37:1", "mac050_141:3.2.37:2", "mac050_141:3.2.42:2")
def test_the_motor_starts_in_startmode_at_power_on_when_home_mode_is_0() -> None:
    m = _motor()
    m.write_many({"STARTMODE": c.V_MODE, "V_SOLL": 500, "HOME_MODE": 0})
    m.enter_safe_mode()
    m.write_flash()  # saved, and the motor restarts
    assert m.mode_name() == "V_MODE"
    m.step(50)
    assert int(m.read("V_IST")[0]) == pytest.approx(500 / 16, abs=1)


@pytest.mark.statements("mac050_141:3.2.42:1", "mac050_141:3.2.42:3", "mac050_141:3.2.42:6",
                        "mac050_141:4.4.13:8")
def test_home_mode_low_byte_homes_at_power_on_then_startmode() -> None:
    """Manual 3.2.42: the low byte of HOME_MODE is the homing mode run after power-on; once the
    home is found the motor goes on in STARTMODE (4.4.13: MODE_REG = STARTMODE)."""
    m = _motor(end_stop_low=-3.0, end_stop_high=3.0)
    m.write_many({"STARTMODE": c.P_MODE, "HOME_MODE": (13 << 8) | c.HOME1_MODE, "V_HOME": -800,
                  "T_HOME": 300, "P_HOME": -100})
    m.enter_safe_mode()
    m.write_flash()
    assert m.mode_name() == "HOME1_MODE"
    _steps_until(m, "HOME1_MODE", 3000)
    assert m.mode_name() == "P_MODE"
    assert abs(int(m.read("P_IST")[0]) + 100) <= 2


@pytest.mark.statements("mac050_141:3.2.38:1", "mac050_141:3.2.40:1", "mac050_141:3.2.40:2",
                        "mac050_141:3.2.41:1", "mac050_141:3.2.41:2", "mac050_141:4.4.13:1",
                        "mac050_141:4.4.13:2", "mac050_141:4.4.13:4", "mac050_141:4.4.13:5",
                        "mac050_141:4.4.13:6", "mac050_141:4.4.13:7", "mac050_141:4.4.13:9")
def test_home1_counts_50_samples_above_t_home_with_the_torque_limited_to_1_25_t_home() -> None:
    """Manual 3.2.41, 4.4.13: HOME1 runs at V_HOME (its sign the direction) into the mechanical
    stop with the torque limited to 1.25·T_HOME; the home is where the torque has exceeded T_HOME
    50 times: there P_IST = P_HOME, P_FNC = 16·P_HOME, P_SOLL = 0, and T_SOLL is unchanged."""
    m = _motor(end_stop_low=-3.0, end_stop_high=3.0)
    m.write_many({"V_HOME": -800, "T_HOME": 200, "P_HOME": -1000, "P_SOLL": 555,
                  "T_SOLL": 900})
    m.write("MODE_REG", c.HOME1_MODE)
    vf = []
    while m.mode_name() == "HOME1_MODE":
        m.step()
        vf.append(int(m.read("VF_OUT")[0]))
        assert int(m.read("FNCERR")[0]) == 0  # no function correction while searching
        assert len(vf) < 3000
    vf = np.abs(vf)
    assert vf.max() <= 250 and vf.max() >= 249  # 1.25 · 200
    assert int(np.sum(vf > 200)) == 50
    assert m.position_rad[0] == pytest.approx(-3.0, abs=0.02)  # the negative stop
    assert abs(int(m.read("P_IST")[0]) + 1000) <= 2
    assert int(m.read("P_SOLL")[0]) == 0 and int(m.read("T_SOLL")[0]) == 900


@pytest.mark.statements("mac050_141:3.2.40:2", "mac050_141:3.2.41:3", "mac050_141:4.4.14:1")
@pytest.mark.parametrize("mode", [c.HOME2_MODE, c.HOME3_MODE])
def test_a_negative_t_home_makes_the_home_sensor_active_low(mode: int) -> None:
    """Manual 3.2.41: the sign of T_HOME is the sensor's polarity: negative, active low. The
    sensor input is high above 1 rad: active low, the active region is below; HOME2 from 2 rad
    towards it (V_HOME negative) finds its zero where the input goes low, HOME3 where it goes
    high again after the slow move back."""
    m = _motor(home_position=1.0, initial_angle=2.0)
    m.write_many({"V_HOME": -400, "T_HOME": -1, "P_HOME": 0, "STARTMODE": c.P_MODE})
    m.write("MODE_REG", mode)
    _steps_until(m, c.MODE_NAMES[mode], 5000)
    zero_rad = m.position_rad[0] - int(m.read("P_IST")[0]) * c.RAD_PER_COUNT
    one_sample = 400 / 16 * c.RAD_PER_COUNT  # V_HOME's travel in one outer sample
    assert zero_rad == pytest.approx(1.0, abs=2 * one_sample)


@pytest.mark.statements("mac050_141:3.2.41:6")
@pytest.mark.parametrize("mode", [c.HOME2_MODE, c.HOME3_MODE])
def test_t_home_0_makes_the_home_sensor_active_low(mode: int) -> None:
    """Manual 3.2.41: the input is active high only if T_HOME is positive, active low otherwise:
    T_HOME = 0 (the default) homes as a negative T_HOME does, on a sensor that pulls the input
    low (high above 1 rad, so the active region is below it)."""
    m = _motor(home_position=1.0, initial_angle=2.0)
    m.write_many({"V_HOME": -400, "T_HOME": 0, "P_HOME": 0, "STARTMODE": c.P_MODE})
    m.write("MODE_REG", mode)
    _steps_until(m, c.MODE_NAMES[mode], 5000)
    zero_rad = m.position_rad[0] - int(m.read("P_IST")[0]) * c.RAD_PER_COUNT
    one_sample = 400 / 16 * c.RAD_PER_COUNT
    assert zero_rad == pytest.approx(1.0, abs=2 * one_sample)


@pytest.mark.statements("mac050_141:4.4.13:10")
def test_homing_writes_its_search_velocity_to_v_soll() -> None:
    """Manual 4.4.13–4.4.15: HOME1 sets V_SOLL = V_HOME; HOME2/3 V_SOLL = V_HOME towards the
    passive sensor, −V_HOME away from the active one, HOME3 then −V_HOME/64 + 1; at the zero
    only T_SOLL is restored, so V_SOLL keeps the last search velocity."""
    m = _motor(end_stop_low=-3.0, end_stop_high=3.0)
    m.write_many({"V_SOLL": 123, "V_HOME": -800, "T_HOME": 300, "T_SOLL": 900,
                  "STARTMODE": c.P_MODE})
    m.write("MODE_REG", c.HOME1_MODE)
    m.step()
    assert int(m.read("V_SOLL")[0]) == -800
    _steps_until(m, "HOME1_MODE", 3000)
    assert int(m.read("V_SOLL")[0]) == -800 and int(m.read("T_SOLL")[0]) == 900

    m = _motor(home_position=1.0, initial_angle=0.0)
    m.write_many({"V_SOLL": 123, "V_HOME": 640, "T_HOME": 1, "STARTMODE": c.P_MODE,
                  "A_SOLL": 1000})
    m.write("MODE_REG", c.HOME3_MODE)
    v = []
    while m.mode_name() == "HOME3_MODE":
        m.step()
        v.append(int(m.read("V_SOLL")[0]))
        assert len(v) < 5000
    assert v[0] == 640 and v[-1] == -640 // 64 + 1
    assert int(m.read("V_SOLL")[0]) == -9  # kept after the zero

    m = _motor(home_position=1.0, initial_angle=2.0)  # HOME2 starting on the active sensor
    m.write_many({"V_SOLL": 123, "V_HOME": 400, "T_HOME": 1, "STARTMODE": c.P_MODE})
    m.write("MODE_REG", c.HOME2_MODE)
    m.step()
    assert int(m.read("V_SOLL")[0]) == -400


@pytest.mark.statements("mac050_141:3.2.40:1", "mac050_141:4.4.15:1", "mac050_141:4.4.15:3")
def test_home3_leaves_the_sensor_slowly_at_minus_v_home_over_64_plus_1() -> None:
    """Manual 4.4.15: HOME3 goes towards the sensor at V_HOME, then, the sensor active, slowly
    back at −V_HOME/64 + 1 until it deactivates: the zero."""
    m = _motor(home_position=1.0, initial_angle=0.0)
    m.write_many({"V_HOME": 640, "T_HOME": 1, "P_HOME": 0, "STARTMODE": c.P_MODE,
                  "A_SOLL": 1000})
    m.write("MODE_REG", c.HOME3_MODE)
    f = []
    while m.mode_name() == "HOME3_MODE":
        m.step()
        f.append(int(m.read("FNC_OUT")[0]))
        assert len(f) < 5000
    assert 640 in f and f[-1] == -640 // 64 + 1 == -9


# ------------------------------------------------------------------ 3.2.89–111 filters; 4.2, 4.3

_VF_TAPS = {"KVFX4": 0, "KVFX3": 1, "KVFX2": 2, "KVFX1": 3}
_VF_POLES = {"KVFY3": 1, "KVFY2": 2, "KVFY1": 3, "KVFY0": 4}


def _vf_impulse(coefficients: dict[str, float], kvout: float = 1.0) -> list[int]:
    """VF_OUT for a velocity-error impulse of 200 through the speed regulator, FF = 1, VB = 0."""
    from jvl_gym.families.mac050_141.firmware.speed_loop import speed_regulator

    m = _motor()
    m.write_many({"KFF3": 1.0, "KFF2": 0.0, "KFF1": 0.0, "KFF0": 0.0, "GEARB": 0.0,
                  "KVOUT": kvout, **dict.fromkeys([*_VF_TAPS, *_VF_POLES], 0.0),
                  **coefficients})
    out = []
    for k in range(6):
        speed_regulator(m.regs[0], m.state[0], 200.0 if k == 0 else 0.0, False, 1023.0)
        out.append(int(m.read("VF_OUT")[0]))
    return out


@pytest.mark.statements("mac050_141:3.2.93:1", "mac050_141:3.2.121:1", "mac050_141:4.2.1:4")
@pytest.mark.parametrize("name", list(_VF_TAPS))
def test_each_vf_numerator_coefficient_has_its_delay(name: str) -> None:
    """Manual 3.2.93–100: VF(z) = (KVFX4 z⁴ + KVFX3 z³ + KVFX2 z² + KVFX1 z)/(z⁴ − …): an
    impulse of the velocity error (FF_OUT − VB_OUT) comes out after the coefficient's delay."""
    expected = [0] * 6
    expected[_VF_TAPS[name]] = 100
    assert _vf_impulse({name: 0.5}) == expected


@pytest.mark.statements("mac050_141:3.2.93:2")
@pytest.mark.parametrize("name", list(_VF_POLES))
def test_each_vf_denominator_coefficient_feeds_back_with_a_plus_sign(name: str) -> None:
    """Manual 3.2.93–100 ("note the change of sign"): the denominator z⁴ − KVFY3 z³ − … − KVFY0
    means a positive KVFYk adds its share of the output k samples later (KVFY3: 1, … KVFY0: 4)."""
    out = _vf_impulse({"KVFX4": 0.5, name: 0.5})
    delay = _VF_POLES[name]
    expected = [0] * 6
    for k in range(0, 6, delay):
        expected[k] = int(100 * 0.5 ** (k // delay) + 0.5)  # rounded half up
    assert out == expected


@pytest.mark.statements("mac050_141:3.2.106:1", "mac050_141:3.2.106:2", "mac050_141:3.2.110:1",
                        "mac050_141:3.2.145:1", "mac050_141:4.3.1:4")
def test_the_current_filters_if_and_ib() -> None:
    """Manual 3.2.106–111, 4.3: per phase the error is IX_SOLL − IB(IX_IST), IB(z) = (KIB1 z +
    KIB0)/z, and the voltage U = IF(error), IF(z) = (KIFX2 z² + KIFX1 z)/(z² − KIFY1 z −
    KIFY0), saturated to ±1023 PWM counts."""
    from jvl_gym.families.mac050_141.firmware.current_loop import phase_step

    # (i_soll, i_ist, e1, u1, u2, i_ist1, KIB1, KIB0, KIFX2, KIFX1, KIFY1, KIFY0)
    u, e = phase_step(100.0, 20.0, 30.0, 40.0, 50.0, 10.0, 1.5, 0.5, 2.0, 0.25, 0.5, -0.25)
    assert e == 100.0 - (1.5 * 20.0 + 0.5 * 10.0)
    assert u == round(2.0 * e + 0.25 * 30.0 + 0.5 * 40.0 - 0.25 * 50.0)
    u, _ = phase_step(1000.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 7.0, 0.0, 0.0, 0.0)
    assert u == 1023.0
    u, _ = phase_step(-1000.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 7.0, 0.0, 0.0, 0.0)
    assert u == -1023.0


@pytest.mark.statements("mac050_141:3.2.126:1", "mac050_141:3.2.127:2", "mac050_141:3.2.131:1",
                        "mac050_141:3.2.133:1", "mac050_141:4.3.1:1", "mac050_141:4.3.1:2",
                        "mac050_141:4.3.1:3")
def test_commutation_gives_the_three_phase_references() -> None:
    """Manual 4.3, 3.2.126/127: I_NOM = |VF_OUT|, PHI_SOLL = ELDEG_IST ± 90° (the sign of the
    torque) + V_ELDEG·PHASE_COMP, and IA/IB/IC_SOLL = I_NOM·AMPLITUDE·sin(PHI_SOLL + 0, 120,
    240°); the largest reference is 1023·AMPLITUDE."""
    from jvl_gym.families.mac050_141.firmware.current_loop import references

    amplitude = 212  # raw Fixed8: 0.828
    for vf, eldeg, v_eldeg in ((1023.0, 0.0, 0.0), (-500.0, 100.0, 10.0), (300.0, 2000.0, -7.0)):
        i_nom, phi, ia, ib, ic = references(vf, eldeg, v_eldeg, 5 * 256, amplitude)
        assert i_nom == abs(vf)
        assert phi == (eldeg + (512 if vf >= 0 else -512) + 5 * v_eldeg) % 2048
        amp = abs(vf) * amplitude / 256
        for k, i in enumerate((ia, ib, ic)):
            assert i == pytest.approx(amp * np.sin((phi / 2048 + k / 3) * 2 * np.pi), abs=1)
    assert references(1023.0, 0.0, 0.0, 0, amplitude)[2] == round(1023 * amplitude / 256)


@pytest.mark.statements("mac050_141:3.2.2:17", "mac050_141:3.2.128:1", "mac050_141:3.2.128:2",
                        "mac050_141:4.4.8:1")
def test_mani_mode_sets_the_stator_field_from_man_i_nom_and_man_alpha() -> None:
    """Manual 3.2.128/129: in MANI_MODE IA/IB/IC_SOLL = MAN_I_NOM·sin(MAN_ALPHA + 0, 120, 240
    electrical degrees)·AMPLITUDE, MAN_ALPHA in 360/2048 electrical degrees."""
    m = _motor(load_inertia=1e-2)
    m.write_many({"MAN_I_NOM": 400, "MAN_ALPHA": 256})  # 45 electrical degrees
    m.write("MODE_REG", c.MANI_MODE)
    m.step(3)
    amp = 400 * float(m.read("AMPLITUDE")[0])
    got = [int(m.read(x)[0]) for x in ("IA_SOLL", "IB_SOLL", "IC_SOLL")]
    want = [amp * np.sin(np.radians(45 + k * 120)) for k in range(3)]
    np.testing.assert_allclose(got, want, atol=1)
    assert int(m.read("VF_OUT")[0]) == 0  # speed regulator passive


@pytest.mark.statements("mac050_141:3.2.137:1", "mac050_141:3.2.148:1", "mac050_141:3.2.148:2")
def test_kia_compensates_the_gain_of_the_phase_a_current_measurement() -> None:
    """Manual 3.2.137, 3.2.148: IA_IST is the measured phase current, scaled by KIA/256 (256 =
    1): at KIA 512 the loop reaches the same IA_IST with half the physical current."""
    amps = []
    for kia in (256, 512):
        m = _motor(load_inertia=1e-2)
        m.write_many({"KIA": kia, "MAN_I_NOM": 400, "MAN_ALPHA": 512})
        m.write("MODE_REG", c.MANI_MODE)
        m.step(20)
        assert int(m.read("IA_IST")[0]) == pytest.approx(int(m.read("IA_SOLL")[0]), abs=25)
        amps.append(m.phase_currents[0][0])
    assert amps[1] / amps[0] == pytest.approx(0.5, rel=0.1)


# ------------------------------------------------------------------ 3.2.112–122 data, analogue


@pytest.mark.statements("mac050_141:3.2.122:1", "mac050_141:3.2.122:2")
def test_aninp_is_the_analogue_input_plus_10_volts_to_1023_in_every_mode() -> None:
    """Manual 3.2.122: ANINP is the measured analogue voltage, ±10 V ↔ ±1023, updated in every
    mode (here INIT_MODE)."""
    m = _motor(4)
    assert m.mode_name() == "INIT_MODE"
    m.set_input(analog_volts=np.array([10.0, -10.0, 5.0, 0.0]))
    m.step()
    np.testing.assert_array_equal(m.read("ANINP"), [1023, -1023, 512, 0])


@pytest.mark.statements("mac050_141:3.2.36:16", "mac050_141:3.2.120:1", "mac050_141:3.2.120:2",
                        "mac050_141:4.1.3:2")
@pytest.mark.parametrize("mode", [c.INIT_MODE, c.GP_MODE, c.AVG_MODE, c.AG_MODE, c.COIL_MODE])
def test_v_ext_is_the_pulse_count_of_the_last_sample(mode: int) -> None:
    m = _motor()
    m.write_many({**COIL, "GEARF1": 1, "GEARF2": 1, "V_SOLL": 2000, "FNCERRMAX": 0})
    assert int(m.interface_bits[0]) & c.USERINTF_MASK == 0  # USERINTF 00: the pulse input
    m.set_input(pulse_counts=7, analog_volts=0.0)
    if mode != c.INIT_MODE:
        m.write("MODE_REG", mode)
    m.step(3)
    assert int(m.read("V_EXT")[0]) == 7
    m.set_input(pulse_counts=-3)
    m.step()
    assert int(m.read("V_EXT")[0]) == -3


@pytest.mark.statements("mac050_141:3.2.2:14", "mac050_141:3.2.122:4", "mac050_141:4.1.4:1",
                        "mac050_141:4.1.4:2", "mac050_141:4.4.5:1", "mac050_141:4.4.5:2")
def test_at_mode_torque_is_the_analogue_input_scaled_to_t_soll() -> None:
    """Manual 4.1.4, 4.4.5: in AT_MODE ±10 V give ±T_SOLL, written to VF_OUT with the speed
    loop passive (FNC_OUT, FF_OUT stay 0); FLWERR, FNCERR and IN_POS are 0."""
    m = _motor(3, load_inertia=1e-2)
    m.write("T_SOLL", 600)
    m.set_input(analog_volts=np.array([10.0, -5.0, 2.0]))
    m.write("MODE_REG", c.AT_MODE)
    m.step(3)
    np.testing.assert_array_equal(m.read("VF_OUT"),
                                  np.round(m.read("ANINP") * 600 / 1023).astype(int))
    assert m.read("VF_OUT")[0] == 600
    assert not m.read("FNC_OUT").any() and not m.read("FF_OUT").any()
    assert not (m.read("ERR_STAT") & c.IN_POS).any()


@pytest.mark.statements("mac050_141:3.2.151:1", "mac050_141:4.5.6:1")
def test_u_supply_is_the_supply_voltage_in_53_7_mv() -> None:
    m = _motor(2)
    m.set_input(supply_volts=np.array([48.0, 56.0]))
    m.run(0.2)
    np.testing.assert_allclose(m.read("U_SUPPLY") * 0.0537, m.bus_voltage, atol=0.06)
    assert m.bus_voltage[1] > 54


@pytest.mark.statements("mac050_141:3.2.144:1")
def test_v_eldeg_is_the_speed_per_inner_sample() -> None:
    """Manual 3.2.144: V_ELDEG is the speed in encoder counts per 7812.5 Hz sample: 1/15 of V_IST
    (counts per 520.8 Hz sample)."""
    m = _motor()
    m.write("V_SOLL", 3000)
    m.write("MODE_REG", c.V_MODE)
    m.run(0.5)
    v = m.trace(["V_ELDEG", "V_IST"], 50)
    assert np.mean(v["V_ELDEG"]) == pytest.approx(np.mean(v["V_IST"]) / 15, abs=0.5)


@pytest.mark.statements("mac050_141:3.2.130:1", "mac050_141:3.2.145:1", "mac050_141:4.4.9:1",
                        "mac050_141:4.4.9:2")
def test_testu_applies_umeas_to_a_and_minus_umeas_to_c_then_init() -> None:
    """Manual 4.4.9: TESTU records UA_VAL (SAMPLE1 = 145) and IC_IST (SAMPLE2 = 139) at the inner
    rate from the start of the buffer, with UA = UMEAS and UC = −UMEAS, for 11 samples, then
    INIT_MODE."""
    m = _motor(load_inertia=1e-2)
    m.write_many({"UMEAS": 40, "SAMPLE3": 147})  # channel 3: UC_VAL
    m.write("MODE_REG", c.TESTU_MODE)
    m.step(2)
    assert m.mode_name() == "INIT_MODE"
    assert [int(m.read(f"SAMPLE{k}")[0]) for k in (1, 2)] == [145, 139]
    buf = m.sample_buffer()
    assert np.all(buf["UA_VAL"][0] == 40) and buf["UA_VAL"].shape[1] == 11
    assert np.all(buf["UC_VAL"][0] == -40)


# ------------------------------------------------------------------ 4.1 function blocks, 4.4 modes


@pytest.mark.statements("mac050_141:4.1.1:4")
def test_the_profile_starts_from_0_after_init_mode() -> None:
    """Manual 4.1.1: V_OLD is set to 0 in INIT_MODE: a velocity profile started after INIT
    ramps up from 0 by A_SOLL, whatever it ran at before."""
    m = _motor(load_inertia=1e-4)
    m.write_many({"V_SOLL": 2000, "A_SOLL": 1000, "FLWERRMAX": 0})
    m.write("MODE_REG", c.V_MODE)
    m.step(10)
    m.write("MODE_REG", c.INIT_MODE)
    _steps_until(m, "STOP_MODE", 500)
    m.write("A_SOLL", 30)
    m.write("MODE_REG", c.V_MODE)
    m.step()
    assert int(m.read("FNC_OUT")[0]) == 30


@pytest.mark.statements("mac050_141:3.2.2:21", "mac050_141:4.1.8:1", "mac050_141:4.1.8:2",
                        "mac050_141:4.4.1:3", "mac050_141:4.4.2:7", "mac050_141:4.4.12:1",
                        "mac050_141:4.4.12:4")
def test_stop_mode_switches_to_init_below_300_rpm() -> None:
    """Manual 4.1.8, 4.4.12: a switch to INIT from V_MODE goes through STOP_MODE, which brakes
    with A_SOLL and goes to INIT_MODE when the measured speed is below 300 rpm."""
    m = _motor()
    m.write_many({"V_SOLL": 3000, "A_SOLL": 10, "ACC_EMERG": 0})
    m.write("MODE_REG", c.V_MODE)
    m.run(0.6)
    m.write("MODE_REG", c.INIT_MODE)
    assert m.mode_name() == "STOP_MODE"
    tr = m.trace(["MODE_REG", "V_IST", "FNC_OUT"], 600)
    modes, v = tr["MODE_REG"][:, 0], tr["V_IST"][:, 0]
    k = int(np.argmax(modes == c.INIT_MODE))
    assert k > 0 and np.all(modes[:k] == c.STOP_MODE)
    assert c.v_ist_to_rpm(abs(int(v[k]))) < 300 <= c.v_ist_to_rpm(abs(int(v[k - 1])))
    assert set(np.diff(tr["FNC_OUT"][:k, 0]).tolist()) <= {-10, 0}


_REGULATED = [c.V_MODE, c.P_MODE, c.GP_MODE, c.AV_MODE, c.AVG_MODE, c.A2POS_MODE, c.APOS_MODE,
              c.GF_MODE, c.VAT_MODE, c.AG_MODE, c.COIL_MODE, c.AVZ_MODE]


@pytest.mark.statements("mac050_141:4.1.8:3", "mac050_141:4.4.2:7", "mac050_141:4.4.3:7",
                        "mac050_141:4.4.4:6", "mac050_141:4.4.6:5", "mac050_141:4.4.7:5",
                        "mac050_141:4.4.12:3", "mac050_141:4.4.21:5", "mac050_141:4.4.22:5",
                        "mac050_141:4.4.25:5")
@pytest.mark.parametrize("mode", _REGULATED, ids=[c.MODE_NAMES[x] for x in _REGULATED])
def test_a_moving_mode_goes_to_init_through_stop_mode(mode: int) -> None:
    m = _motor()
    _set_up_mode(m, mode, pulses=20, volts=10.0)
    m.step(200)
    m.write("MODE_REG", c.INIT_MODE)
    assert m.mode_name() == "STOP_MODE"
    _steps_until(m, "STOP_MODE", 2000)
    assert m.mode_name() == "INIT_MODE"


_IN_POS_0_MODES = [c.AT_MODE, c.AV_MODE, c.AVG_MODE, c.MANI_MODE, c.HOME1_MODE, c.HOME2_MODE,
                   c.INIT_MODE]


@pytest.mark.statements("mac050_141:4.4.1:2", "mac050_141:4.4.5:4", "mac050_141:4.4.6:6",
                        "mac050_141:4.4.7:6", "mac050_141:4.4.8:4", "mac050_141:4.4.13:3",
                        "mac050_141:4.4.14:4")
@pytest.mark.parametrize("mode", _IN_POS_0_MODES, ids=[c.MODE_NAMES[x] for x in _IN_POS_0_MODES])
def test_in_pos_is_0_in_the_modes_that_do_not_position(mode: int) -> None:
    """Manual 4.4.1, 4.4.5–4.4.8, 4.4.13/14: IN_POS = 0 (a motor at rest with a wide window,
    analogue input 0 V, home sensor far)."""
    m = _motor(home_position=10.0)
    m.write_many({"INPOSWIN": 1000, "INPOSCNT": 0, "V_SOLL": 0, "V_HOME": 0, "T_HOME": 100})
    m.set_input(analog_volts=0.0)
    if mode != c.INIT_MODE:
        m.write("MODE_REG", mode)
    tr = m.trace(["ERR_STAT"], 30)
    assert not (tr["ERR_STAT"] & c.IN_POS).any()


@pytest.mark.statements("mac050_141:4.4.4:3", "mac050_141:4.4.25:2")
@pytest.mark.parametrize("mode", [c.GP_MODE, c.GF_MODE])
def test_500_pulses_per_revolution_by_gearf_1024_over_125(mode: int) -> None:
    """Manual 4.4.4/4.4.25: nominally 4096 pulses per revolution; GEARF1/GEARF2 = 1024/125 drives
    the motor at 500 pulses per revolution: 2500 pulses are 5 revolutions."""
    m = _motor()
    m.write_many({"GEARF1": 1024, "GEARF2": 125, "V_SOLL": 20000, "A_SOLL": 200, "FNCERRMAX": 0})
    m.write("MODE_REG", mode)
    m.set_input(pulse_counts=25)
    m.step(100)  # 2500 pulses
    m.set_input(pulse_counts=0)
    m.run(1.0)
    assert int(m.read("P_IST")[0]) == pytest.approx(5 * 4096, abs=2)


@pytest.mark.statements("mac050_141:3.2.2:27", "mac050_141:4.4.18:1", "mac050_141:4.4.18:2")
def test_vat_limits_the_torque_to_aninp_times_t_soll_over_1024() -> None:
    """Manual 4.4.18: VAT is V_MODE with the torque limit |ANINP·T_SOLL/1024|."""
    m = _motor(3, coulomb_friction=5.0)
    m.write_many({"V_SOLL": 1000, "T_SOLL": 800})
    m.set_input(analog_volts=np.array([10.0, -5.0, 2.5]))
    m.write("MODE_REG", c.VAT_MODE)
    vf = np.abs(m.trace(["VF_OUT"], 100)["VF_OUT"]).max(axis=0)
    limit = np.abs(m.read("ANINP") * 800 / 1024)
    assert np.all(vf <= limit + 0.5) and np.all(vf >= limit - 1)


@pytest.mark.statements("mac050_141:4.4.18:3")
def test_vat_reports_in_pos_by_the_velocity_mode_rule() -> None:
    """Manual 4.4.18: VAT is V_MODE but for the torque limit, so IN_POS follows V_MODE's rule
    (4.1.1): with INPOSCNT = 0 at standstill (|V_IST| < INPOSWIN), with INPOSCNT > 0 when
    |V_SOLL − 16·V_IST| < INPOSWIN for INPOSCNT samples; in V_MODE and VAT alike."""
    for mode in (c.V_MODE, c.VAT_MODE):
        m = _motor(2)
        m.write_many({"V_SOLL": np.array([0, 1600]), "T_SOLL": 800, "INPOSWIN": 40,
                      "INPOSCNT": np.array([0, 3])})
        m.set_input(analog_volts=10.0)  # VAT: the full torque limit
        m.write("MODE_REG", mode)
        m.step(10)
        assert [bool(e & c.IN_POS) for e in m.read("ERR_STAT")] == [True, False], mode
        m.run(0.5)
        assert np.abs(1600 - 16 * int(m.read("V_IST")[1])) < 40
        assert [bool(e & c.IN_POS) for e in m.read("ERR_STAT")] == [True, True], mode


@pytest.mark.statements("mac050_141:4.1.10:4", "mac050_141:4.1.10:5")
def test_a2pos_relative_positioning_by_p_fnc() -> None:
    """Manual 4.1.10: with RELPFNC (ERR_STAT RELPOSPFNC) a rising input subtracts 16·P2 from
    P_FNC, a falling one 16·P1: each edge moves the motor by P2 or P1 further."""
    m = _motor()
    m.write_many({"P1": 1000, "P2": 3000, "V_SOLL": 4000})
    m.set_input(analog_volts=0.0)
    m.write("MODE_REG", c.A2POS_MODE)
    m.run(1.0)
    start = int(m.read("P_IST")[0])
    m.write("ERR_STAT", c.RELPOSPFNC)
    p_fnc = int(m.read("P_FNC")[0])
    m.set_input(analog_volts=6.0)
    m.step()
    assert int(m.read("P_FNC")[0]) - int(m.read("FNC_OUT")[0]) == p_fnc - 16 * 3000
    m.run(1.0)
    m.set_input(analog_volts=4.0)
    m.run(1.0)
    assert int(m.read("P_IST")[0]) - start == pytest.approx(3000 + 1000, abs=10)


@pytest.mark.statements("mac050_141:4.4.20:2")
def test_coil_mode_adds_v8_to_the_spindle_pulses() -> None:
    """Manual 4.4.20: in COIL_MODE V8 is added to V_EXT's pulses, so the traverse runs with the
    spindle at rest: V8 = 10 moves like 10 pulses per sample."""
    speeds = []
    for v8, pulses in ((10, 0), (0, 10)):
        m = _motor()
        m.write_many({**COIL, "V8": v8, "GEARF1": 1, "GEARF2": 1, "V_SOLL": 20000,
                      "A_SOLL": 400, "FNCERRMAX": 0})
        m.set_input(analog_volts=0.0, pulse_counts=pulses)
        m.write("MODE_REG", c.COIL_MODE)
        m.step(100)
        speeds.append(np.mean(m.trace(["V_IST"], 50)["V_IST"][:, 0]))
    assert speeds[0] == pytest.approx(speeds[1], abs=0.3)
    assert abs(speeds[0]) == pytest.approx(10, abs=0.3)


@pytest.mark.statements("mac050_141:4.4.16:2", "mac050_141:4.4.16:3")
def test_safe_mode_is_not_entered_or_left_by_writing_mode_reg() -> None:
    """Manual 4.4.16: writing 15 to MODE_REG does not give SAFE_MODE; in SAFE_MODE a write of
    another mode does not leave it (only 256..258, and the MacTalk command)."""
    m = _motor()
    with pytest.raises(ModeError):
        m.write("MODE_REG", c.SAFE_MODE)
    m.enter_safe_mode()
    for mode in (c.INIT_MODE, c.V_MODE):
        with pytest.raises(ModeError):
            m.write("MODE_REG", mode)
    assert m.mode_name() == "SAFE_MODE"
    m.step(5)
    assert int(m.read("VF_OUT")[0]) == 0  # passive, as INIT
    m.exit_safe_mode()
    assert m.mode_name() == "INIT_MODE"


@pytest.mark.statements("mac050_141:3.2.35:11", "mac050_141:3.2.35:12", "mac050_141:4.1.2:2",
                        "mac050_141:4.1.2:3", "mac050_141:4.1.2:4", "mac050_141:4.4.3:8")
def test_the_position_profile_lands_on_p_soll_without_overshoot_and_flags_its_phases() -> None:
    """Manual 4.1.2: the position block brakes so that the function position reaches 16·P_SOLL
    exactly and never passes it; ACC_FLAG while it speeds up, DEC_FLAG while it brakes."""
    m = _motor()
    m.write_many({"P_SOLL": 30000, "V_SOLL": 3000, "A_SOLL": 37})
    m.write("MODE_REG", c.P_MODE)
    tr = m.trace(["P_FNC", "FNC_OUT", "ERR_STAT"], 600)
    p_fnc, f, st = tr["P_FNC"][:, 0], tr["FNC_OUT"][:, 0], tr["ERR_STAT"][:, 0]
    assert p_fnc.max() == 16 * 30000 == p_fnc[-1]
    rising, falling = np.diff([0, *f]) > 0, np.diff([0, *f]) < 0
    np.testing.assert_array_equal((st & c.ACC_FLAG) != 0, rising)
    np.testing.assert_array_equal((st & c.DEC_FLAG) != 0, falling)
    assert rising.any() and falling.any()


@pytest.mark.statements("mac050_141:3.2.36:7", "mac050_141:3.2.116:1")
def test_rewindbit_sets_rec_cnt_to_0_and_clears_itself() -> None:
    m = _motor()
    m.write("CNTRL_BITS", int(m.read("CNTRL_BITS")[0]) | c.RECORDBIT)
    m.step(20)
    assert int(m.read("REC_CNT")[0]) == 20
    m.write("CNTRL_BITS", (int(m.read("CNTRL_BITS")[0]) & ~c.RECORDBIT) | c.REWINDBIT)
    m.step()
    assert int(m.read("REC_CNT")[0]) == 0
    assert not int(m.read("CNTRL_BITS")[0]) & c.REWINDBIT


@pytest.mark.statements("mac050_141:3.2.101:1", "mac050_141:3.2.119:1")
def test_gearb_multiplies_the_vb_filter() -> None:
    """Manual 3.2.101: VB_OUT = GEARB·(KVB3 + KVB2 z⁻¹ + …)·V_IST."""
    from jvl_gym.families.mac050_141.firmware.speed_loop import speed_regulator

    out = []
    for gearb in (1.0, 2.0, 16.0):
        m = _motor()
        m.write_many({"GEARB": gearb, "KVB3": 1.0, "KVB2": 0.0, "KVB1": 0.0, "KVB0": 0.0})
        m.regs[0, m.table.lookup("V_IST").number] = 50
        speed_regulator(m.regs[0], m.state[0], 0.0, False, 1023.0)
        out.append(int(m.read("VB_OUT")[0]))
    assert out == [50, 100, 800]


@pytest.mark.statements("mac050_141:3.2.124:2", "mac050_141:3.2.143:1")
def test_the_electrical_angle_turns_once_per_2048_counts() -> None:
    """Manual 3.2.124/125, 3.2.143: two pole pairs and 4096 counts per turn: ELDEG_IST (0..2047,
    360/2048 electrical degrees) advances one unit per encoder count."""
    m = _motor()
    m.write("V_SOLL", 1600)
    m.write("MODE_REG", c.V_MODE)
    m.run(0.3)
    tr = m.trace(["ELDEG_IST", "P_IST"], 40)
    e, p = tr["ELDEG_IST"][:, 0], tr["P_IST"][:, 0]
    assert e.min() >= 0 and e.max() <= 2047
    # the angle is read at the inner rate, P_IST at the start of the outer sample: equal in sum
    assert int(np.sum(np.diff(e) % 2048)) == pytest.approx(int(p[-1] - p[0]), abs=2)


@pytest.mark.statements("mac050_141:3.2.137:1", "mac050_141:3.2.148:1")
@pytest.mark.parametrize(("gain", "alpha", "phase"), [("KIB", 1877, 1), ("KIC", 1195, 2)])
def test_kib_and_kic_compensate_their_phases(gain: str, alpha: int, phase: int) -> None:
    """Manual 3.2.148–150: KIB and KIC scale the B and C current measurements as KIA does A
    (MAN_ALPHA puts the field's peak on that phase)."""
    amps = []
    for k in (256, 512):
        m = _motor(load_inertia=1e-2)
        m.write_many({gain: k, "MAN_I_NOM": 400, "MAN_ALPHA": alpha})
        m.write("MODE_REG", c.MANI_MODE)
        m.step(20)
        name = "ABC"[phase]
        assert int(m.read(f"I{name}_IST")[0]) == pytest.approx(int(m.read(f"I{name}_SOLL")[0]),
                                                                abs=25)
        amps.append(m.phase_currents[0][phase])
    assert amps[1] / amps[0] == pytest.approx(0.5, rel=0.1)


@pytest.mark.statements("mac050_141:3.2.2:32", "mac050_141:4.4.23:1")
def test_testki_records_the_phase_currents_for_the_gain_calculation() -> None:
    """Manual 4.4.23: TESTKI drives a current through the phases and records the measured
    phase currents, from which the measurement gains (KIA, KIB) follow: the same current flows
    in A and out of B, so a doubled KIA shows as a doubled IA_IST against IB_IST."""
    ratios = []
    for kia in (256, 512):
        m = _motor(load_inertia=1e-2)
        m.write_many({"KIA": kia, "UMEAS": 40})
        m.write("MODE_REG", c.TESTKI_MODE)
        m.step(3)
        assert m.mode_name() == "INIT_MODE"
        buf = m.sample_buffer()
        ia, ib = buf["IA_IST"][0].astype(float), buf["IB_IST"][0].astype(float)
        ratios.append(ia[-1] / -ib[-1])
    assert ratios[0] == pytest.approx(1.0, rel=0.05)
    assert ratios[1] == pytest.approx(2.0, rel=0.05)


@pytest.mark.statements("mac050_141:3.2.152:1", "mac050_141:4.5.6:4")
def test_undervoltage_in_init_mode_uses_1_25_u_min_sup() -> None:
    """Manual 4.5.6: in INIT_MODE UV_DETECT is set below 1.25·U_MIN_SUP, in the other modes
    below U_MIN_SUP: 48 V with U_MIN_SUP = 40 V is an undervoltage only in INIT_MODE."""
    m = _motor(2)
    m.write("U_MIN_SUP", round(40 / 0.0537))
    m.write("V_SOLL", 0)
    m.write("MODE_REG", c.V_MODE, index=[1])
    m.step(20)
    st = m.read("ERR_STAT")
    assert bool(st[0] & c.UV_DETECT) and not st[1] & c.UV_DETECT


@pytest.mark.statements("mac050_141:3.2.18:4", "mac050_141:4.4:3", "mac050_141:4.4:4")
def test_uit_and_the_position_limits_work_in_at_mode_too() -> None:
    """Manual 4.4: UIT, UIT_ERR and PLIM_ERR are updated in every mode: in AT_MODE a torque
    against the motion regenerates (UIT rises), and the motor driven past MAX_P_IST trips."""
    m = _motor(2, initial_speed=200.0)
    m.write_many({"T_SOLL": 1023, "MAX_P_IST": np.array([0, 3000]),
                  "MIN_P_IST": np.array([0, -100000])})
    m.set_input(analog_volts=np.array([-10.0, 10.0]))
    m.write("MODE_REG", c.AT_MODE)
    m.step(30)
    assert int(m.read("UIT")[0]) > 0
    assert int(m.read("ERR_STAT")[1]) & c.PLIM_ERR
    m.step(2)
    assert int(m.read("VF_OUT")[1]) == 0  # torque off, on its way to INIT_MODE (4.4.5)


@pytest.mark.statements("mac050_141:3.2.42:4")
def test_the_fastmac_home_command_runs_the_home_mode_of_the_high_byte() -> None:
    """Manual 3.2.42: HOME_MODE's high byte is the home mode a FastMAC home command starts."""
    from jvl_gym.protocol.mactalk import fastmac as fm
    from jvl_gym.protocol.mactalk.twin16 import Twin

    m = _motor()
    m.write("CNTRL_BITS", 3)  # USERINTF = 11: FastMAC, latched at the next power-on
    m.enter_safe_mode()
    m.write_flash()
    m.write_many({"HOME_MODE": (c.HOME2_MODE << 8) | 0, "V_HOME": 100, "T_HOME": 1})
    twin = Twin(m, [19])
    twin.user[0].feed(bytes((fm.encode_command(fm.FastCommand.HOME, 1),)))
    assert m.mode_name() == "HOME2_MODE"


@pytest.mark.parametrize(("pointer", "size"), [("P_REG_P", 8), ("V_REG_P", 8), ("A_REG_P", 4),
                                               ("T_REG_P", 4), ("L_REG_P", 4), ("Z_REG_P", 4)])
@pytest.mark.statements("mac050_141:3.2.43:2", "mac050_141:3.2.44:2", "mac050_141:3.2.45:2",
                        "mac050_141:3.2.46:2", "mac050_141:3.2.47:2", "mac050_141:3.2.48:2")
def test_register_mode_pointers_refuse_values_past_their_set(pointer: str, size: int) -> None:
    """Manual 3.2.43–3.2.48: P_REG_P and V_REG_P range 0 … 8, the others 0 … 4."""
    from jvl_gym.registers import RegisterError

    m = _motor()
    before = m.regs.copy()
    with pytest.raises(RegisterError):
        m.write(pointer, size + 1)
    np.testing.assert_array_equal(m.regs, before)
    m.write(pointer, size)
    assert int(m.read(pointer)[0]) == 0  # done at once


@pytest.mark.statements("mac050_141:3.2.14:5")
def test_a_gear_ratio_and_its_reduced_fraction_drive_the_motor_alike() -> None:
    """Manual 3.2.14: 15500/10000 reduced is 31/20; both give the same motion."""
    m = _motor(2)
    m.write_many({"GEARF1": np.array([15500, 31]), "GEARF2": np.array([10000, 20]),
                  "V_SOLL": 20000, "A_SOLL": 200, "FNCERRMAX": 0})
    m.set_input(pulse_counts=13)
    m.write("MODE_REG", c.GP_MODE)
    m.step(200)
    m.set_input(pulse_counts=0)
    m.run(0.5)
    p = m.read("P_IST")
    assert p[0] == p[1] == pytest.approx(200 * 13 * 31 / 20, abs=2)


@pytest.mark.parametrize("mode", [c.HOME2_MODE, c.HOME3_MODE])
@pytest.mark.statements("mac050_141:4.4.14:5", "mac050_141:4.4.15:4")
def test_at_the_sensor_zero_p_ist_is_p_home_p_fnc_16_p_home_and_p_soll_0(mode: int) -> None:
    """Manual 4.4.14/4.4.15: at the zero P_IST = P_HOME, P_FNC = 16·P_HOME, P_SOLL = 0 and
    MODE_REG = STARTMODE."""
    m = _motor(home_position=1.0)
    m.write_many({"V_HOME": 400, "T_HOME": 1, "P_HOME": 500, "P_SOLL": 777,
                  "STARTMODE": c.V_MODE, "V_SOLL": 0})
    m.write("MODE_REG", mode)
    _steps_until(m, c.MODE_NAMES[mode], 5000)
    assert m.mode_name() == "V_MODE"
    assert [int(m.read(x)[0]) for x in ("P_SOLL", "P_FNC")] == [0, 16 * 500]
    assert abs(int(m.read("P_IST")[0]) - 500) <= 30  # one sample of travel since the edge


@pytest.mark.parametrize("mode", [c.A2POS_MODE, c.APOS_MODE])
@pytest.mark.statements("mac050_141:4.4.21:4", "mac050_141:4.4.21:6", "mac050_141:4.4.22:4",
                        "mac050_141:4.4.22:6")
def test_the_analogue_position_modes_flag_their_profile_and_report_in_pos(mode: int) -> None:
    """Manual 4.4.21/4.4.22: the analogue position modes run the position block: ACC_FLAG and
    DEC_FLAG follow the profile, and IN_POS comes at the target (|P_SOLL − P_FNC/16 + FLWERR| <
    INPOSWIN)."""
    m = _motor()
    m.write_many({"P1": 20000, "P2": 0, "P3": 0, "V_SOLL": 3000, "A_SOLL": 37, "INPOSWIN": 10,
                  "INPOSCNT": 3})
    m.set_input(analog_volts=0.0)  # A2POS: low → P1; APOS: ANINP 0 → P_NEW = P1
    m.write("MODE_REG", mode)
    tr = m.trace(["P_FNC", "FNC_OUT", "ERR_STAT", "P_SOLL"], 500)
    f, st = tr["FNC_OUT"][:, 0], tr["ERR_STAT"][:, 0]
    assert tr["P_SOLL"][-1, 0] == 20000 and tr["P_FNC"][:, 0].max() == 16 * 20000
    rising, falling = np.diff([0, *f]) > 0, np.diff([0, *f]) < 0
    np.testing.assert_array_equal((st & c.ACC_FLAG) != 0, rising)
    np.testing.assert_array_equal((st & c.DEC_FLAG) != 0, falling)
    assert st[-1] & c.IN_POS and not st[50] & c.IN_POS
    assert abs(int(m.read("P_IST")[0]) - 20000) < 10


_CORRECTING = [c.P_MODE, c.GP_MODE, c.AG_MODE, c.COIL_MODE, c.A2POS_MODE, c.APOS_MODE, c.GF_MODE]


@pytest.mark.parametrize("mode", _CORRECTING, ids=[c.MODE_NAMES[x] for x in _CORRECTING])
@pytest.mark.statements("mac050_141:3.2.24:9", "mac050_141:4.4.3:10", "mac050_141:4.4.4:8",
                        "mac050_141:4.4.4:9", "mac050_141:4.4.19:2", "mac050_141:4.4.20:5",
                        "mac050_141:4.4.21:2", "mac050_141:4.4.21:7", "mac050_141:4.4.22:2",
                        "mac050_141:4.4.22:7", "mac050_141:4.4.25:7", "mac050_141:4.4.25:8")
def test_the_correcting_modes_bound_the_torque_and_trip_on_fncerrmax(mode: int) -> None:
    """Manual 3.2.24, 4.4 (correction of function block: active): a blocked motor's profile is
    corrected so its torque stays at T_SOLL, the corrections sum in FNCERR, and |FNCERR| above
    FNCERRMAX sets FNC_ERR and stops the motor to INIT_MODE."""
    m = _motor(coulomb_friction=5.0)
    _set_up_mode(m, mode, t_soll=300, pulses=20)
    m.write("FNCERRMAX", 5000)
    tr = m.trace(["VF_OUT", "FNCERR", "MODE_REG"], 800)
    assert np.abs(tr["VF_OUT"][:, 0]).max() <= 300
    assert np.abs(tr["FNCERR"][:, 0]).max() > 4000  # the corrections summed up
    assert int(m.read("ERR_STAT")[0]) & c.FNC_ERR
    assert c.STOP_MODE in tr["MODE_REG"][:, 0] and m.mode_name() == "INIT_MODE"


@pytest.mark.statements("mac050_141:4.4.9:4")
def test_testu_sets_rewind_recinner_and_record_and_records_11_samples() -> None:
    """Manual 4.4.9: TESTU sets REWINDBIT, RECINNERBIT (7812 Hz) and RECORDBIT, records for 11
    sampling periods from the start of the buffer (REC_CNT = 11), then INIT_MODE."""
    m = _motor(load_inertia=1e-2)
    m.write("CNTRL_BITS", int(m.read("CNTRL_BITS")[0]) | c.RECORDBIT)
    m.step(5)  # a recording already running: TESTU starts the buffer again
    m.write("CNTRL_BITS", int(m.read("CNTRL_BITS")[0]) & ~c.RECORDBIT)
    m.write("UMEAS", 40)
    m.write("MODE_REG", c.TESTU_MODE)
    m.step(2)
    cb = int(m.read("CNTRL_BITS")[0])
    assert cb & c.RECINNERBIT and not cb & c.RECORDBIT
    assert int(m.read("REC_CNT")[0]) == 11 and m.mode_name() == "INIT_MODE"


@pytest.mark.statements("mac050_141:4.4.10:2", "mac050_141:4.4.10:3", "mac050_141:4.4.10:4")
def test_testa_sets_its_channels_records_11_outer_samples_then_break_mode() -> None:
    """Manual 4.4.10: TESTA sets SAMPLE1 = 7 (T_SOLL), SAMPLE2 = 12 (V_IST), RECINNERBIT = 0
    (520.8 Hz), records 11 sampling periods from the start of the buffer, then BREAK_MODE."""
    m = _motor(load_inertia=1e-4)
    m.write("CNTRL_BITS", int(m.read("CNTRL_BITS")[0]) | c.RECINNERBIT)
    m.write("T_SOLL", 100)
    m.write("MODE_REG", c.TESTA_MODE)
    n = _steps_until(m, "TESTA_MODE", 100)
    assert n == 11 and m.mode_name() == "BREAK_MODE"
    assert [int(m.read(x)[0]) for x in ("SAMPLE1", "SAMPLE2", "REC_CNT")] == [7, 12, 11]
    assert not int(m.read("CNTRL_BITS")[0]) & c.RECINNERBIT
    buf = m.sample_buffer()
    assert np.all(buf["T_SOLL"][0] == 100) and np.all(np.diff(buf["V_IST"][0]) >= 0)


_RANGES = [("INPOSWIN", 0, 32767), ("INPOSCNT", 0, 32767), ("T1", 0, 1023), ("T4", 0, 1023),
           ("Z1", 0, 32767), ("Z4", 0, 32767), ("ELDEGN_OFFSET", 0, 2047),
           ("ELDEGP_OFFSET", 0, 2047), ("MAN_I_NOM", 0, 1023), ("MAN_ALPHA", 0, 2047),
           ("UMEAS", 0, 100), ("P1", -67_000_000, 67_000_000), ("P8", -67_000_000, 67_000_000),
           ("P_HOME", -67_000_000, 67_000_000), ("MIN_P_IST", -2147483647, 2147483647),
           ("MAX_P_IST", -2147483647, 2147483647), ("P_FNC", -2147483647, 2147483647),
           ("P_IST", -2147483647, 2147483647), ("FNCERRMAX", 0, 134217727),
           ("FLWERRMAX", 0, 67_000_000), ("SAMPLE2", 1, 164), ("MYADDR", 1, 254)]


@pytest.mark.parametrize(("name", "low", "high"), _RANGES, ids=[r[0] for r in _RANGES])
@pytest.mark.statements("mac050_141:3.2.8:12", "mac050_141:3.2.10:6", "mac050_141:3.2.22:3",
                        "mac050_141:3.2.26:4", "mac050_141:3.2.28:5", "mac050_141:3.2.33:9",
                        "mac050_141:3.2.38:2", "mac050_141:3.2.49:3", "mac050_141:3.2.77:2",
                        "mac050_141:3.2.85:2", "mac050_141:3.2.112:4", "mac050_141:3.2.124:4",
                        "mac050_141:3.2.128:3", "mac050_141:3.2.130:2", "mac050_141:3.2.156:4")
def test_the_register_ranges_of_the_manual_are_enforced(name: str, low: int, high: int) -> None:
    """Manual 3.2: a register takes the values of its range, and a value outside is refused
    and changes nothing."""
    import warnings

    from jvl_gym.registers import RegisterError

    m = _motor()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # SAMPLE, offsets: a non-default value may warn
        for value in (low, high):
            m.write(name, value)
            assert int(m.read(name)[0]) == value
        before = m.regs.copy()
        for value in (low - 1, high + 1):
            with pytest.raises(RegisterError):
                m.write(name, value)
            np.testing.assert_array_equal(m.regs, before)


@pytest.mark.parametrize("mode", [c.GP_MODE, c.GF_MODE, c.AG_MODE])
@pytest.mark.statements("mac050_141:4.4.4:7", "mac050_141:4.4.19:3", "mac050_141:4.4.25:6")
def test_in_the_gear_modes_in_pos_is_the_follow_error_not_p_fnc(mode: int) -> None:
    """Manual 4.4.4/4.4.25 write IN_POS as |P_FNC| < INPOSWIN; read as the follow error: after
    the pulses stop the motor reports IN_POS where it caught up, with P_FNC far from 0, and not
    while it lags behind the pulses."""
    m = _motor()
    m.write_many({"GEARF1": 1, "GEARF2": 1, "V_SOLL": 4000, "A_SOLL": 100, "INPOSWIN": 10,
                  "INPOSCNT": 3, "FNCERRMAX": 0})
    m.set_input(pulse_counts=20, analog_volts=0.0)  # AG at 0 V: gear factor 1.01
    m.write("MODE_REG", mode)
    m.step(5)
    assert not int(m.read("ERR_STAT")[0]) & c.IN_POS  # lagging
    m.step(195)
    m.set_input(pulse_counts=0)
    m.run(2.0)
    assert int(m.read("ERR_STAT")[0]) & c.IN_POS
    final = 4000 * (1.01 if mode == c.AG_MODE else 1.0)
    assert abs(int(m.read("P_FNC")[0])) > 16 * 3000 and abs(int(m.read("P_IST")[0]) - final) <= 2


@pytest.mark.statements("mac050_141:3.2.20:7", "mac050_141:4.4.13:11")
def test_flwerr_accumulates_in_home1_and_is_0_in_stop_mode() -> None:
    """Manual 4.4.13 (HOME1 updates FLWERR, the accumulated velocity error) against 3.2.20
    (FLWERR 0 outside its list of modes): the homing search accumulates it while the motor
    pushes against the stop; STOP_MODE, not in either list, keeps it 0."""
    m = _motor(end_stop_low=-3.0, end_stop_high=3.0)
    m.write_many({"V_HOME": -800, "T_HOME": 300, "P_HOME": -1000})
    m.write("MODE_REG", c.HOME1_MODE)
    flw = []
    while m.mode_name() == "HOME1_MODE":
        m.step()
        flw.append(int(m.read("FLWERR")[0]))
        assert len(flw) < 3000
    assert min(flw) < -1000  # held by the stop, the profile runs on: the error grows
    m = _motor()
    m.write_many({"V_SOLL": 3000, "A_SOLL": 10})
    m.write("MODE_REG", c.V_MODE)
    m.run(0.5)
    m.write("MODE_REG", c.INIT_MODE)
    tr = m.trace(["FLWERR", "MODE_REG"], 50)
    stop = tr["MODE_REG"][:, 0] == c.STOP_MODE
    assert stop.sum() > 10 and not tr["FLWERR"][stop, 0].any()


@pytest.mark.statements("mac050_141:4.5.6:5")
def test_in_init_mode_an_undervoltage_only_sets_uv_detect() -> None:
    """Manual 4.5.6: in INIT_MODE the undervoltage check presets the timer and sets UV_DETECT;
    UV_ERR and V_SOLL = 0 are the running modes' reactions (48 V below U_MIN_SUP = 50 V, with
    SET_UV_ERR and UV_SOLL0 set)."""
    m = _motor()
    m.write_many({"U_MIN_SUP": round(50 / 0.0537), "UV_HANDLE": c.SET_UV_ERR | c.UV_SOLL0,
                  "V_SOLL": 500})
    m.step(10)
    st = int(m.read("ERR_STAT")[0])
    assert st & c.UV_DETECT and not st & c.UV_ERR
    assert int(m.read("V_SOLL")[0]) == 500
