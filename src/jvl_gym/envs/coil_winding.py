"""CoilWinding-v0: the COIL_MODE traverse laying wire on a spindle."""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np
from numba import njit, typeof, types

from ..engine.apart import apart
from ..engine.jit import KERNEL
from ..families import Capability, Family
from ..physics.fixed import rint
from . import deposition as dep
from .base import Field, MotorVectorEnv
from .compiled import action, end_step, put_obs
from .deposition import flatness_row, lay_turn_row, mean_height, profile_summary_row
from .generator_draws import uniform_rows
from .profiles import SpeedProfile, row_speed
from .single import MotorEnv
from .stepping import TERMINATED
from .task import (
    ERROR_BITS,
    R,
    Task,
    clear_records,
    coil_direction,
    record,
    reg,
    set_pulse_counts,
    set_reg,
    shaft_angle,
)

__all__ = ["CoilWindingEnv", "CoilWindingVectorEnv", "CoilWindingState"]

_GEARF2 = 10000
_GROUPS = 8  #: groups of bins in the observed profile summary
_N_FIXED_OBS = 5  #: observation components before the profile summary
_TURN_EMA = 0.25  #: weight of the newest turn in the laid-pitch averages
_TURN_OBS_SCALE = 10.0  #: laid pitch and gap (relative to d0) × 10 in the observation
_TRAVERSE_RPM = 500.0  #: rpm: scale of the traverse speed channel

#: the env's constants of the compiled step (``spindle_cpr``: spindle counts per revolution,
#: ``metres_per_rad``: traverse travel per motor radian, ``p4``: the upper flange in counts)
CONSTS = record(noise=float, max_steps=float, decimation=float, t_change=float,
                spindle_cpr=float, metres_per_rad=float, width=float, nest=float,
                pitch_trim=float, p4=float, n_layers=float, void_weight=float,
                flatness_weight=float, error_penalty=float)
#: a copy's coil (``v`` and ``x0`` carry the spindle speed and the traverse position of the
#: present outer sample from before to after the block's inner samples; ``profile_changed`` is
#: 1 when a turn was laid since the profile summary was computed)
COIL = record(d0=float, d_mean=float, d_var=float, d_freq=float, d_phase=float, time=float,
              spindle_rev=float, count_acc=float, pulses=float, floor=float, last_std=float,
              layer_void=float, layer_piles=float, step_penalty=float, gear0=float,
              half_d_counts=float, direction=float, layer=float, prev_x=float,
              laid_pitch=float, laid_gap=float, laid_slide=float, v=float, x0=float,
              profile_changed=float, voids=float)


class CoilWindingState(NamedTuple):
    """The task's state (:mod:`jvl_gym.envs.task`)."""

    consts: np.ndarray  #: (1,) :data:`CONSTS`
    profile: np.ndarray  #: (N, profile columns) the spindle speed profiles (:mod:`.profiles`)
    coil: np.ndarray  #: (N,) :data:`COIL`
    h: np.ndarray  #: (N, bins) the heights of the wound surface [m] (:mod:`.deposition`)
    centres: np.ndarray  #: (bins,) the bin centres [m]
    summary: np.ndarray  #: (N, groups) the observed profile summary


def _figures(fam: Family) -> dict[str, float]:
    """The hooks' figures on a family: the outer sample time [s] and the traverse speed scale
    in counts/sample."""
    k = fam.constants
    return {"_DT": k.OUTER_DT,
            "_V_TRAVERSE_NORM": _TRAVERSE_RPM / 60.0 * k.COUNTS_PER_REV / k.OUTER_HZ}


_DT = _V_TRAVERSE_NORM = 1.0  # bound per family by ``_figures``


@apart
@njit(**KERNEL)
def _lay_turn(x, t, h, centres, w, k):  # pragma: no cover - compiled
    """Lay a copy's turn at traverse position ``x`` [m] and time ``t`` [s] on its heights ``h``
    (its coil record ``w``, the env's constants ``k``): once per spindle revolution, so a
    function of its own, compiled apart (``engine.apart``): the step calls its machine
    code."""
    d = w.d_mean * (1.0 + w.d_var * math.sin(
        2.0 * math.pi * w.d_freq * t + w.d_phase))
    base, void, x_laid = lay_turn_row(h, centres, x, d, k.width, k.nest > 0.5)
    w.profile_changed = 1.0
    # what a camera at the laying point sees: the sideways slide of the new turn from the wire
    # guide (pushed ahead by its neighbour when the wire is thicker than the pitch) and, for
    # regular turns (spacing 0.5..1.5 d0 from the previous turn of the layer), the turn
    # spacing and the gap between the two turns (spacing − d), averaged
    d0 = w.d0
    w.laid_slide = (x_laid - x) * w.direction / d0
    spacing = abs(x_laid - w.prev_x) / d0  # NaN for the first turn of a layer
    if 0.5 < spacing < 1.5:
        w.laid_pitch += _TURN_EMA * ((spacing - 1.0) - w.laid_pitch)
        w.laid_gap += _TURN_EMA * ((spacing - d / d0) - w.laid_gap)
    w.prev_x = x_laid
    w.layer_void += void / (d * d)
    w.voids += void / (d * d)
    if base > w.floor + 0.5 * d:
        w.layer_piles += 1.0
    w.step_penalty += k.void_weight * void / (d * d)


