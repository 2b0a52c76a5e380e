"""Positioning-v0: point-to-point moves by torque control through AT_MODE."""

from __future__ import annotations

from functools import cache
from typing import Any, NamedTuple

import numpy as np
from numba import njit

from ..engine.jit import KERNEL
from ..families import Capability, Family
from ..physics.fixed import rint
from .base import Field, MotorVectorEnv
from .compiled import action, end_step, put_obs
from .single import MotorEnv
from .task import ERROR_BITS, R, Task, c, record, reg, set_analog_volts

COPPER_COLUMN = 0  # bound per family: the motors' state column of the copper energy account

__all__ = ["PositioningEnv", "PositioningVectorEnv", "PositioningState", "REWARD_WEIGHTS",
           "step_reward", "full_torque_copper_power"]

_FINE_TURNS = 200.0 / 4096  #: turns: scale of the fine position-error channel
_NORM_RPM = 3000.0  #: rpm: scale of the speed channel
_BASELINE_RPM = 3000.0

#: the reward's weights (the env docstring, "Rewards"): name -> (default, unit)
REWARD_WEIGHTS = {"overshoot_weight": (10.0, "1/turn"), "fine_weight": (0.02, "1"),
                  "window_bonus": (1.0, "1"), "copper_weight": (8.0, "1/J")}

#: the env's constants of the compiled step (the reward's weights: :data:`REWARD_WEIGHTS`)
CONSTS = record(noise=float, max_steps=float, decimation=float, overshoot_weight=float,
                fine_weight=float, window_bonus=float, copper_weight=float, baseline=float)
#: a copy's move: the target [counts], the direction of the move (+1 or −1), the last step
#: that ended outside the in-position window, the largest overshoot past the target [turns],
#: the motor's copper energy account at the end of the last step [J]
COPY = record(target=np.int64, direction=float, unsettled=np.int64, overshoot=float,
              copper=float)


class PositioningState(NamedTuple):
    """The task's state (:mod:`jvl_gym.envs.task`)."""

    consts: np.ndarray  #: (1,) :data:`CONSTS`
    copies: np.ndarray  #: (N,) :data:`COPY`


def _figures(fam: Family) -> dict[str, float]:
    """The hooks' figures on a family: the speed scale in counts/sample and the fine error
    scale in counts."""
    k = fam.constants
    return {"_V_NORM": _NORM_RPM / 60.0 * k.COUNTS_PER_REV / k.OUTER_HZ,
            "_FINE": _FINE_TURNS * k.COUNTS_PER_REV}


_V_NORM = _FINE = 1.0  # bound per family by ``_figures``


def _observe_row(i, view, episode, s):  # pragma: no cover - compiled
    """Observation of copy ``i`` (see the env docstring, "Observation Space")."""
    k = s.consts[0]
    obs, key, count, noise = episode.obs, episode.noise_key[i], episode.t[i], k.noise
    e = float(s.copies[i].target - reg(view, i, R.P_IST))
    put_obs(obs, i, 0, e / (2.0 * c.COUNTS_PER_REV), key, count, noise)
    put_obs(obs, i, 1, e / _FINE, key, count, noise)
    put_obs(obs, i, 2, reg(view, i, R.V_IST) / _V_NORM, key, count, noise)
    put_obs(obs, i, 3, episode.prev_action[i, 0], key, count, noise)


def _step_begin(i, view, episode, s, actions):  # pragma: no cover - compiled
    """Beginning of an env step of copy ``i``: the torque command (unless baseline)."""
    a = action(actions, i, 0)
    baseline = s.consts[0].baseline > 0.5
    if not baseline:
        set_analog_volts(view, i, c.ANINP_VOLTS * a)


@njit(cache=True, inline="always")
def step_reward(error_counts: float, window: float, counts_per_rev: float, overshoot: float,
                copper: float, overshoot_weight: float, fine_weight: float, window_bonus: float,
                copper_weight: float) -> float:  # pragma: no cover - compiled
    """The reward of one env step (the env docstring, "Rewards").

    Parameters
    ----------
    error_counts : float
        The position error at the step's end [counts].
    window : float
        The in-position window INPOSWIN [counts].
    counts_per_rev : float
        Counts per turn.
    overshoot : float
        How far the motor is past the target at the step's end [turns] (≥ 0).
    copper : float
        The motor's copper loss during the step [J].
    overshoot_weight, fine_weight, window_bonus, copper_weight : float
        The weights (:data:`REWARD_WEIGHTS`).
    """
    e = abs(error_counts)
    r = (-e / counts_per_rev - fine_weight * np.log1p(e / max(window, 1.0))
         - overshoot_weight * overshoot - copper_weight * copper)
    if e <= window:
        r += window_bonus
    return r


