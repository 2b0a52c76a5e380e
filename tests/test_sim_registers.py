"""Register access of MotorArray: validation, no change on error, modes rules, buffer, flash."""

from __future__ import annotations

import numpy as np
import pytest

from jvl_gym import ModeError, MotorArray
from jvl_gym.families.mac050_141 import constants as c
from jvl_gym.registers import (
    ReadOnlyRegisterError,
    RegisterError,
    RegisterRangeError,
    UnknownRegisterError,
)
from jvl_gym.registers.formats import whole_only


@pytest.fixture()
def m():
    return MotorArray("MAC140", n=3, seed=0)


def test_read_by_name_and_number_agree(m):
    np.testing.assert_array_equal(m.read("V_IST"), m.read(12))
    assert m.read("KVOUT").dtype == np.float64
    assert m.read("KVOUT")[0] == 1.0


def test_reads_of_some_motors_are_those_motors_of_the_full_read(m):
    m.write_many({"V_SOLL": np.array([100, 200, 300]), "P_SOLL": np.array([-1, 70000, 5])})
    for key in ("V_SOLL", "P_SOLL", 4, "KVOUT"):  # 4: P_SOLL's high word
        for index in ([2, 0], 1, slice(1, None), np.array([True, False, True])):
            full = m.read_raw(key)
            np.testing.assert_array_equal(m.read_raw(key, index),
                                          full[np.arange(3)[index]].reshape(-1))
            np.testing.assert_array_equal(m.read(key, index),
                                          m.read(key)[np.arange(3)[index]].reshape(-1))
    assert m.read_raw(4, [1]).tolist() == [70000 >> 16]
    with pytest.raises(RegisterError, match="index"):
        m.read_raw("V_SOLL", [0, 0])
    kept = m.read_raw("V_SOLL", [0])
    kept[0] = 7  # a copy: the motor keeps its register
    assert m.read_raw("V_SOLL", [0]).tolist() == [100]


@pytest.mark.parametrize(
    ("key", "value", "exc", "needle"),
    [
        ("NO_SUCH_REG", 1, UnknownRegisterError, "NO_SUCH_REG"),
        (999, 1, UnknownRegisterError, "999"),
        ("V_IST", 5, ReadOnlyRegisterError, "3.2.12"),
        ("T_SOLL", 2000, RegisterRangeError, "T_SOLL"),
        ("T_SOLL", float("nan"), RegisterRangeError, "T_SOLL"),
        ("KVOUT", 200.0, RegisterRangeError, "3.2.13"),
        ("V_SOLL", [1, 2], RegisterError, "shape"),
    ],
)
def test_bad_writes_raise_and_change_nothing(m, key, value, exc, needle):
    before = m.regs.copy()
    with pytest.raises(exc) as info:
        m.write(key, value)
    assert needle in str(info.value)
    np.testing.assert_array_equal(m.regs, before)
    with pytest.raises(exc) as info:  # several registers: all validated before any is stored
        m.write_many({"V_SOLL": 5, key: value, "P_SOLL": 7})
    assert needle in str(info.value)
    np.testing.assert_array_equal(m.regs, before)


def test_python_scalars_convert_like_arrays(m):
    rng = np.random.default_rng(1)
    for reg in m.table:
        if reg.access.value != "rw":
            continue
        lo, hi = reg.raw_min / reg.scale, reg.raw_max / reg.scale
        xs = [lo, hi, (reg.raw_max - 0.5) / reg.scale, *rng.uniform(lo, hi, 5)]
        if whole_only(reg):  # codes take whole numbers only
            xs = [float(np.clip(np.round(x), lo, hi)) for x in xs]
        for x in xs:
            for value in (float(x), int(x)):
                np.testing.assert_array_equal(m._validated_raw(reg, value, 3),
                                              m._validated_raw(reg, np.full(3, value), 3))
        for bad in (hi + 1.0, float("nan"), float("inf")):
            with pytest.raises(RegisterRangeError) as info:  # one value, broadcast: one error
                m._validated_raw(reg, bad, 3)
            assert "more" not in str(info.value)
            with pytest.raises(RegisterRangeError, match=r"\(and 2 more\)"):
                m._validated_raw(reg, np.full(3, bad), 3)


def testwrite_many_equals_writes_in_order(m):
    values = {"GEARF1": [300, 400], "GEARF2": 1000, "V_SOLL": 1600, "MODE_REG": c.AG_MODE}
    m.write_many(values, index=[0, 2])
    one_by_one = MotorArray("MAC140", n=3, seed=0)
    for key, value in values.items():
        one_by_one.write(key, value, index=[0, 2])
    np.testing.assert_array_equal(m.regs, one_by_one.regs)
    np.testing.assert_array_equal(m.state, one_by_one.state)