def _spindle_before(i, view, episode, s):  # pragma: no cover - compiled
    """Outer sample of copy ``i``, before the motor: spindle speed and pulses; remembers the
    speed and the traverse position for :func:`_spindle_after`."""
    k = s.consts[0]
    w = s.coil[i]
    v = row_speed(s.profile[i], w.time, w.spindle_rev * 2.0 * math.pi, k.t_change)
    acc = w.count_acc + v * k.spindle_cpr * _DT
    counts = math.floor(acc)
    w.count_acc = acc - counts
    w.pulses += counts
    set_pulse_counts(view, i, counts)
    w.v = v
    w.x0 = shaft_angle(view, i) * k.metres_per_rad


def _spindle_after(i, view, episode, s):  # pragma: no cover - compiled
    """Outer sample of copy ``i``, after the motor: a turn is laid when the spindle completes
    a revolution, at the traverse position interpolated to that instant."""
    k = s.consts[0]
    w = s.coil[i]
    v = w.v
    x0 = w.x0
    rev0 = w.spindle_rev
    rev1 = rev0 + v * _DT
    w.spindle_rev = rev1
    if math.floor(rev1) > math.floor(rev0):
        frac = min(max((math.floor(rev0) + 1.0 - rev0) / max(v * _DT, 1e-12), 0.0), 1.0)
        x1 = shaft_angle(view, i) * k.metres_per_rad
        _lay_turn(x0 + frac * (x1 - x0), w.time + frac * _DT, s.h[i], s.centres, w, k)
    w.time += _DT


def _track_layer(i, view, w, h):  # pragma: no cover - compiled
    """A reversal of the COIL block of copy ``i`` (its coil record ``w``, its heights ``h``)
    closes a layer (:func:`_close_layer`); returns its flatness, else 0."""
    direction = coil_direction(view, i)
    if direction == 0.0:
        return 0.0
    flipped = direction != w.direction
    w.direction = direction
    if not flipped:
        return 0.0
    return _close_layer(w, h)


@apart
@njit(**KERNEL)
def _close_layer(w, h):  # pragma: no cover - compiled
    """Book and score the flatness of the layer closed on the heights ``h`` (coil record
    ``w``): once per layer, so a function of its own, compiled apart (``engine.apart``): the
    step calls its machine code."""
    std, _, _ = flatness_row(h, w.d0)
    w.last_std = std
    w.floor = mean_height(h)
    w.layer += 1.0
    w.layer_void = 0.0
    w.layer_piles = 0.0
    w.prev_x = math.nan
    return std


def _observe_row(i, view, episode, s):  # pragma: no cover - compiled
    """Observation of copy ``i`` (see the env docstring, "Observation Space"): the traverse's
    position and speed here (family names), the rest in :func:`_put_observation`."""
    k = s.consts[0]
    x = shaft_angle(view, i) * k.metres_per_rad
    _put_observation(episode.obs, episode.prev_action, i, episode.t[i], episode.noise_key[i],
                     k, s.coil[i], s.h[i], s.summary[i], 2.0 * x / k.width - 1.0,
                     reg(view, i, R.V_IST) / _V_TRAVERSE_NORM,
                     2000.0 / 60.0 * k.spindle_cpr * _DT)


