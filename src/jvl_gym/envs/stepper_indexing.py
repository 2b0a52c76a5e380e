"""StepperIndexing-v0: a sequence of indexing moves of an MIS step motor, fast and without
losing steps."""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np
from numba import njit

from ..engine.jit import KERNEL
from ..families import Capability, Family
from ..physics.fixed import rint
from .base import Field, MotorVectorEnv
from .compiled import action, end_step, put_obs
from .single import MotorEnv
from .task import (
    ERROR_BITS,
    R,
    Task,
    c,
    copper_energy,
    lost_steps,
    record,
    reg,
    rotor_speed,
    set_reg,
)

__all__ = ["StepperIndexingEnv", "StepperIndexingVectorEnv", "StepperIndexingState"]

#: V_SOLL range of the action [RPM]: a0 = −1 … 1 maps linearly onto it
_RPM_LOW, _RPM_HIGH = 30.0, 1500.0
#: A_SOLL range of the action [RPM/s]: a1 = −1 … 1 maps log-linearly onto it
_ACC_LOW, _ACC_HIGH = 500.0, 100000.0
#: RUN_CURRENT range of the action as a fraction of the type's largest setting
_CUR_LOW, _CUR_HIGH = 0.1, 1.0
#: rotor speed below which a finished profile counts as settled [rad/s]
_SETTLED_RAD_S = 0.5

#: the env's constants of the compiled step
CONSTS = record(noise=float, max_steps=float, time_weight=float, copper_weight=float,
                move_bonus=float, lost_penalty=float, baseline=float, n_moves=float)
#: a copy's moves: P_SOLL of the present move [counts], the counts per move, the moves left,
#: the type's largest RUN_CURRENT setting, the copper energy at the end of the last step [J]
COPY = record(target=np.int64, move=np.int64, moves_left=np.int64, i_max=float, energy=float)


#: the figures of a motor type a reset reads (``StepperIndexingVectorEnv._type_figures``)
_FIGURES = ("rotor_inertia", "holding_torque", "run_current_max")


class StepperIndexingState(NamedTuple):
    """The task's state (:mod:`jvl_gym.envs.task`)."""

    consts: np.ndarray  #: (1,) :data:`CONSTS`
    copies: np.ndarray  #: (N,) :data:`COPY`


def _figures(fam: Family) -> dict[str, float]:
    """The hooks' figures on a family: the speed scale of the observation, 1500 RPM in V_IST
    units."""
    return {"_V_NORM": _RPM_HIGH / fam.constants.VELOCITY_RPM_PER_UNIT}


_V_NORM = 1.0  # bound per family by ``_figures``


def _observe_row(i, view, episode, s):  # pragma: no cover - compiled
    """Observation of copy ``i`` (see the env docstring, "Observation Space")."""
    k = s.consts[0]
    row = s.copies[i]
    obs, key, count, noise = episode.obs, episode.noise_key[i], episode.t[i], k.noise
    put_obs(obs, i, 0, (row.target - reg(view, i, R.P_IST)) / row.move, key, count, noise)
    put_obs(obs, i, 1, row.move / c.COUNTS_PER_REV, key, count, noise)
    put_obs(obs, i, 2, reg(view, i, R.V_IST) / _V_NORM, key, count, noise)
    put_obs(obs, i, 3, reg(view, i, R.FLWERR) / c.COUNTS_PER_FULL_STEP, key, count, noise)
    put_obs(obs, i, 4, row.moves_left / k.n_moves, key, count, noise)
    for a in range(3):
        put_obs(obs, i, 5 + a, episode.prev_action[i, a], key, count, noise)


def _step_begin(i, view, episode, s, actions):  # pragma: no cover - compiled
    """Beginning of an env step of copy ``i``: the profile registers (unless baseline)."""
    if s.consts[0].baseline > 0.5:
        return
    rpm = _RPM_LOW + 0.5 * (action(actions, i, 0) + 1.0) * (_RPM_HIGH - _RPM_LOW)
    acc = _ACC_LOW * (_ACC_HIGH / _ACC_LOW) ** (0.5 * (action(actions, i, 1) + 1.0))
    cur = _CUR_LOW + 0.5 * (action(actions, i, 2) + 1.0) * (_CUR_HIGH - _CUR_LOW)
    set_reg(view, i, R.V_SOLL, int(round(rpm / c.VELOCITY_RPM_PER_UNIT)))
    set_reg(view, i, R.A_SOLL, int(round(acc)))
    set_reg(view, i, R.RUN_CURRENT, int(round(cur * s.copies[i].i_max)))


