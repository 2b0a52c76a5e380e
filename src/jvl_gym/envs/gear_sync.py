"""GearSync-v0: a winder on a web line; the MAC follows the master in AG_MODE."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import njit

from ..engine import TaskDriver
from ..jit import KERNEL
from ..noise import normal
from .base import Column, MotorVectorEnv
from .compiled import action, end_step, put_obs
from .family_task import (
    ERROR_BITS,
    FamilyHooks,
    R,
    TaskFamily,
    reg,
    set_analog_volts,
    set_load_torque,
    set_pulse_counts,
    shaft_angle,
)
from .profiles import SpeedProfile, row_speed
from .single import MotorEnv
from .web import load_cell_s, span_step_s, tension_s, winder_radius_s

__all__ = ["GearSyncEnv", "GearSyncVectorEnv"]

#: the families the task runs on (docs/envs.md)
_FAMILIES = ("mac050_141", "mac800")
_NORM_RPM = 3000.0  #: rpm: scale of the motor speed channel
_GEARF2 = 1000  #: GEARF2 of the nominal gear (GEARF1 = round(ratio·1000))
#: the default gear ratio, 10 at a rated speed of 4000 rpm (MAC140), in proportion to the rated
#: speed of the family's default motor type, so that the line's top speed is within every
#: family's speed range
_DEFAULT_GEAR_RATIO, _DEFAULT_GEAR_RPM = 10.0, 4000.0
_INTEGRAL_TAU = 2.0  #: time constant of the leaky tension-error integral [s]
_LOADCELL_STREAM = np.uint64(0x5EED)  #: noise key offset of the load cell

#: columns of the per-copy line state (the last two carry the master speed and the motor angle
#: of the present outer sample from before to after the block's inner samples)
(_W_EA, _W_THICK, _W_R0, _W_SPAN, _W_REF, _W_STRAIN, _W_WOUND, _W_RADIUS, _W_FORCE, _W_MEASURED,
 _W_MTHETA, _W_TIME, _W_ACC, _W_PREV_MEASURED, _W_PULSES, _W_INTEGRAL, _W_SLACK, _W_V1,
 _W_THETA0, _W_COLS) = range(20)
#: entries of the per-env constants array
(_NOISE, _MAX_STEPS, _DECIMATION, _T_CHANGE, _COUNTS_PER_M, _MASTER_RADIUS, _GEAR_RATIO,
 _LC_K, _LC_NOISE, _TOLERANCE, _RATE_W, _BREAK, _SLACK_SAMPLES, _PENALTY, _N_CONSTS) = range(15)


def _figures(tf: TaskFamily) -> dict[str, float]:
    """The hooks' figures on a family: the outer sample time [s], the motor speed scale in
    counts/sample, the analogue input's centre and span [V]."""
    k = tf.constants
    return {"_DT": k.OUTER_DT, "_V_MOTOR_NORM": _NORM_RPM / 60.0 * k.COUNTS_PER_REV / k.OUTER_HZ,
            "_AG_CENTRE_VOLTS": tf.task.AG_CENTRE_VOLTS, "_AG_SPAN_VOLTS": tf.task.AG_SPAN_VOLTS}


# bound per family by ``_figures``
_DT = _V_MOTOR_NORM = _AG_CENTRE_VOLTS = _AG_SPAN_VOLTS = 1.0


def _line_before(i, view, episode, task):  # pragma: no cover - compiled
    """Outer sample of copy ``i``, before the motor: master speed and pulses; remembers the
    speed and the motor angle for :func:`_line_after`."""
    k, prof, w = task
    v1 = row_speed(prof[i], w[i, _W_TIME], w[i, _W_MTHETA], k[_T_CHANGE])
    acc = w[i, _W_ACC] + v1 * k[_COUNTS_PER_M] * _DT
    counts = math.floor(acc)
    w[i, _W_ACC] = acc - counts
    w[i, _W_PULSES] += counts
    set_pulse_counts(view, i, counts)
    w[i, _W_V1] = v1
    w[i, _W_THETA0] = shaft_angle(view, i)


