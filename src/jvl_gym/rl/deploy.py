"""Run a policy in real time against a motor (a twin served by ``jvl-gym serve``, or a real
one) over MacTalk, behind the safety supervisor (:mod:`jvl_gym.rl.supervisor`).

Each control period the loop reads the observed registers, builds the env's observation from
them, runs the policy (in a thread of its own, under the deadline), bounds the action and
writes it to the motor's registers (:class:`~jvl_gym.rl.supervisor.Supervisor`), beats the
watchdog's heartbeat and waits for the next period. Every period is a row of the trace (CSV);
each episode's return, length and engineering metrics (:mod:`jvl_gym.rl.metrics`) are those
``jvl-gym evaluate`` reports; the loop's achieved rate and its latency (from the read of the
observation to the end of the write of the action) are measured. The loop runs with the heap
frozen (:func:`~jvl_gym.protocol.serving.realtime.heap_frozen`): no full collection of the
loaded simulator, numba and torch stalls a period.

A task reaches the motor through a bridge (:class:`PositioningBridge`, :class:`GearSyncBridge`):
the registers it reads and writes, the observation from them, the reward, and a failure that
ends an episode early (GearSync's web). Positioning commands torque; over the bus
that is velocity mode with the speed command at the speed limit (:data:`SPEED_LIMIT_RPM`) in
the action's direction and the torque limit T_SOLL = |action| × its full scale (MAC050–141
manual 4.4.2: the velocity loop saturates at T_SOLL), so the torque follows the action while
the motor is below the speed limit, which the velocity loop holds. The episode's target is drawn
as the env draws it with the same seed; the motor's load is the twin's (``jvl-gym serve``
options), not drawn.
"""

from __future__ import annotations

import csv
import math
import signal
import threading
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..envs import link as link_model
from ..protocol.serving.realtime import heap_frozen
from .metrics import engineering_metrics
from .supervisor import Limits, PolicyRunner, Stopped, Supervisor, Watchdog, register_bounds

__all__ = ["PositioningBridge", "GearSyncBridge", "BusLink", "DeployReport", "deploy", "BRIDGES",
           "load_policy", "loop_period", "link_latency", "holds_latency", "PeriodReward"]


#: the longest wait for a motor to reach the passive mode at an episode's start [s], and the
#: time between two reads of its mode [s]
SETTLE_TIMEOUT = 2.0
SETTLE_POLL = 0.002


class BusLink:
    """A MacTalk client as the supervisor's :class:`~jvl_gym.rl.supervisor.MotorLink`.

    Parameters
    ----------
    client : MacTalk client
        ``jvl_gym.protocol.mactalk.client16.MacTalkClient`` or ``client32.MacTalk32Client``.
    passive_mode : int
        MODE_REG of the family's passive mode (``family.twin.passive_mode``).
    """

    def __init__(self, client: Any, passive_mode: int) -> None:
        self.client = client
        self.passive_mode = int(passive_mode)

    def write_raws(self, values: Mapping[str, int]) -> None:
        """Write each register's stored integer."""
        for name, raw in values.items():
            reg = self.client.table.lookup(name)
            self.client.write(name, raw / reg.scale)

    def read_raws(self, names: tuple[str, ...]) -> dict[str, int]:
        """Read each register's stored integer."""
        return {name: int(self.client.read_raw(name)) for name in names}

    def passive(self) -> None:
        """MODE_REG = the passive mode."""
        self.client.write("MODE_REG", self.passive_mode)

    def settle_passive(self, timeout: float = SETTLE_TIMEOUT) -> None:
        """MODE_REG = the passive mode, and wait until the motor reads it: a running motor
        stops on its way to passive (MAC050–141 manual 4.4.1), and a mode written before the
        stop is done starts another stop instead of the mode (the mode would be lost).
        Raises TimeoutError when the motor is not passive within ``timeout`` seconds."""
        self.passive()
        pause = getattr(self.client, "pause", time.sleep)
        waited = 0.0
        while int(self.client.read_raw("MODE_REG")) != self.passive_mode:
            if waited > timeout:
                raise TimeoutError(f"the motor did not reach the passive mode within "
                                   f"{timeout:g} s")
            pause(SETTLE_POLL)
            waited += SETTLE_POLL


