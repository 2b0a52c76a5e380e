"""Tuning toolkit on the MAC800 family: identification from sample-buffer torque
steps, the sixth-order main filter, its quantisation to Fixed16/Fixed24, the acceptance move,
and ``jvl-tune autotune/verify --motor MAC800``."""

from __future__ import annotations

import math

import numpy as np
import pytest
import yaml
from tuning.cli import app
from tuning.design_sixth_order import (
    check_sixth_order,
    design_current_filter,
    main_filter_registers,
    quantize_sixth_order,
    synthesize_sixth_order,
    verify_sixth_order,
)
from tuning.family import tuned_family, tuning_spec
from tuning.models import (
    MotorData,
    ff_tf,
    freqresp,
    rigid_speed_plant,
    speed_plant,
    vb_tf,
    vf_tf,
)
from tuning.pipeline import DEFAULT_NAME, autotune
from tuning.quantize import QuantizationError
from tuning.sixth_order import FAMILY, TS_I, TS_O, VFX_KEYS, VFY_KEYS, default_registers
from tuning.strategies.buffer_sixth_order import MOVE_DISTANCE, MOVE_V_SOLL
from tuning.strategy import strategy_of
from tuning.verify import position_move
from typer.testing import CliRunner

from jvl_gym import MotorArray
from jvl_gym.families import Capability
from jvl_gym.families.mac800.table import TABLE
from jvl_gym.registers import from_raw, to_raw

J_M = 1.2e-4  #: rotor inertia of the representative MAC800 (configs/motors/MAC800.yaml)


def test_the_family_comes_from_the_motor_type():
    f = tuning_spec("MAC800")
    fam = tuned_family("MAC800")
    assert fam.key == "mac800" and f.filter_order == 6
    assert not fam.supports(Capability.TEST_MODES) and f.strategy == "buffer_sixth_order"
    assert type(strategy_of("MAC800")).__name__ == "BufferSixthOrderStrategy"
    assert f.outer_dt == pytest.approx(1 / 770) and f.inner_dt == pytest.approx(1 / 11550)
    assert f.counts_per_rev == 8000 and fam.table.lookup("KVFX6").format.value == "Fixed16"
    assert (TS_O, TS_I) == (f.outer_dt, f.inner_dt)
    g = tuning_spec("MAC140")
    assert g.strategy == "testu_pi" and g.filter_order == 4 and g.counts_per_rev == 4096
    assert tuned_family("MAC140").supports(Capability.TEST_MODES)
    with pytest.raises(ValueError, match="no tuning procedure"):
        tuning_spec("MIS231")


def test_one_motor_data_carries_each_familys_numbers():
    md = MotorData.from_config("MAC800")
    assert md.family is FAMILY and md.family is tuned_family("MAC800").tuning
    assert md.amplitude == 776.0 and md.supply_voltage == 325.0  # setup AMPLITUDE, mains bus
    k_t = 1.5 * md.pole_pairs * md.flux_linkage
    assert md.torque_per_vf == pytest.approx(k_t * md.amps_per_count * 776.0 / 1023, rel=1e-15)
    assert md.coil_pole == pytest.approx(np.exp(-md.R_phase / 11550 / md.L_phase), rel=1e-15)
    assert md.volts_per_count == pytest.approx(325.0 / 2 / 1023)
    small = MotorData.from_config("MAC140")
    assert small.family.strategy == "testu_pi" and small.amplitude == 0.83
    assert small.torque_per_vf == 1.5 * small.pole_pairs * small.flux_linkage * \
        small.amps_per_count * 0.83
    assert small.coil_pole == math.exp(-small.R_phase * 128e-6 / small.L_phase)
    with pytest.raises(ValueError, match="no tuning procedure"):
        MotorData.from_config("MIS231")


def test_the_filters_take_the_familys_taps_and_gains():
    regs = default_registers("MAC800")
    regs.update({"KVB4": 1.0, "KVB3": 0.25, "KFF5": 1.0, "KFF0": 0.5, "MODEL_POT": 2.0,
                 "KVOUT": 3.0})
    ff, vb, vf = ff_tf(regs, FAMILY), vb_tf(regs, FAMILY), vf_tf(regs, family=FAMILY)
    assert ff.dt == TS_O and len(ff.num[0][0]) == 6 and ff.num[0][0][-1] == 0.5
    assert list(vb.num[0][0][:2]) == [16.0, 4.0]  # the firmware's 16·V_IST, no GEARB
    assert len(vf.den[0][0]) == 7  # sixth order
    assert vf.num[0][0][0] == 3.0 / 4.0 * regs["KVFX6"]  # KVOUT / 2^MODEL_POT
    with pytest.raises(KeyError, match="KFF5"):
        ff_tf({"KFF3": 1.0}, FAMILY)