def _step_end(i, view, episode, s, actions):  # pragma: no cover - compiled
    """End of an env step of copy ``i``: the next move when this one has settled, reward,
    termination, observation."""
    k = s.consts[0]
    row = s.copies[i]
    t = episode.t
    t[i] += 1
    reward = -k.time_weight
    settled = (reg(view, i, R.P_IST) == row.target
               and abs(rotor_speed(view, i)) < _SETTLED_RAD_S)
    if settled and row.moves_left > 0:
        row.moves_left -= 1
        reward += k.move_bonus
        if row.moves_left > 0:
            row.target += row.move
            set_reg(view, i, R.P_SOLL, row.target)
    e_cu = copper_energy(view, i)
    reward -= k.copper_weight * (e_cu - row.energy)
    row.energy = e_cu
    lost = lost_steps(view, i) != 0
    if lost:
        reward -= k.lost_penalty
    error = (reg(view, i, R.ERR_BITS) & ERROR_BITS) != 0
    episode.reward[i] = reward
    end_step(i, lost or error or row.moves_left == 0, t, int(k.max_steps), episode.terminated,
             episode.truncated)
    for a in range(3):
        episode.prev_action[i, a] = action(actions, i, a)
    _observe_row(i, view, episode, s)


TASK = Task("stepper_indexing", __file__, needs={Capability.STEP_INDEXING},
            state=StepperIndexingState, figures=_figures, begin=_step_begin, end=_step_end,
            observe=_observe_row)


@njit(**KERNEL)
def _reset_rows(idx: np.ndarray, move_turns: np.ndarray, n_moves: int, i_max: np.ndarray,
                copies: np.ndarray, counts_per_rev: int,
                targets: np.ndarray) -> None:  # pragma: no cover - compiled
    """Moves [counts] of copies ``idx`` from the (M,) draws [turns]: the first target (also
    into ``targets`` (M,)), the moves left, the type's largest RUN_CURRENT setting ``i_max``
    (M,), the copper energy counted from power-on (0)."""
    for j in range(idx.shape[0]):
        row = copies[idx[j]]
        row.move = max(int(rint(move_turns[j] * counts_per_rev)), 1)
        row.target = row.move
        row.moves_left = n_moves
        row.i_max = i_max[j]
        row.energy = 0.0
        targets[j] = row.target