#: the speed limit of a deployed Positioning policy [rpm] (:class:`~jvl_gym.envs.link.
#: TorqueLimitCommand`)
SPEED_LIMIT_RPM = link_model.SPEED_LIMIT_RPM


class PositioningBridge:
    """jvl_gym/Positioning-v0 over the registers (module docstring).

    Parameters
    ----------
    fam : Family
        The motor's family.
    weights : float
        The env's reward weights (``jvl_gym.envs.positioning.REWARD_WEIGHTS``: overshoot_weight,
        fine_weight, window_bonus, copper_weight; default theirs).
    speed_limit : float
        The speed command's magnitude [rpm]: the velocity loop holds the motor below it.
    """

    env_id = "jvl_gym/Positioning-v0"
    writes = ("T_SOLL", "V_SOLL")
    #: VF_OUT: the torque command the velocity loop gives under the torque limit (MAC050–141
    #: manual 3.2.121), which the copper loss follows
    reads = ("P_IST", "V_IST", "VF_OUT")
    #: the trace's error column and its unit
    error_label = "error_turns"
    failure_penalty = 0.0

    def __init__(self, fam: Any, speed_limit: float = SPEED_LIMIT_RPM, **weights: float) -> None:
        from ..envs import positioning as pos

        k = fam.constants
        self.fam = fam
        self.cpr = float(k.COUNTS_PER_REV)
        self.fine = pos._FINE_TURNS * k.COUNTS_PER_REV
        self.v_norm = pos._NORM_RPM / 60.0 * k.COUNTS_PER_REV / k.OUTER_HZ
        #: the action's registers: the link model's own (one definition for both)
        self.command = link_model.TorqueLimitCommand(fam, speed_limit)
        self.bounds = register_bounds(fam.table, self.writes)
        self.v_limit = self.command.v_limit
        self.weights = {name: float(weights.pop(name, w)) for name, (w, _) in
                        pos.REWARD_WEIGHTS.items()}
        if weights:
            raise TypeError(f"unknown reward weights {sorted(weights)}; known: "
                            f"{', '.join(pos.REWARD_WEIGHTS)}")
        #: the copper loss of an env step under the full torque command [J]: the copper
        #: account is not read from the motor, its step's share is estimated from the torque
        #: command VF_OUT read with the observation (the command the current follows)
        self.full_copper = (pos.full_torque_copper_power(fam.task.DEFAULT_MOTOR_TYPE)
                            * k.OUTER_DT)
        self.vf_full = float(k.VF_FULL)
        self.target = 0
        self.direction = 1.0
        self.overshoot = 0.0
        self.error = 0.0
        self.window: float | None = None
        self.window_counts = 10.0  # INPOSWIN [counts] of the default setups, read by prepare
        self.torque = 0.0  # VF_OUT of the last read, of full scale

    def prepare(self, link: BusLink) -> None:
        """Once before the episodes: the in-position window INPOSWIN (for the metrics), and the
        reward's compiled code made ready (on a fresh install numba compiles it, 100 ms and
        more: inside the loop, an overrun of the first period)."""
        self.window_counts = float(link.client.read_raw("INPOSWIN"))
        self.window = self.window_counts / self.cpr
        self.rate(np.zeros(1))

    def start(self, link: BusLink, core: Any) -> None:
        """Begin a move to the target the env drew (``core.target``, counts) from here:
        passive, P_IST = 0, the command's start registers (no torque, the largest
        acceleration), then velocity mode."""
        target = int(core.target[0])
        link.settle_passive()
        link.write_raws({"P_IST": 0, **self.command.start_registers()})
        link.client.write("MODE_REG", self.command.mode)
        self.target = target
        self.direction = 1.0 if target >= 0 else -1.0
        self.overshoot = 0.0
        self.torque = 0.0

    def to_registers(self, action: np.ndarray) -> dict[str, int]:
        """Torque limit |a| of full scale, speed command at the speed limit in a's
        direction (:meth:`~jvl_gym.envs.link.TorqueLimitCommand.registers`)."""
        raws = self.command.registers(np.asarray(action, dtype=np.float64).reshape(1, -1))
        return {name: int(v[0]) for name, v in raws.items()}

    def observe(self, raws: Mapping[str, int], previous: np.ndarray, period: float
                ) -> np.ndarray:
        """The env's observation (1, 4); keeps the position error [turns]."""
        from ..envs.compiled import OBS_BOUND

        e = float(self.target - raws["P_IST"])
        obs = np.array([e / (2.0 * self.cpr), e / self.fine, raws["V_IST"] / self.v_norm,
                        float(previous[0])], dtype=np.float32)
        self.error = e / self.cpr
        self.torque = raws["VF_OUT"] / self.vf_full
        return np.clip(obs, -OBS_BOUND, OBS_BOUND)[None]

    def rate(self, action: np.ndarray) -> float:
        """The env's reward of one env step at this error under the command ``action``."""
        from ..envs.positioning import step_reward

        error_turns = self.error
        past = max(-self.direction * error_turns, 0.0)
        self.overshoot = max(self.overshoot, past)
        w = self.weights
        # the copper loss at this read's torque command (the velocity loop's, below the limit
        # the action set wherever the motor needs less)
        return step_reward(error_turns * self.cpr, self.window_counts, self.cpr, past,
                           self.full_copper * self.torque * self.torque, w["overshoot_weight"],
                           w["fine_weight"], w["window_bonus"], w["copper_weight"])

    def penalty(self, action: np.ndarray) -> float:
        """The reward of a new command once (none: Positioning's reward is per step)."""
        return 0.0

    def failure(self) -> str:
        """Why the episode ends early: never (the motor's error bits stop it on its own)."""
        return ""

    def columns(self) -> dict[str, float]:
        """This period's row of the metrics' trace (:func:`~.metrics.engineering_metrics`)."""
        return {"error": self.error, "direction": self.direction}

    def metrics(self, cols: Mapping[str, np.ndarray]) -> dict[str, float]:
        """The episode's engineering metrics from its trace."""
        return engineering_metrics(self.env_id, cols, self.window)


