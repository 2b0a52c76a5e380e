"""Motor configs and setups are validated on load with clear errors."""

from __future__ import annotations

import pytest
import yaml

from jvl_gym import MotorArray
from jvl_gym.families.config import ConfigError
from jvl_gym.families.mac050_141.config import MOTORS_DIR, load_motor, load_setup, motor_types
from jvl_gym.registers import RegisterError


def test_all_motor_types_load_with_provenance():
    assert motor_types() == ["MAC050", "MAC095", "MAC140", "MAC141"]
    for name in motor_types():
        cfg = load_motor(name)
        assert "representative" in cfg.provenance.lower() or "docs/model.md" in cfg.provenance
        # peak torque of the data sheet row and of the electrical model agree within 1 %
        assert cfg.torque_per_vf * 1023 == pytest.approx(cfg.peak_torque, rel=0.01)


def _write(tmp_path, data, name="bad.yaml"):
    path = tmp_path / name
    path.write_text(data if isinstance(data, str) else yaml.safe_dump(data))
    return path


def test_malformed_motor_configs_raise_config_error(tmp_path):
    good = yaml.safe_load((MOTORS_DIR / "MAC140.yaml").read_text())
    with pytest.raises(ConfigError, match="not found"):
        load_motor(tmp_path / "missing.yaml")
    with pytest.raises(ConfigError, match="YAML"):
        load_motor(_write(tmp_path, "name: [unclosed"))
    with pytest.raises(ConfigError, match="rotor_inertia"):
        load_motor(_write(tmp_path, {**good, "rotor_inertia": -1.0}))
    with pytest.raises(ConfigError, match="colour: Extra inputs"):
        load_motor(_write(tmp_path, {**good, "colour": "blue"}))
    with pytest.raises(ConfigError, match="pwm_delay_samples"):
        load_motor(_write(tmp_path, {**good, "pwm_delay_samples": 3}))
    with pytest.raises(ConfigError, match="mapping"):
        load_motor(_write(tmp_path, "- 1\n- 2\n"))


def test_malformed_setups_raise_and_unknown_registers_are_named(tmp_path):
    with pytest.raises(ConfigError, match="finite"):
        load_setup({"KVOUT": float("nan")})
    with pytest.raises(ConfigError):
        load_setup({"registers": {"KVOUT": "fast"}})
    m = MotorArray("MAC140", n=1)
    before = m.regs.copy()
    with pytest.raises(RegisterError, match="KVOUTT"):
        m.load_setup({"KVOUT": 2.0, "KVOUTT": 3.0})
    with pytest.raises(RegisterError, match="T_SOLL"):
        m.load_setup({"KVOUT": 2.0, "T_SOLL": 99999})
    assert (m.regs == before).all()  # validated as a whole: nothing was written
    m.load_setup({"KVOUT": 2.0})
    assert m.read("KVOUT")[0] == 2.0
    with pytest.raises(ConfigError):
        MotorArray(_write(tmp_path, "name: X\n"), n=1)