def test_write_subset_and_vector(m):
    m.write("V_SOLL", [100, 200], index=[0, 2])
    np.testing.assert_array_equal(m.read("V_SOLL"), [100, 0, 200])
    m.write("KVOUT", 3.9, index=np.array([False, True, False]))
    assert m.read("KVOUT")[1] == pytest.approx(3.8984375)


@pytest.mark.statements("mac050_141:3.2:2")
def test_longint_high_word_write(m):
    m.write("P_SOLL", -1)
    assert m.read("P_SOLL")[0] == -1
    m.write(4, 0x0001)  # P_SOLL high word
    assert m.read("P_SOLL")[0] == 0x1FFFF


@pytest.mark.statements("mac050_141:3.2.2:2", "mac050_141:4.4.11:2", "mac050_141:4.4.16:2")
def test_forbidden_modes_raise_and_change_nothing(m):
    for bad in (10, 15, 256, 25, 300):
        before = m.regs.copy()
        with pytest.raises(ModeError if bad <= 258 else RegisterRangeError):
            m.write("MODE_REG", bad)
        np.testing.assert_array_equal(m.regs, before)


@pytest.mark.statements("mac050_141:4.4.1:3", "mac050_141:4.4.12:4")
def test_v_mode_to_init_goes_through_stop(m):
    m.write("V_SOLL", 3000)
    m.write("MODE_REG", 1)
    m.run(0.2)
    m.write("MODE_REG", 0)
    assert m.mode_name() == "STOP_MODE"
    m.run(0.5)
    assert m.mode_name() == "INIT_MODE"


@pytest.mark.statements("mac050_141:3.2.35:18")
def test_error_bits_must_be_cleared_before_leaving_init(m):
    m.regs[:, 35] |= c.FLW_ERR
    with pytest.raises(ModeError, match="error bit"):
        m.write("MODE_REG", 1)
    m.write("ERR_STAT", 0)
    m.write("MODE_REG", 1)
    assert m.mode_name() == "V_MODE"


@pytest.mark.statements("mac050_141:4.4.5:5")
def test_at_mode_only_leaves_to_init():
    # friction slows the coasting rotor down to the low speed at which AT_MODE may stop
    m = MotorArray("MAC140", n=3, seed=0, viscous_friction=2e-5)
    m.write("T_SOLL", 200)
    m.set_input(analog_volts=3.0)
    m.write("MODE_REG", 4)
    m.run(0.05)
    m.write("MODE_REG", 1)  # accepted, but AT goes to INIT (4.4.5)
    m.run(1.0)
    assert m.mode_name() == "INIT_MODE"


def test_test_modes_need_init(m):
    m.write("MODE_REG", 1)
    with pytest.raises(ModeError, match="INIT"):
        m.write("MODE_REG", 8)


@pytest.mark.statements("mac050_141:3.2.36:7", "mac050_141:3.2.36:8", "mac050_141:3.2.116:1",
                        "mac050_141:3.2.116:3")
def test_sample_buffer_records_until_full(m):
    m.write("SAMPLE1", 12)
    m.write("CNTRL_BITS", c.RECORDBIT | c.AUTO_RESYNC)
    m.step(900)
    assert int(m.read("REC_CNT")[0]) == c.REC_CNT_MAX
    assert not int(m.read("CNTRL_BITS")[0]) & c.RECORDBIT
    assert m.sample_buffer()["V_IST"].shape == (3, c.REC_CNT_MAX)
    m.write("CNTRL_BITS", c.REWINDBIT)
    m.step()
    assert int(m.read("REC_CNT")[0]) == 0


@pytest.mark.statements("mac050_141:3.2.2:25", "mac050_141:4.4.16:3", "mac050_141:4.4.16:4",
                        "mac050_141:4.4.16:6")
def test_safe_mode_flash_and_defaults(m):
    with pytest.raises(ModeError):
        m.write_flash()
    m.write("KVOUT", 4.0)
    m.enter_safe_mode()
    assert m.mode_name() == "SAFE_MODE"
    with pytest.raises(ModeError):
        m.write("MODE_REG", 1)
    m.write_flash()
    assert m.read("KVOUT")[0] == 4.0  # reloaded from flash after the reset
    m.enter_safe_mode()
    m.write("MODE_REG", 257)  # ROM defaults, not saved
    assert m.read("KVOUT")[0] == 1.0
    m.write("MODE_REG", 258)  # last saved user parameters
    assert m.read("KVOUT")[0] == 4.0
    m.exit_safe_mode()
    assert m.mode_name() == "INIT_MODE"


