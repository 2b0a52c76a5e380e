"""P_IST after power-up (MIS manual §5.4.3, SETUP_BITS bits 10 and 11 of §8.2.68) and the
position preset of user command 354 (§8.2.22)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from jvl_gym import MotorArray
from jvl_gym.families.mis import constants as c
from jvl_gym.families.mis import layout as L

REV = 409600
SINGLE, MULTI = 1 << 10, 1 << 11  #: SETUP_BITS: single-turn, multi-turn position to P_IST


def _rad(turns: float) -> float:
    return turns * 2.0 * math.pi


@pytest.mark.statements("mis:8.2.68:7", "mis:5.4.3:1")
def test_single_turn_position_at_power_up() -> None:
    """§5.4.3: "Absolute Singleturn Encoder": with an H2 or H4 the single-revolution position
    (0 … 409599) is P_IST after power-up; without an encoder and with an H3 it is 0; without
    the bit it is 0 with any encoder."""
    codes = np.array([0, 1, 2, 3, 4])
    for bits, want in ((SINGLE, [0, REV // 4, 0, REV // 4, REV // 4]), (0, [0] * 5)):
        m = MotorArray(["MIS232"] * 5, n=5, seed=0, setup={"SETUP_BITS": bits},
                       encoder_type=codes, initial_angle=_rad(2.25))  # 2¼ turns from zero
        assert m.read("P_IST").tolist() == want
        assert m.read("P_SOLL").tolist() == want  # no move at power-up
        m.step(2)
        assert m.read("P_IST").tolist() == want
        assert m.read("ENCODER_POS")[1:].tolist() == want[1:]
        assert m.read("FLWERR").tolist() == [0] * 5


@pytest.mark.statements("mis:8.2.68:8", "mis:5.4.2:1", "mis:5.4.3:1")
def test_multi_turn_position_at_power_up() -> None:
    """§5.4.2–5.4.3: "Absolute Multiturn Encoder": without an encoder the last stored position;
    with an H2 the last stored position corrected by the single-turn encoder for a turn of up
    to half a revolution while the power was off; with an H3 the full multi-turn position. A
    position of several turns survives a reset (user command 267) and a power cycle."""
    codes = np.array([0, 3, 2])
    m = MotorArray(["MIS232"] * 3, n=3, seed=0, setup={"SETUP_BITS": MULTI},
                   encoder_type=codes)
    m.write_many({"V_SOLL": 60000, "A_SOLL": 20000, "IN_POSITION_COUNT": 0,
                  "MODE_REG": c.POSITION})
    m.write("P_SOLL", 3 * REV + 1000)
    m.step(1500)
    assert m.read("P_IST").tolist() == [3 * REV + 1000] * 3
    m.write("MODE_REG", c.PASSIVE)
    m.step(50)
    m.write("COMMAND", c.CMD_RESET, index=[0, 1, 2])
    m.step(1)
    p = m.read("P_IST")
    assert p[0] == 3 * REV + 1000  # the stored position
    assert p[1] % REV == m.read("ABSENCODER")[1] and abs(p[1] - (3 * REV + 1000)) < 2048
    assert p[2] == m.read("ABSENCODER")[2] and abs(p[2] - (3 * REV + 1000)) < 2048
    assert (m.read("ENCODER_POS")[1:] == p[1:]).all()
    before = p.copy()
    # a power cycle during which the shaft was turned by a third of a revolution
    m.reset(encoder_type=codes, initial_angle=m.state[:, L.S_THETA] + _rad(1 / 3))
    m.step(1)
    p = m.read("P_IST")
    assert p[0] == before[0]  # no encoder: the stored value as it was
    assert p[1] % REV == m.read("ABSENCODER")[1]
    assert abs(p[1] - (before[1] + REV / 3)) < 2 * REV / 4096
    assert p[2] == m.read("ABSENCODER")[2]


@pytest.mark.statements("mis:8.2.22:13")
def test_command_354_presets_encoder_p_ist_and_p_soll() -> None:
    """§8.2.22: 354 presets the H2/H3/H4 encoder, P_IST and P_SOLL with P_NEW; the follow
    error stays 0."""
    m = MotorArray("MIS232", n=1, seed=0)
    m.write_many({"MODE_REG": c.POSITION, "FLWERRMAX": 100})
    m.step(10)
    m.write_many({"P_NEW": 123456, "COMMAND": 354})
    assert m.read("P_IST")[0] == m.read("P_SOLL")[0] == m.read("ENCODER_POS")[0] == 123456
    m.step(50)
    assert m.read("ERR_BITS")[0] == 0 and abs(m.read("FLWERR")[0]) <= 100
    assert m.read("COMMAND")[0] == 0


def test_a_refused_reset_changes_nothing_the_position_backup_neither() -> None:
    """A reset refused for an encoder_type that is no ENCODER_TYPE code (§8.2.49) leaves every
    motor as it was: registers, state, parameters, inputs and the position back-up that a
    power-up with SETUP_BITS bit 11 restores (§5.4.2)."""
    m = MotorArray("MIS232", n=3, seed=0, setup={"SETUP_BITS": MULTI}, encoder_type=0)
    m.write_many({"V_SOLL": 60000, "A_SOLL": 20000, "MODE_REG": c.POSITION})
    m.write("P_SOLL", REV // 2)
    m.step(200)
    before = [a.copy() for a in (m.regs, m.state, m.params, m.inputs, m._position_backup)]
    with pytest.raises(ValueError, match="encoder_type"):
        m.reset(index=[0, 2], encoder_type=[1, 1.5])
    after = (m.regs, m.state, m.params, m.inputs, m._position_backup)
    assert all(np.array_equal(a, b) for a, b in zip(before, after))


def test_a_refused_reset_to_another_motor_type_keeps_the_motors_types() -> None:
    """A reset that names new motor types and is refused for its encoder_type leaves the
    motors of their old types (the type pool may have learnt the new type; no motor is of it)."""
    m = MotorArray("MIS232", n=3, seed=0)
    m.step(5)
    before = [a.copy() for a in (m.regs, m.state, m.params, m._type_of)]
    with pytest.raises(ValueError, match="encoder_type"):
        m.reset(index=[0, 2], motor_type="MIS171", encoder_type=1.5)
    after = (m.regs, m.state, m.params, m._type_of)
    assert all(np.array_equal(a, b) for a, b in zip(before, after))
    assert [cfg.name for cfg in m.motor_configs] == ["MIS232"] * 3
