"""FilterTuning-v0: one commissioning trial per episode — choose the speed-loop design."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from ..families import Capability, family
from .numpy_step import NumpyTaskEnv
from .single import MotorEnv
from .task import Task

__all__ = ["FilterTuningEnv", "FilterTuningVectorEnv", "Designer"]

#: the task needs a speed-loop filter to design; its step is a whole trial, in numpy
TASK = Task("filter_tuning", __file__, needs={Capability.SPEED_FILTER})
#: the trial's durations [s]: the position step, the velocity step, the load step's time in it,
#: the stretch whose speed ripple is measured (160, 120, 40 and 20 samples at 520.8 Hz)
_POS_TIME, _VEL_TIME, _LOAD_TIME, _RIPPLE_TIME = 0.3072, 0.2304, 0.0768, 0.0384
#: the trial's position figures in turns (20, 100, 200 and 1000 counts at 4096 counts/rev):
#: settled band, final error of a failed trial, FLWERR and FNCERR scales of the cost
_SETTLE_TURNS, _FAIL_TURNS, _FLW_TURNS, _FNC_TURNS = (20.0 / 4096, 100.0 / 4096, 200.0 / 4096,
                                                      1000.0 / 4096)


#: a speed-loop designer: motor type → the speed-loop registers at KVOUT = 1 (the design is
#: load-invariant with KVOUT = J_total/J_m), or None where it has no design (e.g.
#: ``tuning.baseline.speed_loop_registers``, the tuning toolkit's synthesis)
Designer = Callable[[str], "dict[str, float] | None"]


class FilterTuningVectorEnv(NumpyTaskEnv):
    """Vector version of :class:`FilterTuningEnv` (same arguments plus ``num_envs`` and
    ``autoreset_mode``)."""

    task = TASK

    #: the labels after the motor-type one-hot (``type_<name>`` for each type of the env's
    #: family, set per instance)
    obs_labels = ("inertia_ratio_estimate", "viscous_estimate", "coulomb_estimate")
    act_labels = ("proportional_gain", "integral_gain", "kvout")
    default_ranges = {
        "inertia_ratio": (0.0, 10.0),
        "viscous_friction": (0.0, 5e-5),
        "coulomb_ratio": (0.0, 0.05),
    }
    viscous_ranges = ("viscous_friction",)
    default_decimation = 1
    default_max_episode_steps = 1
    scope_channels = ("position error [counts]", "speed [rpm]", "VF_OUT")
    episode_stats = {"design_cost": "design cost", "settling_time": "settling time [s]",
                     "overshoot": "overshoot [%]", "speed_dip": "speed dip [%]",
                     "unstable": "unstable"}

    def __init__(self, num_envs: int = 1, *, motor_type: str | tuple[str, ...] | None = None,
                 baseline: bool = False, estimate_error: float = 0.1,
                 instability_penalty: float = 10.0, designer: Designer | None = None,
                 **kwargs: Any) -> None:
        self.baseline = bool(baseline)
        self.designer = designer
        self.estimate_error = float(estimate_error)
        self.instability_penalty = float(instability_penalty)
        if motor_type is None:  # every type of the default type's family
            motor_type = tuple(family(self.reference_family()).motor_types())
        # the labels of the motor types' family (checked by the base class)
        key = self._family_of(motor_type)
        self.obs_labels = (*(f"type_{t}" for t in family(key).motor_types()),
                           *type(self).obs_labels)
        super().__init__(num_envs, motor_type=motor_type, **kwargs)

    def _build(self) -> None:
        n = self.num_envs
        fam = self.fam
        k = fam.constants
        self._types = tuple(fam.motor_types())
        hz = k.OUTER_HZ
        self._pos_samples = round(_POS_TIME * hz)
        self._vel_samples = round(_VEL_TIME * hz)
        self._load_at = round(_LOAD_TIME * hz)
        self._ripple_samples = round(_RIPPLE_TIME * hz)
        #: the position step [counts]: one turn, and the trial's figures in counts
        self._step_counts = k.COUNTS_PER_REV
        self._settle_tol = _SETTLE_TURNS * k.COUNTS_PER_REV
        self._fail_counts = _FAIL_TURNS * k.COUNTS_PER_REV
        self._flw_scale = _FLW_TURNS * k.COUNTS_PER_REV
        self._fnc_scale = _FNC_TURNS * k.COUNTS_PER_REV
        self.scope_length = self._pos_samples + self._vel_samples
        self.estimates = np.zeros((n, 3))
        self.truth = np.zeros((n, 3))
        self.metrics: dict[str, np.ndarray] = {}
        self._ok = np.arange(n)
        self._trace = np.zeros((n, 3, self.scope_length), dtype=np.float32)
        synthesis = (self.designer is not None
                     and self.designer(fam.task.DEFAULT_MOTOR_TYPE) is not None)
        self._synthesis = synthesis
        self.baseline_source = (("designer" if synthesis else "default setup")
                                if self.baseline else "agent")

    def _motor_params(self, idx: np.ndarray, draws: dict[str, np.ndarray]
                      ) -> dict[str, np.ndarray]:
        return {"load_inertia": draws["inertia_ratio"] * self.rotor_inertia(idx),
                "viscous_friction": draws["viscous_friction"],
                "coulomb_friction": draws["coulomb_ratio"] * self.rated_torque(idx)}

    def _task_reset(self, idx: np.ndarray, draws: dict[str, np.ndarray],
                    rngs: list[np.random.Generator]) -> None:
        # the friction draws relative to the family's default ranges' highs
        truth = np.stack([draws["inertia_ratio"],
                          draws["viscous_friction"] / self.default_ranges["viscous_friction"][1],
                          draws["coulomb_ratio"] / self.default_ranges["coulomb_ratio"][1]],
                         axis=1)
        noise = np.array([rng.standard_normal(3) for rng in rngs]).reshape(idx.size, 3)
        self.truth[idx] = truth
        self.estimates[idx] = np.maximum(truth * (1.0 + self.estimate_error * noise), 0.0)

    def _apply_action(self, action: np.ndarray) -> None:
        m = self.motors
        fam = self.fam
        # a copy left in an error by its last trial (NEXT_STEP: stepped once more before its
        # reset) cannot leave INIT; it is skipped and reset afterwards
        ok = np.flatnonzero((m.read_raw("ERR_STAT") & fam.constants.BLOCKING_ERRORS) == 0)
        self._ok = ok
        kvout_est = 1.0 + self.estimates[:, 0]
        if self.baseline:
            if not self._synthesis:  # default setup, KVOUT from the estimate
                m.write("KVOUT", np.round(kvout_est[ok] * 256) / 256, index=ok)
                return
            for name in sorted(set(self._type_names[ok])):
                regs = None if self.designer is None else self.designer(name)
                sel = ok[self._type_names[ok] == name]
                if regs is None:
                    continue  # default setup
                for name, value in regs.items():
                    m.write(name, value, index=sel)
                m.write("KVOUT", np.round(kvout_est[sel] * 256) / 256, index=sel)
            return
        a = action[ok]
        lead, lag = fam.task.SPEED_PI
        x_lead = m.read(lead)[ok]
        x_lag = m.read(lag)[ok]
        p, i = -x_lag, x_lead + x_lag  # the PI split: lead = c(kp+ki), lag = −c·kp
        feedback = getattr(fam.task, "SPEED_FEEDBACK", None)
        if feedback is not None:  # an I-P setup: kp in the feedback filter, 1 + (kp/ki)(1 − z⁻¹)
            fb_lag = m.read(feedback[1])[ok]
            p, i = p - x_lead * fb_lag, i * (m.read(feedback[0])[ok] + fb_lag)
            m.write_many({feedback[0]: 1.0, feedback[1]: 0.0}, index=ok)  # the PI goes in VF
        sp = 2.0 ** a[:, 0]
        si = 2.0 ** (1.5 * a[:, 1])
        m.write(lead, np.round((sp * p + si * i) * 4096) / 4096, index=ok)
        m.write(lag, np.round(-sp * p * 4096) / 4096, index=ok)
        m.write("KVOUT", np.round(2.0 ** (2.0 * (a[:, 2] + 1.0)) * 256) / 256, index=ok)

    def _advance(self) -> None:
        m = self.motors
        n = self.num_envs
        task = self.fam.task
        n_pos, n_vel, load_at = self._pos_samples, self._vel_samples, self._load_at
        step_counts = self._step_counts
        m.write("V_SOLL", round(task.rpm_to_v_soll(2000.0)), index=self._ok)
        m.write("P_SOLL", step_counts, index=self._ok)
        m.write("MODE_REG", task.POSITION_MODE, index=self._ok)
        pos = np.zeros((n, n_pos))
        flw = np.zeros((n, n_pos))
        fnc_end = np.zeros(n)
        for k in range(n_pos):
            m.step(1)
            pos[:, k] = m.read_raw("P_IST")
            flw[:, k] = m.read_raw("FLWERR")
            self._trace[:, 0, k] = pos[:, k] - step_counts
            self._trace[:, 1, k] = m.speed_rpm
            self._trace[:, 2, k] = m.read_raw("VF_OUT")
        fnc_end[:] = np.abs(m.read_raw("FNCERR"))
        errors = self.error_bits() != 0
        v_ref = task.rpm_to_v_soll(1000.0) / 16.0  # counts/sample
        ok = np.flatnonzero(~errors)
        vel = np.zeros((n, n_vel))
        if ok.size:
            m.write("V_SOLL", round(task.rpm_to_v_soll(1000.0)), index=ok)
            m.write("MODE_REG", task.VELOCITY_MODE, index=ok)
        for k in range(n_vel):
            if k == load_at:
                m.set_input(load_torque=0.3 * self.rated_torque(np.arange(n)))
            m.step(1)
            vel[:, k] = m.read_raw("V_IST")
            j = n_pos + k
            self._trace[:, 0, j] = m.read_raw("P_IST") - step_counts
            self._trace[:, 1, j] = m.speed_rpm
            self._trace[:, 2, j] = m.read_raw("VF_OUT")
        errors |= self.error_bits() != 0
        err = np.abs(pos - step_counts)
        outside = err > self._settle_tol
        last_out = np.where(outside.any(axis=1),
                            n_pos - 1 - np.argmax(outside[:, ::-1], axis=1), 0)
        settle = (last_out + 1) * self.fam.constants.OUTER_DT
        overshoot = np.maximum(pos.max(axis=1) - step_counts, 0.0) / step_counts
        after = vel[:, load_at:]
        dip = np.max(np.abs(after - v_ref), axis=1) / v_ref
        ripple = np.std(vel[:, -self._ripple_samples:], axis=1) / v_ref
        unstable = errors | (ripple > 0.05) | (overshoot > 0.25) | (err[:, -10:].max(axis=1)
                                                                   > self._fail_counts)
        self.metrics = {"settling_time": settle, "overshoot": overshoot,
                        "flwerr_rms": np.sqrt(np.mean(flw * flw, axis=1)), "speed_dip": dip,
                        "speed_ripple": ripple, "fncerr": fnc_end, "unstable": unstable}

    def _termination_reasons(self, idx: np.ndarray) -> list[str]:
        """Every episode is one commissioning trial; say whether the design was unstable: per
        copy of ``idx`` ((M,) int) the code of :meth:`_reason_text`, its text kept per code."""
        codes = (self._error_bits_of(idx) << 1) | self.metrics["unstable"][idx]
        return self._kept_texts(codes.tolist(), self._reason_text, ())

    def _reason_text(self, code: int) -> str:
        """The termination reason of ``code``: bit 0 an unstable design, the bits from 1 up
        the error bits (:meth:`~jvl_gym.envs.stepping.Stepping.error_bits`)."""
        error = self._error_text(code >> 1)
        return ("trial done" + (": unstable design" if code & 1 else "")
                + (f" ({error})" if error else ""))

    def _reward_termination(self, action: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        mt = self.metrics
        cost = (mt["settling_time"] / 0.1 + 10.0 * mt["overshoot"]
                + mt["flwerr_rms"] / self._flw_scale + 2.0 * mt["speed_dip"]
                + 20.0 * mt["speed_ripple"] + mt["fncerr"] / self._fnc_scale)
        cost = np.minimum(cost, self.instability_penalty)
        mt["cost"] = np.where(mt["unstable"], self.instability_penalty, cost)
        return -mt["cost"], np.ones(self.num_envs, dtype=np.bool_)

    def _episode_stats(self, idx: np.ndarray) -> dict[str, np.ndarray]:
        """The trial's design cost, settling time, overshoot, speed dip and whether the design
        was unstable (see "Episode End")."""
        mt = self.metrics
        return {"design_cost": mt["cost"][idx], "settling_time": mt["settling_time"][idx],
                "overshoot": 100.0 * mt["overshoot"][idx],
                "speed_dip": 100.0 * mt["speed_dip"][idx],
                "unstable": mt["unstable"][idx].astype(np.float64)}

    def _observe(self) -> np.ndarray:
        onehot = np.array([[1.0 if name == t else 0.0 for t in self._types]
                           for name in self._type_names])
        est = self.estimates
        return np.concatenate([onehot, np.stack([est[:, 0] / 5.0 - 1.0, est[:, 1] * 2.0 - 1.0,
                                                 est[:, 2] * 2.0 - 1.0], axis=1)], axis=1)

    def scope_trace(self, index: int = 0) -> np.ndarray:
        """The last trial of copy ``index``: position step then velocity step, (3, T)."""
        return self._trace[index].copy()

    def _record_scope(self) -> None:
        """The trial itself is the scope record (see :meth:`scope_trace`)."""


class FilterTuningEnv(MotorEnv):
    """One commissioning trial per episode: choose the speed-loop design for an unknown load.

    ## Description
    Each episode draws a motor type and a load (inertia 0–10 × rotor, viscous and Coulomb
    friction); the agent sees the motor type and noisy estimates of the load (as an
    identification would give) and answers with a normalised speed-loop design. The env writes
    it (VF filter KVFX4/KVFX3 around the default PI, and KVOUT) and runs the standard test: a
    one-turn position step in P_MODE (V_SOLL 2000 rpm, A_SOLL from the setup, 0.31 s), then a
    1000 rpm velocity step in V_MODE with a load torque step of 30 % rated torque (0.23 s).

    ## Action Space
    ``Box(-1, 1, (3,), float32)``: proportional gain × 2^a0 and integral gain × 2^(1.5·a1)
    relative to the default setup's PI, and KVOUT = 2^(2·(a2 + 1)) (1..16).

    ## Observation Space
    ``Box(-5, 5, (7,), float32)``: motor type one-hot (MAC050, MAC095, MAC140, MAC141); inertia
    ratio estimate / 5 − 1; viscous friction estimate / 2.5e-5 − 1; Coulomb friction estimate /
    2.5 % rated − 1 (estimates with relative error ``estimate_error``).

    ## Rewards
    Minus the cost ``settling/0.1 s + 10·overshoot + FLWERR_rms/200 + 2·speed dip + 20·speed
    ripple + |FNCERR|/1000``, capped at ``instability_penalty`` (10), which is also the cost of an
    error bit, an oscillating speed, an overshoot above 25 % or a final error above 100 counts.

    ## Starting State
    The motor powers on at rest with the default setup of its type.

    ## Episode End
    Every episode is one step (terminated after the trial). Its ``info`` holds the trial's
    figures: ``design_cost`` (the cost above, the negated reward), ``settling_time`` [s] (until
    the position stays within 20 counts per 4096 of the target), ``overshoot`` [% of the
    step], ``speed_dip`` [% of 1000 rpm] at the load step, ``unstable`` (1 for an unstable
    design, else 0).

    ## Families
    MAC050–141 (default: all four types) and MAC800 (``motor_type="MAC800"``, ``"MAC400"`` or
    both): the one-hot is over the family's types; the action scales the PI in the main
    filter's leading taps KVFX6/KVFX5 (the other taps keep the setup's values); the trial's
    figures in turns and seconds (docs/envs.md); baseline: the default setup with KVOUT from
    the inertia estimate.

    ## Arguments
    ``motor_type`` (default: all four types), ``randomization`` (``inertia_ratio``,
    ``viscous_friction``, ``coulomb_ratio``), ``obs_noise``, ``render_mode`` (the trial's
    scope), ``estimate_error`` (0.1), ``instability_penalty`` (10), ``baseline`` (True: the
    registers of ``designer`` with KVOUT from the inertia estimate, else the default setup;
    the action is ignored), ``designer`` (motor type → speed-loop registers at KVOUT = 1 or
    None, e.g. ``tuning.baseline.speed_loop_registers``; default none). ``decimation`` and
    ``max_episode_steps`` have no effect.

    ## Version History
    * v0: initial version.
    """

    vector_class = FilterTuningVectorEnv
