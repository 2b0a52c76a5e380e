"""End-to-end benchmark of the tuning toolkit: identification, design and verification.

Draws N random motors (type, load inertia 0–10·J_m, viscous and Coulomb friction, 1 % noise),
runs the toolkit's identification on a ``MotorArray`` (TESTU + two-level TESTA), synthesises
and verifies the filters, then runs the same position move with the default setup (KVOUT = 1)
and with the autotuned setup, and prints one table row per motor.

    python benchmarks/tuning_e2e.py [N] [SEED] [pi|ip]
    python benchmarks/tuning_e2e.py coverage [N] [SEED] [REPEATS] [SAMPLES]

``coverage`` runs the identification only and prints, per identified quantity, how often the
95 % interval holds the true value, the largest and rms relative error and the median
half-width (docs/tuning.md, "Measured numbers").
"""

from __future__ import annotations

import sys
import time

import numpy as np
from tuning.autotune import identify_motors, synthesize, verify_design
from tuning.models import MotorData
from tuning.synthesis import torque_guidance
from tuning.verify import position_move

from jvl_gym import MotorArray

TYPES = ("MAC050", "MAC095", "MAC140", "MAC141")


def draw_motors(n: int, seed: int) -> dict[str, np.ndarray]:
    """Random motor parameters (SI): type, load ratio, b, T_c."""
    rng = np.random.default_rng(seed)
    types = rng.choice(TYPES, n)
    data = [MotorData.from_config(t) for t in types]
    jm = np.array([d.J_m for d in data])
    peak = np.array([d.torque_per_vf * 1023 for d in data])
    return {"type": types, "J_m": jm, "ratio": rng.uniform(0.0, 10.0, n),
            "coulomb": rng.uniform(0.0, 0.02, n) * peak,  # up to 2 % of peak torque
            "viscous": rng.uniform(0.0, 1e-5, n), "angle": rng.uniform(0, 2 * np.pi, n)}


def _array(p: dict[str, np.ndarray], seed: int) -> MotorArray:
    return MotorArray(list(p["type"]), n=len(p["type"]), seed=seed,
                      load_inertia=p["ratio"] * p["J_m"], coulomb_friction=p["coulomb"],
                      viscous_friction=p["viscous"], current_noise=2.0, position_noise=0.85,
                      initial_angle=p["angle"])


def run_e2e(n: int = 20, seed: int = 0, distance: int = 20000, v_soll: int = 2000,
            structure: str = "pi", subset: list[int] | None = None) -> list[dict[str, float]]:
    """Run the benchmark; one dict per motor (identification errors, margins, settle times).

    ``subset`` keeps only those motors of the ``n`` drawn (the tests run two of the 20).
    """
    p = draw_motors(n, seed)
    if subset is not None:
        p = {k: v[subset] for k, v in p.items()}
    m = _array(p, seed)
    ids = identify_motors(m)
    rows = []
    setups = []
    for i, idn in enumerate(ids):
        true = MotorData.from_config(p["type"][i])
        J = p["J_m"][i] * (1 + p["ratio"][i])
        d = synthesize(idn.motor, idn.mechanics.J, idn.mechanics.coulomb, structure=structure)
        setups.append(d.registers)
        c, mc = idn.coil, idn.mechanics
        rows.append({
            "type": p["type"][i], "ratio": p["ratio"][i], "coulomb": p["coulomb"][i],
            "viscous": p["viscous"][i],
            "dR": c.R_phase / true.R_phase - 1, "dL": c.L_phase / true.L_phase - 1,
            "delay_ok": c.delay == true.pwm_delay,
            "R_in": c.ci["R_phase"][0] <= true.R_phase <= c.ci["R_phase"][1],
            "L_in": c.ci["L_phase"][0] <= true.L_phase <= c.ci["L_phase"][1],
            "dJ": mc.J / J - 1, "J_in": mc.ci["J"][0] <= J <= mc.ci["J"][1],
            "cur_pm": d.current_report.nominal.pm_deg, "cur_gm": d.current_report.nominal.gm_db,
            "spd_pm": d.speed_report.nominal.pm_deg, "spd_gm": d.speed_report.nominal.gm_db,
            "robust_pm": min(d.current_report.worst_robust_pm, d.speed_report.worst_robust_pm),
            "radius": max(d.current_report.nominal.pole_radius,
                          d.speed_report.nominal.pole_radius),
            "checks": "; ".join(verify_design(d)) or "ok",
            "a_soll": torque_guidance(idn.motor, mc.J, mc.coulomb)["A_SOLL_max"],
        })
    a_soll = int(max(10, min(200, min(r["a_soll"] for r in rows))))
    base = _array(p, seed + 1)
    tuned = _array(p, seed + 1)
    for i, regs in enumerate(setups):
        tuned.load_setup({"registers": regs}, index=[i])
    mv0 = position_move(base, distance, v_soll, a_soll, seconds=2.0)
    mv1 = position_move(tuned, distance, v_soll, a_soll, seconds=2.0)
    for i, r in enumerate(rows):
        r.update({"a_soll_move": a_soll, "settle_default": mv0.settle_s[i],
                  "settle_tuned": mv1.settle_s[i], "over_default": mv0.overshoot[i],
                  "over_tuned": mv1.overshoot[i], "fncerr_tuned": mv1.fncerr[i],
                  "err_tuned": int(mv1.errors[i])})
    return rows


