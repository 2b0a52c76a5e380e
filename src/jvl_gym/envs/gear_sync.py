"""GearSync-v0: a winder on a web line; the MAC follows the master in AG_MODE."""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np
from numba import njit, typeof, types

from ..engine.jit import KERNEL
from ..families import Capability, Family
from ..motor.noise import normal
from ..physics.fixed import rint
from .base import Field, MotorVectorEnv
from .compiled import action, end_step, put_obs
from .profiles import SpeedProfile, row_speed
from .single import MotorEnv
from .stepping import TERMINATED
from .task import (
    ERROR_BITS,
    R,
    Task,
    clear_records,
    record,
    reg,
    set_analog_volts,
    set_load_torque,
    set_pulse_counts,
    shaft_angle,
)
from .web import load_cell_s, span_step_s, tension_s, winder_radius_s

__all__ = ["GearSyncEnv", "GearSyncVectorEnv", "GearSyncState"]

_NORM_RPM = 3000.0  #: rpm: scale of the motor speed channel
_GEARF2 = 1000  #: GEARF2 of the nominal gear (GEARF1 = round(ratio·1000))
#: the default gear ratio, 10 at a rated speed of 4000 rpm (MAC140), in proportion to the rated
#: speed of the family's default motor type, so that the line's top speed is within every
#: family's speed range
_DEFAULT_GEAR_RATIO, _DEFAULT_GEAR_RPM = 10.0, 4000.0
_INTEGRAL_TAU = 2.0  #: time constant of the leaky tension-error integral [s]
_LOADCELL_STREAM = np.uint64(0x5EED)  #: noise key offset of the load cell

#: the env's constants of the compiled step (``counts_per_m``: master counts per metre;
#: ``loadcell_k``: the load cell's filter gain per outer sample)
CONSTS = record(noise=float, max_steps=float, decimation=float, t_change=float,
                counts_per_m=float, master_radius=float, gear_ratio=float, loadcell_k=float,
                loadcell_noise=float, tension_tolerance=float, action_rate_weight=float,
                break_ratio=float, slack_samples=float, failure_penalty=float)
#: a copy's line (``v1`` and ``theta0`` carry the master speed and the motor angle of the
#: present outer sample from before to after the block's inner samples; ``error_sum`` and
#: ``error_max``: sum and largest of the |tension error| / reference at the episode's steps)
LINE = record(ea=float, thickness=float, r0=float, span=float, tension_ref=float, strain=float,
              wound=float, radius=float, force=float, measured=float, master_theta=float,
              time=float, count_acc=float, prev_measured=float, pulses=float,
              error_integral=float, slack_count=float, v1=float, theta0=float, error_sum=float,
              error_max=float)


class GearSyncState(NamedTuple):
    """The task's state (:mod:`jvl_gym.envs.task`)."""

    consts: np.ndarray  #: (1,) :data:`CONSTS`
    profile: np.ndarray  #: (N, profile columns) the master speed profiles (:mod:`.profiles`)
    line: np.ndarray  #: (N,) :data:`LINE`


def _figures(fam: Family) -> dict[str, float]:
    """The hooks' figures on a family: the outer sample time [s], the motor speed scale in
    counts/sample, the analogue input's centre and span [V]."""
    k = fam.constants
    return {"_DT": k.OUTER_DT, "_V_MOTOR_NORM": _NORM_RPM / 60.0 * k.COUNTS_PER_REV / k.OUTER_HZ,
            "_AG_CENTRE_VOLTS": fam.task.AG_CENTRE_VOLTS,
            "_AG_SPAN_VOLTS": fam.task.AG_SPAN_VOLTS}


# bound per family by ``_figures``
_DT = _V_MOTOR_NORM = _AG_CENTRE_VOLTS = _AG_SPAN_VOLTS = 1.0


def _line_before(i, view, episode, s):  # pragma: no cover - compiled
    """Outer sample of copy ``i``, before the motor: master speed and pulses; remembers the
    speed and the motor angle for :func:`_line_after`."""
    k = s.consts[0]
    w = s.line[i]
    v1 = row_speed(s.profile[i], w.time, w.master_theta, k.t_change)
    acc = w.count_acc + v1 * k.counts_per_m * _DT
    counts = math.floor(acc)
    w.count_acc = acc - counts
    w.pulses += counts
    set_pulse_counts(view, i, counts)
    w.v1 = v1
    w.theta0 = shaft_angle(view, i)


