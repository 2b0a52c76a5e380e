"""Every input path either does what it says or raises a documented error and changes
nothing (indices, values, flash images, setups, motor configs, wording of the errors)."""

from __future__ import annotations

import numpy as np
import pytest
import yaml

from jvl_gym import ModeError, MotorArray
from jvl_gym.families.config import ConfigError
from jvl_gym.families.mac050_141.config import MOTORS_DIR, load_motor
from jvl_gym.registers import (
    ReadOnlyRegisterError,
    RegisterError,
    RegisterRangeError,
    RegisterShapeError,
)


@pytest.fixture()
def m():
    return MotorArray("MAC140", n=3, seed=0)


def _snapshot(m: MotorArray) -> tuple:
    flash = None if m._flash is None else m._flash.copy()
    return (m.regs.copy(), m.state.copy(), m.params.copy(), m.inputs.copy(), flash,
            m._has_flash.copy())


def _assert_unchanged(m: MotorArray, before: tuple) -> None:
    after = _snapshot(m)
    for a, b in zip(before, after):
        if a is None or b is None:
            assert a is None and b is None
        else:
            np.testing.assert_array_equal(a, b)


# ------------------------------------------------------------------ flash images
def test_refused_flash_load_keeps_the_old_flash(m):
    m.load_flash_image(0, {13: 1024})  # KVOUT 4.0
    before = _snapshot(m)
    old = m.flash_image(0)
    for bad in ({13: 512, 12: 5},  # V_IST is read-only
                {13: 512, 7: 5000},  # T_SOLL out of range
                {13: 1.5},  # a float for a raw word
                {13: True},
                {13: "512"},
                {2: 1},  # MODE_REG is not stored in flash
                {4: 1},  # a LongInt's high word
                {999: 1},
                {"13": 512}):
        with pytest.raises(RegisterError):
            m.load_flash_image(0, bad)
        _assert_unchanged(m, before)
        assert m.flash_image(0) == old


def test_flash_image_index_is_checked(m):
    for bad in (5, -4, 1.5, True, None, np.uint64(2**64 - 1)):
        with pytest.raises(RegisterShapeError, match="motor"):
            m.load_flash_image(bad, {13: 512})
        with pytest.raises(RegisterShapeError, match="motor"):
            m.flash_image(bad)
        with pytest.raises(RegisterShapeError, match="motor"):
            m.sample_buffer_raw(bad)
        with pytest.raises(RegisterShapeError, match="motor"):
            m.mode_name(bad)
    assert m.flash_image(np.int64(1)) == {}
    assert m.mode_name(-1) == "INIT_MODE"


def test_load_flash_image_needs_a_mapping(m):
    before = _snapshot(m)
    for bad in ([(13, 512)], None, 13):
        with pytest.raises(RegisterError, match="mapping"):
            m.load_flash_image(0, bad)
    _assert_unchanged(m, before)


# ------------------------------------------------------------------ indices
@pytest.mark.parametrize("index", [1.5, np.array([0.5]), np.uint64(2**64 - 1), [1.0],
                                   np.array([1.0, 2.0]), True, np.bool_(False), "1", b"1",
                                   [True, False], np.array([[0, 1]]), 3, -4, [0, 3],
                                   np.array([2**63 - 1], dtype=np.uint64), [0, 0], 1 + 0j,
                                   slice(0.5, 2), [None]])
def test_bad_indices_are_refused(m, index):
    before = _snapshot(m)
    with pytest.raises(RegisterShapeError, match="index"):
        m.write("V_SOLL", 5, index=index)
    _assert_unchanged(m, before)


def test_good_indices_select_the_motors(m):
    for index, want in ((None, [0, 1, 2]), (1, [1]), (-1, [2]), (np.int32(2), [2]),
                        ([0, 2], [0, 2]), (np.array([2, 0], dtype=np.uint8), [0, 2]),
                        (np.array([True, False, True]), [0, 2]), (slice(1, None), [1, 2]),
                        ([], []), (np.array([], dtype=np.int64), []), (range(2), [0, 1])):
        fresh = MotorArray("MAC140", n=3, seed=0)
        fresh.write("V_SOLL", 7, index=index)
        assert np.flatnonzero(fresh.read("V_SOLL") == 7).tolist() == want, index