@apart
@njit(**KERNEL)
def _put_observation(obs, prev, i, counter, key, k, w, h, summary, position, speed,
                     spindle_norm):  # pragma: no cover - compiled
    """Store copy ``i``'s observation in ``obs`` (N, obs) with noise (``key``, ``counter``)
    and clipping: the normalised traverse ``position`` and ``speed``, the spindle speed (its
    pulses per step over ``spindle_norm``), the coil record ``w`` and profile summary
    ``summary`` (groups,) of the heights ``h`` (recomputed when a turn was laid), the
    previous action ``prev[i]`` (env constants ``k``). Compiled once, apart
    (``engine.apart``): the end of a step and the observation after a reset call its machine
    code, instead of each optimising a copy of it again."""
    noise = k.noise
    head = (position, speed, w.pulses / k.decimation / spindle_norm, w.layer / k.n_layers,
            w.direction)
    for c in range(_N_FIXED_OBS):
        put_obs(obs, i, c, head[c], key, counter, noise)
    if w.profile_changed != 0.0:  # else summary is still that of h
        profile_summary_row(h, _GROUPS, w.d0, summary)
        w.profile_changed = 0.0
    for g in range(_GROUPS):
        put_obs(obs, i, _N_FIXED_OBS + g, summary[g], key, counter, noise)
    j = _N_FIXED_OBS + _GROUPS
    turns = (w.last_std, w.layer_void / 5.0, w.layer_piles / 5.0,
             _TURN_OBS_SCALE * w.laid_pitch, _TURN_OBS_SCALE * w.laid_gap, 2.0 * w.laid_slide)
    for c in range(len(turns)):
        put_obs(obs, i, j + c, turns[c], key, counter, noise)
    j += len(turns)
    for a in range(prev.shape[1]):
        put_obs(obs, i, j + a, prev[i, a], key, counter, noise)


def _step_begin(i, view, episode, s, actions):  # pragma: no cover - compiled
    """Beginning of an env step of copy ``i``: pitch and dwell trims, step accumulators."""
    k = s.consts[0]
    w = s.coil[i]
    a0 = action(actions, i, 0)
    a1 = action(actions, i, 1)
    a2 = action(actions, i, 2)
    half = w.half_d_counts
    set_reg(view, i, R.GEARF1, round(w.gear0 * (1.0 + k.pitch_trim * a0) * _GEARF2))
    set_reg(view, i, R.P2, round((1.0 + a1) * half))
    set_reg(view, i, R.P3, int(k.p4) - round((1.0 + a2) * half))
    w.pulses = 0.0
    w.step_penalty = 0.0


def _step_end(i, view, episode, s, actions):  # pragma: no cover - compiled
    """End of an env step of copy ``i``: layer bookkeeping, reward, termination, observation
    (the actions are clipped again: a pure function of ``actions``)."""
    k = s.consts[0]
    w = s.coil[i]
    prev, t = episode.prev_action, episode.t
    a0 = action(actions, i, 0)
    a1 = action(actions, i, 1)
    a2 = action(actions, i, 2)
    w.step_penalty += k.flatness_weight * _track_layer(i, view, w, s.h[i])
    t[i] += 1
    error = (reg(view, i, R.ERR_STAT) & ERROR_BITS) != 0
    episode.reward[i] = -w.step_penalty - (k.error_penalty if error else 0.0)
    end_step(i, error or w.layer >= k.n_layers, t, int(k.max_steps),
             episode.terminated, episode.truncated)
    prev[i, 0] = a0
    prev[i, 1] = a1
    prev[i, 2] = a2
    _observe_row(i, view, episode, s)


def _beside(env: Any) -> list[tuple[Any, tuple]]:
    """The turn and the layer's end (called by the step only, each compiled apart), with
    their argument types for ``env``'s state (``Task.beside``)."""
    s = env.state
    h, coil, k = typeof(s.h[0]), typeof(s.coil[0]), typeof(s.consts[0])
    f8 = types.float64
    return [(_lay_turn, (f8, f8, h, typeof(s.centres), coil, k)), (_close_layer, (coil, h))]


TASK = Task("coil_winding", __file__, needs={Capability.COIL_MODE}, state=CoilWindingState,
            figures=_figures, helpers={"_track_layer": _track_layer},
            begin=_step_begin, before=_spindle_before, after=_spindle_after, end=_step_end,
            observe=_observe_row, beside=_beside)


