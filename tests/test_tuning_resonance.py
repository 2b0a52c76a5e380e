"""Two-mass loads in the tuning toolkit: the resonance from joined torque-step windows and the
speed loop with a notch or low-pass in VF's free order (docs/tuning.md, "Two-mass loads")."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest
from tuning.autotune import synthesize
from tuning.identify_resonance import (
    ELDEG_TURN,
    apparent_resonance,
    coupling_resonance,
    identify_resonance,
    step_record,
)
from tuning.models import MotorData, freqresp, speed_plant
from tuning.quantize import quantize_registers, quantize_value
from tuning.records import RecordError
from tuning.resonance_design import (
    GM_MIN,
    PM_MIN,
    alias_hz,
    balanced,
    choose,
    coupling_of,
    design_cases,
    lowpass_section,
    notch_section,
    resonance_designs,
    scaled_gains,
    two_mass_metrics,
    with_section,
)
from tuning.testmode_facts import record_facts

from jvl_gym import MotorArray
from jvl_gym.families import family

MAC = record_facts(family("mac050_141"))  #: the MAC050–141's TESTU/TESTA facts
TS_O, TS_I = MAC.ts_o, MAC.ts_i

#: (type, resonance [Hz], load ratio J_l/J_m, damping ratio): one low resonance (the long
#: record) and one above the speed loop's Nyquist frequency (the short record, alias 211 Hz)
LOADS = (("MAC140", 70.0, 4.0, 0.02), ("MAC050", 310.0, 2.0, 0.03))


def _loads() -> tuple[MotorArray, list[SimpleNamespace]]:
    mds = [MotorData.from_config(t) for t, *_ in LOADS]
    cps = [coupling_of(md.J_m, r, f, z) for md, (_, f, r, z) in zip(mds, LOADS)]
    m = MotorArray([t for t, *_ in LOADS], n=len(LOADS), seed=4,
                   load_inertia=[c[0] for c in cps], coupling_stiffness=[c[1] for c in cps],
                   coupling_damping=[c[2] for c in cps], current_noise=2.0, position_noise=0.85)
    idents = []
    for md, (_, _, r, _) in zip(mds, LOADS):
        J = md.J_m * (1 + r)
        mech = SimpleNamespace(J=J, ci={"J": (0.98 * J, 1.02 * J)})
        idents.append(SimpleNamespace(motor=md, mechanics=mech))
    return m, idents


def test_resonance_is_found_within_five_percent() -> None:
    m, idents = _loads()
    est = identify_resonance(m, idents)
    for e, (_, f, r, _) in zip(est, LOADS):
        assert e.detected
        assert e.f_res == pytest.approx(f, rel=0.05)
        assert e.load_ratio == pytest.approx(r, rel=1e-9)
        assert e.f_anti == pytest.approx(e.f_res / math.sqrt(1 + r))
        lo, hi = e.ci["f_res"]
        assert lo < e.f_res < hi
    assert [e.used for e in est] == [1, 0]  # the long record for 70 Hz, the short for 310 Hz
    assert np.all(m.read("MODE_REG") == 0)  # left in INIT_MODE


def test_step_record_starts_at_the_step_and_ends_at_the_brake() -> None:
    n = 895
    k0, k1 = 37, 600  # the step and the brake, inner samples
    vf = np.zeros(n)
    vf[k0:k1], vf[k1:] = 300.0, -300.0
    x = np.zeros(n)
    t = np.arange(k1 - k0)
    x[k0:k1] = 0.5 * t**2 + 3.0 * np.sin(0.2 * t)  # angle after the step [counts]
    x[:k0] = 0.0
    x[k1:] = x[k1 - 1]
    rec = step_record(np.floor(x + 100.0) % ELDEG_TURN, vf, TS_I)
    assert rec.size == k1 - k0
    np.testing.assert_allclose(rec, np.floor(x[k0:k1] + 100.0) - np.floor(x[k0] + 100.0))
    with pytest.raises(RecordError, match="not in the sample buffer"):
        step_record(x % ELDEG_TURN, np.zeros(n), TS_I)
    late = np.zeros(n)
    late[n - 20:] = 300.0
    with pytest.raises(RecordError, match="came late"):
        step_record(x % ELDEG_TURN, late, TS_I)


def test_sections_have_unity_dc_gain_and_fit_the_free_order() -> None:
    assert alias_hz(310.0, 1 / TS_O) == pytest.approx(1 / TS_O - 310.0)
    assert alias_hz(100.0, 1 / TS_O) == 100.0
    for num, den in (notch_section(310.0, 0.5, TS_O), lowpass_section(0.4)):
        assert num.sum() == pytest.approx(den.sum())
    md = MotorData.from_config("MAC140")
    pi = synthesize(md, 5 * md.J_m, structure="pi", position_integral=False).registers
    out = with_section(pi, notch_section(100.0, 0.6, TS_O))
    # VF·N: the PI's integrator kept, the notch's zeros on the unit circle at 100 Hz
    den = [1.0, -out["KVFY3"], -out["KVFY2"], -out["KVFY1"], -out["KVFY0"]]
    assert np.polyval(den, 1.0) == pytest.approx(0.0, abs=1e-12)
    num = [out["KVFX4"], out["KVFX3"], out["KVFX2"], out["KVFX1"]]
    z = np.exp(1j * 2 * math.pi * 100.0 * TS_O)
    assert abs(np.polyval(num, z)) < 1e-9
    with pytest.raises(ValueError, match="position integral"):
        with_section({**pi, "KVFX2": 0.1, "KVFY2": -1.0}, lowpass_section(0.3))


def test_stiff_coupling_speed_plant_is_the_rigid_one() -> None:
    md = MotorData.from_config("MAC140")
    regs = synthesize(md, 3 * md.J_m, structure="pi").registers
    rigid = speed_plant(md, regs, 3 * md.J_m)
    j_l, k, d = coupling_of(md.J_m, 2.0, 2000.0, 0.3)
    elastic = speed_plant(md, regs, md.J_m, 0.0, (j_l, k, d))
    w = 2 * math.pi * np.array([1.0, 10.0, 50.0])
    np.testing.assert_allclose(freqresp(elastic, w), freqresp(rigid, w), rtol=0.02)


def test_notch_design_has_the_margins_after_quantisation_and_the_plain_one_not() -> None:
    t, f, r, z = LOADS[0]
    md = MotorData.from_config(t)
    plain = synthesize(md, md.J_m * (1 + r), structure="pi", position_integral=False)
    cp = coupling_of(md.J_m, r, f, z)
    assert two_mass_metrics(md, plain.registers, cp).pm_deg < PM_MIN
    cands = resonance_designs(md, plain.registers, f, r, z)
    kinds = [c.kind for c in cands]
    assert "notch" in kinds
    for c in cands:
        m = two_mass_metrics(md, c.registers, cp)
        assert m.stable and m.pm_deg >= PM_MIN
        assert all(quantize_value(k, v, MAC.table) == v for k, v in c.registers.items()
                   if k.startswith("KVF"))
    # the acceptance step on the two-mass motor: the kept design settles, without sustained
    # oscillation, where the plain design oscillates or is slower
    params = {"load_inertia": cp[0], "coupling_stiffness": cp[1], "coupling_damping": cp[2]}
    ch = choose(t, params, plain.registers, cands, 100)
    assert ch.chosen is not None
    assert ch.oscillation[ch.chosen.name] <= 20 and math.isfinite(ch.settle_s[ch.chosen.name])
    assert (ch.oscillation["plain design"] > 20
            or ch.settle_s["plain design"] > ch.settle_s[ch.chosen.name])
    assert "PM" in ch.reason


def test_two_mass_bode_marks_crossover_margins_and_resonance() -> None:
    from tuning.report import two_mass_bode_figure

    t, f, r, z = LOADS[1]
    md = MotorData.from_config(t)
    plain = synthesize(md, md.J_m * (1 + r), structure="pi", position_integral=False)
    cp = coupling_of(md.J_m, r, f, z)
    notch = with_section(plain.registers, notch_section(f, 0.5, TS_O))
    fig = two_mass_bode_figure(md, [("plain", plain.registers), ("notch", notch)], cp, f,
                               f / math.sqrt(1 + r))
    labels = [t.get_text() for t in fig.axes[1].get_legend().get_texts()]
    assert any("resonance 310 Hz" in s for s in labels)
    assert any("alias 211 Hz" in s for s in labels)
    assert any("anti-resonance" in s for s in labels)
    assert all("PM" in t.get_text() for t in fig.axes[0].get_legend().get_texts()[:2])


def test_current_loop_lowers_the_recorded_resonance_and_the_correction_undoes_it() -> None:
    md = MotorData.from_config("MAC141")
    regs = {k: float(MotorArray("MAC141", n=1).read(k)[0])
            for k in ("KIFX2", "KIFX1", "KIFY1", "KIFY0", "KIB1", "KIB0")}
    f_seen, z_seen = apparent_resonance(md, regs, 7.8, 200.0, 0.02)
    assert 0.9 * 200.0 < f_seen < 0.99 * 200.0  # the back-EMF through the current loop
    assert z_seen > 0.02
    f, z = coupling_resonance(md, regs, 7.8, f_seen, z_seen)
    assert f == pytest.approx(200.0, rel=1e-4) and z == pytest.approx(0.02, abs=1e-4)


def test_balanced_keeps_the_loop_and_the_integral_gain_through_quantisation() -> None:
    md = MotorData.from_config("MAC140")
    pi = synthesize(md, 8 * md.J_m, structure="pi", position_integral=False).registers
    low = with_section(scaled_gains(pi, 0.1), notch_section(35.0, 0.65, TS_O))
    b = balanced(low)
    keys = ("KVFX4", "KVFX3", "KVFX2", "KVFX1")
    np.testing.assert_allclose([b["KVOUT"] * b[k] for k in keys],
                               [low["KVOUT"] * low[k] for k in keys], rtol=1e-12)

    def integral(r: dict[str, float]) -> float:
        return r["KVOUT"] * sum(r[k] for k in keys)

    plain_err = abs(integral(quantize_registers(low, MAC.table)) / integral(low) - 1)
    bal_err = abs(integral(quantize_registers(b, MAC.table)) / integral(low) - 1)
    assert plain_err > 0.5  # rounded to (almost) no integral action
    assert bal_err < 0.03


def test_low_resonance_with_a_large_load_ratio_gets_a_design_with_the_margins() -> None:
    # 34.7 Hz, J_l/J_m = 7: the anti-resonance (12.3 Hz) lies inside the rigid design's
    # bandwidth; a lower crossover with a notch has the margins on every design case and on
    # the true plant, after quantisation
    md = MotorData.from_config("MAC140")
    f, r, z = 34.7, 7.0, 0.012
    plain = synthesize(md, md.J_m * (1 + r), structure="pi", position_integral=False)
    ci = {"f_res": (0.97 * f, 1.03 * f), "load_ratio": (0.95 * r, 1.05 * r),
          "zeta": (0.008, 0.016)}
    cases = design_cases(f, r, z, ci)
    assert len(cases) == 5 and min(c[2] for c in cases) == 0.008
    cands = resonance_designs(md, plain.registers, f, r, z, 0.0, ci)
    assert cands
    for c in cands:
        assert c.gain < 1.0
        for f_c, r_c, z_c in cases:
            m = two_mass_metrics(md, c.registers, coupling_of(md.J_m, r_c, f_c, z_c))
            assert m.stable and m.pm_deg >= PM_MIN and m.gm_db >= GM_MIN
        assert c.registers == quantize_registers(c.registers, MAC.table)