def _step_end(i, view, episode, s, actions):  # pragma: no cover - compiled
    """End of an env step of copy ``i``: reward, termination, observation (the action is
    clipped again: a pure function of ``actions``)."""
    k = s.consts[0]
    row = s.copies[i]
    t = episode.t
    a = action(actions, i, 0)
    t[i] += 1
    e_counts = row.target - reg(view, i, R.P_IST)
    window = reg(view, i, R.INPOSWIN)
    if abs(e_counts) > window:
        row.unsettled = t[i]
    overshoot = max(-e_counts / c.COUNTS_PER_REV * row.direction, 0.0)
    row.overshoot = max(row.overshoot, overshoot)
    copper = view.state[i, COPPER_COLUMN]
    episode.reward[i] = step_reward(float(e_counts), float(window), float(c.COUNTS_PER_REV),
                                    overshoot, copper - row.copper, k.overshoot_weight,
                                    k.fine_weight, k.window_bonus, k.copper_weight)
    row.copper = copper
    end_step(i, (reg(view, i, R.ERR_STAT) & ERROR_BITS) != 0, t, int(k.max_steps),
             episode.terminated, episode.truncated)
    episode.prev_action[i, 0] = a
    _observe_row(i, view, episode, s)


TASK = Task("positioning", __file__, needs={Capability.ANALOG_TORQUE, Capability.ENERGY},
            state=PositioningState,
            figures=_figures, begin=_step_begin, end=_step_end, observe=_observe_row)


@njit(**KERNEL)
def _reset_rows(idx: np.ndarray, target_turns: np.ndarray, target: np.ndarray,
                direction: np.ndarray, counts_per_rev: int) -> None:  # pragma: no cover
    """Targets [counts] (N,) int64 of copies ``idx`` from the (M,) draws [turns], and the
    direction of the move (N,) (+1 or −1)."""
    for j in range(idx.shape[0]):
        i = idx[j]
        target[i] = int(rint(target_turns[j] * counts_per_rev))
        direction[i] = 1.0 if target[i] >= 0 else -1.0


