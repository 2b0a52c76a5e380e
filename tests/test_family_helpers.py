"""The generic helpers a family folder states its facts with: named bits, linear register units,
register numbers by name, motor-config loading and bounded config fields."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml
from pydantic import BaseModel

from jvl_gym.families import families, family
from jvl_gym.families.config import ConfigError, MotorConfigs, MotorData, Real, bounded_by
from jvl_gym.registers.bits import bit_masks, mask_of
from jvl_gym.registers.scaling import linear_unit


def test_bit_masks_count_from_bit_0_and_skip_unnamed_bits():
    bits = bit_masks("A - B C")
    assert bits == {"A": 1, "B": 4, "C": 8}
    assert mask_of(bits, "A C") == 9
    for bad in ("A A", "A 1B"):
        with pytest.raises(ValueError):
            bit_masks(bad)


def test_err_stat_bits_are_the_constants_and_the_twin_status_bits():
    for key in ("mac050_141", "mac800"):
        fam = family(key)
        bits = fam.constants.ERR_STAT_BITS
        assert list(bits.values()) == sorted(bits.values())
        for name, mask in bits.items():
            assert getattr(fam.constants, name) == mask
        assert fam.twin.status_bits == {mask: name for name, mask in bits.items()}


def test_linear_unit_uses_the_printed_factor_both_ways():
    to_volts, to_units = linear_unit("U_BUS", "DC bus voltage [V]", "register 198",
                                     quantity_per_unit=0.888798)
    assert to_volts(366) == 366 * 0.888798
    assert to_units(325.0) == 325.0 / 0.888798
    to_rpm, to_v = linear_unit("V_SOLL", "velocity [RPM]", "register 5",
                               units_per_quantity=2.77056)
    assert to_rpm(277.056) == 277.056 / 2.77056 and to_v(100.0) == 100.0 * 2.77056
    assert "register 5" in to_rpm.__doc__ and "inverse" in to_v.__doc__
    for kwargs in ({}, {"quantity_per_unit": 1.0, "units_per_quantity": 1.0},
                   {"quantity_per_unit": 0.0}, {"units_per_quantity": float("inf")}):
        with pytest.raises(ValueError):
            linear_unit("R", "q", "s", **kwargs)


@pytest.mark.parametrize("key", families())
def test_firmware_register_constants_are_the_table_numbers(key):
    fam = family(key)
    numbers = fam.table.numbers_by_name()
    assert len(numbers) == len(fam.table)
    for name, number in numbers.items():
        assert fam.table.lookup(name).number == number


class _Bounded(BaseModel):
    low: Real
    high: Real
    _high_above_low = bounded_by("high", "low", strict=True, unit="V", why="reason")


class _AtLeast(BaseModel):
    low: Real
    high: Real
    _high_at_least_low = bounded_by("high", "low")


def test_bounded_by_refuses_a_field_below_its_bound():
    assert _Bounded(low=1.0, high=2.0).high == 2.0
    with pytest.raises(ValueError, match=r"must be above low \(1.0 V\), got 1.0 V: reason"):
        _Bounded(low=1.0, high=1.0)
    assert _AtLeast(low=1.0, high=1.0).high == 1.0
    with pytest.raises(ValueError, match=r"must be >= low \(1.0\), got 0.5"):
        _AtLeast(low=1.0, high=0.5)


class _Toy(MotorData):
    name: str
    mass: Real


def _configs(tmp_path: Path, **kwargs) -> MotorConfigs:
    (tmp_path / "motors").mkdir()
    for name in ("ONE", "TWO"):
        (tmp_path / "motors" / f"{name}.yaml").write_text(yaml.safe_dump(
            {"name": name, "mass": 1.0, "provenance": "a test, not a motor"}))
    return MotorConfigs(_Toy, tmp_path, "toy type", **kwargs)


def test_motor_configs_load_by_name_path_or_config(tmp_path):
    cfgs = _configs(tmp_path, setups=False, canonical=str.upper)
    assert cfgs.motor_types() == ["ONE", "TWO"]
    one = cfgs.load_motor("one")
    assert one.name == "ONE" and cfgs.load_motor(one) is one
    assert cfgs.load_motor(tmp_path / "motors" / "TWO.yaml").name == "TWO"
    assert cfgs.load_motor("one") is not one  # read again: not cached
    with pytest.raises(ConfigError, match="unknown toy type 'THREE'; known: ONE, TWO"):
        cfgs.load_motor("three")
    with pytest.raises(ConfigError, match="a motor is a type name, a config path or a _Toy"):
        cfgs.load_motor(3)
    with pytest.raises(ValueError, match="the toy types have no default setups"):
        cfgs.setup_path("ONE")
    (tmp_path / "motors" / "BAD.yaml").write_text("name: BAD\nmass: 1.0\nprovenance: short\n")
    with pytest.raises(ConfigError, match="provenance"):
        cfgs.load_motor("BAD")


def test_cached_motor_configs_read_a_file_once(tmp_path):
    cfgs = _configs(tmp_path, cached=True)
    assert cfgs.load_motor("ONE") is cfgs.load_motor("ONE")
    assert cfgs.setup_path("S") == tmp_path / "setups" / "S.yaml"
