"""Tuning toolkit: records, coil and mechanics identification."""

from __future__ import annotations

import numpy as np
import pytest
from tuning.identify_coil import identify_coil
from tuning.identify_mechanics import coil_uncertainty, identify_mechanics, two_level_torques
from tuning.models import MotorData
from tuning.records import (
    Record,
    RecordError,
    load_csv,
    save_csv,
    simulate_testa,
    simulate_testu,
    validate,
)
from tuning.testmode_facts import record_facts_of

MD = MotorData.from_config("MAC140")


@pytest.mark.parametrize("delay", [0, 1])
@pytest.mark.parametrize("n", [11, 64])
def test_noiseless_coil_is_exact(delay, n):
    true = MD.with_(pwm_delay=delay)
    est = identify_coil(simulate_testu(true, 100, n, quantize=False), MD)
    assert est.delay == delay
    assert est.R_phase == pytest.approx(MD.R_phase, rel=1e-3)
    assert est.L_phase == pytest.approx(MD.L_phase, rel=1e-3)
    assert est.R_line == pytest.approx(2 * MD.R_phase, rel=1e-3)
    assert est.nrmse_fit > 99.9


def test_realistic_coil_at_the_recommended_length():
    errs, inside = [], []
    for seed in range(40):
        rec = simulate_testu(MD, 100, 64, quantize=True, noise_std=2.0, rng=seed)
        est = identify_coil(rec, MD)
        assert est.delay == 1
        errs.append((est.R_phase / MD.R_phase - 1, est.L_phase / MD.L_phase - 1))
        inside.append((est.ci["R_phase"][0] <= MD.R_phase <= est.ci["R_phase"][1])
                      and (est.ci["L_phase"][0] <= MD.L_phase <= est.ci["L_phase"][1]))
    errs = np.abs(np.array(errs))
    assert errs[:, 0].max() < 0.02 and errs[:, 1].max() < 0.05
    assert np.mean(inside) >= 0.85


def test_noiseless_inertia_one_level_without_friction():
    J = 4.0 * MD.J_m
    rec = simulate_testa(MD, J, 40, 11, quantize=False)
    est = identify_mechanics(rec, MD, coulomb=False, viscous=False)
    assert est.J == pytest.approx(J, rel=1e-6)
    assert est.kvout == pytest.approx(4.0, rel=1e-6)


def test_one_level_cannot_separate_inertia_and_coulomb_friction():
    rec = simulate_testa(MD, MD.J_m, 40, 32)
    with pytest.raises(RecordError, match="two T_SOLL levels"):
        identify_mechanics(rec, MD)


def _random_mechanics(rng: np.random.Generator) -> tuple[float, float, float, int, int]:
    """A random load (J, T_c, b) and its two TESTA levels (raised by the friction torque)."""
    J = MD.J_m * (1 + rng.uniform(0, 10))
    tc, b = rng.uniform(0, 0.02), rng.uniform(0, 1e-5)
    t1, t2 = two_level_torques(J, MD, 64)
    return J, tc, b, t1 + int(tc / MD.torque_per_vf), t2 + int(tc / MD.torque_per_vf)


def test_two_level_procedure_with_friction_and_noise():
    errs = []
    for seed in range(20):
        rng = np.random.default_rng(seed)
        J, tc, b, t1, t2 = _random_mechanics(rng)
        recs = [simulate_testa(MD, J, t, 64, b, tc, position_noise=0.85, rng=rng)
                for t in (t1, t2)]
        est = identify_mechanics(recs, MD)
        errs.append(est.J / J - 1)
    assert np.max(np.abs(errs)) < 0.05