# ------------------------------------------------------------------ values
@pytest.mark.parametrize(("key", "value"), [
    ("MODE_REG", 0.5), ("MODE_REG", 1.5), ("MODE_REG", np.float64(1.5)), ("CNTRL_BITS", 0.5),
    ("HOME_MODE", 12.5), ("MYADDR", 3.25),
    ("V_SOLL", 1 + 0j), ("V_SOLL", np.complex128(5)), ("V_SOLL", np.array([1j, 2, 3])),
    ("V_SOLL", "100"), ("V_SOLL", b"1"), ("V_SOLL", True), ("KVOUT", "2.0"), ("V_SOLL", None),
    ("V_SOLL", [1, "2", 3]), ("V_SOLL", {"a": 1}), ("V_SOLL", np.array(["1", "2", "3"])),
    ("MODE_REG", 1e300), ("V_SOLL", np.uint64(2**64 - 1)),
])
def test_bad_values_are_refused(m, key, value):
    before = _snapshot(m)
    with pytest.raises(RegisterRangeError):
        m.write(key, value)
    with pytest.raises(RegisterRangeError):
        m.write_many({"KVOUT": 2.0, key: value})
    _assert_unchanged(m, before)


def test_quantities_round_half_away_from_zero_codes_need_whole_numbers(m):
    m.write("V_SOLL", 1600.7)
    assert m.read("V_SOLL").tolist() == [1601] * 3
    m.write("V_SOLL", np.array([2.5, -2.5, 2.49]))
    assert m.read("V_SOLL").tolist() == [3, -3, 2]
    m.write("MODE_REG", 1.0)  # a whole number as a float is the code 1
    assert m.mode_name() == "V_MODE"


def test_write_raw_needs_integers(m):
    before = _snapshot(m)
    for bad in (1.5, np.array([1.0, 2.0, 3.0]), True, "5", 1 + 0j):
        with pytest.raises(RegisterRangeError):
            m.write_raw("V_SOLL", bad)
    _assert_unchanged(m, before)


# ------------------------------------------------------------------ setups
@pytest.mark.parametrize(("registers", "needle"), [
    ({"SERIAL_NMB": 5}, "SERIAL_NMB"), ({"V_IST": 5}, "V_IST"), ({"MOTOR_TYPE": 1}, "MOTOR_TYPE"),
    ({"HOME_MODE": 1}, "HOME_MODE"), ({"MODE_REG": 1}, "MODE_REG"), ({"KVOUT": 999}, "KVOUT"),
    ({"NO_SUCH": 1}, "NO_SUCH"), ({"STARTMODE": 0.5}, "STARTMODE"),
])
def test_constructor_setup_is_validated_like_load_setup(registers, needle):
    with pytest.raises(RegisterError, match=needle):
        MotorArray("MAC140", n=1).load_setup(registers)
    with pytest.raises(RegisterError, match=needle):
        MotorArray("MAC140", n=1, setup=registers)


def test_constructor_setup_error_names_the_file(tmp_path):
    path = tmp_path / "mine.yaml"
    path.write_text("registers:\n  V_IST: 5\n")
    with pytest.raises(RegisterError, match="mine.yaml"):
        MotorArray("MAC140", n=1, setup=path)


# ------------------------------------------------------------------ motor configs
def _motor_file(tmp_path, **changes):
    data = yaml.safe_load((MOTORS_DIR / "MAC140.yaml").read_text())
    data.update(changes)
    path = tmp_path / "motor.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


@pytest.mark.parametrize(("field", "value"), [
    ("rated_torque", float("inf")), ("dump_voltage", float("inf")), ("phase_resistance", True),
    ("bus_capacitance", 1e-12), ("supply_resistance", float("nan")), ("pole_pairs", True),
    ("pole_pairs", 2.5), ("rotor_inertia", "heavy"), ("thermal_time_constant", 1e-9),
    ("dump_voltage", 30.0), ("peak_torque", 0.1), ("motor_type_code", 1.5),
    ("amps_per_count", [1]), ("name", 5), ("dump_resistance", 1e-9), ("flux_linkage", 1e-12),
    ("phase_inductance", 1e-12), ("rated_speed_rpm", float("inf")), ("rotor_inertia", 2e-6),
])
def test_motor_config_values_are_checked_at_load(tmp_path, field, value):
    path = _motor_file(tmp_path, **{field: value})
    with pytest.raises(ConfigError, match=field) as info:
        load_motor(path)
    assert "motor.yaml" in str(info.value)


def test_yaml_exponent_without_a_dot_is_a_number(tmp_path):
    path = _motor_file(tmp_path)
    path.write_text(path.read_text().replace("bus_capacitance: 0.002", "bus_capacitance: 2e-3"))
    assert "2e-3" in path.read_text()
    assert load_motor(path).bus_capacitance == 2e-3


