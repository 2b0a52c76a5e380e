"""MAC800 register access: by name, MacTalk name or number; the 32-bit formats' write paths
(hypothesis); the register-set selectors; motor configs validated at load."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st

from jvl_gym import MotorArray
from jvl_gym.families.config import ConfigError
from jvl_gym.families.mac800 import constants as c
from jvl_gym.families.mac800 import units as u
from jvl_gym.families.mac800.config import CONFIGS, load_motor, motor_types
from jvl_gym.registers import RegisterError

SETTINGS = settings(max_examples=60, deadline=None, derandomize=True)
M = MotorArray("MAC800", n=2, seed=0)


def test_read_write_by_name_alias_and_number() -> None:
    M.write("V_SOLL", 277)
    assert M.read(5)[0] == 277 and M.read("Max velocity")[0] == 277
    M.write("Acceleration", 500)
    assert M.read("A_SOLL")[0] == 500
    M.write(13, 2.5)
    assert M.read("KVOUT")[0] == 2.5 and M.read("Load")[0] == 2.5
    M.write_many({"A_SOLL": 360, "KVOUT": 1.0, "V_SOLL": 0})


@SETTINGS
@given(st.floats(-200.0, 200.0, allow_nan=False), st.sampled_from(["KFF5", "KVB2", "KIB1"]))
@pytest.mark.statements("mac800:1.1:4", "mac800:1.1:5")
def test_fixed24_write_path(value: float, name: str) -> None:
    before = M.regs.copy()
    if -128.0 <= value <= 127.99999994039536:
        M.write(name, value, 0)
        raw = M.read_raw(name)[0]
        assert raw == np.sign(value) * np.floor(abs(value) * 2**24 + 0.5)
        assert M.read(name)[0] == raw / 2**24
        M.regs[:] = before
    else:
        with pytest.raises(RegisterError):
            M.write(name, value, 0)
        np.testing.assert_array_equal(M.regs, before)


@SETTINGS
@given(st.floats(-40000.0, 40000.0, allow_nan=False),
       st.sampled_from(["KVFX6", "KVFY0", "KIFX2", "KVOUT", "LOAD3"]))
@pytest.mark.statements("mac800:1.1:3", "mac800:1.1:5")
def test_fixed16_write_path(value: float, name: str) -> None:
    before = M.regs.copy()
    state = M.state.copy()
    if -32768.0 <= value <= 32767.9999847412109375:
        M.write(name, value, 1)
        assert abs(M.read(name)[1] - value) <= 0.5 / 65536
        M.regs[:] = before
        M.state[:] = state
    else:
        with pytest.raises(RegisterError):
            M.write(name, value, 1)
        np.testing.assert_array_equal(M.regs, before)


@SETTINGS
@given(st.integers(-2**33, 2**33), st.sampled_from(["P_SOLL", "POS3", "FLWERRMAX", "T_SOLL"]))
@pytest.mark.statements("mac800:1.1:2")
def test_int32_write_path(value: int, name: str) -> None:
    before = M.regs.copy()
    reg = M.table.lookup(name)
    if reg.raw_min <= value <= reg.raw_max:
        M.write(name, value)
        assert np.all(M.read(name) == value)
        M.regs[:] = before
    else:
        with pytest.raises(RegisterError):
            M.write(name, value)
        np.testing.assert_array_equal(M.regs, before)


@SETTINGS
@given(st.sampled_from([float("nan"), float("inf"), "1", True, 1 + 2j]))
def test_refused_values_change_nothing(value) -> None:
    before = M.regs.copy()
    with pytest.raises((RegisterError, TypeError, ValueError)):
        M.write_many({"V_SOLL": 100, "KVFX6": value})
    np.testing.assert_array_equal(M.regs, before)


def test_read_only_and_reserved_registers_are_refused() -> None:
    with pytest.raises(RegisterError):
        M.write("V_IST", 1)
    with pytest.raises(RegisterError):
        M.write("OUTLOOPDIV", 5)
    assert M.read("OUTLOOPDIV")[0] == c.INNER_PER_OUTER


@pytest.mark.statements("mac800:reg36:5", "mac800:reg43:1", "mac800:reg44:1", "mac800:reg45:1",
                        "mac800:reg46:1", "mac800:reg47:1", "mac800:reg48:1")
def test_register_set_selectors() -> None:
    m = MotorArray("MAC800", n=1, seed=0)
    m.write_many({"POS2": 12345, "VEL5": 999, "ACC1": 77, "TQ3": 500, "LOAD2": 3.0,
                  "ZERO1": 42})
    m.write_many({"P_REG_P": 3, "V_REG_P": 6, "A_REG_P": 2, "T_REG_P": 4, "L_REG_P": 3,
                  "Z_REG_P": 2})
    assert (m.read("P_SOLL")[0], m.read("V_SOLL")[0], m.read("A_SOLL")[0]) == (12345, 999, 77)
    assert (m.read("T_SOLL")[0], m.read("KVOUT")[0], m.read("INPOSWIN")[0]) == (500, 3.0, 42)
    m.write("CNTRL_BITS", c.RELPOSPSOLL)
    m.write("P_REG_P", 3)
    assert m.read("P_SOLL")[0] == 24690


@pytest.mark.statements("mac800:reg2:10")
def test_unrunnable_modes_are_refused() -> None:
    from jvl_gym.motor.array import ModeError

    m = MotorArray("MAC800", n=1, seed=0)
    for mode in (7, 19, 20):
        with pytest.raises(ModeError):
            m.write("MODE_REG", mode)
    assert m.read("MODE_REG")[0] == 0


@pytest.mark.statements("mac800:reg7:3")
def test_motor_configs_load() -> None:
    assert motor_types() == ["MAC400", "MAC800"]
    cfg = load_motor("MAC800")
    assert cfg.rated_torque * 3 == pytest.approx(cfg.peak_torque, rel=0.01)


@pytest.mark.parametrize("field, value", [("rotor_inertia", 1e-7), ("flux_linkage", "x"),
                                          ("supply_voltage", float("inf")),
                                          ("pole_pairs", 2.5), ("dump_voltage", 300.0),
                                          ("unknown", 1)])
def test_bad_motor_config_names_file_and_field(tmp_path: Path, field: str, value) -> None:
    data = yaml.safe_load((CONFIGS / "motors" / "MAC800.yaml").read_text())
    data[field] = value
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(data))
    with pytest.raises(ConfigError) as err:
        load_motor(path)
    assert str(path) in str(err.value) and field in str(err.value)


def test_unknown_motor_type() -> None:
    with pytest.raises(ConfigError, match="MAC400, MAC800"):
        load_motor("MAC900")


def test_task_interface() -> None:
    """``mac800.task``: the MAC050–141 task interface's names with this family's registers."""
    from jvl_gym.engine.view import EngineView
    from jvl_gym.families.mac050_141 import task as t050
    from jvl_gym.families.mac800 import task

    # coil_direction: the coil mode; GEAR_MODE, ag_factor: GearSync deployed over the bus,
    # which the MAC050–141 alone offers
    shared = set(t050.__all__) - {"coil_direction", "GEAR_MODE", "ag_factor"}
    assert shared <= set(task.__all__)
    assert task.FAMILY_KEY == "mac800" and task.DEFAULT_MOTOR_TYPE == "MAC800"
    assert dict(task.TERMINAL_ERRORS)["OV_ERR"] == c.OV_ERR
    m = MotorArray("MAC800", n=2, seed=0)
    view = EngineView(*m.engine_view())
    task.set_reg(view, 1, task.R.T_SOLL, 5000)  # saturated to the range 0..1023
    assert task.reg(view, 1, task.R.T_SOLL) == 1023 and m.read("T_SOLL")[0] == 1023
    task.set_load_torque(view, 0, 1.5)
    task.set_analog_volts(view, 0, 2.0)
    task.set_pulse_counts(view, 0, 7.0)
    m.step()
    assert m.read("ANINP")[0] == round(2.0 / u.ANINP_VOLTS_PER_UNIT)
    assert m.read("V_EXT")[0] == 7
    assert task.shaft_angle(view, 0) == m.position_rad[0]


def test_function_error_is_stated_in_the_profiles_sixteenth_counts() -> None:
    """FNCERR accumulates the function generator's velocity corrections, which are in the
    profile's 1/16 count per sample (MAC050–141 manual 3.2.24, which the MAC800 overview's
    function error follows; the overview gives no unit): the table states its unit, and
    FNCERRMAX's, as 1/16 count, as the MAC050–141's table does."""
    mac800 = MotorArray("MAC800", n=1, seed=0).table
    mac140 = MotorArray("MAC140", n=1, seed=0).table
    for name in ("FNCERR", "FNCERRMAX"):
        assert mac800.lookup(name).unit == mac140.lookup(name).unit == "1/16 count"
