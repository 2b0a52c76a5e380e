"""The MAC800 plant and current loop: energy balance, current tracking, torque, the DC bus."""

from __future__ import annotations

import numpy as np
import pytest

from jvl_gym import MotorArray
from jvl_gym.families.mac800 import units as u


def test_energy_balance_in_a_regulated_run() -> None:
    """Electrical energy into the windings = copper loss + friction + load work + kinetic
    energy gained + the windings' magnetic energy (all from the plant's accounts)."""
    m = MotorArray("MAC800", n=1, seed=0, viscous_friction=1e-3, coulomb_friction=0.05,
                   load_inertia=2e-4)
    m.write_many({"V_SOLL": round(u.rpm_to_v_soll(1500)), "MODE_REG": 1})
    m.set_input(load_torque=1.0)
    m.run(0.6)
    e = m.energy
    cfg = m.motor_configs[0]
    i2 = m.state[0, 3] ** 2 + m.state[0, 4] ** 2
    magnetic = 0.75 * cfg.phase_inductance * i2
    out = e["copper"] + e["friction"] + e["load"] + e["kinetic"] + magnetic
    assert e["electrical"][0] == pytest.approx(out[0], rel=2e-3)


@pytest.mark.statements("mac800:reg7:3", "mac800:reg169:1")
def test_current_loop_follows_its_reference_and_gives_the_torque() -> None:
    """Holding against 3 N·m: the phase currents reach their references, the torque the load."""
    m = MotorArray("MAC800", n=1, seed=0)
    m.write_many({"V_SOLL": 0, "MODE_REG": 1})
    m.set_input(load_torque=3.0)
    m.run(0.5)
    assert m.torque[0] == pytest.approx(3.0, rel=0.02)
    for k in range(3):
        soll = m.read(("IA_SOLL", "IB_SOLL", "IC_SOLL")[k])[0]
        ist = m.read(("IA_IST", "IB_IST", "IC_IST")[k])[0]
        assert abs(soll - ist) <= 3
    vf = m.read("VF_OUT")[0]
    assert vf == pytest.approx(3.0 / m.motor_configs[0].peak_torque * 1023, rel=0.03)


def test_braking_charges_the_bus_and_the_dump_holds_it() -> None:
    m = MotorArray("MAC800", n=1, seed=0, load_inertia=2e-3)
    m.write_many({"V_SOLL": round(u.rpm_to_v_soll(2500)), "A_SOLL": 40, "MODE_REG": 1})
    m.run(2.0)
    m.write_many({"V_SOLL": 0, "A_SOLL": 360})
    ubus = m.trace(["bus_voltage"], 800)["bus_voltage"][:, 0]
    assert ubus.max() > 380.0 and ubus.max() < 420.0  # the dump switches on above 390 V
    assert m.energy["dump"][0] > 0.0
    m.run(2.0)
    assert abs(m.speed_rpm[0]) < 5.0


@pytest.mark.statements("mac800:reg2:2")
def test_passive_turns_freely() -> None:
    m = MotorArray("MAC800", n=1, seed=0, initial_speed=100.0)
    m.run(0.2)
    assert m.speed_rad_s[0] == 100.0 and m.torque[0] == 0.0
    assert np.all(m.read("VF_OUT") == 0)