def _line_after(i, view, episode, s):  # pragma: no cover - compiled
    """Outer sample of copy ``i``, after the motor: span strain, winder radius, tension, load
    torque (for the next sample), load cell (``jvl_gym.envs.web``), master angle and time."""
    k = s.consts[0]
    w = s.line[i]
    v1 = w.v1
    theta0 = w.theta0
    gear_ratio = k.gear_ratio
    travel = w.radius * (shaft_angle(view, i) - theta0) / gear_ratio
    strain = span_step_s(w.strain, v1, travel / _DT, w.span, _DT)
    w.strain = strain
    w.wound += travel
    radius = winder_radius_s(w.r0, w.thickness, w.wound)
    w.radius = radius
    force = tension_s(strain, w.ea)
    w.force = force
    set_load_torque(view, i, radius * force / gear_ratio)
    w.measured = load_cell_s(w.measured, force, k.loadcell_k)
    w.slack_count = w.slack_count + 1.0 if strain <= 0.0 else 0.0
    w.master_theta += v1 * _DT / k.master_radius
    w.time += _DT


def _observe_row(i, view, episode, s):  # pragma: no cover - compiled
    """Observation of copy ``i`` (see the env docstring, "Observation Space")."""
    k = s.consts[0]
    w = s.line[i]
    obs, t = episode.obs, episode.t
    ref = w.tension_ref
    key = episode.noise_key[i]
    noise = k.noise
    meas = w.measured
    if k.loadcell_noise > 0.0:
        meas += k.loadcell_noise * ref * normal(key ^ _LOADCELL_STREAM, t[i], 0, 1)
    decimation = k.decimation
    v1_counts = k.counts_per_m * _DT  # master counts per sample at 1 m/s
    put_obs(obs, i, 0, (meas - ref) / ref, key, t[i], noise)
    put_obs(obs, i, 1, (w.measured - w.prev_measured) / ref
            * (0.1 / (decimation * _DT)), key, t[i], noise)
    put_obs(obs, i, 2, w.error_integral * 10.0, key, t[i], noise)
    put_obs(obs, i, 3, w.pulses / decimation / v1_counts, key, t[i], noise)
    put_obs(obs, i, 4, reg(view, i, R.V_IST) / _V_MOTOR_NORM, key, t[i], noise)
    put_obs(obs, i, 5, reg(view, i, R.FLWERR) / 100.0, key, t[i], noise)
    put_obs(obs, i, 6, reg(view, i, R.FNCERR) / 10000.0, key, t[i], noise)
    put_obs(obs, i, 7, episode.prev_action[i, 0], key, t[i], noise)


def _step_begin(i, view, episode, s, actions):  # pragma: no cover - compiled
    """Beginning of an env step of copy ``i``: analogue input, step accumulators."""
    w = s.line[i]
    a = action(actions, i, 0)
    set_analog_volts(view, i, _AG_CENTRE_VOLTS + _AG_SPAN_VOLTS * a)
    w.prev_measured = w.measured
    w.pulses = 0.0


def _step_end(i, view, episode, s, actions):  # pragma: no cover - compiled
    """End of an env step of copy ``i``: leaky error integral, reward, termination,
    observation (the action is clipped again: a pure function of ``actions``)."""
    k = s.consts[0]
    w = s.line[i]
    prev, t = episode.prev_action, episode.t
    a = action(actions, i, 0)
    decimation = int(k.decimation)
    ref = w.tension_ref
    e_meas = (w.measured - ref) / ref
    w.error_integral += decimation * _DT * (e_meas - w.error_integral / _INTEGRAL_TAU)
    t[i] += 1
    e = (w.force - ref) / ref
    w.error_sum += abs(e)
    w.error_max = max(w.error_max, abs(e))
    da = a - prev[i, 0]
    r = 1.0 - min(abs(e) / k.tension_tolerance, 2.0) - k.action_rate_weight * da * da
    failed = (w.force > k.break_ratio * ref or w.slack_count >= k.slack_samples
              or (reg(view, i, R.ERR_STAT) & ERROR_BITS) != 0)
    episode.reward[i] = r - k.failure_penalty if failed else r
    end_step(i, failed, t, int(k.max_steps), episode.terminated, episode.truncated)
    prev[i, 0] = a
    _observe_row(i, view, episode, s)