def _line_after(i, view, episode, task):  # pragma: no cover - compiled
    """Outer sample of copy ``i``, after the motor: span strain, winder radius, tension, load
    torque (for the next sample), load cell (``jvl_gym.envs.web``), master angle and time."""
    k, _, w = task
    v1 = w[i, _W_V1]
    theta0 = w[i, _W_THETA0]
    gear_ratio = k[_GEAR_RATIO]
    travel = w[i, _W_RADIUS] * (shaft_angle(view, i) - theta0) / gear_ratio
    strain = span_step_s(w[i, _W_STRAIN], v1, travel / _DT, w[i, _W_SPAN], _DT)
    w[i, _W_STRAIN] = strain
    w[i, _W_WOUND] += travel
    radius = winder_radius_s(w[i, _W_R0], w[i, _W_THICK], w[i, _W_WOUND])
    w[i, _W_RADIUS] = radius
    force = tension_s(strain, w[i, _W_EA])
    w[i, _W_FORCE] = force
    set_load_torque(view, i, radius * force / gear_ratio)
    w[i, _W_MEASURED] = load_cell_s(w[i, _W_MEASURED], force, k[_LC_K])
    w[i, _W_SLACK] = w[i, _W_SLACK] + 1.0 if strain <= 0.0 else 0.0
    w[i, _W_MTHETA] += v1 * _DT / k[_MASTER_RADIUS]
    w[i, _W_TIME] += _DT


def _observe_row(i, view, episode, task):  # pragma: no cover - compiled
    """Observation of copy ``i`` (see the env docstring, "Observation Space")."""
    k, _, w = task
    obs, t = episode.obs, episode.t
    ref = w[i, _W_REF]
    key = episode.noise_key[i]
    noise = k[_NOISE]
    meas = w[i, _W_MEASURED]
    if k[_LC_NOISE] > 0.0:
        meas += k[_LC_NOISE] * ref * normal(key ^ _LOADCELL_STREAM, t[i], 0, 1)
    decimation = k[_DECIMATION]
    v1_counts = k[_COUNTS_PER_M] * _DT  # master counts per sample at 1 m/s
    put_obs(obs, i, 0, (meas - ref) / ref, key, t[i], noise)
    put_obs(obs, i, 1, (w[i, _W_MEASURED] - w[i, _W_PREV_MEASURED]) / ref
            * (0.1 / (decimation * _DT)), key, t[i], noise)
    put_obs(obs, i, 2, w[i, _W_INTEGRAL] * 10.0, key, t[i], noise)
    put_obs(obs, i, 3, w[i, _W_PULSES] / decimation / v1_counts, key, t[i], noise)
    put_obs(obs, i, 4, reg(view, i, R.V_IST) / _V_MOTOR_NORM, key, t[i], noise)
    put_obs(obs, i, 5, reg(view, i, R.FLWERR) / 100.0, key, t[i], noise)
    put_obs(obs, i, 6, reg(view, i, R.FNCERR) / 10000.0, key, t[i], noise)
    put_obs(obs, i, 7, episode.prev_action[i, 0], key, t[i], noise)


def _step_begin(i, view, episode, task, actions):  # pragma: no cover - compiled
    """Beginning of an env step of copy ``i``: analogue input, step accumulators."""
    w = task[2]
    a = action(actions, i, 0)
    set_analog_volts(view, i, _AG_CENTRE_VOLTS + _AG_SPAN_VOLTS * a)
    w[i, _W_PREV_MEASURED] = w[i, _W_MEASURED]
    w[i, _W_PULSES] = 0.0


def _step_end(i, view, episode, task, actions):  # pragma: no cover - compiled
    """End of an env step of copy ``i``: leaky error integral, reward, termination,
    observation (the action is clipped again: a pure function of ``actions``)."""
    k, _, w = task
    prev, t = episode.prev_action, episode.t
    a = action(actions, i, 0)
    decimation = int(k[_DECIMATION])
    ref = w[i, _W_REF]
    e_meas = (w[i, _W_MEASURED] - ref) / ref
    w[i, _W_INTEGRAL] += decimation * _DT * (e_meas - w[i, _W_INTEGRAL] / _INTEGRAL_TAU)
    t[i] += 1
    e = (w[i, _W_FORCE] - ref) / ref
    da = a - prev[i, 0]
    r = 1.0 - min(abs(e) / k[_TOLERANCE], 2.0) - k[_RATE_W] * da * da
    failed = (w[i, _W_FORCE] > k[_BREAK] * ref or w[i, _W_SLACK] >= k[_SLACK_SAMPLES]
              or (reg(view, i, R.ERR_STAT) & ERROR_BITS) != 0)
    episode.reward[i] = r - k[_PENALTY] if failed else r
    end_step(i, failed, t, int(k[_MAX_STEPS]), episode.terminated, episode.truncated)
    prev[i, 0] = a
    _observe_row(i, view, episode, task)


