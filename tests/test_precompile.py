"""``jvl-gym compile``'s plan and scheduler (:mod:`jvl_gym.precompile`): units per family and
environment, environments after their family, expected times from the last measured run."""

from __future__ import annotations

import functools
import json

import pytest

from jvl_gym.cli import precompile
from jvl_gym.cli.precompile import Unit
from jvl_gym.envs.registration import ENV_IDS
from jvl_gym.families import families, family_of_motor
from jvl_gym.families.config import ConfigError


def test_motor_units_every_family_by_default() -> None:
    units = precompile.motor_units()
    assert sorted(u.family for u in units) == sorted(families())
    assert all(u.kind == "motors" and not u.after for u in units)


def test_motor_units_only_the_families_of_the_types_given() -> None:
    units = precompile.motor_units(["mac140", "MAC141"])
    assert [(u.family, u.motor_type) for u in units] == [(family_of_motor("MAC140").key,
                                                          "MAC140")]


def test_motor_units_refuse_an_unknown_type() -> None:
    with pytest.raises(ConfigError, match="MAC14O"):
        precompile.motor_units(["MAC14O"])


def test_env_units_come_after_their_family() -> None:
    motors = precompile.motor_units()
    by_family = {u.family: u.name for u in motors}
    units = precompile.env_units(ENV_IDS, motors)
    assert {u.env_id for u in units} == set(ENV_IDS)
    assert all(u.after == (by_family[u.family],) for u in units)
    for u in units:  # a further family's unit runs that family's default type
        if u.motor_type is not None:
            assert family_of_motor(u.motor_type).key == u.family


def test_scheduler_order_progress_and_expected_times(tmp_path, monkeypatch) -> None:
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    (tmp_path / "jvl_gym.compile-times.json").write_text(json.dumps({"m1": 42.0}))
    units = [Unit("m1", "motors", "f1", "T1"), Unit("m2", "motors", "f2", "T2"),
             Unit("e1", "env", "f1", None, "E", ("m1",)),
             Unit("e2", "env", "f2", "T2", "E", ("m2",))]
    lines: list[str] = []
    # the work of each unit returns at once and says it took these seconds
    took = {"m1": 1.0, "m2": 30.0, "e1": 1.0, "e2": 1.0}
    run = functools.partial(precompile.expected_seconds, measured=took)
    times = precompile.compile_units(units, workers=2, say=lines.append, run=run)
    assert times == took
    assert any("m1: compiling, expected 42 s" in ln for ln in lines)
    assert any("e1: compiling, expected 20 s" in ln for ln in lines)
    for env, motors in (("e1", "m1"), ("e2", "m2")):
        start = next(k for k, ln in enumerate(lines) if f"{env}: compiling" in ln)
        done = next(k for k, ln in enumerate(lines) if ln.startswith(f"{motors}: done"))
        assert done < start
    # a unit that compiled leaves its time; one that loaded its code from the cache keeps the
    # time of its last compile; one with neither is not listed
    assert json.loads((tmp_path / "jvl_gym.compile-times.json").read_text()) == {
        "m1": 42.0, "m2": 30.0}