def run_coverage(n: int = 40, seed: int = 7, repeats: int = 4, samples: int = 64
                 ) -> dict[str, dict[str, float]]:
    """Interval coverage of the identification on ``n`` random motors.

    Returns, for "R", "L", "J", "coulomb", "viscous": "coverage" (fraction of motors whose
    95 % interval holds the true value), "max_err" and "rms_err" (relative), "median_hw"
    (median half-width relative to the estimate) and "median_hw_abs" (SI units).
    """
    p = draw_motors(n, seed)
    ids = identify_motors(_array(p, seed), samples, samples, repeats=repeats)
    rows: dict[str, list[tuple[bool, float, float, float]]] = {
        k: [] for k in ("R", "L", "J", "coulomb", "viscous")}
    for i, idn in enumerate(ids):
        true = MotorData.from_config(p["type"][i])
        c, mc = idn.coil, idn.mechanics
        cases = (("R", c.R_phase, c.ci["R_phase"], true.R_phase),
                 ("L", c.L_phase, c.ci["L_phase"], true.L_phase),
                 ("J", mc.J, mc.ci["J"], p["J_m"][i] * (1 + p["ratio"][i])),
                 ("coulomb", mc.coulomb, mc.ci["coulomb"], p["coulomb"][i]),
                 ("viscous", mc.viscous, mc.ci["viscous"], p["viscous"][i]))
        for key, val, ci, tv in cases:
            hw = (ci[1] - ci[0]) / 2
            rows[key].append((ci[0] <= tv <= ci[1], val / tv - 1, hw / abs(val), hw))
    out = {}
    for key, r in rows.items():
        a = np.array(r, dtype=float)
        out[key] = {"coverage": float(a[:, 0].mean()),
                    "max_err": float(np.max(np.abs(a[:, 1]))),
                    "rms_err": float(np.sqrt(np.mean(a[:, 1] ** 2))),
                    "median_hw": float(np.median(a[:, 2])),
                    "median_hw_abs": float(np.median(a[:, 3]))}
    return out


def print_table(rows: list[dict[str, float]]) -> None:
    """Print the per-motor table and the summary against the acceptance items."""
    hdr = (f"{'#':>2} {'type':<6} {'Jl/Jm':>5} {'dR%':>6} {'dL%':>6} {'dJ%':>6} {'CI R/L/J':>8} "
           f"{'cPM':>5} {'cGM':>5} {'sPM':>5} {'sGM':>5} {'rPM':>5} {'|z|':>5} "
           f"{'t_def ms':>8} {'t_tun ms':>8} {'ovr d/t':>8} {'FNCERR':>6}")
    print(hdr)
    for i, r in enumerate(rows):
        ci = "".join("y" if r[k] else "n" for k in ("R_in", "L_in", "J_in"))
        print(f"{i:>2} {r['type']:<6} {r['ratio']:>5.2f} {100 * r['dR']:>6.2f} "
              f"{100 * r['dL']:>6.2f} {100 * r['dJ']:>6.2f} {ci:>8} {r['cur_pm']:>5.1f} "
              f"{r['cur_gm']:>5.1f} {r['spd_pm']:>5.1f} {r['spd_gm']:>5.1f} "
              f"{r['robust_pm']:>5.1f} {r['radius']:>5.3f} {1e3 * r['settle_default']:>8.1f} "
              f"{1e3 * r['settle_tuned']:>8.1f} "
              f"{r['over_default']:>4.0f}/{r['over_tuned']:<3.0f} {r['fncerr_tuned']:>6.0f}")
    n = len(rows)
    faster = sum(r["settle_tuned"] < r["settle_default"] for r in rows)
    print(f"\nmotors: {n}; move: 20000 counts, V_SOLL 2000, A_SOLL {rows[0]['a_soll_move']}")
    print(f"max |dR| {100 * max(abs(r['dR']) for r in rows):.2f} %, max |dL| "
          f"{100 * max(abs(r['dL']) for r in rows):.2f} %, max |dJ| "
          f"{100 * max(abs(r['dJ']) for r in rows):.2f} %, delay exact "
          f"{sum(r['delay_ok'] for r in rows)}/{n}")
    print(f"95 % intervals hold the truth: R {sum(r['R_in'] for r in rows)}/{n}, "
          f"L {sum(r['L_in'] for r in rows)}/{n}, J {sum(r['J_in'] for r in rows)}/{n}")
    print(f"design checks ok {sum(r['checks'] == 'ok' for r in rows)}/{n}; tuned settles faster "
          f"{faster}/{n}; FNCERR = 0 (tuned) {sum(r['fncerr_tuned'] == 0 for r in rows)}/{n}; "
          f"error bits (tuned) {sum(r['err_tuned'] != 0 for r in rows)}")


if __name__ == "__main__" and len(sys.argv) > 1 and sys.argv[1] == "coverage":
    a = [int(x) for x in sys.argv[2:]] + [40, 7, 4, 64][len(sys.argv) - 2:]
    t0 = time.time()
    for key, v in run_coverage(*a[:4]).items():
        print(f"{key:<8} coverage {100 * v['coverage']:5.1f} %  "
              f"max |err| {100 * v['max_err']:7.2f} %  rms {100 * v['rms_err']:7.2f} %  "
              f"median half-width {100 * v['median_hw']:6.2f} % ({v['median_hw_abs']:.3g})")
    print(f"({a[0]} motors, seed {a[1]}, {a[2]} repeats, {a[3]} samples; {time.time() - t0:.1f} s)")
elif __name__ == "__main__":
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 20
    seed = int(sys.argv[2]) if len(sys.argv) > 2 else 0
    structure = sys.argv[3] if len(sys.argv) > 3 else "pi"
    t0 = time.time()
    rows = run_e2e(n, seed, structure=structure)
    print_table(rows)
    print(f"({time.time() - t0:.1f} s)")