@njit(**KERNEL)
def _reset_rows(idx: np.ndarray, w: np.ndarray, h: np.ndarray, d0: np.ndarray,
                bias: np.ndarray, variation: np.ndarray, a_soll: np.ndarray, u: np.ndarray,
                counts_per_m: float, spindle_cpr: int, gearf1: np.ndarray, half: np.ndarray,
                a_soll_raw: np.ndarray) -> None:  # pragma: no cover - compiled
    """Coil state ``w`` (N,) :data:`COIL` and heights ``h`` (N, bins) of copies ``idx`` empty
    (zeroed by the caller), from
    the (M,) draws (wire diameter d0 [m], diameter bias, variation, A_SOLL) and the (M, 2)
    uniform numbers ``u`` of the diameter variation (frequency 0.05–0.3 Hz, phase); the
    nominal registers from d0 (the traverse advances d0 per spindle revolution, ``counts_per_m``
    traverse counts per metre, ``spindle_cpr`` spindle counts per revolution): GEARF1
    ``gearf1``, half a wire diameter in traverse counts ``half`` and A_SOLL rounded
    ``a_soll_raw``, (M,) each."""
    for j in range(idx.shape[0]):
        i = idx[j]
        r = w[i]
        r.d0 = d0[j]
        r.d_mean = d0[j] * (1.0 + bias[j])
        r.d_var = variation[j]
        r.d_freq = 0.05 + 0.25 * u[j, 0]
        r.d_phase = 2 * np.pi * u[j, 1]
        r.direction = 1.0
        r.prev_x = np.nan
        r.profile_changed = 1.0  # the empty profile is summarised anew
        gear = d0[j] * counts_per_m / spindle_cpr
        r.gear0 = gear
        r.half_d_counts = 0.5 * d0[j] * counts_per_m
        gearf1[j] = rint(gear * _GEARF2)
        half[j] = int(rint(r.half_d_counts))
        a_soll_raw[j] = rint(a_soll[j])