def _beside(env: Any) -> list[tuple[Any, tuple]]:
    """The master's speed and the web's steps (called by the step only, each compiled on its
    own), with their argument types for ``env``'s state (``Task.beside``)."""
    f8 = types.float64
    return [(row_speed, (typeof(env.state.profile[0]), f8, f8, f8)),
            (span_step_s, (f8,) * 5), (winder_radius_s, (f8,) * 3), (tension_s, (f8,) * 2),
            (load_cell_s, (f8,) * 3)]


TASK = Task("gear_sync", __file__, needs={Capability.ANALOG_GEAR}, state=GearSyncState,
            figures=_figures, begin=_step_begin, before=_line_before, after=_line_after,
            end=_step_end, observe=_observe_row, beside=_beside)


@njit(**KERNEL)
def _reset_rows(idx: np.ndarray, line: np.ndarray, gear: np.ndarray, ea: np.ndarray,
                thickness: np.ndarray, r0: np.ndarray, span: np.ndarray,
                tension_ref: np.ndarray, master_radius: float, gear_ratio: float,
                master_counts_per_rev: int, counts_per_rev: int, ag_centre: float,
                gearf1: np.ndarray, load: np.ndarray) -> None:  # pragma: no cover - compiled
    """Line state (N,) :data:`LINE` of copies ``idx`` (zeroed) at rest, the web pre-tensioned to the
    reference, from the (M,) draws (E·A [N], thickness [m], core radius [m], span [m],
    reference tension [N]); the nominal gear ``gear`` (N,) and its GEARF1 ``gearf1`` (M,) (at
    the core radius and the analogue input's centre, where the AG factor is ``ag_centre``, the
    winder runs at v1/(1 − ε_ref)); the load torque ``load`` (M,) [N·m] of the pre-tension;
    ``counts_per_rev``: the motor's encoder counts per revolution."""
    for j in range(idx.shape[0]):
        i = idx[j]
        w = line[i]  # zeroed: wound, master angle, time, counts, integral, slack
        w.ea = ea[j]
        w.thickness = thickness[j]
        w.r0 = r0[j]
        w.span = span[j]
        w.tension_ref = tension_ref[j]
        strain_ref = tension_ref[j] / ea[j]
        w.strain = strain_ref
        w.radius = r0[j]
        w.force = tension_ref[j]
        w.measured = tension_ref[j]
        w.prev_measured = tension_ref[j]
        motor_per_master = (master_radius / r0[j] * gear_ratio / (1.0 - strain_ref)
                            / ag_centre)
        ratio = motor_per_master * counts_per_rev / master_counts_per_rev
        gearf1[j] = rint(ratio * _GEARF2)
        gear[i] = gearf1[j] / _GEARF2
        load[j] = r0[j] * tension_ref[j] / gear_ratio