def test_bad_parameters_and_inputs_raise(m):
    with pytest.raises(TypeError):
        MotorArray("MAC140", n=1, bogus=1.0)
    with pytest.raises(ValueError):
        MotorArray("MAC140", n=2, load_inertia=[1e-5, -1e-5])
    with pytest.raises(ValueError):
        m.set_input(load_torque=float("nan"))
    with pytest.raises(ValueError):
        m.set_input(pulse_counts=1.5)
    with pytest.raises(ValueError):
        m.step(-1)


def test_trace_records_registers_and_physics(m):
    m.write("V_SOLL", 1600)
    m.write("MODE_REG", 1)
    tr = m.trace(["V_IST", "speed_rpm", 117], 20)
    assert tr["t"].shape == (20,) and tr["V_IST"].shape == (20, 3) and tr["117"].shape == (20, 3)
    assert np.all(np.diff(tr["t"]) == pytest.approx(c.OUTER_DT))
    with pytest.raises(UnknownRegisterError):
        m.trace(["NOPE"], 5)


@pytest.mark.statements("mac050_141:3.2.153:1")
def test_reset_can_change_the_motor_type_of_some_motors():
    from jvl_gym.families.mac050_141 import layout as L
    from jvl_gym.families.mac050_141.config import load_motor

    m = MotorArray("MAC140", n=3, seed=0)
    m.write("MODE_REG", c.V_MODE, index=[0])
    before = (m.regs.copy(), m.state.copy(), m.params.copy())
    with pytest.raises(ValueError):
        m.reset(index=[1], motor_type="MAC999")
    with pytest.raises(ValueError):
        m.reset(index=[1, 2], motor_type=["MAC050"])
    for x, y in zip(before, (m.regs, m.state, m.params)):
        np.testing.assert_array_equal(x, y)
    m.reset(index=[1, 2], motor_type=["MAC050", "MAC095"])
    assert [cfg.name for cfg in m.motor_configs] == ["MAC140", "MAC050", "MAC095"]
    assert m.params[1, L.P_J_MOTOR] == load_motor("MAC050").rotor_inertia
    assert m.read_raw("MOTOR_TYPE")[2] == load_motor("MAC095").motor_type_code
    assert m.read("MODE_REG")[0] == c.V_MODE  # motor 0 untouched
    m.reset(index=[1])  # keeps its new type
    assert m.motor_configs[1].name == "MAC050"


def _writable(reg) -> bool:
    """Registers a batch test writes: read-write, not MODE_REG (its own tests)."""
    return reg.access.value == "rw" and reg.name != "MODE_REG"


def _random_values(m, rng, regs, size):
    """In-range values (user units) for ``regs``: scalars and (size,) arrays, legal for the
    write rules (HOME_MODE bytes, register-mode pointers 0) and leaving no error bit set."""
    values = {}
    for k, reg in enumerate(regs):
        lo, hi = reg.raw_min / reg.scale, reg.raw_max / reg.scale
        if reg.name == "HOME_MODE":
            value = 13 | (12 << 8)
        elif reg.name.endswith("_REG_P") or reg.name == "ERR_STAT":
            value = 0
        elif k % 2:
            value = float(rng.uniform(lo, hi))
        else:
            value = rng.uniform(lo, hi, size)
        if whole_only(reg):  # codes take whole numbers only
            value = np.clip(np.round(value), lo, hi)
            value = float(value) if np.ndim(value) == 0 else value
        values[reg.name] = value
    return values


@pytest.mark.parametrize("compiled", [True, False])
def test_batched_write_equals_writes_one_by_one(compiled):
    """write_many (one compiled conversion and store) = write() register by register, for
    every writable register (without CNTRL_BITS and the register-mode pointers: the compiled
    store; with them: stored one by one)."""
    rng = np.random.default_rng(3)
    regs = [r for r in MotorArray("MAC140", n=1).table if _writable(r)
            and not (compiled and (r.name == "CNTRL_BITS" or r.name.endswith("_REG_P")))]
    batch, one_by_one = (MotorArray("MAC140", n=4, seed=0) for _ in range(2))
    values = _random_values(batch, rng, regs, 2)
    batch.write_many({**values, "MODE_REG": c.V_MODE}, index=[3, 1])
    for key, value in {**values, "MODE_REG": c.V_MODE}.items():
        one_by_one.write(key, value, index=[3, 1])
    np.testing.assert_array_equal(batch.regs, one_by_one.regs)
    np.testing.assert_array_equal(batch.state, one_by_one.state)