class GearSyncBridge:
    """jvl_gym/GearSync-v0 over the registers of a bus-trimmed winder (module docstring).

    The env trims the gear through the analogue input in AG_MODE (MAC050–141 manual 4.1.9,
    4.4.19: gear GEARF1/GEARF2 × AG factor, the factor 0.87..1.15 over −10..+10 V). Over
    MacTalk the controller writes the trimmed gear itself: the motor runs in gear position
    mode GP_MODE (manual 4.4.4; the gear position block of 4.1.12, the block AG_MODE runs),
    and each period the action ``a`` becomes GEARF1 = nominal GEARF1 × the AG factor at
    ANINP = round(1023·a) (manual 3.2.14: GEARF1 is read each sample), so the motor's gear is
    the env's to GEARF1's resolution. The nominal GEARF1 and GEARF2 are the line's set-up,
    read at the start of each episode; the task's bounds on GEARF1 follow from them.

    The analogue input is then free for the load cell (:mod:`jvl_gym.rl.lines`): the
    tension is ANINP/1023 × :data:`~jvl_gym.envs.link.LOADCELL_FULL_SCALE` (manual 3.2.122);
    the master's speed is the pulse input V_EXT (3.2.120); V_IST, FLWERR and FNCERR are read
    as the env observes them. The tension's rate is the change since the last period and the
    leaky integral is kept by the controller, both as the env computes them per step, over
    the period. The reward is the env's from the load cell's tension (the env's uses the
    true tension, which no controller reads); the episode ends with the env's failure penalty
    when the load cell reads above ``break_ratio`` × the reference (a web break) or nothing
    (a web slack, or broken between two reads).

    Parameters
    ----------
    fam : Family
        The motor's family: the MAC050–141 (its GP_MODE and AG factor).
    """

    env_id = "jvl_gym/GearSync-v0"
    writes = ("GEARF1",)
    reads = ("ANINP", "V_EXT", "V_IST", "FLWERR", "FNCERR")
    error_label = "load_cell_error"

    def __init__(self, fam: Any) -> None:
        from ..envs import gear_sync as gs
        gear_mode = getattr(fam.task, "GEAR_MODE", None)
        ag = getattr(fam.task, "ag_factor", None)
        if gear_mode is None or ag is None:
            raise ValueError(f"jvl-gym deploy runs GearSync on a family whose task module states "
                             f"its gear mode and AG factor (the MAC050–141), not the {fam.title}")
        k = fam.constants
        self.fam = fam
        self.gp_mode = int(gear_mode)
        self.dt = float(k.OUTER_DT)
        self.v_norm = gs._NORM_RPM / 60.0 * k.COUNTS_PER_REV / k.OUTER_HZ
        self.tau = float(gs._INTEGRAL_TAU)
        self.full_scale = float(link_model.LOADCELL_FULL_SCALE)
        self.aninp_full = 1023.0  # ±10 V (manual 3.2.122)

        def factor(a: float) -> float:
            return float(ag(int(round(self.aninp_full * min(max(a, -1.0), 1.0)))))

        self.factor = factor
        self.bounds = register_bounds(fam.table, self.writes)
        self.nominal = 0
        self.ref = 1.0
        self.error = 0.0
        self._reset_state()

    def _reset_state(self) -> None:
        #: the tension channels from the load cell (the link model's own)
        self.load_cell = link_model.LoadCellObserver(1, self.tau)
        self.last_action = 0.0
        self.tension = self.ref

    def prepare(self, link: BusLink) -> None:
        """Once before the episodes: nothing to read."""

    def start(self, link: BusLink, core: Any) -> None:
        """Begin a line: passive (the line threads a new web), the env's figures (reference
        tension, weights: ``core``), the nominal gear read, GEARF1 at the action 0, the speed
        limit V_SOLL the env sets (the family's rated speed), then GP_MODE (GEARF2 is the
        line's, as set up)."""
        link.settle_passive()
        self.ref = float(core.tension_ref[0])
        self.tolerance = float(core.tension_tolerance)
        self.rate_weight = float(core.action_rate_weight)
        self.break_ratio = float(core.break_ratio)
        self.failure_penalty = float(core.failure_penalty)
        self.master_counts = float(core._counts_per_m) * self.dt  # counts/sample at 1 m/s
        self.set_nominal(int(link.read_raws(("GEARF1",))["GEARF1"]))
        self._reset_state()
        v_soll = int(round(self.fam.task.rpm_to_v_soll(core.rated_rpm)))
        link.write_raws({**self.to_registers(np.zeros(1)), "V_SOLL": v_soll})
        link.client.write("MODE_REG", self.gp_mode)

    def set_nominal(self, gearf1: int) -> None:
        """The line's nominal GEARF1, and the task's bounds on GEARF1 from it: the gears of
        the actions −1 and +1, within the register's range."""
        self.nominal = int(gearf1)
        lo, hi = register_bounds(self.fam.table, self.writes)["GEARF1"]
        ends = sorted(round(self.nominal * self.factor(a)) for a in (-1.0, 1.0))
        self.bounds = {"GEARF1": (max(lo, int(ends[0])), min(hi, int(ends[1])))}

    def to_registers(self, action: np.ndarray) -> dict[str, int]:
        """GEARF1 = nominal × the AG factor at the action (class docstring)."""
        return {"GEARF1": int(round(self.nominal * self.factor(float(action[0]))))}

    def observe(self, raws: Mapping[str, int], previous: np.ndarray, period: float
                ) -> np.ndarray:
        """The env's observation (1, 8) from the registers and the controller's own state."""
        from ..envs.compiled import OBS_BOUND

        one = np.zeros(1, dtype=np.int64)
        tension = self.load_cell.tension_of(np.array([raws["ANINP"]]))
        self.tension = float(tension[0])
        chans = self.load_cell.observe(one, tension, np.array([self.ref]), period)[0]
        self.error = float(chans[0])
        obs = np.array([*chans, raws["V_EXT"] / self.master_counts, raws["V_IST"] / self.v_norm,
                        raws["FLWERR"] / 100.0, raws["FNCERR"] / 10000.0, float(previous[0])],
                       dtype=np.float32)
        return np.clip(obs, -OBS_BOUND, OBS_BOUND)[None]

    def rate(self, action: np.ndarray) -> float:
        """The env's reward of one env step at this tension."""
        return 1.0 - min(abs(self.error) / self.tolerance, 2.0)

    def penalty(self, action: np.ndarray) -> float:
        """The env's reward of the action's change, counted once (the command changes once
        a period)."""
        a = float(action[0])
        da, self.last_action = a - self.last_action, a
        return -self.rate_weight * da * da

    def failure(self) -> str:
        """A web break or slack seen by the load cell, or ""."""
        if self.tension > self.break_ratio * self.ref:
            return f"web break: tension above {self.break_ratio:g} × the reference"
        if self.tension <= 0.0:
            return "web slack or broken: the load cell reads no tension"
        return ""

    def columns(self) -> dict[str, float]:
        """This period's row of the metrics' trace: the tension error [%]."""
        return {"tension_error": 100.0 * self.error}

    def metrics(self, cols: Mapping[str, np.ndarray]) -> dict[str, float]:
        """The episode's engineering metrics from its trace."""
        return engineering_metrics(self.env_id, cols)