class GearSyncVectorEnv(MotorVectorEnv):
    """Vector version of :class:`GearSyncEnv` (same arguments plus ``num_envs`` and
    ``autoreset_mode``)."""

    task = TASK
    ea = Field("line")  #: E·A [N]
    thickness = Field("line")  #: web thickness [m]
    r0 = Field("line")  #: core radius [m]
    span = Field("line")  #: span length [m]
    tension_ref = Field("line")  #: reference tension [N]
    strain = Field("line")
    wound = Field("line")  #: web wound [m]
    radius = Field("line")  #: winder radius [m]
    force = Field("line")  #: web tension [N]
    measured = Field("line")  #: load-cell reading without noise [N]
    master_theta = Field("line")  #: master roll angle [rad]
    time = Field("line")  #: episode time [s]
    count_acc = Field("line")  #: fractional master counts
    prev_measured = Field("line")
    pulses = Field("line")  #: master counts in the last step
    error_integral = Field("line")  #: leaky tension-error integral [s]
    slack_count = Field("line")  #: outer samples the web has been slack
    error_sum = Field("line")  #: sum of |tension error| / reference over the episode's steps
    error_max = Field("line")  #: largest |tension error| / reference at a step

    obs_labels = ("tension_error", "tension_rate", "tension_error_integral", "master_speed",
                  "motor_speed", "flwerr", "fncerr", "previous_action")
    act_labels = ("analog_input",)
    default_ranges = {
        "ea": (3e3, 8e3),  # E·A [N]
        "thickness": (50e-6, 300e-6),  # web thickness h [m]
        "r0": (0.04, 0.06),  # winder core radius [m]
        "span": (0.5, 2.0),  # span length L [m]
        "line_speed": (0.5, 1.2),  # master surface speed after run-up [m/s]
        "ramp_time": (0.3, 1.0),  # run-up time [s]
        "speed_step": (-0.3, 0.3),  # relative speed change ...
        "step_time": (1.5, 4.5),  # ... at this time [s]
        "walk": (0.0, 0.02),  # random-walk amplitude (relative std)
        "ripple": (0.0, 0.005),  # master roll eccentricity a
        "tension_ref": (10.0, 25.0),  # reference tension [N]
        "inertia_ratio": (0.5, 3.0),  # winder roll inertia at the motor / rotor inertia
    }
    default_decimation = 2
    default_max_episode_steps = 1500
    scope_channels = ("tension [N]", "tension ref [N]", "analogue input [V]", "winder rpm")
    episode_stats = {"tension_error": "mean tension error (abs.) [%]",
                     "tension_error_max": "max tension error (abs.) [%]",
                     "copper_loss": "copper loss [J]"}

    def __init__(self, num_envs: int = 1, *, gear_ratio: float | None = None,
                 master_radius: float = 0.05,
                 master_counts_per_rev: int = 8192, loadcell_tau: float = 0.005,
                 loadcell_noise: float = 0.01, break_ratio: float = 3.0, slack_time: float = 0.01,
                 action_rate_weight: float = 0.05, tension_tolerance: float = 0.1,
                 failure_penalty: float = 100.0, **kwargs: Any) -> None:
        if ((gear_ratio is not None and gear_ratio <= 0) or master_radius <= 0
                or master_counts_per_rev <= 0):
            raise ValueError("gear_ratio, master_radius and master_counts_per_rev must be > 0")
        self.gear_ratio = None if gear_ratio is None else float(gear_ratio)
        self._slack_time = float(slack_time)
        self.master_radius = float(master_radius)
        self.master_counts_per_rev = int(master_counts_per_rev)
        self.loadcell_tau = float(loadcell_tau)
        self.loadcell_noise = float(loadcell_noise)
        self.break_ratio = float(break_ratio)
        self.action_rate_weight = float(action_rate_weight)
        self.tension_tolerance = float(tension_tolerance)
        self.failure_penalty = float(failure_penalty)
        #: master counts per outer sample at 1 m/s
        self._counts_per_m = master_counts_per_rev / (2 * math.pi * master_radius)
        super().__init__(num_envs, **kwargs)

    def _build(self) -> None:
        n = self.num_envs
        fam = self.fam
        self._dt = dt = fam.constants.OUTER_DT
        #: the motor's top speed in the task: the rated speed of the family's default type
        self.rated_rpm = float(
            fam.array_class.load_motor(fam.task.DEFAULT_MOTOR_TYPE).rated_speed_rpm)
        if self.gear_ratio is None:
            self.gear_ratio = _DEFAULT_GEAR_RATIO * self.rated_rpm / _DEFAULT_GEAR_RPM
        self.slack_samples = max(1, int(round(self._slack_time / dt)))
        self.profile = SpeedProfile(n)
        self.gear = np.ones(n)
        consts = np.zeros(1, dtype=CONSTS)
        consts[0] = (
            self.obs_noise, self.max_episode_steps, self.decimation, self.profile.t_change,
            self._counts_per_m, self.master_radius, self.gear_ratio,
            1.0 - math.exp(-dt / self.loadcell_tau) if self.loadcell_tau > 0 else 1.0,
            self.loadcell_noise, self.tension_tolerance, self.action_rate_weight,
            self.break_ratio, self.slack_samples, self.failure_penalty)
        self.state = GearSyncState(consts, self.profile.params, np.zeros(n, dtype=LINE))

    def _motor_params(self, idx: np.ndarray, draws: dict[str, np.ndarray]
                      ) -> dict[str, np.ndarray]:
        return {"load_inertia": draws["inertia_ratio"] * self.rotor_inertia(idx)}

    def _task_reset(self, idx: np.ndarray, draws: dict[str, np.ndarray],
                    rngs: list[np.random.Generator]) -> None:
        self.profile.reset(idx, rngs, draws["line_speed"], draws["ramp_time"],
                           draws["speed_step"], draws["step_time"], draws["walk"],
                           draws["ripple"])
        m = self.motors
        fam = self.fam
        gearf1, load = np.empty(idx.size), np.empty(idx.size)
        clear_records(self.state.line, idx)
        _reset_rows(idx, self.state.line, self.gear, draws["ea"], draws["thickness"],
                    draws["r0"], draws["span"], draws["tension_ref"], self.master_radius,
                    self.gear_ratio, self.master_counts_per_rev, fam.constants.COUNTS_PER_REV,
                    fam.task.AG_CENTRE_FACTOR, gearf1, load)
        num, den = fam.task.GEARF
        m.write_many({**self._load_writes(draws["inertia_ratio"]), num: gearf1, den: _GEARF2,
                      "V_SOLL": round(fam.task.rpm_to_v_soll(self.rated_rpm)),
                      "MODE_REG": fam.task.ANALOG_GEAR_MODE}, idx)
        if hasattr(m, "start_under_load"):  # the speed regulator already holds the load
            m.start_under_load(load, idx)
        else:  # the motor takes the load up in its first samples
            m.set_input(idx, load_torque=load)

    def _termination_reasons(self, idx: np.ndarray) -> list[str]:
        """Web break (tension above ``break_ratio`` × reference), slack longer than
        ``slack_time``, or the motor error bits, as the compiled step decides: per copy of
        ``idx`` ((M,) int) the key of :meth:`_reason_text`, its text kept per key."""
        line = self.state.line  # the fields' table, read once
        broke = line["force"][idx] > self.break_ratio * line["tension_ref"][idx]
        slack = line["slack_count"][idx] >= self.slack_samples
        keys = zip(broke.tolist(), slack.tolist(), self._error_bits_of(idx).tolist())
        return self._kept_texts(list(keys), self._reason_text,
                                (self.break_ratio, self.slack_samples))

    def _reason_text(self, key: tuple[bool, bool, int]) -> str:
        """The termination reason of ``key``: (web break, web slack, error bits
        (:meth:`~jvl_gym.envs.stepping.Stepping.error_bits`)), '; ' between the reasons."""
        broke, slack, bits = key
        why = []
        if broke:
            why.append(f"web break: tension above {self.break_ratio:g} × the reference")
        if slack:
            why.append(f"web slack for {self.slack_samples} outer samples")
        error = self._error_text(bits)
        if error:
            why.append(error)
        return "; ".join(why) or TERMINATED

    def _episode_stats(self, idx: np.ndarray) -> dict[str, np.ndarray]:
        """Mean and largest |tension error| over the episode's steps in % of the reference,
        copper loss (see "Episode End")."""
        line = self.state.line  # the fields' table, read once
        return {"tension_error": 100.0 * line["error_sum"][idx] / np.maximum(self._t[idx], 1),
                "tension_error_max": 100.0 * line["error_max"][idx],
                "copper_loss": self.copper_loss(idx)}

    def _scope_values(self) -> np.ndarray:
        task = self.fam.task
        volts = task.AG_CENTRE_VOLTS + task.AG_SPAN_VOLTS * self._prev_action[:, 0]
        return np.stack([self.force, self.tension_ref, volts,
                         self.motors.speed_rpm / self.gear_ratio], axis=1)


