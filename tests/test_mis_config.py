"""MIS motor configs: every type loads and is stable; a bad file names the file and the field
and loads nothing."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from jvl_gym import MotorArray
from jvl_gym.families import family_of_motor
from jvl_gym.families.config import ConfigError
from jvl_gym.families.mis.config import MOTORS_DIR, load_motor, motor_types
from jvl_gym.families.mis.units import MOTOR_TYPE_CODES


@pytest.mark.statements("mis:8.2.89:2")
def test_every_type_loads_runs_and_names_its_motor_type_code() -> None:
    types = motor_types()
    assert {"MIS171", "MIS176", "MIS231", "MIS232", "MIS234", "MIS340", "MIS343", "MIS432",
            "SMC66", "SMC85"} <= set(types)
    m = MotorArray(types, n=len(types), seed=0)
    assert m.read("MOTORTYPE").tolist() == [MOTOR_TYPE_CODES[t] for t in types]
    m.write_many({"V_SOLL": 30000, "A_SOLL": 3000, "MODE_REG": 1})
    m.run(0.5)
    assert m.lost_steps.tolist() == [0] * len(types)
    for t in types:
        assert family_of_motor(t).key == "mis"
        assert "§" in load_motor(t).provenance or "chosen" in load_motor(t).provenance


@pytest.mark.parametrize("field,value,match", [
    ("holding_torque", "strong", "holding_torque"),
    ("rotor_inertia", 1e-7, "rotor_inertia"),
    ("phase_resistance", float("nan"), "phase_resistance"),
    ("encoder_type", 9, "encoder_type"),
    ("surprise", 1, "surprise"),
    ("rotor_inertia", 1.5e-6, "unstable"),
])
def test_bad_configs_name_file_and_field(tmp_path: Path, field: str, value: object,
                                         match: str) -> None:
    data = yaml.safe_load((MOTORS_DIR / "MIS232.yaml").read_text())
    data[field] = value
    path = tmp_path / "BAD.yaml"
    path.write_text(yaml.safe_dump(data))
    with pytest.raises(ConfigError, match=match) as err:
        load_motor(path)
    assert "BAD.yaml" in str(err.value)


def test_unknown_type_is_refused() -> None:
    with pytest.raises(ConfigError, match="MIS999"):
        load_motor("MIS999")