def test_record_validation_errors(tmp_path):
    good = simulate_testu(MD, 100, 20)
    RATES = record_facts_of(MD).rates
    with pytest.raises(RecordError, match="too short"):
        validate(Record("TESTU", RATES["TESTU"], good.input[:5], good.output[:5], MD.name))
    with pytest.raises(RecordError, match="wrong sample rate"):
        validate(Record("TESTU", RATES["TESTA"], good.input, good.output, MD.name))
    with pytest.raises(RecordError, match="saturated"):
        validate(Record("TESTU", RATES["TESTU"], good.input, good.output * 10, MD.name))
    with pytest.raises(RecordError, match="did not move"):
        validate(Record("TESTA", RATES["TESTA"], np.full(11, 5.0), np.zeros(11), MD.name))
    path = save_csv(good, tmp_path / "u.csv")
    back = load_csv(path)
    np.testing.assert_array_equal(back.output, good.output)
    assert back.kind == "TESTU" and back.motor == "MAC140"
    (tmp_path / "bad.csv").write_text("# kind: TESTU\nsample,UA_VAL,IC_IST\n0,1,2\n")
    with pytest.raises(RecordError, match="rate_hz"):
        load_csv(tmp_path / "bad.csv")


def test_identify_from_csv_gives_the_in_memory_inertia(tmp_path):
    # records from the simulator carry their current-loop registers (# registers: line), so
    # the CSV path uses the same electrical TESTA model as the in-memory procedure
    from tuning.autotune import identify_motors
    from tuning.cli import app
    from typer.testing import CliRunner

    from jvl_gym import MotorArray

    m = MotorArray("MAC140", n=1, seed=3, load_inertia=2e-5, coulomb_friction=0.01,
                   current_noise=2.0, position_noise=0.85)
    ident = identify_motors(m)[0]
    assert ident.mechanics.repeats == 4 and len(ident.records) == 9
    u = save_csv(ident.records[0], tmp_path / "u.csv")
    files = [save_csv(r, tmp_path / f"a{k}.csv") for k, r in enumerate(ident.records[1:])]
    assert "# registers: KIFX2=" in files[0].read_text()
    recs = [load_csv(f) for f in files]
    assert recs[0].meta["registers"] == ident.records[1].meta["registers"]
    coil = identify_coil(load_csv(u), MD)
    est = identify_mechanics(recs, coil.motor(MD), coil_sd=coil_uncertainty(coil))
    assert est.J == pytest.approx(ident.mechanics.J, rel=1e-9)
    assert est.ci["J"] == pytest.approx(ident.mechanics.ci["J"], rel=1e-9)
    args = ["identify", "--motor", "MAC140", "--testu", str(u)]
    for f in files:
        args += ["--testa", str(f)]
    res = CliRunner().invoke(app, args)
    assert res.exit_code == 0, res.output
    assert "(electrical model)" in res.output
    j_cli = float(res.output.split("J ")[1].split()[0])
    assert j_cli == pytest.approx(ident.mechanics.J, rel=1e-9)
    # without the registers the rigid model is used and reads the current loop's lag as inertia
    for r in recs:
        r.meta.pop("registers")
    rigid = identify_mechanics(recs, coil.motor(MD))
    assert abs(rigid.J / ident.mechanics.J - 1) > 1e-3


def test_repeated_two_level_sets_give_intervals_from_their_spread():
    from scipy import stats

    inside, widths = {"J": [], "coulomb": [], "viscous": []}, []
    for seed in range(20):
        rng = np.random.default_rng(100 + seed)
        J, tc, b, t1, t2 = _random_mechanics(rng)
        recs = [simulate_testa(MD, J, t, 64, b, tc, position_noise=0.85, rng=rng)
                for _ in range(4) for t in (t1, t2)]
        est = identify_mechanics(recs, MD)
        assert est.repeats == 4 and len(est.J_repeats) == 4
        assert est.J == pytest.approx(np.mean(est.J_repeats))
        # at least the batch-means interval (spread between the sets, t with 3 dof)
        h = stats.t.ppf(0.975, 3) * np.std(est.J_repeats, ddof=1) / 2
        assert est.ci["J"][0] <= est.J - h * (1 - 1e-9) and est.ci["J"][1] >= est.J + h * (1 - 1e-9)
        assert est.ci["kvout"][1] == pytest.approx(est.ci["J"][1] / MD.J_m)
        for k, tv in (("J", J), ("coulomb", tc), ("viscous", b)):
            inside[k].append(est.ci[k][0] <= tv <= est.ci[k][1])
        widths.append((est.ci["J"][1] - est.ci["J"][0]) / 2 / est.J)
    for k, v in inside.items():
        assert 0.85 <= np.mean(v) <= 1.0, (k, np.mean(v))
    assert np.median(widths) < 0.02