class PeriodReward:
    """The env's reward of a period of ``steps`` env steps, from the bridge's per-step
    reward at the reads that begin and end it: the env sums its reward after each step, which
    the controller does not see; between its two reads the per-step reward is taken as linear,
    so the period's is ``(steps − 1)/2 · r_begin + (steps + 1)/2 · r_end`` (the steps' sum of a
    linear change), plus the bridge's penalty of the new command, and the failure penalty when
    the read that ends the period finds the task failed (the env's last step).

    Parameters
    ----------
    bridge : object
        The task's bridge (:data:`BRIDGES`).
    steps : float
        Env steps a period.
    """

    def __init__(self, bridge: Any, steps: float) -> None:
        self.bridge = bridge
        self.steps = float(steps)
        self.begun = 0.0
        self.action = np.zeros(1)
        self.extra = 0.0
        self.open = False

    def begin(self, action: np.ndarray) -> None:
        """A period begins under the command ``action`` (after the read that begins it)."""
        self.action = np.asarray(action, dtype=np.float64).copy()
        self.begun = self.bridge.rate(self.action)
        self.extra = self.bridge.penalty(self.action)
        self.open = True

    def close(self) -> tuple[float, str]:
        """The period's reward at the read that ends it, and the task's failure, or ""."""
        end = self.bridge.rate(self.action)
        r = 0.5 * (self.steps - 1.0) * self.begun + 0.5 * (self.steps + 1.0) * end + self.extra
        failed = self.bridge.failure()
        if failed:
            r -= self.bridge.failure_penalty
        self.open = False
        return r, failed


