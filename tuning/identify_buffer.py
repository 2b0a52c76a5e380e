"""Identification of a motor from sample-buffer records of torque steps (the MAC800 family).

The MAC800 has no TESTU/TESTA test modes (its modes, register overview §1.2 register 2: 0–6,
12–14, 16–21). The toolkit records with the sample buffer instead (registers 158–162, SAMPLE1–4
and REC_CNT; CNTRL_BITS register 36 bits RECORDBIT and RECINNERBIT, ``firmware/recorder.py``)
while the motor runs in analogue torque mode 4 (VF_OUT = ANINP·T_SOLL/2047, register 170):
a step of the analogue input is a torque step with no speed loop in the way.

*Coil*: one step recorded at the current-loop rate (RECINNERBIT, 11550 Hz), channels IA_IST,
IB_IST, UA_VAL, UB_VAL. Per phase, the ZOH-exact coil (:mod:`tuning.sixth_order`)::

    I(k+1) = a·I(k) + β·U(k − d) − β·E(k)/k_u,   a = exp(−R·TS_I/L),  β = g(1 − a)

where E is the back-EMF. The rotor starts from rest, so over the short record E is a smooth
function of time that starts at 0: a cubic in k without a constant term per phase (speed ∝ t,
the electrical angle ∝ t²) absorbs it. The phase voltages are to the bus midpoint; the star
point's common-mode voltage U_n (the current filters' integrators hold one that no current
corrects) is the same in both phases, one shared constant ``−β·U_n``; the loops start from an
empty history (passive mode before the step) so it stays nearly constant. The fit is linear
least squares in (a, β, β·U_n) shared by both phases and the cubics; d ∈ {0, 1} is the one
with the smaller residual. Then ``R = k_u(1 − a)/(β·A_count)``, ``L = −R·TS_I/ln a`` with
k_u from U_BUS (register 198). The step is taken :data:`COIL_REPEATS` times; R and L are the
means and their 95 % intervals come from the spread (:func:`combine_coil_steps`).

*Mechanics*: steps at two levels VF₁ and VF₂ ≈ VF₁/2, each recorded ``repeats`` times at the
servo rate (770 Hz), channels P_IST, VF_OUT, V_IST, each from rest. With the rigid rotor
``J dω/dt = K_vf·VF_OUT − T_c − b·ω`` (ω > 0), integrating twice from the step at t = 0::

    J·θ(t) + T_c·t²/2 + b·∫₀ᵗθ + c_r·t + d_r = K_vf·VF_r·t²/2

is linear in J, T_c, b (shared) and c_r, d_r (per record: the initial speed and the position
offset, which also take up the current loop's onset). K_vf = 1.5·p·λ·A_count·AMPLITUDE/1023
(the motor config's λ, AMPLITUDE read from the motor). Two levels separate J from T_c.

The rigid model takes the torque as ``K_vf·VF_OUT`` at every speed. It is not: the per-phase
current loops follow a reference turning at the electrical speed and reject the back-EMF only
as well as their gain allows, so the torque falls as the rotor speeds up, which the rigid fit
reads as viscous friction the motor does not have. The rigid estimate is therefore the start of
an output-error fit with the current loop, the coil and the back-EMF modelled
(:func:`tuning.identify_mechanics.refine_electrical`, the model of
:func:`tuning.identify_mechanics.electrical_position`, whose current filter structure is the
MAC800's, registers 144–149), per record free in the position offset and the initial speed as
above. The smooth model computes in real numbers where the firmware rounds (current readings,
setpoints, PWM values, the electrical angle): the records are first corrected by that
rounding's mean effect over the rotor's start angle (:mod:`tuning.loop_quantisation`), which
would otherwise read as Coulomb friction and an inertia off by a few 0.1 %. Each repetition
of the two levels is fitted on its own; the values are their mean and the 95 % intervals of J,
T_c and b come from the spread between the repetitions (batch means, Student t with K − 1
degrees of freedom) and the encoder quantisation floor
(:func:`tuning.identify_mechanics.combine_sets`); a friction whose interval reaches 0 is
reported as 0 (not detected).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .design_sixth_order import design_current_filter
from .identify_mechanics import MechanicsEstimate, combine_sets, refine_electrical
from .intervals import batch_means, positive, student_halfwidth
from .loop_quantisation import quantisation_error
from .models import MotorData
from .sixth_order import CONSTANTS as _c
from .sixth_order import COUNTS_PER_RAD, CURRENT_KEYS, TS_I, TS_O

__all__ = ["CoilRecord", "TorqueRecord", "CoilStepEstimate", "TorqueStepEstimate",
           "BufferIdentification", "record_coil", "record_torque_steps", "identify_coil_step",
           "combine_coil_steps", "identify_torque_steps", "identify_from_buffer"]

Progress = Callable[[str], None]

#: channels of the coil record (current-loop rate) and of the torque steps (servo rate)
COIL_CHANNELS = ("IA_IST", "IB_IST", "UA_VAL", "UB_VAL")
STEP_CHANNELS = ("P_IST", "VF_OUT", "V_IST")
COIL_VF: int = 100  #: VF_OUT of the coil step (about 10 % of peak torque)
COIL_SAMPLES: int = 60  #: current-loop samples of the coil fit (5.2 ms, 1.7 L/R)
COIL_REPEATS: int = 4  #: coil steps per motor (R and L intervals from their spread)
REPEAT_BRAKE: float = 0.5  #: longest brake [s] around the repeated coil steps
PILOT_VF: int = 50  #: VF_OUT of the pilot step that sizes the levels
MECH_SAMPLES: int = 100  #: servo samples per torque step (130 ms)
#: V_IST at the end of the higher step [counts/sample] (173 = 1000 RPM, register 12)
FINAL_SPEED: float = 1000.0 * _c.V_IST_COUNTS_PER_RPM


@dataclass
class CoilRecord:
    """One coil step of one motor at the current-loop rate (ADC and PWM counts)."""

    ia: np.ndarray
    ib: np.ndarray
    ua: np.ndarray
    ub: np.ndarray
    bus_voltage: float


@dataclass
class TorqueRecord:
    """One torque step of one motor at the servo rate from its onset (P_IST [counts], VF_OUT)."""

    position: np.ndarray
    vf_out: np.ndarray
    v_ist: np.ndarray


@dataclass
class CoilStepEstimate:
    """Identified coil: per-phase R [Ω], L [H], the PWM delay, the fit's NRMSE [%].

    Attributes
    ----------
    ci : dict
        95 % intervals (lo, hi) of "R_phase" [Ω] and "L_phase" [H] from the spread of the
        repeated coil steps (:func:`combine_coil_steps`); empty for one step.
    repeats : list of (float, float)
        (R, L) of each coil step.
    """

    R_phase: float
    L_phase: float
    delay: int
    nrmse: float
    ci: dict[str, tuple[float, float]] = field(default_factory=dict)
    repeats: list[tuple[float, float]] = field(default_factory=list)

    def motor(self, base: MotorData) -> MotorData:
        """``base`` with the identified coil."""
        return base.with_(R_phase=self.R_phase, L_phase=self.L_phase, pwm_delay=self.delay)


@dataclass
class TorqueStepEstimate:
    """Identified mechanics: J [kg·m²], T_c [N·m], b [N·m·s/rad] with their 95 % intervals.

    Attributes
    ----------
    ci_J : tuple of float
        The 95 % interval of J (``ci["J"]``).
    repeats : list of float
        J of each repetition [kg·m²].
    nrmse : float
        NRMSE [%] of the rigid position fit over all records (the start of the electrical fit).
    ci : dict
        95 % intervals (lo, hi) of "J", "coulomb", "viscous".
    detected : dict
        "J", "coulomb", "viscous": the interval lies above 0 (else the value is reported as 0,
        :func:`tuning.intervals.positive`).
    model : str
        ``"electrical"`` (current loop and back-EMF modelled) or ``"rigid"``.
    phase_comp : float
        PHASE_COMP (register 173) the steps ran with (the electrical model's).
    """

    J: float
    coulomb: float
    viscous: float
    ci_J: tuple[float, float]
    repeats: list[float] = field(default_factory=list)
    nrmse: float = math.nan
    ci: dict[str, tuple[float, float]] = field(default_factory=dict)
    detected: dict[str, bool] = field(default_factory=dict)
    model: str = "rigid"
    phase_comp: float = 0.0


@dataclass
class BufferIdentification:
    """What the identification found for one motor."""

    motor: MotorData
    coil: CoilStepEstimate
    mechanics: TorqueStepEstimate
    current_registers: dict[str, float]
    #: the coil record and the torque steps (higher, lower level of every repetition)
    coil_record: CoilRecord | None = None
    torque_records: list[TorqueRecord] = field(default_factory=list)


# ----------------------------------------------------------------------------- records
def _number(m: Any, name: str) -> int:
    return int(m.table.lookup(name).number)


def _start_recording(m: Any, channels: Sequence[str], inner: bool) -> None:
    """SAMPLE1–4 = ``channels``, REC_CNT = 0, RECORDBIT (and RECINNERBIT) set."""
    for k, ch in enumerate(channels):
        m.write(f"SAMPLE{k + 1}", _number(m, ch))
    m.write("REC_CNT", 0)
    cb = np.asarray(m.read("CNTRL_BITS")).astype(np.int64)
    bits = _c.RECORDBIT | (_c.RECINNERBIT if inner else 0)
    m.write("CNTRL_BITS", (cb & ~(_c.RECORDBIT | _c.RECINNERBIT)) | bits)


def _stop_recording(m: Any) -> None:
    cb = np.asarray(m.read("CNTRL_BITS")).astype(np.int64)
    m.write("CNTRL_BITS", cb & ~(_c.RECORDBIT | _c.RECINNERBIT))


def _analog_volts(vf: np.ndarray, t_soll: np.ndarray) -> np.ndarray:
    """The analogue input [V] for VF_OUT = ``vf`` in mode 4 (VF_OUT = ANINP·T_SOLL/2047)."""
    return vf / t_soll * _c.ANINP_FULL * _c.ANINP_VOLTS_PER_UNIT


def brake(m: Any, seconds: float = 4.0) -> None:
    """Stop every motor (velocity mode 1, V_SOLL = 0) until V_IST = 0 for 10 samples, then
    analogue torque mode 4 at 0 V (no torque)."""
    m.set_input(analog_volts=0.0)
    m.write("V_SOLL", 0)
    m.write("A_SOLL", 2000)
    m.write("MODE_REG", _c.VELOCITY_MODE)
    quiet = np.zeros(m.n, dtype=int)
    for _ in range(int(seconds / TS_O / 5)):
        m.step(5)
        quiet = np.where(np.asarray(m.read("V_IST")) == 0, quiet + 1, 0)
        if np.all(quiet >= 2):
            break
    m.write("MODE_REG", _c.ANALOG_TORQUE_MODE)
    m.step(5)


def record_coil(m: Any, vf: float = COIL_VF, n: int = COIL_SAMPLES,
                brake_seconds: float = 4.0) -> list[CoilRecord]:
    """A torque step of VF_OUT = ``vf`` from rest in mode 4, recorded at the current-loop rate
    (RECINNERBIT) for ``n`` samples; one record per motor. The motors are braked for at most
    ``brake_seconds`` [s] before the step and after it (:func:`brake`)."""
    brake(m, brake_seconds)
    m.write("MODE_REG", _c.PASSIVE_MODE)  # the current filters' histories cleared
    m.step(3)
    m.write("MODE_REG", _c.ANALOG_TORQUE_MODE)
    m.step(2)
    t_soll = np.asarray(m.read("T_SOLL"), dtype=float)
    _start_recording(m, COIL_CHANNELS, inner=True)
    m.set_input(analog_volts=_analog_volts(np.full(m.n, float(vf)), t_soll))
    m.step(int(math.ceil(n / _c.INNER_PER_OUTER)) + 2)
    _stop_recording(m)
    bus = np.asarray(m.read("U_BUS"), dtype=float) * _c.U_BUS_VOLTS
    out = []
    for i in range(m.n):
        buf = m.sample_buffer(i)
        out.append(CoilRecord(*(np.asarray(buf[ch], dtype=float) for ch in COIL_CHANNELS),
                              bus_voltage=float(bus[i])))
    brake(m, brake_seconds)
    return out


def record_torque_steps(m: Any, vf: np.ndarray, n: int = MECH_SAMPLES) -> list[TorqueRecord]:
    """A torque step of VF_OUT = ``vf[i]`` from rest on every motor, recorded at the servo rate
    for ``n`` samples from its onset; the motors are braked after it."""
    t_soll = np.asarray(m.read("T_SOLL"), dtype=float)
    _start_recording(m, STEP_CHANNELS, inner=False)
    m.set_input(analog_volts=_analog_volts(np.asarray(vf, dtype=float), t_soll))
    m.step(n + 3)
    _stop_recording(m)
    out = []
    for i in range(m.n):
        buf = m.sample_buffer(i)
        vfo = np.asarray(buf["VF_OUT"], dtype=float)
        on = np.flatnonzero(vfo != 0)
        k0 = int(on[0]) if on.size else 0
        out.append(TorqueRecord(np.asarray(buf["P_IST"], dtype=float)[k0:k0 + n],
                                vfo[k0:k0 + n], np.asarray(buf["V_IST"], dtype=float)[k0:k0 + n]))
    brake(m)
    return out


# ----------------------------------------------------------------------------- fits
def identify_coil_step(rec: CoilRecord, base: MotorData) -> CoilStepEstimate:
    """R, L and the PWM delay from one coil record (module docstring).

    Raises
    ------
    ValueError
        The record is too short, or the fit gives no physical coil (0 < a < 1, β > 0).
    """
    best: tuple[float, float, float, int] | None = None
    for d in (0, 1):
        rows, rhs = [], []
        for i, u in ((rec.ia, rec.ua), (rec.ib, rec.ub)):
            n = min(i.size, u.size)
            k = np.arange(d, n - 1)
            if k.size < 12:
                raise ValueError(f"the coil record has {n} samples; at least {14 + d} needed")
            poly = np.vander(k / n, 4, increasing=True)[:, 1:]
            block = np.zeros((k.size, 3 + 6))
            block[:, 0] = i[k]
            block[:, 1] = u[k - d]
            block[:, 2] = 1.0
            off = 3 if len(rows) == 0 else 6
            block[:, off:off + 3] = poly
            rows.append(block)
            rhs.append(i[k + 1])
        a_mat, y = np.vstack(rows), np.concatenate(rhs)
        x, *_ = np.linalg.lstsq(a_mat, y, rcond=None)
        res = y - a_mat @ x
        nrmse = 100.0 * float(np.sqrt(np.mean(res**2)) / max(np.std(y), 1e-12))
        if best is None or nrmse < best[0]:
            best = (nrmse, float(x[0]), float(x[1]), d)
    nrmse, a, beta, d = best  # type: ignore[misc]
    if not (0.0 < a < 1.0 and beta > 0.0):
        raise ValueError(f"coil fit gives no physical coil (a = {a:.4g}, β = {beta:.4g}); "
                         "check the record")
    k_u = base.with_(supply_voltage=rec.bus_voltage).volts_per_count
    R = k_u * (1.0 - a) / (beta * base.amps_per_count)
    L = -R * TS_I / math.log(a)
    return CoilStepEstimate(R, L, d, nrmse)


def combine_coil_steps(ests: Sequence[CoilStepEstimate]) -> CoilStepEstimate:
    """The mean of K ≥ 2 coil-step fits with 95 % intervals of R and L from their spread
    (batch means, Student t with K − 1 degrees of freedom, :mod:`tuning.intervals`): each step
    starts at another rotor angle, so the current loop's rounding and the ADC's quantisation
    differ from step to step. The PWM delay is the one most steps give.
    """
    if len(ests) < 2:
        raise ValueError("combining coil steps needs at least two")
    out: dict[str, float] = {}
    ci: dict[str, tuple[float, float]] = {}
    for key in ("R_phase", "L_phase"):
        mean, var, dof = batch_means([getattr(e, key) for e in ests])
        h = student_halfwidth(math.sqrt(var), dof)
        out[key], ci[key] = mean, (mean - h, mean + h)
    delays = [e.delay for e in ests]
    return CoilStepEstimate(out["R_phase"], out["L_phase"], max(set(delays), key=delays.count),
                            float(np.mean([e.nrmse for e in ests])), ci,
                            [(e.R_phase, e.L_phase) for e in ests])


def _fit_rigid(recs: Sequence[TorqueRecord], k_vf: float
               ) -> tuple[float, float, float, float]:
    """J, T_c, b and the NRMSE [%] of the position fit (module docstring)."""
    nr = len(recs)
    rows, rhs = [], []
    for r_i, r in enumerate(recs):
        t = np.arange(r.position.size) * TS_O
        theta = (r.position - r.position[0]) / COUNTS_PER_RAD
        integ = np.concatenate([[0.0], np.cumsum(0.5 * (theta[1:] + theta[:-1]) * TS_O)])
        torque = k_vf * float(np.median(r.vf_out))
        blk = np.zeros((t.size, 3 + 2 * nr))
        blk[:, 0] = theta
        blk[:, 1] = t**2 / 2
        blk[:, 2] = integ
        blk[:, 3 + 2 * r_i] = t
        blk[:, 4 + 2 * r_i] = 1.0
        rows.append(blk)
        rhs.append(torque * t**2 / 2)
    a_mat, y = np.vstack(rows), np.concatenate(rhs)
    scale = np.maximum(np.abs(a_mat).max(axis=0), 1e-300)
    x, *_ = np.linalg.lstsq(a_mat / scale, y, rcond=None)
    x = x / scale
    res = y - a_mat @ x
    nrmse = 100.0 * float(np.sqrt(np.mean(res**2)) / max(np.std(y), 1e-300))
    return float(x[0]), float(x[1]), float(x[2]), nrmse


def identify_torque_steps(pairs: Sequence[tuple[TorqueRecord, TorqueRecord]], motor: MotorData,
                          current_regs: Mapping[str, float] | None = None,
                          phase_comp: float = 0.0) -> TorqueStepEstimate:
    """J, T_c and b from the two-level torque steps (module docstring).

    Parameters
    ----------
    pairs : sequence of (TorqueRecord, TorqueRecord)
        Per repetition, the steps at the higher and the lower level.
    motor : MotorData
        K_vf (torque constant, A_count, AMPLITUDE) and, for the electrical model, the
        identified coil, PWM delay and bus voltage.
    current_regs : mapping, optional
        The current filter registers (KIFX2..KIB0) the steps ran on: the electrical model.
        Without them the rigid model's values (its interval of each from the spread of the
        repetitions' rigid fits).
    phase_comp : float
        PHASE_COMP (register 173) in use.

    Raises
    ------
    ValueError
        No records, or the fit gives no positive inertia.
    """
    recs = [r for p in pairs for r in p]
    if not recs:
        raise ValueError("no torque-step records to identify the mechanics from")
    k_vf = motor.torque_per_vf
    J, tc, b, nrmse = _fit_rigid(recs, k_vf)
    if not J > 0.0:
        raise ValueError(f"the torque steps give no positive inertia (J = {J:.4g} kg m^2)")
    rigid = [_fit_rigid(list(p), k_vf) for p in pairs]
    if current_regs is not None:
        steps = {(float(np.median(r.vf_out)), r.position.size) for r in recs}
        errors = {(lv, n): quantisation_error(n, lv, J, motor, current_regs, phase_comp)
                  for lv, n in steps}
        ests = [_electrical(p, motor, current_regs, phase_comp, fit, errors)
                for p, fit in zip(pairs, rigid)]
        if len(ests) >= 2:
            est = combine_sets(ests, [[2 * i, 2 * i + 1] for i in range(len(pairs))],
                               len(recs), motor)
            return TorqueStepEstimate(est.J, est.coulomb, est.viscous, est.ci["J"],
                                      [e.J for e in ests], nrmse,
                                      {nm: est.ci[nm] for nm in ("J", "coulomb", "viscous")},
                                      dict(est.detected), "electrical", phase_comp)
        J, tc, b = ests[0].J, ests[0].coulomb, ests[0].viscous  # one fit: its own interval
    ci, det, vals = {}, {}, {}
    for i, nm in enumerate(("J", "coulomb", "viscous")):
        whole = (J, tc, b)[i]
        if current_regs is not None:
            lo, hi = ests[0].ci[nm]
            h = 0.5 * (hi - lo)
        elif len(rigid) >= 2:
            _, var, dof = batch_means([f[i] for f in rigid])
            h = student_halfwidth(math.sqrt(var), dof)
        else:
            h = math.nan
        bnd = positive(whole, whole - h, whole + h)
        vals[nm], ci[nm], det[nm] = bnd.value, bnd.interval, bnd.detected
    return TorqueStepEstimate(J, vals["coulomb"], vals["viscous"], ci["J"],
                              [f[0] for f in rigid], nrmse, ci, det,
                              "rigid" if current_regs is None else "electrical", phase_comp)


def _electrical(pair: tuple[TorqueRecord, TorqueRecord], motor: MotorData,
                current_regs: Mapping[str, float], phase_comp: float,
                start: tuple[float, float, float, float],
                errors: Mapping[tuple[float, int], np.ndarray]) -> MechanicsEstimate:
    """The electrical fit of one repetition from its rigid fit ``start`` (J, T_c, b, …), on
    the positions less the integer current loop's mean error ``errors`` (by level and length,
    :func:`tuning.loop_quantisation.quantisation_error`)."""
    levels = [float(np.median(r.vf_out)) for r in pair]
    pos = [r.position - r.position[0] - errors[(lv, r.position.size)]
           for r, lv in zip(pair, levels)]
    return refine_electrical(levels, pos, motor, current_regs, phase_comp / 256.0, start[0],
                             start[1], start[2], free_terms=2)


# ----------------------------------------------------------------------------- procedure
def identify_from_buffer(m: Any, repeats: int = 2, progress: Progress = lambda _: None,
                         current_design: Callable[[MotorData], dict[str, float]] | None = None
                        ) -> list[BufferIdentification]:
    """Identify every motor of ``m`` (a MAC800-family ``MotorArray`` or compatible).

    1. Coil step at the current-loop rate → R, L, PWM delay (:func:`identify_coil_step`).
    2. The current loop designed for the identified coil (``current_design``, default
       :func:`tuning.design_sixth_order.design_current_filter`) and written, so the torque
       steps run on it.
    3. A pilot step (VF_OUT = :data:`PILOT_VF`) sizes the higher level so the motor reaches
       about :data:`FINAL_SPEED` at the end of its record; then the two levels ``repeats``
       times → J, T_c, b (:func:`identify_torque_steps`).
    """
    if current_design is None:
        current_design = design_current_filter
    amp = np.asarray(m.read("AMPLITUDE"), dtype=float)
    base = [MotorData.from_config(cfg, amplitude=float(amp[i]))
            for i, cfg in enumerate(m.motor_configs)]
    progress(f"coil: {COIL_REPEATS} torque steps in analogue torque mode 4, recorded at "
             "11550 Hz")
    # a coil step leaves the rotor at a few rad/s, which velocity mode stops within
    # milliseconds: the repeats are braked for REPEAT_BRAKE instead of the full brake
    coil_sets = [record_coil(m, brake_seconds=4.0 if k == 0 else REPEAT_BRAKE)
                 for k in range(COIL_REPEATS)]
    coil_recs = coil_sets[0]
    coils = [combine_coil_steps([identify_coil_step(rs[i], md) for rs in coil_sets])
             for i, md in enumerate(base)]
    motors = [c.motor(md).with_(supply_voltage=r.bus_voltage)
              for c, md, r in zip(coils, base, coil_recs)]
    progress("current loop: designed for the identified coils and written")
    cur = []
    for i, md in enumerate(motors):
        regs = current_design(md)
        m.load_setup({"registers": regs}, index=[i])
        cur.append(regs)
    brake(m)
    progress("mechanics: pilot torque step")
    pilot = record_torque_steps(m, np.full(m.n, float(PILOT_VF)), 40)
    vf_hi = np.empty(m.n)
    for i, (r, md) in enumerate(zip(pilot, motors)):
        t = np.arange(r.position.size) * TS_O
        c2 = np.polyfit(t, r.position, 2)[0]
        alpha = max(2.0 * c2 / COUNTS_PER_RAD, 1e-9)
        j_guess = md.torque_per_vf * PILOT_VF / alpha
        want = FINAL_SPEED / COUNTS_PER_RAD / TS_O / (MECH_SAMPLES * TS_O)
        vf_hi[i] = float(np.clip(round(j_guess * want / md.torque_per_vf), 20, 600))
    vf_lo = np.round(vf_hi / 2)
    progress(f"mechanics: {repeats} x two torque levels, {MECH_SAMPLES} samples each at "
             f"{1 / TS_O:.0f} Hz")
    pairs: list[list[tuple[TorqueRecord, TorqueRecord]]] = [[] for _ in range(m.n)]
    for _ in range(repeats):
        hi = record_torque_steps(m, vf_hi)
        lo = record_torque_steps(m, vf_lo)
        for i in range(m.n):
            pairs[i].append((hi[i], lo[i]))
    phase_comp = np.asarray(m.read("PHASE_COMP"), dtype=float)
    out = []
    for i, md in enumerate(motors):
        mech = identify_torque_steps(pairs[i], md, cur[i], float(phase_comp[i]))
        out.append(BufferIdentification(md, coils[i], mech,
                                        {k: cur[i][k] for k in CURRENT_KEYS}, coil_recs[i],
                                        [r for p in pairs[i] for r in p]))
    progress("identification done")
    return out