class PositioningVectorEnv(MotorVectorEnv):
    """Vector version of :class:`PositioningEnv` (same arguments plus ``num_envs`` and
    ``autoreset_mode``)."""

    task = TASK
    target = Field()  #: the target [counts]
    direction = Field()  #: the direction of the move (+1 or −1)
    unsettled = Field()  #: the last step that ended outside the in-position window
    overshoot = Field()  #: the largest overshoot past the target [turns]
    copper = Field()  #: the copper energy account at the end of the last step [J]

    obs_labels = ("position_error", "position_error_fine", "speed", "previous_action")
    act_labels = ("torque",)
    default_ranges = {
        "inertia_ratio": (0.0, 10.0),
        "viscous_friction": (0.0, 1e-4),
        "coulomb_ratio": (0.0, 0.1),
        "target_turns": (-2.0, 2.0),
    }
    viscous_ranges = ("viscous_friction",)
    default_decimation = 1
    default_max_episode_steps = 300
    scope_channels = ("position error [turns]", "speed [rpm]", "torque command [1]")
    episode_stats = {"settle_time": "settle time [s]", "final_error": "final error (abs.) [turns]",
                     "overshoot": "overshoot [turns]", "copper_loss": "copper loss [J]"}

    def __init__(self, num_envs: int = 1, *, baseline: bool = False,
                 overshoot_weight: float = REWARD_WEIGHTS["overshoot_weight"][0],
                 fine_weight: float = REWARD_WEIGHTS["fine_weight"][0],
                 window_bonus: float = REWARD_WEIGHTS["window_bonus"][0],
                 copper_weight: float = REWARD_WEIGHTS["copper_weight"][0],
                 **kwargs: Any) -> None:
        self.baseline = bool(baseline)
        self.overshoot_weight = float(overshoot_weight)
        self.fine_weight = float(fine_weight)
        self.window_bonus = float(window_bonus)
        self.copper_weight = float(copper_weight)
        super().__init__(num_envs, **kwargs)

    def _build(self) -> None:
        consts = np.zeros(1, dtype=CONSTS)
        consts[0] = (self.obs_noise, self.max_episode_steps, self.decimation,
                     self.overshoot_weight, self.fine_weight, self.window_bonus,
                     self.copper_weight, float(self.baseline))
        copies = np.zeros(self.num_envs, dtype=COPY)
        copies["direction"] = 1.0
        self.state = PositioningState(consts, copies)

    def _motor_params(self, idx: np.ndarray, draws: dict[str, np.ndarray]
                      ) -> dict[str, np.ndarray]:
        return {"load_inertia": draws["inertia_ratio"] * self.rotor_inertia(idx),
                "viscous_friction": draws["viscous_friction"],
                "coulomb_friction": draws["coulomb_ratio"] * self.rated_torque(idx)}

    def _task_reset(self, idx: np.ndarray, draws: dict[str, np.ndarray],
                    rngs: list[np.random.Generator]) -> None:
        fam = self.fam
        _reset_rows(idx, draws["target_turns"], self.target, self.direction,
                    fam.constants.COUNTS_PER_REV)
        self.unsettled[idx] = 0
        self.overshoot[idx] = 0.0
        self.copper[idx] = self.copper_loss(idx)
        if self.baseline:
            self.motors.write_many({**self._load_writes(draws["inertia_ratio"]),
                                    "V_SOLL": round(fam.task.rpm_to_v_soll(_BASELINE_RPM)),
                                    "P_SOLL": self.target[idx],
                                    "MODE_REG": fam.task.POSITION_MODE}, idx)
        else:
            self.motors.write_many({**self._load_writes(draws["inertia_ratio"]),
                                    "MODE_REG": fam.task.ANALOG_TORQUE_MODE}, idx)

    def _episode_stats(self, idx: np.ndarray) -> dict[str, np.ndarray]:
        """Settle time (steps until the error stays within INPOSWIN, the episode's length when
        it ends outside), final |error|, largest overshoot, copper loss (see "Episode End")."""
        k = self.fam.constants
        return {"settle_time": self.unsettled[idx] * self.decimation * k.OUTER_DT,
                "final_error": np.abs(self._error_counts(idx)) / k.COUNTS_PER_REV,
                "overshoot": self.overshoot[idx], "copper_loss": self.copper_loss(idx)}

    def _error_counts(self, idx: np.ndarray | None = None) -> np.ndarray:
        """Position error (target − P_IST) [counts] of the copies ``idx`` (M,) (default all),
        float64."""
        target = self.target if idx is None else self.target[idx]
        return (target - self.motors.read_raw("P_IST", idx)).astype(np.float64)

    def _scope_values(self) -> np.ndarray:
        return np.stack([self._error_counts() / self.fam.constants.COUNTS_PER_REV,
                         self.motors.speed_rpm,
                         self._prev_action[:, 0]], axis=1)


@cache
def full_torque_copper_power(motor_type: str) -> float:
    """The copper loss of a ``motor_type`` motor under the full torque command (action 1) [W],
    as the motor model accounts it: a copy at rest under the full command for 12 steps, loaded
    with 10 × the rotor's inertia and no friction (far below the speed where the supply
    voltage limits the current), its copper account over the last 10 steps. The copper loss
    of a command ``a`` is this times ``a²``: where the copper account cannot be read (a
    deployed motor), the reward's copper term is estimated from the command with it."""
    env = PositioningVectorEnv(1, motor_type=motor_type, randomization={
        "inertia_ratio": (10.0, 10.0), "viscous_friction": (0.0, 0.0),
        "coulomb_ratio": (0.0, 0.0)})
    idx = np.zeros(1, dtype=np.int64)
    full = np.ones((1, 1), dtype=np.float32)
    env.reset(seed=0)
    for _ in range(2):
        env.step(full)
    start = float(env.copper_loss(idx)[0])
    for _ in range(10):
        env.step(full)
    energy = float(env.copper_loss(idx)[0]) - start
    env.close()
    return energy / (10 * env.step_seconds(motor_type, env.decimation))


