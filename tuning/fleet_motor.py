"""Autotuning one motor of a fleet (the body of one Ray task).

A simulated motor runs the procedure of ``jvl-tune autotune`` on a one-motor ``MotorArray``
(:func:`tuning.autotune.identify_motors`, then the design with its acceptance step,
:func:`tuning.pipeline.design_and_accept`, checked by :func:`tuning.autotune.verify_design`); a
recorded motor is identified from its CSVs (:func:`tuning.identify_coil.identify_coil`,
:func:`tuning.identify_mechanics.identify_mechanics`) and designed the same way. Then the same
position move (:func:`tuning.verify.position_move`) runs with the default setup and with the
designed one —
on the motor itself when simulated, on a simulated motor with the identified inertia and
friction when recorded. The result carries the register set, the report files (as bytes, so
the driver writes them wherever it runs) and one row for the fleet report.

An identification is *credible* when :func:`tuning.credibility.problems` finds nothing (J, R, L
positive with intervals clear of zero, J at least half the rotor's, KVOUT within its format,
fits of at least ``tuning.credibility.MIN_FIT``) and, for a fleet, J's 95 % interval is within
:data:`MAX_J_HALF_WIDTH` of J and the coil's R and L intervals within
:data:`MAX_RL_HALF_WIDTH`; otherwise the row lists the reasons.
"""

from __future__ import annotations

import math
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from .fleet_spec import FleetMotor, FleetSpec

__all__ = ["tune_motor", "credibility", "MAX_J_HALF_WIDTH", "MAX_RL_HALF_WIDTH"]

MAX_J_HALF_WIDTH = 0.05  #: largest credible half-width of J's 95 % interval, relative to J
MAX_RL_HALF_WIDTH = 0.10  #: largest credible half-width of R's and L's intervals (relative)


def credibility(ident: Any) -> list[str]:
    """Reasons an identification is not credible (module docstring); empty when it is.

    Parameters
    ----------
    ident : tuning.autotune.Identification
        The identified coil and mechanics with their 95 % intervals and fits.

    Returns
    -------
    list of str
        One reason per failed criterion.
    """
    from .credibility import problems

    c, m = ident.coil, ident.mechanics
    out = problems(ident.motor, m, c)
    if not (math.isfinite(m.J) and m.J > 0):
        return out or [f"J = {m.J!r} is not a positive number"]
    hw = (m.ci["J"][1] - m.ci["J"][0]) / 2 / m.J
    if not hw <= MAX_J_HALF_WIDTH:
        out.append(f"J interval ±{100 * hw:.1f} % > ±{100 * MAX_J_HALF_WIDTH:.0f} %")
    for key, value in (("R_phase", c.R_phase), ("L_phase", c.L_phase)):
        lo, hi = c.ci[key]
        rel = (hi - lo) / 2 / abs(value) if value else math.inf
        if not rel <= MAX_RL_HALF_WIDTH:
            out.append(f"{key[0]} interval ±{100 * rel:.1f} % > "
                       f"±{100 * MAX_RL_HALF_WIDTH:.0f} %")
    return out


def _identify_records(motor: FleetMotor) -> Any:
    from .autotune import Identification
    from .identify_coil import identify_coil
    from .identify_mechanics import identify_mechanics
    from .models import MotorData
    from .records import load_csv, record_registers

    if motor.record_data:
        with tempfile.TemporaryDirectory(prefix="jvl-records-") as tmp:
            paths = []
            for name, data in sorted(motor.record_data.items()):
                paths.append(Path(tmp) / name)
                paths[-1].write_bytes(data)
            recs = [load_csv(p, motor.type) for p in paths]
    else:
        recs = [load_csv(p, motor.type) for p in motor.records]
    testu = [r for r in recs if r.kind == "TESTU"]
    testa = [r for r in recs if r.kind == "TESTA"]
    regs = record_registers(testa) or {}
    md = MotorData.from_config(motor.type, amplitude=float(regs.get("AMPLITUDE", 0.83)))
    coil = identify_coil(testu, md)
    md = coil.motor(md)
    mech = identify_mechanics(testa, md)
    return Identification(md, coil, mech, [*testu, *testa])