class StepperIndexingVectorEnv(MotorVectorEnv):
    """Vector version of :class:`StepperIndexingEnv` (same arguments plus ``num_envs`` and
    ``autoreset_mode``)."""

    task = TASK
    #: the register of the error bits in the family's ``TERMINAL_ERRORS`` (MIS manual §11.4)
    error_register = "ERR_BITS"
    target = Field()  #: P_SOLL of the present move [counts]
    move = Field()  #: counts per move
    moves_left = Field()  #: moves left

    obs_labels = ("distance_to_go", "move_length", "profile_speed", "rotor_lag",
                  "moves_left", "previous_speed", "previous_acceleration", "previous_current")
    act_labels = ("speed", "acceleration", "current")
    default_ranges = {
        "inertia_ratio": (0.0, 20.0),
        "coulomb_ratio": (0.0, 0.1),
        "load_torque_ratio": (0.0, 0.6),
        "move_turns": (0.1, 0.5),
    }
    default_decimation = 2
    default_max_episode_steps = 1000
    scope_channels = ("distance to go [turns]", "speed [rpm]", "lag [full steps]")
    episode_stats = {"lost_steps": "lost full steps", "moves_done": "moves done",
                     "copper_loss": "copper loss [J]"}

    def __init__(self, num_envs: int = 1, *, baseline: bool = False, n_moves: int = 3,
                 time_weight: float = 0.05, copper_weight: float = 0.1, move_bonus: float = 1.0,
                 lost_penalty: float = 10.0, **kwargs: Any) -> None:
        self.baseline = bool(baseline)
        if isinstance(n_moves, bool) or not isinstance(n_moves, (int, np.integer)) or n_moves < 1:
            raise ValueError(f"n_moves must be an integer >= 1, got {n_moves!r}")
        self.n_moves = int(n_moves)
        weights = {"time_weight": time_weight, "copper_weight": copper_weight,
                   "move_bonus": move_bonus, "lost_penalty": lost_penalty}
        for name, value in weights.items():
            if isinstance(value, bool) or not np.isfinite(value) or value < 0:
                raise ValueError(f"{name} must be a finite number >= 0, got {value!r}")
        self.weights = {name: float(v) for name, v in weights.items()}
        super().__init__(num_envs, **kwargs)

    def _build(self) -> None:
        consts = np.zeros(1, dtype=CONSTS)
        w = self.weights
        consts[0] = (self.obs_noise, self.max_episode_steps, w["time_weight"],
                     w["copper_weight"], w["move_bonus"], w["lost_penalty"],
                     float(self.baseline), self.n_moves)
        copies = np.zeros(self.num_envs, dtype=COPY)
        copies["move"] = 1
        self.state = StepperIndexingState(consts, copies)
        self._figures_of_type: dict[str, tuple[float, ...]] = {}

    def _type_figures(self, idx: np.ndarray) -> np.ndarray:
        """The rotor inertia [kg·m²], the holding torque at the largest current [N·m] and the
        largest RUN_CURRENT setting of the motor types of copies ``idx`` (set at their reset),
        (M, 3) (:data:`_FIGURES`, kept per type name)."""
        known = self._figures_of_type
        names = self._type_names[idx].tolist()
        try:
            rows = [known[name] for name in names]
        except KeyError:  # a type's first reset
            for name, cfg in zip(names, self._type_configs(idx)):
                known[name] = tuple(float(getattr(cfg, figure)) for figure in _FIGURES)
            rows = [known[name] for name in names]
        return np.array(rows).reshape(idx.size, len(_FIGURES))

    def _motor_params(self, idx: np.ndarray, draws: dict[str, np.ndarray]
                      ) -> dict[str, np.ndarray]:
        figures = self._type_figures(idx)
        return {"load_inertia": draws["inertia_ratio"] * figures[:, 0],
                "coulomb_friction": draws["coulomb_ratio"] * figures[:, 1]}

    def _task_reset(self, idx: np.ndarray, draws: dict[str, np.ndarray],
                    rngs: list[np.random.Generator]) -> None:
        figures = self._type_figures(idx)
        targets = np.empty(idx.size, dtype=np.int64)
        _reset_rows(idx, draws["move_turns"], self.n_moves, figures[:, 2], self.state.copies,
                    self.fam.constants.COUNTS_PER_REV, targets)
        self.motors.set_input(idx, load_torque=draws["load_torque_ratio"] * figures[:, 1])
        # D_SOLL = 0: the profile decelerates with A_SOLL too (MIS manual §8.2.1, D_SOLL), so
        # the agent's acceleration shapes the whole trapezoid
        self.motors.write_many({"D_SOLL": 0, "P_SOLL": targets,
                                "MODE_REG": self.fam.constants.POSITION}, idx)

    def _episode_stats(self, idx: np.ndarray) -> dict[str, np.ndarray]:
        """Full steps lost, moves done, copper loss (see "Episode End")."""
        return {"lost_steps": np.abs(self.motors.lost_steps[idx]).astype(np.float64),
                "moves_done": (self.n_moves - self.moves_left[idx]).astype(np.float64),
                "copper_loss": self.copper_loss(idx)}

    def _termination_reasons(self, idx: np.ndarray) -> list[str]:
        """All moves done, full steps lost or a motor error bit set: per copy of ``idx`` ((M,)
        int) the key of :meth:`_reason_text`, its text kept per key."""
        keys = zip((self.moves_left[idx] == 0).tolist(), self.motors.lost_steps[idx].tolist(),
                   self._error_bits_of(idx).tolist())
        return self._kept_texts(list(keys), self._reason_text, ())

    def _reason_text(self, key: tuple[bool, int, int]) -> str:
        """The termination reason of ``key``: (no move left, full steps lost, error bits
        (:meth:`~jvl_gym.envs.stepping.Stepping.error_bits`)); steps lost before an error."""
        done, lost, bits = key
        error = self._error_text(bits)
        return ("all moves done" if done and not lost and not error
                else (f"lost {abs(lost)} full steps" if lost else error))

    def _scope_values(self) -> np.ndarray:
        k = self.fam.constants
        togo = (self.target - self.motors.read_raw("P_IST")) / k.COUNTS_PER_REV
        lag = self.motors.read_raw("FLWERR") / k.COUNTS_PER_FULL_STEP
        return np.stack([togo, self.motors.speed_rpm, lag], axis=1)


