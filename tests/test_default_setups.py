"""The default register sets give stable, well-damped control for KVOUT 1–10."""

from __future__ import annotations

import numpy as np
import pytest

from jvl_gym import MotorArray
from jvl_gym.families.mac050_141 import constants as c
from jvl_gym.families.mac050_141.config import load_setup, motor_types

RATIOS = np.array([1.0, 2.0, 5.0, 10.0])


@pytest.mark.parametrize("motor", motor_types())
@pytest.mark.statements("mac050_141:3.2.13:5")
def test_velocity_step_and_position_move_for_kvout_1_to_10(motor):
    m = MotorArray(motor, n=RATIOS.size, seed=0)
    jm = m.motor_configs[0].rotor_inertia
    m.reset(load_inertia=(RATIOS - 1) * jm)
    m.write("KVOUT", RATIOS)  # KVOUT = (J_m + J_l)/J_m, manual 3.2.13
    m.write("A_SOLL", 1000)
    m.write("V_SOLL", 1000)  # a step of 62.5 counts/sample
    m.write("MODE_REG", c.V_MODE)
    v = []
    for _ in range(300):
        m.step()
        v.append(m.read("V_IST").copy())
    v = np.asarray(v, dtype=float)
    assert np.all(v.max(axis=0) < 1.3 * 62.5)  # overshoot of a PI velocity loop, PM ≈ 54°
    assert np.all(np.abs(v[200:].mean(axis=0) - 62.5) < 0.5)  # no steady-state error
    assert np.all(v[200:].std(axis=0) <= 1.0)  # no limit cycle beyond the 1-count quantisation

    m = MotorArray(motor, n=RATIOS.size, seed=0)
    m.reset(load_inertia=(RATIOS - 1) * jm)
    m.write("KVOUT", RATIOS)
    m.write("A_SOLL", 50)
    m.write("V_SOLL", 2000)
    m.write("P_SOLL", 20000)
    m.write("MODE_REG", c.P_MODE)
    p = []
    for _ in range(800):
        m.step()
        p.append(m.read("P_IST").copy())
    p = np.asarray(p, dtype=float)
    assert np.all(p.max(axis=0) - 20000 < 0.01 * 20000)
    assert np.all(np.abs(p[-100:] - 20000) < 10)
    assert np.all(m.read("ERR_STAT") & c.IN_POS)
    assert np.all(m.read("FNCERR") == 0)


def test_setups_are_valid_register_sets():
    for motor in motor_types():
        regs = load_setup(motor).registers
        assert regs["KVFY3"] == 1.0 and regs["KIFY1"] == 1.0  # integrators exact
        m = MotorArray(motor, n=1)
        for name, value in regs.items():
            assert m.read(name)[0] == pytest.approx(value, abs=0.5 / 256)  # Fixed8 resolution