def test_refused_batch_changes_nothing(m):
    """A batch the rules refuse at a later register (the earlier ones already stored, by the
    compiled store or one by one) leaves every motor as it was; the message is the one of a
    write of that register alone."""
    m.write("MODE_REG", c.V_MODE, index=[2])
    before_regs, before_state = m.regs.copy(), m.state.copy()
    with pytest.raises(ModeError, match=r"P1 ≤ P2 .*\(P1=5, P2=1, P3=0"):
        m.write_many({"GEARF1": 3, "P1": 5, "P2": 1, "MODE_REG": c.COIL_MODE}, index=[0, 1])
    with pytest.raises(ModeError, match="GEARF2 = 0"):
        m.write_many({"GEARF1": 3, "GEARF2": 0, "MODE_REG": c.AG_MODE})
    with pytest.raises(RegisterError, match="HOME_MODE bytes"):
        m.write_many({"V_SOLL": 5, "HOME_MODE": 11, "P_SOLL": 7})
    with pytest.raises(ModeError, match="in V_MODE: can only be entered from INIT"):
        m.write_many({"V_SOLL": 200, "MODE_REG": c.TESTU_MODE})  # stored one by one
    np.testing.assert_array_equal(m.regs, before_regs)
    np.testing.assert_array_equal(m.state, before_state)


def test_refusal_names_the_first_refused_motor(m):
    """check_write (compiled rules per motor) words the refusal of the first refused motor."""
    from jvl_gym.families.mac050_141.firmware import write_rules as W

    m.write_many({"P1": 0, "P2": 10, "P3": 20, "P4": 30, "P5": 10, "P6": 1, "GEARF2": 1000,
                   "MODE_REG": c.COIL_MODE})
    idx = np.array([0, 1, 2])
    assert W.check_write(m.regs, idx, 51, np.array([15, 25, 40])) == (
        "COIL_MODE rules P1 ≤ P2 ≤ P3 ≤ P4, P1 ≤ P5 ≤ P4, P6 = ±1 (manual 4.4.20) are violated "
        "(P1=0, P2=25, P3=20, P4=30, P5=10, P6=1)")
    assert W.check_write(m.regs, idx, 51, np.array([15, 20, 0])) is None
    assert W.check_write(m.regs, idx, 15, np.array([1, 0, 1])).startswith("GEARF2 = 0")
    assert W.check_mode_request(m.regs, idx, np.array([0, 0, 0])) is None


def test_reset_checks_keywords_in_order():
    """MotorArray.reset checks its keywords in the given order (compiled value rules): the
    first bad one is reported, and a bad call changes nothing."""
    m = MotorArray("MAC140", n=3, seed=0)
    before = m.params.copy(), m.state.copy(), m.regs.copy()
    for params, exc, needle in [
        ({"load_inertia": -1.0, "foo": 1}, ValueError, "load_inertia: values must be >= 0"),
        ({"foo": 1, "load_inertia": -1.0}, TypeError, "unknown motor parameter 'foo'"),
        ({"load_inertia": -1.0, "torque_noise": [1, 2]}, ValueError, "load_inertia"),
        ({"load_inertia": 1.0, "torque_noise": [1, 2]}, ValueError, "torque_noise: expected"),
        ({"viscous_friction": [0.0, np.nan, 0.0]}, ValueError, "must be finite"),
        ({"phase_resistance": [1.0, 0.0, 1.0]}, ValueError, "phase_resistance: values must be > 0"),
        ({"hall_start": 0.5}, ValueError, "hall_start must be 0 or 1"),
        ({"initial_angle": np.inf}, ValueError, "initial_angle: values must be finite"),
    ]:
        with pytest.raises(exc, match=needle):
            m.reset(**params)
    for got, want in zip((m.params, m.state, m.regs), before):
        np.testing.assert_array_equal(got, want)
    m.reset(index=[2, 0], home_position=np.inf, initial_angle=[0.5, -0.5], initial_speed=2.0,
            load_inertia=[1e-4, 2e-4], motor_type=["MAC050", "MAC141"])
    np.testing.assert_array_equal(m.position_rad, [-0.5, 0.0, 0.5])
    np.testing.assert_array_equal(m.speed_rad_s, [2.0, 0.0, 2.0])
    np.testing.assert_array_equal(m.parameters["load_inertia"], [2e-4, 0.0, 1e-4])
    assert [cfg.name for cfg in m.motor_configs] == ["MAC141", "MAC140", "MAC050"]