BRIDGES: dict[str, Callable[..., Any]] = {PositioningBridge.env_id: PositioningBridge,
                                          GearSyncBridge.env_id: GearSyncBridge}


@dataclass
class DeployReport:
    """What a deployment did."""

    returns: list[float] = field(default_factory=list)
    lengths: list[int] = field(default_factory=list)
    #: why each episode ended early (a task's failure: GearSync's web break or slack), or ""
    ended: list[str] = field(default_factory=list)
    stats: dict[str, list[float]] = field(default_factory=dict)
    reason: str = ""
    periods: int = 0
    rate_hz: float = float("nan")
    latency_mean: float = float("nan")
    latency_max: float = float("nan")
    trace: Path | None = None

    def summary(self) -> str:
        """A few lines for the terminal."""
        lines = [f"episodes: {len(self.returns)}, stopped: {self.reason}",
                 f"loop: {self.rate_hz:.1f} Hz achieved over {self.periods} periods; latency "
                 f"(read to written) mean {1e3 * self.latency_mean:.2f} ms, max "
                 f"{1e3 * self.latency_max:.2f} ms"]
        if self.returns:
            lines.append(f"return: {np.mean(self.returns):.3f} ± {np.std(self.returns):.3f}")
        early = [f"episode {k}: {why}" for k, why in enumerate(self.ended) if why]
        if early:
            lines.append("ended early: " + "; ".join(early))
        for name, values in self.stats.items():
            known = [v for v in values if not math.isnan(v)]
            lines.append(f"{name}: {np.mean(known):.4g}" if known else f"{name}: n/a")
        return "\n".join(lines)


