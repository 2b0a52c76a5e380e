"""The families' facts stated as data and read by generic loaders: the Family record's plain
facts (``family.yaml``), the servo motor-data bounds (``configs/limits.yaml``), the linear
register units (``units.csv``), and the TESTU/TESTA facts of the family a tool is asked about
(:mod:`tuning.testmode_facts`)."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pydantic
import pytest
import yaml
from tuning.models import MotorData
from tuning.records import Record, RecordError, simulate_testu, validate
from tuning.testmode_facts import record_facts, record_facts_of

from jvl_gym import MotorArray
from jvl_gym.families import Capability, UnsupportedOperation, family
from jvl_gym.families.config import ConfigError
from jvl_gym.families.record_file import record_fields
from jvl_gym.families.servo_config import ServoMotorData, bounded_servo_data
from jvl_gym.registers.scaling import UNIT_COLUMNS, linear_units

FAMILIES = Path(__file__).resolve().parents[1] / "src" / "jvl_gym" / "families"


# ------------------------------------------------------------------ family.yaml
def test_the_record_file_states_the_twin_facts_by_constant_name() -> None:
    mac800 = family("mac800")
    c = mac800.constants
    assert mac800.key == "mac800" and mac800.twin.passive_mode == c.PASSIVE_MODE == 0
    assert mac800.twin.status_bits == {m: n for n, m in c.ERR_STAT_BITS.items()}
    # a mask names the status bits it covers, in bit order
    assert mac800.twin.error_bits == tuple(c.ERROR_NAMES.values())
    mis = family("mis")
    assert mis.j1939_name == mis.constants.J1939_NAME
    assert mis.twin.commands["reset"] == mis.constants.CMD_RESET
    assert family("mac050_141").supports(Capability.TEST_MODES)
    assert not mac800.supports(Capability.TEST_MODES)


@pytest.mark.parametrize("change, needle", [
    ({"capabilities": ["TORQUE", "WARP_DRIVE"]}, "no capability 'WARP_DRIVE'"),
    ({"twin": {"dialects": ["NO_SUCH_CONSTANT"]}}, "'NO_SUCH_CONSTANT' is not a constant"),
    ({"twin": {"dialects": ["MACTALK_DIALECT"], "status_bits": ["I2T_ERR"],
               "error_bits": ["FLW_ERR"]}}, "'FLW_ERR' is not one of the status bits"),
    ({"twin": {"dialects": ["MACTALK_DIALECT"], "colour": "red"}}, "unknown entries"),
    ({"motto": "fast"}, "unknown entries \\['motto'\\]"),
])
def test_a_malformed_record_file_is_refused_naming_the_entry(
        tmp_path: Path, change: dict, needle: str) -> None:
    data = yaml.safe_load((FAMILIES / "mac800" / "family.yaml").read_text())
    (tmp_path / "family.yaml").write_text(yaml.safe_dump({**data, **change}))
    with pytest.raises(ValueError, match=needle) as info:
        record_fields(tmp_path, family("mac800").constants)
    assert "family.yaml" in str(info.value)
    with pytest.raises(ValueError, match="cannot read"):
        record_fields(tmp_path / "missing", family("mac800").constants)


# ------------------------------------------------------------------ configs/limits.yaml
@pytest.mark.parametrize("key", ["mac050_141", "mac800"])
def test_every_servo_field_is_bounded_by_the_family_file(key: str) -> None:
    model = type(family(key).load_motor(family(key).motor_types()[0]))
    assert issubclass(model, ServoMotorData)
    limits = yaml.safe_load((FAMILIES / key / "configs" / "limits.yaml").read_text())
    for name, entry in limits.items():
        meta = {type(m).__name__.lower(): getattr(m, type(m).__name__.lower())
                for m in model.model_fields[name].metadata
                if type(m).__name__ in ("Gt", "Ge", "Lt", "Le")}
        assert meta == {k: v for k, v in entry.items() if k != "default"}, name
        if "default" in entry:
            assert model.model_fields[name].default == entry["default"]
        else:
            assert model.model_fields[name].is_required()


def test_the_two_servo_families_bound_the_same_field_differently() -> None:
    for key, motor, bad in (("mac800", "MAC800", 48.0), ("mac050_141", "MAC140", 325.0)):
        cfg = family(key).load_motor(motor)
        with pytest.raises(pydantic.ValidationError, match="supply_voltage"):
            type(cfg).model_validate({**cfg.model_dump(), "supply_voltage": bad})


@pytest.mark.parametrize("limits, needle", [
    ({"rotor_inertia": {"ge": "small"}}, "rotor_inertia"),
    ({"rotor_inertia": {"ge": 1.0e-5, "about": 3}}, "rotor_inertia"),
    ({"rotor_inertia": {}}, "at least one bound"),
    ({"colour": {"ge": 1}}, "no servo motor-data field"),
])
def test_a_malformed_limits_file_is_refused(tmp_path: Path, limits: dict, needle: str) -> None:
    base = yaml.safe_load((FAMILIES / "mac800" / "configs" / "limits.yaml").read_text())
    path = tmp_path / "limits.yaml"
    path.write_text(yaml.safe_dump({**base, **limits}))
    with pytest.raises(ConfigError, match=needle):
        bounded_servo_data(path, "Broken")
    del base["rotor_inertia"]
    path.write_text(yaml.safe_dump(base))
    with pytest.raises(ConfigError, match="rotor_inertia"):
        bounded_servo_data(path, "Broken")


# ------------------------------------------------------------------ units.csv
def test_unit_tables_give_the_manual_examples() -> None:
    mu, su = family("mac800").units, family("mis").units
    assert mu.u_bus_to_volts(366) == pytest.approx(325.3, abs=0.05)  # register 198
    assert mu.rpm_to_v_soll(100) == pytest.approx(277.056)  # register 5
    assert su.rpm_to_v_soll(250) == pytest.approx(25000)  # MIS manual §8.2.5
    assert su.run_current_to_amps(100) == pytest.approx(0.587)  # §8.2.7
    assert {"u_bus_to_volts", "volts_to_u_bus", "aninp_to_volts"} <= set(mu.__all__)
    assert "aninp_to_volts" in mu.CONVERSIONS and "volts_to_aninp" not in mu.CONVERSIONS


@pytest.mark.parametrize("row, needle", [
    ("a_to_b,b_to_a,R,q [x],s,NO_SUCH,quantity_per_unit", "NO_SUCH"),
    ("a_to_b,b_to_a,R,q [x],s,FACTOR,per_fortnight", "per_fortnight"),
    ("a_to_b,b_to_a,R,q [x],s,ZERO,quantity_per_unit", "finite positive"),
])
def test_a_malformed_unit_table_is_refused(tmp_path: Path, row: str, needle: str) -> None:
    path = tmp_path / "units.csv"
    path.write_text(",".join(UNIT_COLUMNS) + "\n" + row + "\n")
    with pytest.raises(ValueError, match=needle):
        linear_units(path, {"FACTOR": 2.0, "ZERO": 0.0})
    path.write_text("name,factor\nx,1\n")
    with pytest.raises(ValueError, match="columns"):
        linear_units(path, {})


# ------------------------------------------------------------------ TESTU/TESTA facts
def test_record_facts_are_those_of_the_family_asked_about() -> None:
    mac = family("mac050_141")
    facts = record_facts(mac)
    assert facts.family is mac and facts.table is mac.table
    assert facts.ts_i == pytest.approx(128e-6) and facts.ts_o == pytest.approx(1.92e-3)
    assert facts.test_record_samples == 11 and facts.adc_full == 1023  # manual 4.4.9, 3.2.139
    assert facts.counts_per_rad == pytest.approx(4096 / (2 * math.pi))
    assert record_facts_of("MAC140") == facts
    assert record_facts_of(MotorArray("MAC050", n=1)).family is mac
    assert record_facts_of(MotorData.from_config("MAC095")).family is mac
    with pytest.raises(UnsupportedOperation, match="TEST_MODES"):
        record_facts(family("mac800"))
    with pytest.raises(UnsupportedOperation, match="TEST_MODES"):
        record_facts_of("MAC800")


def test_a_second_family_with_test_modes_gets_its_own_rates() -> None:
    """A family whose current loop runs twice as fast: its facts, not the first test-mode
    family's, decide whether a record's rate is right."""
    mac = family("mac050_141")
    spec = dataclasses.replace(mac.tuning, inner_dt=mac.tuning.inner_dt / 2,
                               outer_dt=mac.tuning.outer_dt / 2)
    fast = dataclasses.replace(mac, key="mac050_fast", tuning=spec)
    facts = record_facts(fast)
    assert facts.rates["TESTU"] == pytest.approx(2 * record_facts(mac).rates["TESTU"])
    good = simulate_testu(MotorData.from_config("MAC140"), 100, 20)
    assert validate(good) is good  # at the MAC050–141's rate
    with pytest.raises(RecordError, match="wrong sample rate"):
        validate(good, facts)
    doubled = Record("TESTU", facts.rates["TESTU"], good.input, good.output, good.motor)
    assert validate(doubled, facts) is doubled
    with pytest.raises(RecordError, match="names no motor type"):
        validate(Record("TESTU", good.rate_hz, good.input, good.output))
    assert np.all(np.abs(good.output) < facts.adc_full)


def test_jvl_tune_defaults_refuses_a_family_without_test_modes(tmp_path: Path) -> None:
    from tuning.cli import app
    from typer.testing import CliRunner

    for key, needle in (("mac800", "TEST_MODES"), ("no_such_family", "unknown motor family")):
        res = CliRunner().invoke(app, ["defaults", "--family", key, "--out", str(tmp_path / key)])
        assert res.exit_code != 0 and needle in res.output, res.output
        assert not (tmp_path / key).exists()