def _array(motor: FleetMotor, spec: FleetSpec, seed: int, load: float, viscous: float,
           coulomb: float) -> Any:
    from jvl_gym import MotorArray

    params: dict[str, Any] = {"load_inertia": load, "viscous_friction": viscous,
                              "coulomb_friction": coulomb, "initial_angle": motor.initial_angle}
    if spec.noise:
        params.update(current_noise=2.0, position_noise=0.85)
    return MotorArray(motor.type, n=1, seed=seed, **params)


def _setup_text(motor: FleetMotor, regs: dict[str, float], note: str) -> str:
    clean = {k: float(v) if isinstance(v, (float, np.floating)) else v for k, v in regs.items()}
    return f"# {note}\n" + yaml.safe_dump(
        {"motor": motor.type, "provenance": "jvl-tune fleet", "registers": clean},
        sort_keys=False)


def tune_motor(motor: FleetMotor, spec: FleetSpec, save_records: bool = False
               ) -> dict[str, Any]:
    """Identify, synthesise, verify and compare one motor.

    Parameters
    ----------
    motor : FleetMotor
        The motor (simulated or recorded).
    spec : FleetSpec
        Fleet options (noise, structure, record lengths, the settle-time move).
    save_records : bool
        Also return the records as CSVs (``records/*.csv``) and a ``motor.yaml`` with the
        truth, so the motor's folder is a records-folder entry.

    Returns
    -------
    dict
        ``row`` (the fleet-report row), ``files`` (relative path -> bytes: ``setup.yaml``,
        ``report.txt``, plots, ``motor.yaml``, records) and ``registers``.
    """
    from .autotune import identify_motors, verify_design
    from .models import MotorData
    from .pipeline import design_and_accept
    from .records import save_csv
    from .report import write_report
    from .strategy import strategy_of
    from .synthesis import torque_guidance
    from .verify import position_move

    t0 = time.perf_counter()
    c0 = time.process_time()
    row: dict[str, Any] = {"motor": motor.motor_id, "type": motor.type,
                           "source": "simulated" if motor.simulated else "records",
                           **{f"true_{k}": v for k, v in motor.truth.items()}}
    base = MotorData.from_config(motor.type)
    row["J_m"] = base.J_m
    try:
        if motor.simulated:
            m = _array(motor, spec, motor.seed, motor.load_inertia, motor.viscous, motor.coulomb)
            ident = identify_motors(m, spec.n_coil, spec.n_mech)[0]
            truth = {"J": motor.truth["J"], "kvout": motor.truth["J"] / base.J_m,
                     "viscous": motor.viscous, "coulomb": motor.coulomb,
                     "R_line": 2 * m.motor_configs[0].phase_resistance,
                     "L_line_mH": 2e3 * m.motor_configs[0].phase_inductance}
        else:
            ident = _identify_records(motor)
            truth = dict(motor.truth) or None
    except Exception as exc:  # noqa: BLE001  (a failed identification is a fleet result)
        row.update(credible=False, reasons=f"identification failed: {exc}",
                   wall_s=time.perf_counter() - t0)
        return {"row": row, "files": {}, "registers": None}
    c, mech = ident.coil, ident.mechanics
    reasons = credibility(ident)
    row.update(J=mech.J, J_lo=mech.ci["J"][0], J_hi=mech.ci["J"][1], kvout=mech.kvout,
               viscous=mech.viscous, coulomb=mech.coulomb, R_line=c.R_line, L_line=c.L_line,
               testu_fit=c.nrmse_fit, testa_fit=mech.nrmse_fit, credible=not reasons,
               reasons="; ".join(reasons))
    if "J" in motor.truth:
        row["J_err"] = mech.J / motor.truth["J"] - 1
    for key in ("viscous", "coulomb"):
        if key in motor.truth:
            row[f"{key}_err_abs"] = getattr(mech, key) - motor.truth[key]
    if motor.simulated:
        row["R_err"] = c.R_line / truth["R_line"] - 1
        row["L_err"] = c.L_line * 1e3 / truth["L_line_mH"] - 1
    files: dict[str, bytes] = {}
    if not (math.isfinite(mech.J) and mech.J > 0):
        row.update(checks="no design: J not identified", wall_s=time.perf_counter() - t0)
        return {"row": row, "files": files, "registers": None}
    strategy = strategy_of(motor.type)
    acc = design_and_accept(strategy, [ident], {"structure": spec.structure})[0]
    d = acc.chosen.design
    bad = verify_design(d)
    cr, sr = d.current_report.nominal, d.speed_report.nominal
    row.update(current_pm=cr.pm_deg, current_gm=cr.gm_db, speed_pm=sr.pm_deg,
               speed_gm=sr.gm_db, speed_bw=sr.bandwidth_hz,
               robust_pm=min(d.current_report.worst_robust_pm, d.speed_report.worst_robust_pm),
               checks="; ".join(bad) or "ok", design=acc.chosen.name)
    note = (f"jvl-tune fleet: {motor.motor_id} ({motor.type}), identified J = {mech.J:.4g} "
            "kg m^2")
    files["setup.yaml"] = _setup_text(motor, d.registers, note).encode()
    # the settle-time comparison: the motor itself, or a model of it from the identification
    if motor.simulated:
        load, visc, coul = motor.load_inertia, motor.viscous, motor.coulomb
    else:
        load, visc, coul = max(mech.J - base.J_m, 0.0), max(mech.viscous, 0.0), \
            max(mech.coulomb, 0.0)
    a_soll = int(max(10, min(200, torque_guidance(ident.motor, mech.J,
                                                  mech.coulomb)["A_SOLL_max"])))
    mv = {}
    for name, regs in (("default", None), ("tuned", d.registers)):
        sim = _array(motor, spec, motor.seed + 1, load, visc, coul)
        if regs is not None:
            sim.load_setup({"registers": regs})
        res = position_move(sim, int(spec.move["distance"]), int(spec.move["v_soll"]), a_soll,
                            seconds=spec.move["seconds"])
        mv[name] = res
    row.update(a_soll=a_soll, settle_default_s=float(mv["default"].settle_s[0]),
               settle_tuned_s=float(mv["tuned"].settle_s[0]),
               overshoot_default=float(mv["default"].overshoot[0]),
               overshoot_tuned=float(mv["tuned"].overshoot[0]),
               move_model="motor" if motor.simulated else "identified model")
    with tempfile.TemporaryDirectory(prefix="jvl-fleet-") as tmp:
        tmp_path = Path(tmp)
        step: tuple[Any, Any] = (None, None)
        if motor.simulated:
            sim = _array(motor, spec, motor.seed, load, visc, coul)
            sim.load_setup({"registers": d.registers})
            step = strategy.speed_step(sim)
        report = write_report(tmp_path, strategy, acc, truth, *step)
        for f in report:
            files[f.name] = f.read_bytes()
        if save_records:
            for k, rec in enumerate(ident.records):
                name = f"records/{k:02d}-{rec.kind.lower()}.csv"
                files[name] = save_csv(rec, tmp_path / f"rec{k}.csv").read_bytes()
    meta = {"type": motor.type, "truth": {k: float(v) for k, v in motor.truth.items()},
            "load_inertia": float(motor.load_inertia)}
    files["motor.yaml"] = yaml.safe_dump(meta, sort_keys=False).encode()
    row["wall_s"] = time.perf_counter() - t0
    row["cpu_s"] = time.process_time() - c0
    return {"row": row, "files": files, "registers": d.registers}