def test_the_lifted_speed_plant_meets_the_rigid_rotor_at_low_frequency():
    md = MotorData.from_config("MAC800")
    plant = speed_plant(md, default_registers("MAC800"))
    assert plant.dt == TS_O
    w = np.array([2 * np.pi * 0.5, 2 * np.pi * 2.0])
    ratio = freqresp(plant, w) / freqresp(rigid_speed_plant(md), w)
    assert np.allclose(ratio, 1.0, atol=0.02)


def test_autotune_of_two_loaded_mac800s_meets_the_acceptance():
    # load ratios 3 and 7 (J = 4 and 8 x J_m); the second with Coulomb friction, which holds
    # the default setup's loop (KVOUT = 1) outside the in-position window
    loads = np.array([3.0, 7.0]) * J_M
    kw = dict(load_inertia=loads, coulomb_friction=np.array([0.0, 0.05]),
              viscous_friction=np.array([2e-4, 0.0]))
    m = MotorArray("MAC800", n=2, seed=0, position_noise=0.85, **kw)
    res = autotune(m, strategy_of("MAC800"))
    for i, r in enumerate(res):
        j_true = J_M + loads[i]
        assert abs(r.ident.mechanics.J / j_true - 1) < 0.05
        assert r.ident.mechanics.ci_J[0] < r.ident.mechanics.J < r.ident.mechanics.ci_J[1]
        assert abs(r.ident.coil.R_phase / 2.9 - 1) < 0.1
        assert abs(r.ident.coil.L_phase / 8.7e-3 - 1) < 0.05 and r.ident.coil.delay == 1
        assert r.chosen.name != DEFAULT_NAME and "settles in" in r.reason
        d = r.chosen.design
        # stable after quantisation with PM >= 45 deg, on the identified and the true motor
        assert check_sixth_order(d.verification) == []
        assert d.verification.speed.pm_deg >= 45 and d.verification.all_stable
        true = verify_sixth_order(MotorData.from_config("MAC800"), d.registers, j_true)
        assert true.speed.pm_deg >= 45 and true.current.pm_deg >= 45 and true.all_stable
        # the 20 000-count move on the true motor: faster than the default setup
        sim = MotorArray("MAC800", n=2, seed=1, position_noise=0.85,
                         **{k: v[i] for k, v in kw.items()})
        sim.load_setup({"registers": r.chosen.registers}, index=[0])
        mv = position_move(sim, MOVE_DISTANCE, MOVE_V_SOLL, r.move.a_soll, seconds=2.0, dt=TS_O)
        assert np.isfinite(mv.settle_s[0]) and mv.settle_s[0] < mv.settle_s[1]
        assert mv.errors[0] == 0
    assert res[1].settle_s[DEFAULT_NAME] == np.inf  # friction: the default never settles


def test_quantisation_round_trip_to_the_exact_fixed16_and_fixed24_raw_values():
    md = MotorData.from_config("MAC800")
    d = synthesize_sixth_order(md, 5 * J_M, notch_hz=120.0)
    q, ideal = d.registers, d.ideal
    raws = {}
    for name, value in q.items():
        reg = TABLE.lookup(name)
        raw = int(to_raw(reg, value))
        raws[name] = raw
        assert from_raw(reg, raw) == value  # exactly representable
        if reg.format.value in ("Fixed16", "Fixed24"):
            assert abs(raw - ideal[name] * reg.scale) <= 1.0  # rounded to the nearest raw
    assert TABLE.lookup("KVFX6").scale == 2**16 and TABLE.lookup("KVB4").scale == 2**24
    # the integrator's pole stays at z = 1: the stored KVFY sum to exactly 1 (65536 raw)
    assert sum(raws[k] for k in VFY_KEYS) == 2**16
    assert raws["KIFY1"] + raws["KIFY0"] == 2**16
    # PI, low-pass and notch: 4 numerator taps, 5 denominator taps (fifth order)
    assert raws["KVFX3"] != 0 and raws["KVFX2"] == 0
    assert raws["KVFY1"] != 0 and raws["KVFY0"] == 0
    # the motor stores the same raw values
    m = MotorArray("MAC800", n=1)
    m.load_setup({"registers": q})
    for name, value in q.items():
        assert float(m.read(name)[0]) == value
    assert check_sixth_order(d.verification) == []
    assert d.verification.ideal_speed is not None