class CoilWindingVectorEnv(MotorVectorEnv):
    """Vector version of :class:`CoilWindingEnv` (same arguments plus ``num_envs`` and
    ``autoreset_mode``)."""

    task = TASK

    d0 = Field("coil")  #: nominal wire diameter [m]
    d_mean = Field("coil")  #: true mean wire diameter [m]
    d_var = Field("coil")  #: relative amplitude of the diameter variation
    d_freq = Field("coil")  #: frequency of the diameter variation [Hz]
    d_phase = Field("coil")  #: phase of the diameter variation [rad]
    time = Field("coil")  #: episode time [s]
    spindle_rev = Field("coil")  #: spindle revolutions
    count_acc = Field("coil")  #: fractional spindle counts
    pulses = Field("coil")  #: spindle counts in the last step
    floor = Field("coil")  #: mean height at the last reversal [m]
    last_std = Field("coil")  #: flatness (std / d0) at the last reversal
    layer_void = Field("coil")  #: voids of this layer [wire cross-sections]
    layer_piles = Field("coil")  #: pile-up turns of this layer
    step_penalty = Field("coil")  #: penalty of the last step
    gear0 = Field("coil")  #: nominal gear factor
    half_d_counts = Field("coil")  #: d0/2 in traverse counts
    direction = Field("coil")  #: direction of the COIL block (±1)
    layer = Field("coil")  #: layers completed
    prev_x = Field("coil")  #: where the previous turn of this layer lies [m]
    laid_pitch = Field("coil")  #: average laid turn spacing / d0 − 1
    laid_gap = Field("coil")  #: average gap between laid turns / d0
    laid_slide = Field("coil")  #: slide of the last turn from the guide / d0
    voids = Field("coil")  #: voids of the episode [wire cross-sections]

    obs_labels = ("traverse_position", "traverse_speed", "spindle_speed", "layer",
                  "direction", *(f"profile_{k}" for k in range(_GROUPS)), "last_flatness",
                  "layer_voids", "layer_pileups", "laid_pitch", "laid_gap", "laid_slide",
                  "previous_pitch_trim", "previous_p2_trim", "previous_p3_trim")
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
    episode_stats = {"layers": "layers wound", "flatness": "flatness [std/d0]",
                     "voids": "voids [d²]", "copper_loss": "copper loss [J]"}

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
        super().__init__(num_envs, **kwargs)

    def _build(self) -> None:
        n = self.num_envs
        #: traverse counts per metre
        self._counts_per_m = self.fam.constants.COUNTS_PER_REV / self.screw_pitch
        self.profile = SpeedProfile(n)
        self.h = np.zeros((n, self.centres.size))
        self.p4 = int(round(self.coil_width * self._counts_per_m))
        consts = np.zeros(1, dtype=CONSTS)
        consts[0] = (
            self.obs_noise, self.max_episode_steps, self.decimation, self.profile.t_change,
            self.spindle_counts_per_rev, self.screw_pitch / (2 * math.pi), self.coil_width,
            float(self.nest), self.pitch_trim, self.p4, self.n_layers, self.void_weight,
            self.flatness_weight, self.error_penalty)
        self.state = CoilWindingState(consts, self.profile.params, np.zeros(n, dtype=COIL),
                                      self.h, self.centres, np.zeros((n, _GROUPS)))

    def _motor_params(self, idx: np.ndarray, draws: dict[str, np.ndarray]
                      ) -> dict[str, np.ndarray]:
        return {"load_inertia": draws["inertia_ratio"] * self.rotor_inertia(idx)}

    def _task_reset(self, idx: np.ndarray, draws: dict[str, np.ndarray],
                    rngs: list[np.random.Generator]) -> None:
        u = uniform_rows(rngs, 2)
        self.profile.reset(idx, rngs, draws["spindle_rpm"] / 60.0, draws["ramp_time"],
                           draws["speed_step"], draws["step_time"], draws["walk"],
                           np.zeros(idx.size))
        gearf1, a_soll = np.empty(idx.size), np.empty(idx.size)
        half = np.empty(idx.size, dtype=np.int64)
        clear_records(self.state.coil, idx)
        self.h[idx] = 0.0
        _reset_rows(idx, self.state.coil, self.h, draws["wire_diameter"], draws["diameter_bias"],
                    draws["diameter_variation"], draws["a_soll"], u, self._counts_per_m,
                    self.spindle_counts_per_rev, gearf1, half, a_soll)
        fam = self.fam
        self.motors.write_many({
            "GEARF1": gearf1, "GEARF2": _GEARF2, "V_SOLL": round(fam.task.rpm_to_v_soll(3000.0)),
            "A_SOLL": a_soll, "P1": 0, "P2": half, "P3": self.p4 - half, "P4": self.p4,
            "P5": half, "P6": 1, "MODE_REG": fam.constants.COIL_MODE}, idx)

    def _episode_stats(self, idx: np.ndarray) -> dict[str, np.ndarray]:
        """Layers wound, flatness of the final surface, voids, copper loss (see "Episode
        End") of the copies ``idx`` ((M,) int), each (M,)."""
        h, flatness_row = self.h, dep.flatness_row
        flat = np.array([flatness_row(h[i], d)[0]
                         for i, d in zip(idx.tolist(), self.d0[idx].tolist())])
        return {"layers": self.layer[idx], "flatness": flat.reshape(idx.size),
                "voids": self.voids[idx], "copper_loss": self.copper_loss(idx)}

    def _termination_reasons(self, idx: np.ndarray) -> list[str]:
        """The coil is complete (all layers wound) or a motor error bit is set: per copy of
        ``idx`` ((M,) int) the key of :meth:`_reason_text`, its text kept per key."""
        complete = self.layer[idx] >= self.n_layers
        keys = zip(complete.tolist(), self._error_bits_of(idx).tolist())
        return self._kept_texts(list(keys), self._reason_text, (self.n_layers,))

    def _reason_text(self, key: tuple[bool, int]) -> str:
        """The termination reason of ``key``: (the coil complete, error bits
        (:meth:`~jvl_gym.envs.stepping.Stepping.error_bits`)), '; ' between them."""
        complete, bits = key
        done = f"coil complete: {self.n_layers} layers wound" if complete else ""
        return "; ".join(t for t in (done, self._error_text(bits)) if t) or TERMINATED

    def traverse_position(self) -> np.ndarray:
        """Traverse position from the lower flange [m], (N,)."""
        return self.motors.position_rad / (2 * math.pi) * self.screw_pitch

    def _scope_values(self) -> np.ndarray:
        dt = self.fam.constants.OUTER_DT
        return np.stack([self.traverse_position() * 1e3, self.pulses / self.decimation / dt
                         / self.spindle_counts_per_rev * 60.0, self.layer,
                         self.last_std], axis=1)


class CoilWindingEnv(MotorEnv):
    """The COIL_MODE traverse of a coil winder: lay flat layers between the flanges.

    ## Description
    A spindle (pulse output 1024 counts/rev) winds wire on a coil of width 20 mm between two
    flanges; a MAC motor drives the traverse through a lead screw (2 mm/rev) in COIL_MODE
    (manual 4.4.20, ``mac050_141.firmware.coil``): it follows the spindle pulses with the gear
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
    ``max_episode_steps`` (1500 steps = 11.5 s at the default decimation 4). The last step's
    ``info`` holds the episode's statistics: ``layers`` wound, ``flatness`` (std of the final
    surface's height / d0), ``voids`` (void area under every turn laid, in wire
    cross-sections d²) and ``copper_loss`` [J], the traverse motor's copper loss in the
    episode.

    ## Families
    MAC050–141 only: ``motor_type="MAC800"`` (or ``"MAC400"``) is refused, since the MAC800
    register overview gives no registers for mode 19 (Coil) and the family does not model it.

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