def loop_period(env_id: str, link: str, motor_type: str | None) -> float:
    """The control period [s] of ``link`` on ``env_id``: the link model's period in whole env
    steps (:mod:`jvl_gym.envs.link`), as a policy trained for the link acts."""
    from ..envs.link import observed_registers, parse_link
    from ..envs.registration import vector_class

    cls = vector_class(env_id)
    step = cls.step_seconds(motor_type)
    period, _ = parse_link(link).times(len(cls.act_labels), observed_registers(cls.obs_labels),
                                       step)
    return max(1, math.ceil(period / step - 1e-9)) * step


def link_latency(env_id: str, link: str, motor_type: str | None) -> float:
    """The link model's latency [s] of ``link`` on ``env_id`` (:mod:`jvl_gym.envs.link`), in
    whole env steps as the model lands the action: from the answer to the read to the end of
    the write (a serial line's time, or MacTalk over TCP's stated latency)."""
    from ..envs.link import observed_registers, parse_link
    from ..envs.registration import vector_class

    cls = vector_class(env_id)
    step = cls.step_seconds(motor_type)
    latency = parse_link(link).times(len(cls.act_labels), observed_registers(cls.obs_labels),
                                     step)[1]
    return round(latency / step) * step


def holds_latency(link: str) -> bool:
    """Whether a deployment over ``link`` holds each write to the link model's latency by
    default: MacTalk over TCP, whose stated latency is that hold."""
    from ..envs.link import parse_link

    return parse_link(link).kind == "mactalk-tcp"


def load_policy(text: str, env_id: str, act_dim: int, step_seconds: float
                ) -> Callable[[np.ndarray], np.ndarray]:
    """A policy from ``text``: an SB3 zip, or a scripted baseline by name (``zero``)."""
    if text == "zero":
        from ..envs.baselines import ZeroAction

        return ZeroAction(1, act_dim)
    path = Path(text)
    if not path.is_file():
        raise FileNotFoundError(f"no policy {text!r}: give an SB3 .zip or 'zero'")
    from .config import rl_config
    from .evaluate import _model_policy

    return _model_policy(path, rl_config(env_id)["algo"])


def _client(url: str, address: int, fam: Any, timeout: float, retries: int) -> Any:
    from ..protocol.mactalk import codec16
    from ..protocol.mactalk.client16 import MacTalkClient
    from ..protocol.mactalk.client32 import MacTalk32Client

    cls = MacTalkClient if fam.twin.dialect == codec16.DIALECT else MacTalk32Client
    return cls(url, address, timeout=timeout, retries=retries, table=fam.table)


#: the client's time-out [s] while an episode is set up (before the loop's own)
SETUP_TIMEOUT = 2.0
#: the time the policy's first call (outside the loop) may take [s]
WARM_UP_SECONDS = 60.0


class _Terminate(BaseException):
    """SIGTERM, raised in the loop's thread."""