class GearSyncEnv(MotorEnv):
    """A web winder synchronised to a master roll in AG_MODE; hold the web tension.

    ## Description
    A master roll (radius 5 cm, encoder 8192 counts/rev) feeds an elastic web through a span to
    a winding roll driven by a MAC motor through a gearbox (ratio 10). The motor runs in AG_MODE
    (manual 4.1.9, 4.4.19): it follows the master's pulse input with the gear factor
    GEARF1/GEARF2, scaled by the analogue input (−10 V ↔ 0.87, +10 V ↔ 1.15). GEARF1/GEARF2 is
    set so that 0 V holds the reference tension at the core radius; as web is wound the winder
    radius grows (``r² = r0² + h·ℓ/π``) and the ratio that holds tension drifts, unseen. The
    span follows the standard strain model ``L·dε/dt = v2(1 − ε) − v1`` (``jvl_gym.envs.web``);
    the tension ``E·A·max(ε, 0)`` loads the motor with ``r·F/n``. The master speed has a run-up,
    a speed change, a smooth random walk and eccentric-roll ripple (``jvl_gym.envs.profiles``).

    ## Action Space
    ``Box(-1, 1, (1,), float32)``: the analogue input, 10 V × action.

    ## Observation Space
    ``Box(-5, 5, (8,), float32)``: load-cell tension error / reference (filtered, τ = 5 ms,
    noise ``loadcell_noise`` × reference); its change over the step per 0.1 s / reference;
    a leaky integral (τ = 2 s) of the filtered tension error / reference × 10 [s] (the state
    a PI controller keeps, so a memoryless policy can act on it); master speed (pulse counts
    per sample / counts at 1 m/s); motor speed V_IST / 3000 rpm; FLWERR / 100 counts; FNCERR /
    10000 counts; previous action.

    ## Rewards
    Per step ``1 − min(|e|/tension_tolerance, 2) − action_rate_weight·Δa²`` with ``e`` the true
    tension error over the reference (tolerance 0.1) and ``Δa`` the change of action, and
    ``−failure_penalty`` (100) at a web break, slack or error bit. At most 1 per step
    (positive while within tolerance), so ending early costs the rest of the episode too.

    ## Starting State
    The line is at rest, the web pre-tensioned to the reference; the motor powers on with the
    default setup, GEARF1/GEARF2 nominal, V_SOLL 4000 rpm, in AG_MODE. Web, roll, profile and
    tension reference are drawn from the ranges ``ea``, ``thickness``, ``r0``, ``span``,
    ``line_speed``, ``ramp_time``, ``speed_step``, ``step_time``, ``walk``, ``ripple``,
    ``tension_ref``, ``inertia_ratio``.

    ## Episode End
    Terminated on a web break (tension > ``break_ratio`` × reference), slack longer than
    ``slack_time`` (10 ms) or a motor error bit; truncated after ``max_episode_steps`` (1500
    steps = 5.76 s at the default decimation 2). The last step's ``info`` holds the episode's
    statistics: ``tension_error`` and ``tension_error_max``, the mean and the largest true
    |tension error| at the episode's steps in % of the reference, and ``copper_loss`` [J], the
    motor's copper loss in the episode.

    ## Families
    MAC050–141 (default MAC140) and MAC800 (``motor_type="MAC800"`` or ``"MAC400"``): mode 18,
    Analog gear (factor ANINP/2047), the analogue input 5 V + 1 V × action, the nominal gear
    holding the reference at 5 V; gear ratio 7.5 and V_SOLL 3000 rpm (docs/envs.md).

    ## Arguments
    ``motor_type``, ``randomization``, ``decimation`` (2), ``obs_noise``, ``max_episode_steps``,
    ``render_mode``, ``gear_ratio`` (10 at the MAC140's 4000 rpm rated speed, in proportion to
    the rated speed of the family's default type), ``master_radius`` (0.05 m),
    ``master_counts_per_rev`` (8192), ``loadcell_tau`` (5 ms), ``loadcell_noise`` (0.01),
    ``break_ratio`` (3), ``slack_time`` (0.01 s), ``action_rate_weight`` (0.05),
    ``tension_tolerance`` (0.1), ``failure_penalty`` (100). Reset options:
    ``randomization``, ``motor_type``. Baseline: :class:`jvl_gym.envs.baselines.PITension`.

    ## Version History
    * v0: initial version.
    """

    vector_class = GearSyncVectorEnv