def test_unknown_motor_lists_the_known_ones_and_short_names_work():
    with pytest.raises(ConfigError, match="MAC050, MAC095, MAC140, MAC141"):
        MotorArray("MAC999")
    assert load_motor("MAC50").name == "MAC050"
    assert load_motor("MAC95").name == "MAC095"
    assert MotorArray("MAC50").motor_configs[0].name == "MAC050"


@pytest.mark.parametrize("motor", ["MAC14O", "MIS999", 5])
def test_unknown_motor_lists_every_familys_types(motor):
    with pytest.raises(ConfigError) as err:
        MotorArray(motor)
    assert all(t in str(err.value) for t in ("MAC140", "MIS232", "SMC66", "MAC800"))


def test_env_motor_type_that_is_no_name_is_named():
    import gymnasium as gym

    with pytest.raises(ValueError, match="motor_type must be one or more of .* got 5"):
        gym.make("jvl_gym/Positioning-v0", motor_type=5)


# ------------------------------------------------------------------ wording
def test_a_broadcast_scalar_is_one_bad_value(m):
    with pytest.raises(RegisterRangeError) as info:
        m.write("V_SOLL", 1e6)
    assert "more" not in str(info.value)
    with pytest.raises(RegisterRangeError, match=r"\(and 1 more\)"):
        m.write("V_SOLL", [1e6, 0, -1e6])


def test_unknown_mode_is_not_named_twice(m):
    with pytest.raises(ModeError) as info:
        m.write("MODE_REG", 99)
    assert "(99)" not in str(info.value)
    assert "MODE_REG = 99" in str(info.value)


def test_trace_and_step_need_whole_non_negative_counts(m):
    before = _snapshot(m)
    for bad in (-1, 1.5, "2", None):
        with pytest.raises(ValueError, match="n_outer"):
            m.trace(["V_IST"], bad)
    _assert_unchanged(m, before)


def test_read_only_register_error_is_unchanged(m):
    with pytest.raises(ReadOnlyRegisterError):
        m.write("V_IST", 5)


# ------------------------------------------------------------------ the same kind elsewhere
@pytest.mark.parametrize("kwargs", [
    {"load_torque": "0.1"}, {"load_torque": 1j}, {"load_torque": True}, {"supply_volts": b"4"},
    {"analog_volts": [0.1, "x", 0.2]}, {"pulse_counts": [1, None, 2]}, {"home": "yes"},
])
def test_set_input_refuses_non_numbers(m, kwargs):
    before = _snapshot(m)
    with pytest.raises(ValueError):
        m.set_input(**kwargs)
    _assert_unchanged(m, before)


def test_set_input_takes_a_boolean_home_level(m):
    from jvl_gym.families.mac050_141 import layout as L

    m.set_input(home=np.array([True, False, True]))
    assert m.inputs[:, L.I_HOME].tolist() == [1.0, 0.0, 1.0]


@pytest.mark.parametrize("kwargs", [
    {"load_inertia": "1e-5"}, {"load_inertia": True}, {"viscous_friction": 1j},
    {"coulomb_friction": None}, {"hall_start": "1"}, {"initial_angle": b"0"},
])
def test_reset_keywords_refuse_non_numbers(m, kwargs):
    before = _snapshot(m)
    with pytest.raises((ValueError, TypeError)):
        m.reset(**kwargs)
    _assert_unchanged(m, before)
    with pytest.raises((ValueError, TypeError)):
        MotorArray("MAC140", n=1, **kwargs)


@pytest.mark.parametrize("n", [True, 1.5, "2", 0, -1, None])
def test_motor_count_must_be_a_positive_integer(n):
    with pytest.raises((ValueError, TypeError)):
        MotorArray("MAC140", n=n)


@pytest.mark.parametrize("length", [True, 1.5, "20", 0, 10_000, None])
def test_record_length_must_be_a_whole_number_in_range(m, length):
    before = _snapshot(m)
    with pytest.raises(ValueError):
        m.set_record_length(length)
    _assert_unchanged(m, before)


@pytest.mark.parametrize("seed", [[1.5, 2, 3], [-1, 2, 3], ["a", "b", "c"], [True, False, True]])
def test_seed_sequences_are_integer_keys(seed):
    with pytest.raises(ValueError, match="seed"):
        MotorArray("MAC140", n=3, seed=seed)