# the heap frozen before the client, the watchdog and the loop start: the one full collection
# (100 ms and more) comes first, and none stalls a period after it (protocol.serving.realtime)
@heap_frozen()
def deploy(env_id: str, policy: Callable[[np.ndarray], Any], url: str, address: int,
           motor_type: str, *, period: float, deadline: float | None = None,
           episodes: int = 1, seed: int = 0, max_seconds: float | None = None,
           max_step: float = 0.5, watchdog_url: str | None = None,
           watchdog_timeout: float = 0.25, timeout: float = 0.1, retries: int = 1,
           trace: str | Path | None = None, stop: threading.Event | None = None,
           hold: float = 0.0, env_kwargs: Mapping[str, Any] | None = None) -> DeployReport:
    """Run ``policy`` on the motor at ``address`` of ``url`` for ``episodes`` episodes.

    Parameters
    ----------
    env_id : str
        A key of :data:`BRIDGES`.
    policy : callable
        ``(1, K) observation -> (1, A) action``.
    url, address, motor_type : str, int, str
        The motor's MacTalk port (pyserial URL), address and type (its family).
    period : float
        Control period [s].
    deadline : float, optional
        Time the policy has for an action [s] (default: the period). A period that ends more
        than a period late (the command two periods old) stops the loop too.
    episodes, seed : int
        Episodes, and the seed of the first (the env's target draw; ``seed + k`` for the k-th).
    max_seconds : float, optional
        Length of an episode [s] (default: the env's horizon).
    max_step : float
        The rate limit: largest change of the command per period (action units).
    watchdog_url : str, optional
        The watchdog's own connection (default ``url``).
    watchdog_timeout : float
        Seconds without a heartbeat before the watchdog stops the motor.
    timeout, retries : float, int
        The client's answer time-out and retries (a link that drops is given up on after
        ``timeout × (1 + retries)``).
    trace : path, optional
        CSV of every period.
    stop : threading.Event, optional
        Set to end the run (as Ctrl-C does).
    hold : float
        Hold each period's write so that it ends this long after its read [s] (0: at once;
        the write starts the last write's duration before): the line time a serial link at the
        link model's baud rate takes (:func:`link_latency`), which a twin over TCP does not,
        so that the action lands as late as the link model has it.
    env_kwargs : mapping, optional
        Arguments of the env that draws the episodes (an identified motor's,
        :func:`jvl_gym.envs.identified.env_kwargs_from_identification`; its ``motor_type``
        must be ``motor_type``).
    """
    import gymnasium as gym

    import jvl_gym  # noqa: F401

    from ..families import family_of_motor

    if env_id not in BRIDGES:
        raise ValueError(f"jvl-gym deploy knows how {', '.join(BRIDGES)} reaches a motor, "
                         f"not {env_id}")
    if not (period > 0 and math.isfinite(period)):
        raise ValueError(f"period must be > 0 s, got {period}")
    fam = family_of_motor(motor_type)
    deadline = period if deadline is None else float(deadline)
    bridge = BRIDGES[env_id](fam)
    env_kwargs = dict(env_kwargs or {})
    if env_kwargs.setdefault("motor_type", motor_type) != motor_type:
        raise ValueError(f"the env's motor type {env_kwargs['motor_type']!r} is not the "
                         f"motor's, {motor_type!r}")
    env = gym.make(env_id, **env_kwargs).unwrapped
    step_seconds = env.core.decimation * fam.constants.OUTER_DT
    horizon = env.core.max_episode_steps * step_seconds if max_seconds is None else max_seconds
    n_periods = max(1, int(math.ceil(horizon / period - 1e-9)))
    client = _client(url, address, fam, max(timeout, SETUP_TIMEOUT), retries)
    link = BusLink(client, fam.twin.passive_mode)
    bridge.prepare(link)
    watchdog = Watchdog(watchdog_url or url, address, motor_type, watchdog_timeout)
    act_dim = len(env.core.act_labels)
    limits = Limits((-1.0,) * act_dim, (1.0,) * act_dim, max_step)
    supervisor = Supervisor(link, limits, bridge.to_registers, bridge.bounds, watchdog)
    runner = PolicyRunner(policy)
    # a first call outside the deadline: a network's first inference loads and allocates
    runner(np.zeros((1, len(env.core.obs_labels)), dtype=np.float32), WARM_UP_SECONDS)
    if hasattr(policy, "reset"):
        policy.reset(None)
    report = DeployReport(trace=None if trace is None else Path(trace))
    rows: list[list[float]] = []
    latencies: list[float] = []
    old_term = old_int = None
    if threading.current_thread() is threading.main_thread():
        def on_term(signum: int, frame: Any) -> None:
            raise _Terminate()

        old_term = signal.signal(signal.SIGTERM, on_term)
        # Ctrl-C stops the loop even in a process started with SIGINT ignored (a shell's
        # background job, a parent that ignores it), which Python would otherwise keep
        old_int = signal.signal(signal.SIGINT, signal.default_int_handler)
    t_first = time.monotonic()
    loop_time, t0, write_time = 0.0, t_first, 0.0
    try:
        for ep in range(episodes):
            env.reset(seed=seed + ep)
            client.timeout = max(timeout, SETUP_TIMEOUT)
            watchdog.check()
            bridge.start(link, env.core)
            # the task's register bounds may follow from the episode's set-up (GearSync's
            # nominal gear)
            supervisor.bounds.update(bridge.bounds)
            client.timeout = timeout
            supervisor.last = np.zeros(act_dim)
            ret, t0, length = 0.0, time.monotonic(), 0
            cols: dict[str, list[float]] = {"t": []}
            rewards = PeriodReward(bridge, period / step_seconds)
            for k in range(n_periods + 1):  # the read after the last period closes it
                if stop is not None and stop.is_set():
                    raise KeyboardInterrupt
                start = t0 + k * period
                raws = link.read_raws(bridge.reads)
                t_read = time.monotonic()
                obs = bridge.observe(raws, supervisor.last, period)
                if rewards.open:
                    r, failed = rewards.close()
                    ret += r
                    rows[-1][-2] = r
                    if failed:
                        report.ended.append(failed)
                        break
                if k == n_periods:
                    break
                action = runner(obs, deadline)
                if hold > 0.0:  # the write is to end ``hold`` after the read: it starts
                    # the last write's duration earlier
                    time.sleep(max(0.0, t_read + hold - write_time - time.monotonic()))
                t_write = time.monotonic()
                watchdog.check()  # a watchdog that put the motor passive ends the loop
                a, written = supervisor.command(np.asarray(action).reshape(-1))
                t_written = time.monotonic()
                write_time = t_written - t_write
                watchdog.beat()
                latencies.append(t_written - t_read)
                rewards.begin(a)
                cols["t"].append(start - t0)
                for key, value in bridge.columns().items():
                    cols.setdefault(key, []).append(value)
                rows.append([ep, k, start - t_first, bridge.error, *obs[0].tolist(),
                             float(a[0]), *written.values(), float("nan"), t_written - t_read])
                report.periods += 1
                length += 1
                late = time.monotonic() - (start + period)
                if late > period:
                    raise Stopped(f"loop overrun: period {k} ended {late * 1e3:.1f} ms late "
                                  "(more than a period)")
                time.sleep(max(0.0, start + period - time.monotonic()))
            loop_time += time.monotonic() - t0
            supervisor.link.passive()
            report.returns.append(ret)
            report.lengths.append(length)
            if len(report.ended) < len(report.returns):
                report.ended.append("")
            trace_cols = {key: np.asarray(v) for key, v in cols.items()}
            for name, value in bridge.metrics(trace_cols).items():
                report.stats.setdefault(name, []).append(value)
        report.reason = "done"
        supervisor.stop("done")
    except Stopped as exc:
        supervisor.stop(exc.reason)
    except KeyboardInterrupt:
        supervisor.stop("interrupted (Ctrl-C)")
    except _Terminate:
        supervisor.stop("terminated (SIGTERM)")
    except (TimeoutError, OSError) as exc:
        supervisor.stop(f"link: {str(exc).splitlines()[0] if str(exc) else type(exc).__name__}")
    except Exception as exc:
        supervisor.stop(f"error: {type(exc).__name__}: {exc}")
        raise
    finally:
        if old_term is not None:
            signal.signal(signal.SIGTERM, old_term)
        if old_int is not None:
            signal.signal(signal.SIGINT, old_int)
        report.reason = supervisor.reason
        watchdog.close()
        with_client_closed(client)
        if report.periods:
            # the periods of the episodes run (an unfinished one to its stop), set-ups aside
            done = sum(report.lengths)
            loop_time += (report.periods - done) and time.monotonic() - t0
            report.rate_hz = report.periods / loop_time
            report.latency_mean = float(np.mean(latencies))
            report.latency_max = float(np.max(latencies))
        if report.trace is not None:
            _write_trace(report.trace, rows, bridge, env.core.obs_labels)
    return report


def with_client_closed(client: Any) -> None:
    """Close ``client``, ignoring a link already gone."""
    try:
        client.close()
    except OSError:
        pass


def _write_trace(path: Path, rows: list[list[float]], bridge: Any,
                 obs_labels: tuple[str, ...]) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["episode", "period", "time_s", bridge.error_label, *obs_labels, "action",
                    *bridge.writes, "reward", "latency_s"])
        w.writerows(rows)
