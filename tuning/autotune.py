"""Autotune: identify the coil and the mechanics, synthesise, quantise and verify.

Procedure on a motor (a ``MotorArray`` here; a real motor through the same register interface,
:data:`tuning.records.SERIAL_SOURCE_HOOK`):

1. TESTU (manual 4.4.9) with the rotor turned to the zero-torque angle, ``n_coil`` samples
   → R, L, PWM delay (:func:`tuning.identify_coil.identify_coil`).
2. Current loop from the identified coil (:func:`tuning.synthesis.design_current_loop`),
   quantised and written, so TESTA runs on the designed current loop.
3. TESTA pilot (11 samples, small T_SOLL, raised until the motor moves) → a rough inertia;
   then the two-level procedure: TESTA at T₁ and T₂ = T₁/2, ``n_mech`` samples each, the pair
   repeated ``repeats`` (4) times → J, KVOUT, b, T_c with intervals from the spread between
   the repetitions (:func:`tuning.identify_mechanics.identify_mechanics`).
4. Speed loop for the identified J (:func:`tuning.synthesis.design_speed_loop`), quantisation
   (:func:`tuning.quantize.quantize_registers`) and verification (:mod:`tuning.verify`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .identify_coil import CoilEstimate, identify_coil
from .identify_mechanics import (
    MechanicsEstimate,
    coil_uncertainty,
    identify_mechanics,
    two_level_torques,
)
from .models import MotorData
from .quantize import quantize_registers
from .record_lengths import (
    RECOMMENDED_COIL_SAMPLES,
    RECOMMENDED_MECH_SAMPLES,
    RECOMMENDED_TESTA_REPEATS,
)
from .records import Record, acquire_testa, acquire_testu, align_rotor
from .synthesis import (
    CurrentDesign,
    SpeedDesign,
    design_current_loop,
    design_speed_loop,
    torque_guidance,
)
from .testmode_facts import record_facts_of
from .verify import CurrentLoopReport, SpeedLoopReport, verify_current_loop, verify_speed_loop

__all__ = ["RECOMMENDED_COIL_SAMPLES", "RECOMMENDED_MECH_SAMPLES", "RECOMMENDED_TESTA_REPEATS",
           "Identification",
           "Design", "identify_motors", "synthesize", "verify_design", "CURRENT_KEYS",
           "SPEED_KEYS"]

CURRENT_KEYS = ("KIFX2", "KIFX1", "KIFY1", "KIFY0", "KIB1", "KIB0")
SPEED_KEYS = ("KFF3", "KFF2", "KFF1", "KFF0", "GEARB", "KVB3", "KVB2", "KVB1", "KVB0",
              "KVFX4", "KVFX3", "KVFX2", "KVFX1", "KVFY3", "KVFY2", "KVFY1", "KVFY0", "KVOUT")

Progress = Callable[[str], None]


def _quiet(_: str) -> None:
    return None


@dataclass
class Identification:
    """Identified data of one motor and the records they came from."""

    motor: MotorData
    coil: CoilEstimate
    mechanics: MechanicsEstimate
    records: list[Record] = field(default_factory=list)


@dataclass
class Design:
    """A complete, quantised design with its verification."""

    registers: dict[str, float]
    ideal: dict[str, float]
    current: CurrentDesign
    speed: SpeedDesign
    current_report: CurrentLoopReport
    speed_report: SpeedLoopReport
    quantization_delta: dict[str, float]
    guidance: dict[str, float]
    notes: list[str] = field(default_factory=list)


def identify_motors(m: Any, n_coil: int = RECOMMENDED_COIL_SAMPLES,
                    n_mech: int = RECOMMENDED_MECH_SAMPLES, umeas: int = 100,
                    final_speed_counts: float = 120.0, progress: Progress = _quiet,
                    repeats: int | None = None, coil_repeats: int | None = None
                    ) -> list[Identification]:
    """Run the identification procedure (module docstring, steps 1–3) on every motor of ``m``.

    Parameters
    ----------
    m : MotorArray or compatible
        Motors in INIT_MODE, at rest.
    n_coil, n_mech : int
        TESTU and TESTA record lengths.
    umeas : int
        TESTU voltage step [PWM counts].
    final_speed_counts : float
        V_IST the higher TESTA level should reach at the end of its record [counts/sample]
        (120 = 916 rpm; the back-EMF's effect on the current loop is modelled).
    progress : callable
        Receives one line of text per stage.
    repeats : int, optional
        K, how often the two TESTA levels are recorded; K ≥ 2 gives honest 95 % intervals from
        the spread between the repetitions (:func:`tuning.identify_mechanics.identify_mechanics`).
        Default :func:`testa_repeats` (4 for 64-sample records, more for shorter ones: the
        firmware's 11-sample records are combined, 24 pairs).
    coil_repeats : int, optional
        TESTU records per motor (one alignment, each record from zero current); default
        :func:`testu_repeats` (1 for 64 samples, 6 for 11). Several records are fitted jointly
        with the whole-record jackknife interval (:func:`tuning.identify_coil.identify_coil`).
    """
    repeats = testa_repeats(n_mech) if repeats is None else int(repeats)
    coil_repeats = testu_repeats(n_coil) if coil_repeats is None else int(coil_repeats)
    base = [MotorData.from_config(cfg, amplitude=float(m.read("AMPLITUDE")[i]))
            for i, cfg in enumerate(m.motor_configs)]
    progress(f"TESTU: aligning rotors and recording {coil_repeats} x {n_coil} samples at "
             "7812.5 Hz")
    align_rotor(m)
    per_motor: list[list[Record]] = [[] for _ in range(m.n)]
    for _ in range(max(coil_repeats, 1)):
        _wait_current_zero(m)
        for i, r in enumerate(acquire_testu(m, umeas, n_coil, align=False)):
            per_motor[i].append(r)
    coils = [identify_coil(rs, md) for rs, md in zip(per_motor, base)]
    motors = [c.motor(md) for c, md in zip(coils, base)]
    progress("current loop: designing from the identified coils")
    cur_regs = []
    for i, md in enumerate(motors):
        regs = quantize_registers(design_current_loop(md).registers, record_facts_of(md).table)
        m.load_setup({"registers": regs}, index=[i])
        cur_regs.append(regs)
    phase_comp = np.asarray(m.read("PHASE_COMP"), dtype=float)
    progress("TESTA: pilot records")
    t_pilot = np.full(m.n, 20.0)
    for _ in range(8):
        pilot = acquire_testa(m, t_pilot, 11)
        moved = np.array([np.count_nonzero(r.output) >= 5 for r in pilot])
        if np.all(moved):
            break
        t_pilot = np.where(moved, t_pilot, np.minimum(2 * t_pilot, 1023))
    levels = []
    for r, md, tp in zip(pilot, motors, t_pilot):
        p = np.cumsum(r.output)
        t = np.arange(r.n) * md.family.outer_dt
        c2 = np.polyfit(t[2:], p[2:], 2)[0] if r.n > 4 else 0.0
        alpha = max(2 * c2 / md.family.counts_per_rad, 1e-9)
        j_guess = md.torque_per_vf * tp / alpha  # includes friction: an upper bound on J
        t1, t2 = two_level_torques(j_guess, md, n_mech, final_speed_counts)
        # keep the lower level well above the friction torque seen in the pilot
        t2 = max(t2, int(tp))
        t1 = max(t1, 2 * t2)
        levels.append((min(t1, 1023), t2))
    progress(f"TESTA: two-level procedure, {n_mech} samples per level at 520.8 Hz")
    t_hi = np.array([lv[0] for lv in levels], dtype=float)
    recs_hi = _adaptive_testa(m, t_hi, n_mech, final_speed_counts)
    t_lo = np.array([max(2.0, round(r.input[0] / 2)) for r in recs_hi])
    recs_lo = _adaptive_testa(m, t_lo, n_mech, final_speed_counts / 2)
    pairs = [list(zip(recs_hi, recs_lo))]
    t_hi = np.array([r.input[0] for r in recs_hi])
    if repeats > 1:
        progress(f"TESTA: {repeats - 1} more repetitions of the two levels")
    for _ in range(repeats - 1):
        pairs.append(list(zip(acquire_testa(m, t_hi, n_mech), acquire_testa(m, t_lo, n_mech))))
    out = []
    for i, md in enumerate(motors):
        mech_recs = [r for rep in pairs for r in rep[i]]
        mech = identify_mechanics(mech_recs, md, current_regs=cur_regs[i],
                                  phase_comp=float(phase_comp[i]),
                                  coil_sd=coil_uncertainty(coils[i]))
        out.append(Identification(md, coils[i], mech, [*per_motor[i], *mech_recs]))
    progress("identification done")
    return out


def testa_repeats(n_mech: int) -> int:
    """Default K of the two-level TESTA pair for ``n_mech``-sample records: as much test motion
    as :data:`RECOMMENDED_TESTA_REPEATS` pairs of :data:`RECOMMENDED_MECH_SAMPLES` samples,
    at least that many pairs and at most 24."""
    need = math.ceil(RECOMMENDED_TESTA_REPEATS * RECOMMENDED_MECH_SAMPLES / max(n_mech, 1))
    return int(min(max(RECOMMENDED_TESTA_REPEATS, need), 24))


def testu_repeats(n_coil: int) -> int:
    """Default number of TESTU records for ``n_coil``-sample records: 1 from 32 samples on
    (about 4 coil time constants), else 6 (combined, whole-record jackknife)."""
    return 1 if n_coil >= 32 else 6


def _wait_current_zero(m: Any, max_samples: int = 500) -> None:
    """Step until every motor's measured currents are back at zero (within 8 ADC counts of
    noise) and it stands still, for 3 polls in a row: a TESTU record must start from zero
    current (the model's i₀ is free, but a decaying current of another mode is not in it).
    The motor's own clock decides (a serial link may lag behind wall-clock time)."""
    quiet = np.zeros(m.n, dtype=int)
    for _ in range(0, max_samples, 5):
        m.step(5)
        ok = np.ones(m.n, dtype=bool)
        for key in ("IA_IST", "IC_IST"):
            ok &= np.abs(np.asarray(m.read(key), dtype=float)) <= 8
        ok &= np.asarray(m.read("V_IST")) == 0
        quiet = np.where(ok, quiet + 1, 0)
        if np.all(quiet >= 3):
            return


def _adaptive_testa(m: Any, t_soll: np.ndarray, n: int, target: float) -> list[Record]:
    """TESTA at ``t_soll``, repeated with a rescaled T_SOLL (up to 4 times) for the motors whose
    final speed is outside 0.5–2 × ``target`` (friction makes the pilot's guess inexact)."""
    t = t_soll.astype(float).copy()
    recs = acquire_testa(m, t, n)
    for _ in range(4):
        vmax = np.array([max(float(np.max(r.output)), 0.0) for r in recs])
        bad = (vmax > 2 * target) | (vmax < 0.5 * target)
        if not np.any(bad):
            break
        # the speed is roughly proportional to (T − T_friction); scale conservatively
        scale = np.where(vmax > 0, np.sqrt(target / np.maximum(vmax, 1.0)), 2.0)
        t = np.where(bad, np.clip(np.round(t * scale), 2, 1023), t)
        again = acquire_testa(m, t, n)
        recs = [again[i] if bad[i] else recs[i] for i in range(m.n)]
    return recs


def synthesize(motor: MotorData, J_total: float, coulomb: float = 0.0,
               current_bandwidth_hz: float | None = None,
               speed_bandwidth_hz: float | None = None, structure: str = "ip",
               robust: bool = True, current_gains: tuple[float, float] | None = None,
               speed_gains: tuple[float, float] | None = None,
               position_integral: bool | None = None) -> Design:
    """Design, quantise and verify all filters for an identified motor (steps 2 and 4).

    ``current_gains`` / ``speed_gains`` fix the normalised (kp, ki) instead of searching;
    ``position_integral`` forces the ``"pi"`` structure's position integral on or off
    (:func:`tuning.synthesis.design_speed_loop`).
    """
    cur = design_current_loop(motor, current_bandwidth_hz, gains=current_gains)
    spd = design_speed_loop(motor, cur.registers, J_total, speed_bandwidth_hz, structure,
                            gains=speed_gains, coulomb=coulomb,
                            position_integral=position_integral)
    ideal = {**cur.registers, **spd.registers}
    regs = quantize_registers(ideal, record_facts_of(motor).table)
    crep = verify_current_loop(motor, regs, robust)
    srep = verify_speed_loop(motor, regs, J_total, robust)
    ci = verify_current_loop(motor, ideal, robust=False).nominal
    si = verify_speed_loop(motor, ideal, J_total, robust=False).nominal
    delta = {"current_pm_deg": crep.nominal.pm_deg - ci.pm_deg,
             "current_gm_db": crep.nominal.gm_db - ci.gm_db,
             "speed_pm_deg": srep.nominal.pm_deg - si.pm_deg,
             "speed_gm_db": srep.nominal.gm_db - si.gm_db}
    guide = torque_guidance(motor, J_total, coulomb)
    return Design(regs, ideal, cur, spd, crep, srep, delta, guide, cur.notes + spd.notes)


def verify_design(design: Design) -> list[str]:
    """The acceptance checks of a design; returns the failures (empty if all pass)."""
    bad = []
    c, s = design.current_report.nominal, design.speed_report.nominal
    if not (c.pm_deg >= 45 and c.gm_db >= 6):
        bad.append(f"current margins PM {c.pm_deg:.1f} deg, GM {c.gm_db:.1f} dB")
    if not (s.pm_deg >= 45 and s.gm_db >= 8):
        bad.append(f"speed margins PM {s.pm_deg:.1f} deg, GM {s.gm_db:.1f} dB")
    if not (design.current_report.all_stable and design.speed_report.all_stable):
        bad.append("a closed-loop pole at |z| >= 0.999")
    for k, v in design.quantization_delta.items():
        if (k.endswith("deg") and abs(v) > 2) or (k.endswith("db") and abs(v) > 1):
            bad.append(f"quantisation changed {k} by {v:.2f}")
    worst = min(design.current_report.worst_robust_pm, design.speed_report.worst_robust_pm)
    if not worst >= 30:
        bad.append(f"robust PM {worst:.1f} deg < 30")
    if math.isnan(worst):
        bad.append("robust PM not computed")
    return bad