_HOOKS = FamilyHooks(__file__, "gear_sync", _figures, begin=_step_begin, before=_line_before,
                     after=_line_after, end=_step_end, observe=_observe_row)


@njit(**KERNEL)
def _reset_rows(idx: np.ndarray, line: np.ndarray, gear: np.ndarray, ea: np.ndarray,
                thickness: np.ndarray, r0: np.ndarray, span: np.ndarray,
                tension_ref: np.ndarray, master_radius: float, gear_ratio: float,
                master_counts_per_rev: int, counts_per_rev: int, ag_centre: float,
                gearf1: np.ndarray, load: np.ndarray) -> None:  # pragma: no cover - compiled
    """Line state (N, _W_COLS) of copies ``idx`` at rest, the web pre-tensioned to the
    reference, from the (M,) draws (E·A [N], thickness [m], core radius [m], span [m],
    reference tension [N]); the nominal gear ``gear`` (N,) and its GEARF1 ``gearf1`` (M,) (at
    the core radius and the analogue input's centre, where the AG factor is ``ag_centre``, the
    winder runs at v1/(1 − ε_ref)); the load torque ``load`` (M,) [N·m] of the pre-tension;
    ``counts_per_rev``: the motor's encoder counts per revolution."""
    for j in range(idx.shape[0]):
        i = idx[j]
        w = line[i]
        w.fill(0.0)  # wound, master angle, time, counts, integral, slack
        w[_W_EA] = ea[j]
        w[_W_THICK] = thickness[j]
        w[_W_R0] = r0[j]
        w[_W_SPAN] = span[j]
        w[_W_REF] = tension_ref[j]
        strain_ref = tension_ref[j] / ea[j]
        w[_W_STRAIN] = strain_ref
        w[_W_RADIUS] = r0[j]
        w[_W_FORCE] = tension_ref[j]
        w[_W_MEASURED] = tension_ref[j]
        w[_W_PREV_MEASURED] = tension_ref[j]
        motor_per_master = (master_radius / r0[j] * gear_ratio / (1.0 - strain_ref)
                            / ag_centre)
        ratio = motor_per_master * counts_per_rev / master_counts_per_rev
        gearf1[j] = np.round(ratio * _GEARF2)
        gear[i] = gearf1[j] / _GEARF2
        load[j] = r0[j] * tension_ref[j] / gear_ratio