class StepperIndexingEnv(MotorEnv):
    """A sequence of indexing moves of an MIS integrated step motor, fast and without losing
    steps.

    ## Description
    An MIS step motor (MIS232 by default) drives an indexing axis: a load inertia of 0–20 ×
    the rotor's, Coulomb friction and a constant load torque of up to 60 % of the holding
    torque at full current. The firmware runs in position mode (MIS manual §8.2.3) and moves
    ``n_moves`` times by the same random distance (0.1–0.5 turns); a move ends when the
    commanded position P_IST has reached P_SOLL and the rotor has settled, and the next starts
    at once. Every few milliseconds the agent sets the profile's maximum speed V_SOLL, its
    acceleration A_SOLL and the phase current RUN_CURRENT. The firmware's profile rules hold
    (§8.2.5, §8.2.6): a new A_SOLL takes effect at standstill or a direction change only. Too
    much speed or acceleration for the load, or too little current, and the rotor slips poles:
    steps are lost (the open-loop P_IST keeps counting, the encoder sees the rotor). More
    current costs copper loss.

    ## Action Space
    ``Box(-1, 1, (3,), float32)``: V_SOLL from 30 to 1500 RPM (linear), A_SOLL from 500 to
    100 000 RPM/s (log-linear), RUN_CURRENT from 10 to 100 % of the type's largest setting
    (§8.2.7), written before each step of ``decimation`` firmware samples of 1 ms.

    ## Observation Space
    ``Box(-5, 5, (8,), float32)``: the distance to go of the present move as a fraction of the
    move; the move length in turns; the profile speed V_IST in units of 1500 RPM; the rotor lag
    FLWERR (P_IST − encoder, §8.2.18) in full steps; the fraction of moves left; the previous
    action. Optional Gaussian noise (``obs_noise``) is added before clipping.

    ## Rewards
    Per step: ``−time_weight − copper_weight·ΔE_cu`` with the copper loss ΔE_cu [J] of the
    step; ``+move_bonus`` for each move finished; ``−lost_penalty`` when steps are lost.

    ## Starting State
    The motor powers on at rest with its default registers (V_SOLL 100 RPM, A_SOLL 1000 RPM/s,
    RUN_CURRENT 50 %) but D_SOLL = 0 (the deceleration is A_SOLL), the load from
    ``inertia_ratio`` (× rotor inertia), ``coulomb_ratio`` and ``load_torque_ratio`` (× holding
    torque at the largest current), and the first move requested (P_SOLL, position mode).

    ## Episode End
    Terminated when every move is done, when the rotor has lost steps, or on an ERR_BITS error
    (follow error, position limit, low bus voltage); truncated after ``max_episode_steps``
    steps (default 1000 = 2 s at decimation 2). ``info["termination_reason"]`` says which;
    the last step's ``info`` also holds the episode's statistics: ``lost_steps``, the full
    steps the rotor lost (its lag behind P_IST in whole electrical turns of 4 full steps),
    ``moves_done`` and ``copper_loss`` [J], the motor's copper loss in the episode.

    ## Arguments
    ``motor_type`` (an MIS/SMC type or a list drawn per episode), ``randomization`` (overrides
    of the ranges above), ``decimation`` (1 ms firmware samples per step, default 2),
    ``obs_noise``, ``max_episode_steps``, ``render_mode`` (``"rgb_array"``: scope plot),
    ``n_moves`` (3), ``time_weight`` (0.05), ``copper_weight`` (0.1 per J), ``move_bonus`` (1),
    ``lost_penalty`` (10), ``baseline`` (True: the firmware's trapezoid with the default
    registers; the action is ignored). Reset options: ``randomization``, ``motor_type``.
    """

    vector_class = StepperIndexingVectorEnv