def test_quantisation_refuses_values_outside_the_table_ranges():
    with pytest.raises(QuantizationError, match="KVB4.*Fixed24"):
        quantize_sixth_order({"KVB4": 200.0})
    with pytest.raises(QuantizationError, match="KVFX6.*Fixed16"):
        quantize_sixth_order({"KVFX6": 40000.0})
    with pytest.raises(ValueError, match="not in"):
        main_filter_registers(0.01, 0.001, 4.0, f_lp=500.0)


def test_lowpass_takes_the_speed_noise_down_at_nyquist():
    md = MotorData.from_config("MAC800")
    cur = design_current_filter(md)
    lp = synthesize_sixth_order(md, 4 * J_M, cur, lowpass=True)
    pi = synthesize_sixth_order(md, 4 * J_M, cur, lowpass=False)

    def nyquist_gain(regs):
        num = sum(regs[k] * (-1) ** n for n, k in enumerate(VFX_KEYS))
        den = 1 - sum(regs[k] * (-1) ** (n + 1) for n, k in enumerate(VFY_KEYS))
        return abs(num / den) * regs["KVOUT"] * 2.0 ** -regs["MODEL_POT"]

    assert nyquist_gain(lp.registers) < 0.6 * nyquist_gain(pi.registers)
    assert lp.f_lp and lp.f_lp < 0.5 / TS_O
    assert sum(1 for k in VFY_KEYS if lp.registers[k] != 0) == 3  # integrator + 2 poles


def test_cli_autotune_mac800_writes_a_setup_the_family_loads(tmp_path):
    res = CliRunner().invoke(app, ["autotune", "--motor", "MAC800", "--load-inertia", "6e-4",
                                   "--out", str(tmp_path)])
    assert res.exit_code == 0, res.output
    setup = tmp_path / "setup.yaml"
    data = yaml.safe_load(setup.read_text())
    assert data["motor"] == "MAC800"
    assert abs(data["registers"]["KVOUT"] - 6.0) < 0.3
    assert data["registers"]["S_ORDER"] == 6
    m = MotorArray("MAC800", n=1, setup=setup)
    assert float(m.read("KVOUT")[0]) == data["registers"]["KVOUT"]
    report = (tmp_path / "report.txt").read_text()
    assert "Acceptance step" in report and "default setup" in report
    res = CliRunner().invoke(app, ["verify", "--setup", str(setup)])
    assert res.exit_code == 0, res.output
    assert "all stable True" in res.output
    res = CliRunner().invoke(app, ["autotune", "--motor", "MAC800", "--port", "loop://",
                                   "--out", str(tmp_path)])
    assert res.exit_code != 0 and "not available for the MAC800" in res.output


def test_cli_synthesize_mac800_and_refusals(tmp_path):
    out = tmp_path / "s.yaml"
    res = CliRunner().invoke(app, ["synthesize", "--motor", "MAC400", "--inertia", "3e-4",
                                   "--out", str(out)])
    assert res.exit_code == 0, res.output
    assert "pi + low-pass" in res.output
    regs = yaml.safe_load(out.read_text())["registers"]
    assert regs["KVOUT"] == pytest.approx(5.0, abs=1e-4)  # 3e-4 / J_m 6e-5 (MAC400.yaml)
    MotorArray("MAC400", n=1, setup=out)
    res = CliRunner().invoke(app, ["verify", "--setup", str(out), "--inertia", "3e-4"])
    assert res.exit_code == 0 and "all stable True" in res.output
    res = CliRunner().invoke(app, ["identify", "--motor", "MAC800", "--testu", str(out)])
    assert res.exit_code != 0 and "no TESTU/TESTA" in res.output


def test_default_filters_are_the_family_setup():
    regs = default_registers("MAC800")
    # the I-P arrangement of configs/setups/MAC800.yaml: ki in VF, kp/ki in VB
    assert regs["KVFX6"] == pytest.approx(0.015 / 2.004, rel=2e-3) and regs["KVFY5"] == 1.0
    assert regs["KVB3"] == pytest.approx(-0.2 / 0.015) and regs["KVB4"] + regs["KVB3"] == 1.0
    assert regs["S_ORDER"] == 6  # the table's default: the full order