class PositioningEnv(MotorEnv):
    """Point-to-point moves of a MAC motor commanded in torque (AT_MODE).

    ## Description
    A MAC motor with a random load (inertia 0–10 × rotor, viscous and Coulomb friction) must
    move to a random target up to ±2 turns away and stop there. The agent commands the torque
    directly: the motor runs in AT_MODE (manual 4.4.5), where the analogue input sets
    ``VF_OUT = ANINP·T_SOLL/1023`` (±10 V ↔ ±peak torque). The firmware's current loops still
    run at 7812.5 Hz; the agent replaces the velocity and position loops.

    ## Action Space
    ``Box(-1, 1, (1,), float32)``: torque command as a fraction of the peak torque
    (analogue input = 10 V × action), held for ``decimation`` outer samples (1.92 ms each).

    ## Observation Space
    ``Box(-5, 5, (4,), float32)``: position error ``(target − P_IST)`` in units of 2 turns; the
    same error in units of 200 counts (fine, clipped); the measured speed V_IST in units of
    3000 rpm; the previous action. Optional Gaussian noise (``obs_noise``) is added before
    clipping.

    ## Rewards
    Per step, with the position error ``e`` [counts] and the in-position window ``W``
    (INPOSWIN) at the step's end, how far the motor is past the target ``o`` [turns] and the
    motor's copper loss during the step ``ΔE`` [J]::

        r = −|e|/counts_per_rev − fine_weight·ln(1 + |e|/W) − overshoot_weight·o
            − copper_weight·ΔE + window_bonus·[|e| ≤ W]

    Each term pays one of the task's engineering metrics (see "Episode End"):

    * settle time: ``window_bonus`` (1.0) every step that ends inside INPOSWIN, so settling
      0.1 s earlier earns some 52 at decimation 1 on the MAC050–141 (77 on the MAC800); the
      ``−|e|`` term [turns] pays a fast approach;
    * final error: ``−|e|`` and the logarithmic term (``fine_weight`` 0.02), which still pays
      the last counts: from 50 counts off to the window's edge it gains 0.02·ln 3 ≈ 0.022 a
      step, more than twice what ``−|e|`` pays (0.0098) on the MAC050–141;
    * overshoot: ``overshoot_weight`` (10 per turn) every step the motor is past the target;
    * copper loss: ``ΔE`` is the step's increment of the account the ``copper_loss`` statistic
      reads (the motor model's ∫ R·i² dt over the windings), so an episode's energy term is
      exactly ``copper_weight`` (8 per J) × its copper loss: the firmware's some 4 J cost 31,
      50 J cost 400, far more than any settle time gains.

    The weights are the constructor's arguments (:data:`REWARD_WEIGHTS`); the reward is
    :func:`step_reward` of each step, the same for the firmware baseline.

    ## Starting State
    The motor powers on at rest with P_IST = 0 and the default register set; the target is
    drawn from ``target_turns``; load from ``inertia_ratio`` (× rotor inertia),
    ``viscous_friction`` [N·m·s/rad] and ``coulomb_ratio`` (× rated torque).

    ## Episode End
    Terminated when an error bit (I2T, FLW, FNC, UIT, position limit) is set; truncated after
    ``max_episode_steps`` steps (default 300 ≈ 0.58 s at decimation 1). The last step's
    ``info`` holds the episode's statistics: ``settle_time`` [s], the motor time until the
    position error stays within the in-position window INPOSWIN (MAC050–141 manual
    "INPOSWIN - Register 33", MAC800 manual register 33; 10 counts in the default setups) to
    the episode's end (its whole length when it ends outside); ``final_error`` [turns];
    ``overshoot`` [turns], the largest past the target; ``copper_loss`` [J], the motor's
    copper loss in the episode.

    ## Families
    MAC050–141 (default MAC140) and MAC800 (``motor_type="MAC800"`` or ``"MAC400"``: mode 4,
    Analog torque, ±2047 ANINP ↔ ±T_SOLL; 8000 counts/rev and 770 Hz, so a step is 1.30 ms and
    the observation's scales are in those units; the viscous friction range scaled to the
    motor, docs/envs.md "Motor families").

    ## Arguments
    ``motor_type`` (str or list of types drawn per episode), ``randomization`` (overrides of the
    ranges above), ``decimation`` (outer samples per step, default 1 = 520.8 Hz),
    ``obs_noise``, ``max_episode_steps``, ``render_mode`` (``"rgb_array"``: scope plot),
    ``overshoot_weight`` (10 per turn), ``fine_weight`` (0.02), ``window_bonus`` (1.0 per
    step), ``copper_weight`` (8 per J) (see "Rewards"), ``baseline`` (True: the firmware's
    P_MODE moves to the target with the default setup, V_SOLL = 3000 rpm and A_SOLL from the
    setup; the action is ignored). Reset options: ``randomization``, ``motor_type``.

    ## Version History
    * v0: initial version; the reward pays settling into INPOSWIN and copper loss (the
      in-window bonus, the logarithmic error term and the copper loss replaced a torque² effort
      term weighted 0.01).
    """

    vector_class = PositioningVectorEnv