class GearSyncVectorEnv(MotorVectorEnv):
    """Vector version of :class:`GearSyncEnv` (same arguments plus ``num_envs`` and
    ``autoreset_mode``)."""

    families = _FAMILIES
    refused_families = {"mis": "a step motor has no analogue gear mode (StepperIndexing-v0 is "
                                "the MIS task)"}
    terminal_errors = None

    ea = Column("line", _W_EA)  #: E·A [N]
    thickness = Column("line", _W_THICK)  #: web thickness [m]
    r0 = Column("line", _W_R0)  #: core radius [m]
    span = Column("line", _W_SPAN)  #: span length [m]
    tension_ref = Column("line", _W_REF)  #: reference tension [N]
    strain = Column("line", _W_STRAIN)
    wound = Column("line", _W_WOUND)  #: web wound [m]
    radius = Column("line", _W_RADIUS)  #: winder radius [m]
    force = Column("line", _W_FORCE)  #: web tension [N]
    measured = Column("line", _W_MEASURED)  #: load-cell reading without noise [N]
    master_theta = Column("line", _W_MTHETA)  #: master roll angle [rad]
    time = Column("line", _W_TIME)  #: episode time [s]
    count_acc = Column("line", _W_ACC)  #: fractional master counts
    prev_measured = Column("line", _W_PREV_MEASURED)
    pulses = Column("line", _W_PULSES)  #: master counts in the last step
    error_integral = Column("line", _W_INTEGRAL)  #: leaky tension-error integral [s]
    slack_count = Column("line", _W_SLACK)  #: outer samples the web has been slack

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
        self.__dict__.update(self._transient())
        fam = self._fam
        self._dt = dt = fam.constants.OUTER_DT
        #: the motor's top speed in the task: the rated speed of the family's default type
        self.rated_rpm = float(
            fam.family.array_class.load_motor(fam.task.DEFAULT_MOTOR_TYPE).rated_speed_rpm)
        if self.gear_ratio is None:
            self.gear_ratio = _DEFAULT_GEAR_RATIO * self.rated_rpm / _DEFAULT_GEAR_RPM
        self.slack_samples = max(1, int(round(self._slack_time / dt)))
        self.profile = SpeedProfile(n)
        self.line = np.zeros((n, _W_COLS))
        self.gear = np.ones(n)
        self._k = np.zeros(_N_CONSTS)  # constants of the compiled step
        self._k[[_NOISE, _MAX_STEPS, _DECIMATION, _T_CHANGE, _COUNTS_PER_M, _MASTER_RADIUS,
                 _GEAR_RATIO, _LC_K, _LC_NOISE, _TOLERANCE, _RATE_W, _BREAK, _SLACK_SAMPLES,
                 _PENALTY]] = (
            self.obs_noise, self.max_episode_steps, self.decimation, self.profile.t_change,
            self._counts_per_m, self.master_radius, self.gear_ratio,
            1.0 - math.exp(-dt / self.loadcell_tau) if self.loadcell_tau > 0 else 1.0,
            self.loadcell_noise, self.tension_tolerance, self.action_rate_weight,
            self.break_ratio, self.slack_samples, self.failure_penalty)
        #: the arrays the compiled hooks unpack: constants, master profiles, line state
        self._task = (self._k, self.profile.params, self.line)

    def _motor_params(self, idx: np.ndarray, draws: dict[str, np.ndarray]
                      ) -> dict[str, np.ndarray]:
        return {"load_inertia": draws["inertia_ratio"] * self.rotor_inertia(idx)}

    def _task_reset(self, idx: np.ndarray, draws: dict[str, np.ndarray],
                    rngs: list[np.random.Generator]) -> None:
        self.profile.reset(idx, rngs, draws["line_speed"], draws["ramp_time"],
                           draws["speed_step"], draws["step_time"], draws["walk"],
                           draws["ripple"])
        m = self.motors
        fam = self._fam
        gearf1, load = np.empty(idx.size), np.empty(idx.size)
        _reset_rows(idx, self.line, self.gear, draws["ea"], draws["thickness"],
                    draws["r0"], draws["span"], draws["tension_ref"], self.master_radius,
                    self.gear_ratio, self.master_counts_per_rev, fam.constants.COUNTS_PER_REV,
                    fam.task.AG_CENTRE_FACTOR, gearf1, load)
        self._kvout_for_load(idx, draws["inertia_ratio"])
        num, den = fam.task.GEARF
        m.write_many({num: gearf1, den: _GEARF2,
                      "V_SOLL": round(fam.task.rpm_to_v_soll(self.rated_rpm)),
                      "MODE_REG": fam.task.ANALOG_GEAR_MODE}, idx)
        if hasattr(m, "start_under_load"):  # the speed regulator already holds the load
            m.start_under_load(load, idx)
        else:  # the motor takes the load up in its first samples
            m.set_input(idx, load_torque=load)

    def _transient(self) -> dict[str, TaskDriver]:
        """The compiled step of the task on the env's family (rebuilt after unpickling)."""
        return {"_driver": _HOOKS.driver(self.family_key)}

    def _step_copies(self, actions: np.ndarray) -> bool:
        return self._driver.step(self.motors.engine_view(), self._episode, self._task, actions,
                                 self.decimation)

    def _termination_reasons(self, idx: np.ndarray) -> list[str]:
        """Web break (tension above ``break_ratio`` × reference), slack longer than
        ``slack_time``, or the motor error bits, as the compiled step decides."""
        ref = self.line[idx, _W_REF]
        broke = (self.line[idx, _W_FORCE] > self.break_ratio * ref).tolist()
        slack = (self.line[idx, _W_SLACK] >= self.slack_samples).tolist()
        web_break = f"web break: tension above {self.break_ratio:g} × the reference"
        web_slack = f"web slack for {self.slack_samples} outer samples"
        out = []
        for b, s, error in zip(broke, slack, self._error_reasons(idx)):
            why = [text for flag, text in ((b, web_break), (s, web_slack), (error, error))
                   if flag]
            out.append("; ".join(why) or "terminated by the task")
        return out

    def _observe_copies(self, idx: np.ndarray) -> None:
        self._driver.observe(self.motors.engine_view(), self._episode, self._task, idx)

    def _scope_values(self) -> np.ndarray:
        task = self._fam.task
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
    steps = 5.76 s at the default decimation 2).

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
