"""Tuning toolkit: models, synthesis, quantisation and verification."""

from __future__ import annotations

import numpy as np
import pytest
from tuning.autotune import synthesize, verify_design
from tuning.models import (
    MotorData,
    coil_tf,
    freqresp,
    rigid_speed_plant,
    speed_plant,
)
from tuning.quantize import QuantizationError, quantize_registers, quantize_value
from tuning.testmode_facts import record_facts
from tuning.verify import loop_metrics

from jvl_gym.families import family

TYPES = ["MAC050", "MAC095", "MAC140", "MAC141"]
MAC = record_facts(family("mac050_141"))  #: the MAC050–141's TESTU/TESTA facts
TS_O = MAC.ts_o


def test_lifted_speed_plant_tends_to_the_rigid_body_model():
    md = MotorData.from_config("MAC140")
    regs = {"KIFX2": 1.6, "KIFX1": -1.35, "KIFY1": 1.0, "KIFY0": 0.0, "KIB1": 1.0, "KIB0": 0.0}
    w = np.array([0.5, 2.0, 10.0])
    exact = freqresp(speed_plant(md, regs), w)
    rigid = freqresp(rigid_speed_plant(md), w)
    np.testing.assert_allclose(np.abs(exact), np.abs(rigid), rtol=2e-3)
    assert speed_plant(md, regs).dt == pytest.approx(TS_O)
    # the velocity plant keeps one integrator only (no spurious pole at z = 1 left over)
    assert np.sum(np.abs(speed_plant(md, regs).poles() - 1.0) < 1e-6) == 1


def test_coil_model_steady_state_gain_is_g():
    md = MotorData.from_config("MAC140")
    assert float(np.real(freqresp(coil_tf(md), np.array([1e-3]))[0])) == pytest.approx(
        md.coil_gain, rel=1e-6)


@pytest.mark.parametrize("motor", TYPES)
@pytest.mark.parametrize("ratio", [1.0, 6.0])
def test_designed_loops_meet_margins_robustness_and_quantisation(motor, ratio):
    md = MotorData.from_config(motor)
    d = synthesize(md, ratio * md.J_m)
    c, s = d.current_report.nominal, d.speed_report.nominal
    assert c.pm_deg >= 45 and c.gm_db >= 6
    assert s.pm_deg >= 45 and s.gm_db >= 8
    assert c.pole_radius < 0.999 and s.pole_radius < 0.999
    assert d.current_report.all_stable and d.speed_report.all_stable
    assert min(d.current_report.worst_robust_pm, d.speed_report.worst_robust_pm) >= 30
    assert abs(d.quantization_delta["current_pm_deg"]) <= 2
    assert abs(d.quantization_delta["speed_pm_deg"]) <= 2
    assert abs(d.quantization_delta["current_gm_db"]) <= 1
    assert abs(d.quantization_delta["speed_gm_db"]) <= 1
    assert verify_design(d) == []
    assert d.registers["KVOUT"] == pytest.approx(ratio, abs=1 / 256)
    assert d.registers["KIFY1"] + d.registers["KIFY0"] == 1.0  # integrator exact
    assert d.speed_report.step_overshoot < 0.02  # I-P: no step overshoot


def test_pole_radius_decides_stability_not_margins():
    md = MotorData.from_config("MAC140")
    d = synthesize(md, md.J_m, structure="pi")
    regs = dict(d.registers)
    regs["KVOUT"] = 6.0  # a loop gain six times too high: unstable
    from tuning.models import speed_open_loop

    m = loop_metrics(speed_open_loop(speed_plant(md, regs), regs, md.family))
    assert not m.stable and m.pole_radius > 1.0


def test_quantisation_range_errors_and_exact_sums():
    with pytest.raises(QuantizationError, match="KVFX4"):
        quantize_value("KVFX4", 9.0, MAC.table)
    with pytest.raises(QuantizationError, match="KFF3"):
        quantize_value("KFF3", 200.0, MAC.table)
    q = quantize_registers({"KVFX4": 0.123456, "KVFX3": -0.1, "KVFX2": 0.0, "KVFX1": 0.0,
                            "KVFY3": 0.3333333, "KVFY2": 0.3333333, "KVFY1": 0.3333334,
                            "KVFY0": 0.0, "KVOUT": 3.9}, MAC.table)
    assert q["KVFY3"] + q["KVFY2"] + q["KVFY1"] + q["KVFY0"] == 1.0
    assert round((q["KVFX4"] + q["KVFX3"]) * 4096) == round(0.023456 * 4096)
    assert q["KVOUT"] * 256 == round(3.9 * 256)


@pytest.mark.parametrize("motor", TYPES)
def test_default_setups_are_the_toolkit_output(motor):
    from tuning.defaults import render_setup

    from jvl_gym.families.mac050_141.config import SETUPS_DIR

    assert (SETUPS_DIR / f"{motor}.yaml").read_text() == render_setup(motor)


def test_friction_dead_band_gets_a_position_integral_that_settles_the_move():
    # motor 3 of the benchmark (seed 0): MAC095, load 0.34 J_m, T_c 1.4 % of peak torque. The
    # PI speed loop is a PD position loop: T_c holds it 36 counts off target (window 10).
    from tuning.synthesis import friction_dead_band
    from tuning.verify import position_move

    from jvl_gym import MotorArray

    md = MotorData.from_config("MAC095", amplitude=0.828125)
    J, tc, b = 1.3359 * md.J_m, 0.009546, 5.86e-7
    plain = synthesize(md, J, 0.0, structure="pi")
    fric = synthesize(md, J, tc, structure="pi")
    assert plain.registers["KVFY3"] == 1.0
    ki = plain.speed.ki
    assert friction_dead_band(md, tc, J / md.J_m, ki) > 5
    assert fric.registers["KVFY3"] == 2.0 and fric.registers["KVFY2"] == -1.0
    assert fric.speed.kii > 0
    assert verify_design(fric) == []
    m = MotorArray("MAC095", n=2, seed=1, load_inertia=J - md.J_m, coulomb_friction=tc,
                   viscous_friction=b, current_noise=2.0, position_noise=0.85)
    m.load_setup({"registers": plain.registers}, index=[0])
    m.load_setup({"registers": fric.registers}, index=[1])
    mv = position_move(m, 20000, 2000, 86, seconds=2.0)
    assert mv.settle_s[0] == np.inf  # PI: stuck outside the window
    assert mv.settle_s[1] < 1.0  # with the position integral
    assert np.abs(mv.position[-100:, 1] - mv.position[0, 1] - 20000).max() <= 10