def test_friction_is_never_negative_and_undetected_friction_is_zero():
    # no friction at all: the estimates scatter around 0; the reported value is never negative
    # and an interval reaching 0 is "not detected" with the value 0
    J = 3.0 * MD.J_m
    t1, t2 = two_level_torques(J, MD, 64)
    reported, detected, covered = [], [], []
    for seed in range(12):
        rng = np.random.default_rng(300 + seed)
        recs = [simulate_testa(MD, J, t, 64, 0.0, 0.0, position_noise=0.85, rng=rng)
                for _ in range(4) for t in (t1, t2)]
        est = identify_mechanics(recs, MD)
        for k in ("coulomb", "viscous"):
            assert getattr(est, k) >= 0.0 and est.ci[k][0] >= 0.0
            if not est.detected[k]:
                assert getattr(est, k) == 0.0 and est.ci[k][0] == 0.0
            reported.append(getattr(est, k))
            detected.append(est.detected[k])
            covered.append(est.ci[k][0] <= 0.0 <= est.ci[k][1])
        assert est.detected["J"]
    assert np.mean(detected) <= 0.25  # a 95 % interval excludes the true 0 rarely
    assert np.mean(covered) >= 0.75


def test_coil_intervals_cover_with_several_short_records_and_the_delay_set():
    # the port's case: several 11-sample TESTU records combined (jackknife over whole records
    # plus the quantisation floor); noise-free records repeat exactly, the floor keeps the
    # interval honest
    inside = []
    for seed in range(30):
        recs = [simulate_testu(MD, 100, 11, quantize=True, noise_std=2.0, rng=1000 * seed + k)
                for k in range(6)]
        est = identify_coil(recs, MD)
        inside.append(est.ci["R_phase"][0] <= MD.R_phase <= est.ci["R_phase"][1]
                      and est.ci["L_phase"][0] <= MD.L_phase <= est.ci["L_phase"][1])
        assert est.ci["delay"][0] <= est.delay <= est.ci["delay"][1]
    assert 0.8 <= np.mean(inside) <= 1.0
    same = [simulate_testu(MD, 100, 11, quantize=True) for _ in range(4)]
    est = identify_coil(same, MD)
    assert est.ci["R_phase"][0] <= MD.R_phase <= est.ci["R_phase"][1]
    assert est.ci["R_phase"][1] > est.ci["R_phase"][0]
    assert est.ci["delay"] == (1.0, 1.0)


def test_interval_helpers():
    from tuning.intervals import batch_means, combined_halfwidth, jackknife, positive

    b = positive(-0.2, -0.5, 0.1)
    assert not b.detected and b.value == 0.0 and b.interval == (0.0, 0.1) and b.raw == -0.2
    assert positive(1.0, 0.5, 1.5).detected
    assert positive(0.1, -0.5, -0.1).interval == (0.0, 0.0)
    mean, var, dof = batch_means([1.0, 2.0, 3.0, 4.0])
    assert (mean, dof) == (2.5, 3) and var == pytest.approx(np.var([1, 2, 3, 4], ddof=1) / 4)
    # the jackknife of a mean is the variance of the mean
    x = np.array([1.0, 4.0, 2.0, 7.0, 5.0])
    loo = np.array([[np.delete(x, i).mean()] for i in range(x.size)])
    v, k = jackknife(np.array([x.mean()]), loo)
    assert k == 4 and v[0] == pytest.approx(np.var(x, ddof=1) / x.size)
    # never narrower than either part
    assert combined_halfwidth(1.0, 3, 0.0) == pytest.approx(3.182446, rel=1e-5)
    assert combined_halfwidth(0.0, 3, 1.0) == pytest.approx(1.959964, rel=1e-5)
    assert combined_halfwidth(1.0, 3, 1.0) > 3.182446
