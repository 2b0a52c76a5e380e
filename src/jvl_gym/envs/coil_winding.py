"""CoilWinding-v0: the COIL_MODE traverse laying wire on a spindle."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import njit

from .. import constants as c
from .. import layout as L
from ..firmware import regs as R
from ..kernel import run_serial
from . import deposition as dep
from .base import MotorVectorEnv
from .profiles import SpeedProfile, row_speed
from .single import MotorEnv

__all__ = ["CoilWindingEnv", "CoilWindingVectorEnv"]

_DT = c.OUTER_DT
_GEARF2 = 10000
_GROUPS = 8  #: groups of bins in the observed profile summary
_V_TRAVERSE_NORM = 500.0 / 60.0 * c.COUNTS_PER_REV / c.OUTER_HZ  #: 500 rpm in counts/sample
_PARALLEL_MIN = 32  #: from this many copies the motor kernel runs multi-threaded (MotorArray)
_TURN_EMA = 0.25  #: weight of the newest turn in the laid-pitch averages
_TURN_OBS_SCALE = 10.0  #: laid pitch and gap (relative to d0) × 10 in the observation


@njit(cache=True)
def _spindle_pre(inputs, state, prof, t_change, time, spindle_rev, count_acc, pulses,
                 counts_per_rev, metres_per_rad, x0, rps):  # pragma: no cover - compiled
    """Before an outer sample: spindle speed and pulses, traverse position."""
    for i in range(inputs.shape[0]):
        v = row_speed(prof[i], time[i], spindle_rev[i] * 2.0 * math.pi, t_change)
        rps[i] = v
        acc = count_acc[i] + v * counts_per_rev * _DT
        counts = math.floor(acc)
        count_acc[i] = acc - counts
        pulses[i] += counts
        inputs[i, L.I_PULSE_COUNTS] = counts
        x0[i] = state[i, L.S_THETA] * metres_per_rad


@njit(cache=True)
def _spindle_post(state, k, time, spindle_rev, metres_per_rad, x0, rps, turn_x,
                  turn_t):  # pragma: no cover - compiled
    """After outer sample ``k``: record where a turn is laid when a revolution completes.

    A turn is laid when the spindle completes a revolution; its position is the traverse
    position interpolated to that instant. ``turn_x[i, k]`` / ``turn_t[i, k]`` get its
    position and time (NaN when none).
    """
    for i in range(state.shape[0]):
        rev0 = spindle_rev[i]
        rev1 = rev0 + rps[i] * _DT
        spindle_rev[i] = rev1
        turn_x[i, k] = math.nan
        turn_t[i, k] = math.nan
        if math.floor(rev1) > math.floor(rev0):
            frac = min(max((math.floor(rev0) + 1.0 - rev0) / max(rps[i] * _DT, 1e-12), 0.0),
                       1.0)
            x1 = state[i, L.S_THETA] * metres_per_rad
            turn_x[i, k] = x0[i] + frac * (x1 - x0[i])
            turn_t[i, k] = time[i] + frac * _DT
        time[i] += _DT


@njit(cache=True)
def _advance_spindle_serial(regs, state, params, inputs, keys, buf, rec, fmt, plan, decimation,
                            prof, t_change, time, spindle_rev, count_acc, pulses,
                            counts_per_rev, metres_per_rad, turn_x,
                            turn_t):  # pragma: no cover - compiled
    """``decimation`` outer samples of spindle and motor in one compiled call (few copies;
    see ``gear_sync._advance_line_serial`` for why the parallel kernel is not called here)."""
    n = regs.shape[0]
    x0 = np.empty(n)
    rps = np.empty(n)
    for k in range(decimation):
        _spindle_pre(inputs, state, prof, t_change, time, spindle_rev, count_acc, pulses,
                     counts_per_rev, metres_per_rad, x0, rps)
        run_serial(regs, state, params, inputs, keys, buf, rec, fmt, 1, plan)
        _spindle_post(state, k, time, spindle_rev, metres_per_rad, x0, rps, turn_x, turn_t)


class CoilWindingVectorEnv(MotorVectorEnv):
    """Vector version of :class:`CoilWindingEnv` (same arguments plus ``num_envs`` and
    ``autoreset_mode``)."""

    obs_labels = ("traverse_position", "traverse_speed", "spindle_speed", "layer",
                  "direction", *(f"profile_{k}" for k in range(_GROUPS)), "last_flatness",
                  "layer_voids", "layer_pileups", "laid_pitch", "laid_gap", "laid_slide",
                  "previous_pitch_trim", "previous_p2_trim",
                  "previous_p3_trim")
    act_labels = ("pitch_trim", "p2_trim", "p3_trim")
    default_ranges = {
        "wire_diameter": (0.4e-3, 0.6e-3),  # nominal d0 [m]
        "diameter_bias": (-0.04, 0.04),  # true mean diameter = d0·(1 + bias)
        "diameter_variation": (0.0, 0.03),  # slow relative variation amplitude
        "spindle_rpm": (1000.0, 2400.0),
        "ramp_time": (0.2, 1.0),
        "speed_step": (-0.4, 0.4),
        "step_time": (2.0, 6.0),
        "walk": (0.0, 0.05),
        "a_soll": (20.0, 160.0),  # traverse acceleration A_SOLL [1/16 count/sample²]
        "inertia_ratio": (0.0, 3.0),
    }
    default_decimation = 4
    default_max_episode_steps = 1500
    scope_channels = ("traverse x [mm]", "spindle [rpm]", "layer", "flatness std/d")

    def __init__(self, num_envs: int = 1, *, coil_width: float = 20e-3,
                 screw_pitch: float = 2e-3, spindle_counts_per_rev: int = 1024,
                 n_layers: int = 4, pitch_trim: float = 0.05, bin_width: float = 0.05e-3,
                 void_weight: float = 1.0, flatness_weight: float = 5.0,
                 error_penalty: float = 50.0, nest: bool = True,
                 **kwargs: Any) -> None:
        if min(coil_width, screw_pitch, bin_width) <= 0 or spindle_counts_per_rev <= 0:
            raise ValueError("coil_width, screw_pitch, bin_width, spindle_counts_per_rev > 0")
        if n_layers < 1:
            raise ValueError("n_layers must be >= 1")
        self.coil_width = float(coil_width)
        self.screw_pitch = float(screw_pitch)
        self.spindle_counts_per_rev = int(spindle_counts_per_rev)
        self.n_layers = int(n_layers)
        self.pitch_trim = float(pitch_trim)
        self.void_weight = float(void_weight)
        self.nest = bool(nest)
        self.flatness_weight = float(flatness_weight)
        self.error_penalty = float(error_penalty)
        self.centres = dep.bin_centres(self.coil_width, float(bin_width))
        self._counts_per_m = c.COUNTS_PER_REV / self.screw_pitch
        super().__init__(num_envs, **kwargs)

    def _build(self) -> None:
        n = self.num_envs
        self.profile = SpeedProfile(n)
        self.h = np.zeros((n, self.centres.size))
        for name in ("d0", "d_mean", "d_var", "d_freq", "d_phase", "time", "spindle_rev",
                     "count_acc", "pulses", "floor", "last_std", "layer_void", "step_penalty",
                     "gear0", "half_d_counts", "direction", "prev_x", "laid_pitch",
                     "laid_gap", "laid_slide"):
            setattr(self, name, np.zeros(n))
        self.layer = np.zeros(n, dtype=np.int64)
        self.layer_piles = np.zeros(n)
        self.p4 = int(round(self.coil_width * self._counts_per_m))
        self._turn_x = np.zeros((n, self.decimation))
        self._turn_t = np.zeros((n, self.decimation))

    def _motor_params(self, idx: np.ndarray, draws: dict[str, np.ndarray]
                      ) -> dict[str, np.ndarray]:
        return {"load_inertia": draws["inertia_ratio"] * self.rotor_inertia(idx)}

    def _task_reset(self, idx: np.ndarray, draws: dict[str, np.ndarray],
                    rngs: list[np.random.Generator]) -> None:
        d0 = draws["wire_diameter"]
        self.d0[idx] = d0
        self.d_mean[idx] = d0 * (1.0 + draws["diameter_bias"])
        self.d_var[idx] = draws["diameter_variation"]
        u = np.array([rng.random(2) for rng in rngs]).reshape(idx.size, 2)
        self.d_freq[idx] = 0.05 + 0.25 * u[:, 0]
        self.d_phase[idx] = 2 * np.pi * u[:, 1]
        self.profile.reset(idx, rngs, draws["spindle_rpm"] / 60.0, draws["ramp_time"],
                           draws["speed_step"], draws["step_time"], draws["walk"],
                           np.zeros(idx.size))
        for name in ("time", "spindle_rev", "count_acc", "pulses", "floor", "last_std",
                     "layer_void", "layer_piles", "step_penalty", "laid_pitch", "laid_gap",
                     "laid_slide"):
            getattr(self, name)[idx] = 0.0
        self.prev_x[idx] = np.nan
        self.h[idx] = 0.0
        self.layer[idx] = 0
        self.direction[idx] = 1.0
        # nominal registers from d0: the traverse advances d0 per spindle revolution
        gear = d0 * self._counts_per_m / self.spindle_counts_per_rev
        self.gear0[idx] = gear
        self.half_d_counts[idx] = 0.5 * d0 * self._counts_per_m
        half = np.round(self.half_d_counts[idx]).astype(np.int64)
        m = self.motors
        m.write("GEARF1", np.round(gear * _GEARF2), index=idx)
        m.write("GEARF2", _GEARF2, index=idx)
        m.write("V_SOLL", round(c.rpm_to_v_soll(3000.0)), index=idx)
        m.write("A_SOLL", np.round(draws["a_soll"]), index=idx)
        m.write("P1", 0, index=idx)
        m.write("P2", half, index=idx)
        m.write("P3", self.p4 - half, index=idx)
        m.write("P4", self.p4, index=idx)
        m.write("P5", half, index=idx)
        m.write("P6", 1, index=idx)
        m.write("MODE_REG", c.COIL_MODE, index=idx)

    def _apply_action(self, action: np.ndarray) -> None:
        r = self.motors.regs
        r[:, R.GEARF1] = np.round(self.gear0 * (1.0 + self.pitch_trim * action[:, 0]) * _GEARF2)
        r[:, R.P2] = np.round((1.0 + action[:, 1]) * self.half_d_counts)
        r[:, R.P3] = self.p4 - np.round((1.0 + action[:, 2]) * self.half_d_counts)

    def traverse_position(self) -> np.ndarray:
        """Traverse position from the lower flange [m], (N,)."""
        return self.motors.state[:, L.S_THETA] / (2 * math.pi) * self.screw_pitch

    def wire_diameter(self, t: np.ndarray | None = None, idx: np.ndarray | None = None
                      ) -> np.ndarray:
        """Wire diameter [m] at time ``t`` (default: now) of copies ``idx`` (default: all)."""
        sel = slice(None) if idx is None else idx
        t = self.time[sel] if t is None else t
        return self.d_mean[sel] * (1.0 + self.d_var[sel] * np.sin(
            2 * np.pi * self.d_freq[sel] * t + self.d_phase[sel]))

    def _advance(self) -> None:
        m = self.motors
        self.pulses[:] = 0.0
        self.step_penalty[:] = 0.0
        prof, tc = self.profile.params, self.profile.t_change
        cpr, mpr = float(self.spindle_counts_per_rev), self.screw_pitch / (2 * math.pi)
        if self.num_envs < _PARALLEL_MIN:
            _advance_spindle_serial(m.regs, m.state, m.params, m.inputs, m.keys, m._buf,
                                    m._buf_allocated, m._fmt, m._no_schedule, self.decimation,
                                    prof, tc, self.time, self.spindle_rev, self.count_acc,
                                    self.pulses, cpr, mpr, self._turn_x, self._turn_t)
        else:
            x0 = np.empty(self.num_envs)
            rps = np.empty(self.num_envs)
            for k in range(self.decimation):
                _spindle_pre(m.inputs, m.state, prof, tc, self.time, self.spindle_rev,
                             self.count_acc, self.pulses, cpr, mpr, x0, rps)
                m.step(1)
                _spindle_post(m.state, k, self.time, self.spindle_rev, mpr, x0, rps,
                              self._turn_x, self._turn_t)
        for k in range(self.decimation):  # turns in the order they were laid
            idx = np.flatnonzero(~np.isnan(self._turn_x[:, k]))
            if idx.size:
                self._lay(idx, self._turn_x[idx, k], self._turn_t[idx, k])
        self._track_layers()

    def _lay(self, idx: np.ndarray, x: np.ndarray, t: np.ndarray) -> None:
        d = self.wire_diameter(t, idx)
        base, void, x_laid = dep.lay_turns(self.h, self.centres, idx, x, d, self.coil_width,
                                           nest=self.nest)
        d0 = self.d0[idx]
        # what a camera at the laying point sees: the sideways slide of the new turn from the
        # wire guide (pushed ahead by its neighbour when the wire is thicker than the pitch)
        # and, for regular turns (spacing 0.5..1.5 d0 from the previous turn of the layer),
        # the turn spacing and the gap between the two turns (spacing − d), averaged
        self.laid_slide[idx] = (x_laid - x) * self.direction[idx] / d0
        spacing = np.abs(x_laid - self.prev_x[idx]) / d0  # NaN for the first turn of a layer
        regular = (spacing > 0.5) & (spacing < 1.5)
        for name, value in (("laid_pitch", spacing - 1.0), ("laid_gap", spacing - d / d0)):
            avg = getattr(self, name)
            avg[idx] = np.where(regular, avg[idx] + _TURN_EMA * (value - avg[idx]), avg[idx])
        self.prev_x[idx] = x_laid
        self.layer_void[idx] += void / (d * d)
        self.layer_piles[idx] += base > self.floor[idx] + 0.5 * d
        self.step_penalty[idx] += self.void_weight * void / (d * d)

    def _track_layers(self) -> None:
        direction = self.motors.state[:, L.S_AUX1]
        flipped = (direction != self.direction) & (direction != 0.0)
        self.direction[:] = np.where(direction != 0.0, direction, self.direction)
        if flipped.any():
            idx = np.flatnonzero(flipped)
            std, _, _ = dep.layer_flatness(self.h, idx, self.d0[idx])
            self.last_std[idx] = std
            self.step_penalty[idx] += self.flatness_weight * std
            self.floor[idx] = self.h[idx].mean(axis=1)
            self.layer[idx] += 1
            self.layer_void[idx] = 0.0
            self.layer_piles[idx] = 0.0
            self.prev_x[idx] = np.nan

    def _reward_termination(self, action: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        error = self.error_bits() != 0
        reward = -self.step_penalty - self.error_penalty * error
        return reward, error | (self.layer >= self.n_layers)

    def _observe(self) -> np.ndarray:
        r = self.motors.regs
        x = self.traverse_position()
        spindle_norm = 2000.0 / 60.0 * self.spindle_counts_per_rev * _DT
        return np.concatenate([
            np.stack([2.0 * x / self.coil_width - 1.0, r[:, R.V_IST] / _V_TRAVERSE_NORM,
                      self.pulses / self.decimation / spindle_norm,
                      self.layer / self.n_layers, self.direction], axis=1),
            dep.profile_summary(self.h, _GROUPS, self.d0),
            np.stack([self.last_std, self.layer_void / 5.0, self.layer_piles / 5.0,
                      _TURN_OBS_SCALE * self.laid_pitch, _TURN_OBS_SCALE * self.laid_gap,
                      2.0 * self.laid_slide], axis=1),
            self._prev_action,
        ], axis=1)

    def _scope_values(self) -> np.ndarray:
        return np.stack([self.traverse_position() * 1e3, self.pulses / self.decimation / _DT
                         / self.spindle_counts_per_rev * 60.0, self.layer.astype(float),
                         self.last_std], axis=1)


class CoilWindingEnv(MotorEnv):
    """The COIL_MODE traverse of a coil winder: lay flat layers between the flanges.

    ## Description
    A spindle (pulse output 1024 counts/rev) winds wire on a coil of width 20 mm between two
    flanges; a MAC motor drives the traverse through a lead screw (2 mm/rev) in COIL_MODE
    (manual 4.4.20, ``jvl_gym.firmware.coil``): it follows the spindle pulses with the gear
    factor GEARF1/GEARF2, reverses at the thread positions P1/P4 (the flanges) and dwells at the
    stop positions P2/P3. The nominal registers are computed from the nominal wire diameter d0:
    the traverse advances d0 per spindle revolution and dwells one turn at each flange
    (P2 = P1 + d0/2, P3 = P4 − d0/2). The real wire is ``d0·(1 + bias)`` with a slow variation,
    the spindle speed runs up, changes and wanders, and the traverse brakes with a finite
    A_SOLL, so turns bunch at the reversals. Every spindle revolution lays one turn at the
    traverse position on a height profile of the coil (``jvl_gym.envs.deposition``).

    ## Action Space
    ``Box(-1, 1, (3,), float32)``: pitch trim (gear factor × (1 + 0.05·a0)), dwell trims of
    P2 and P3 (stop position = flange ± (1 + a)·d0/2, i.e. a dwell of 0..2 turns), written to
    the registers every step.

    ## Observation Space
    ``Box(-5, 5, (22,), float32)``: traverse position (−1..1 across the width), traverse speed
    V_IST / 500 rpm, spindle speed / 2000 rpm, layer / n_layers, direction of the COIL block
    (±1), the mean height of 8 groups across the width minus the overall mean (/ d0), the
    flatness (std / d0) at the last reversal, voids (/ 5 wire cross-sections) and pile-up turns
    (resting above the layer floor + d/2, / 5) of the present layer, what a camera at the
    laying point sees of the laid turns (below), and the previous action.

    Laid turns: when a turn of diameter d is laid at ``x_laid`` (after nesting) while the
    traverse is at ``x``, with ``s = |x_laid − x_prev| / d0`` the spacing from the previous
    turn of the same layer, and only for regular turns (0.5 < s < 1.5; not the first turn of a
    layer, dwell turns or climbs), the averages ``pitch ← pitch + 0.25·((s − 1) − pitch)`` and
    ``gap ← gap + 0.25·((s − d/d0) − gap)`` are updated (both 0 at reset); every turn sets
    ``slide = (x_laid − x)·direction / d0``. Observed: ``laid_pitch = 10·pitch``,
    ``laid_gap = 10·gap`` (open gaps between turns > 0) and ``laid_slide = 2·slide`` (turns
    pushed ahead by their neighbour > 0), held between turns. Their difference
    ``laid_pitch − laid_gap = 10·(d/d0 − 1)`` reveals the true wire diameter.

    ## Rewards
    Per step, minus: ``void_weight`` × void area under the turns laid (gaps, in wire
    cross-sections d²), ``flatness_weight`` × std of the height profile / d0 at each reversal
    (pile-ups and gaps, especially at the flanges), and ``error_penalty`` on a motor error bit.

    ## Starting State
    An empty coil; the spindle at rest; the motor powers on with the default setup and enters
    COIL_MODE with the nominal registers, V_SOLL 3000 rpm and A_SOLL from ``a_soll``, starting
    at P5 = P2 in the direction P6 = +1. Wire, spindle profile and traverse are drawn from
    ``wire_diameter``, ``diameter_bias``, ``diameter_variation``, ``spindle_rpm``,
    ``ramp_time``, ``speed_step``, ``step_time``, ``walk``, ``a_soll``, ``inertia_ratio``.

    ## Episode End
    Terminated when ``n_layers`` (4) layers are wound or on a motor error bit; truncated after
    ``max_episode_steps`` (1500 steps = 11.5 s at the default decimation 4).

    ## Arguments
    ``motor_type``, ``randomization``, ``decimation`` (4), ``obs_noise``,
    ``max_episode_steps``, ``render_mode``, ``coil_width`` (20 mm), ``screw_pitch`` (2 mm),
    ``spindle_counts_per_rev`` (1024), ``n_layers`` (4), ``pitch_trim`` (0.05),
    ``bin_width`` (0.05 mm), ``void_weight`` (1), ``flatness_weight`` (5),
    ``error_penalty`` (50), ``nest`` (True: turns slide into the lowest place within ±d/2).
    Reset options: ``randomization``, ``motor_type``. Baseline: the zero action (firmware
    COIL_MODE, nominal registers).

    ## Version History
    * v0: initial version; the laid-turn observations (``laid_pitch``, ``laid_gap``,
      ``laid_slide``: 19 → 22 observations) were added before the RL results of docs/envs.md.
    """

    vector_class = CoilWindingVectorEnv
