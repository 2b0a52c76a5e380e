"""Run a policy in real time against a motor (a twin served by ``jvl-gym serve``, or a real
one) over MacTalk, behind the safety supervisor (:mod:`jvl_gym.rl.supervisor`).

Each control period the loop reads the observed registers, builds the env's observation from
them, runs the policy (in a thread of its own, under the deadline), bounds the action and
writes it to the motor's registers (:class:`~jvl_gym.rl.supervisor.Supervisor`), beats the
watchdog's heartbeat and waits for the next period. Every period is a row of the trace (CSV);
each episode's return, length and engineering metrics (:mod:`jvl_gym.rl.metrics`) are those
``jvl-gym evaluate`` reports; the loop's achieved rate and its latency (from the read of the
observation to the end of the write of the action) are measured.

A task reaches the motor through a bridge (:class:`PositioningBridge`): the registers it reads
and writes, the observation from them, the reward. Positioning commands torque; over the bus
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

from .metrics import engineering_metrics
from .supervisor import Limits, PolicyRunner, Stopped, Supervisor, Watchdog, register_bounds

__all__ = ["PositioningBridge", "BusLink", "DeployReport", "deploy", "BRIDGES", "load_policy"]


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


#: the speed limit of a deployed Positioning policy [rpm]: the scale of the env's speed
#: observation and the speed of its firmware baseline
SPEED_LIMIT_RPM = 3000.0


class PositioningBridge:
    """jvl_gym/Positioning-v0 over the registers (module docstring).

    Parameters
    ----------
    fam : Family
        The motor's family.
    overshoot_weight, effort_weight : float
        The env's reward weights.
    speed_limit : float
        The speed command's magnitude [rpm]: the velocity loop holds the motor below it.
    """

    env_id = "jvl_gym/Positioning-v0"
    writes = ("T_SOLL", "V_SOLL")
    reads = ("P_IST", "V_IST")

    def __init__(self, fam: Any, overshoot_weight: float = 2.0, effort_weight: float = 0.01,
                 speed_limit: float = SPEED_LIMIT_RPM) -> None:
        from ..envs import positioning as pos

        k = fam.constants
        self.fam = fam
        self.cpr = float(k.COUNTS_PER_REV)
        self.fine = pos._FINE_TURNS * k.COUNTS_PER_REV
        self.v_norm = pos._NORM_RPM / 60.0 * k.COUNTS_PER_REV / k.OUTER_HZ
        self.bounds = register_bounds(fam.table, self.writes)
        lo, hi = self.bounds["V_SOLL"]
        self.v_limit = int(min(abs(round(fam.task.rpm_to_v_soll(speed_limit))), hi, -lo))
        self.w_over, self.w_effort = float(overshoot_weight), float(effort_weight)
        self.target = 0
        self.direction = 1.0
        self.overshoot = 0.0

    def start(self, link: BusLink, target: int) -> None:
        """Begin a move to ``target`` [counts] from here: passive, P_IST = 0, no torque, then
        velocity mode."""
        link.passive()
        link.write_raws({"P_IST": 0, "T_SOLL": 0, "V_SOLL": 0})
        link.client.write("MODE_REG", int(self.fam.task.VELOCITY_MODE))
        self.target = int(target)
        self.direction = 1.0 if target >= 0 else -1.0
        self.overshoot = 0.0

    def to_registers(self, action: np.ndarray) -> dict[str, int]:
        """Torque limit |a| of full scale, speed command at the speed limit in a's
        direction."""
        a = float(action[0])
        t_full = self.bounds["T_SOLL"][1]
        return {"T_SOLL": int(round(abs(a) * t_full)),
                "V_SOLL": self.v_limit if a >= 0 else -self.v_limit}

    def observe(self, raws: Mapping[str, int], previous: float) -> tuple[np.ndarray, float]:
        """The env's observation (1, 4) and the position error [turns]."""
        from ..envs.compiled import OBS_BOUND

        e = float(self.target - raws["P_IST"])
        obs = np.array([e / (2.0 * self.cpr), e / self.fine, raws["V_IST"] / self.v_norm,
                        previous], dtype=np.float32)
        return np.clip(obs, -OBS_BOUND, OBS_BOUND)[None], e / self.cpr

    def reward(self, error_turns: float, action: float) -> float:
        """The env's reward of one env step at this error and command."""
        past = max(-self.direction * error_turns, 0.0)
        self.overshoot = max(self.overshoot, past)
        return -abs(error_turns) - self.w_over * past - self.w_effort * action * action


BRIDGES: dict[str, Callable[..., Any]] = {PositioningBridge.env_id: PositioningBridge}


@dataclass
class DeployReport:
    """What a deployment did."""

    returns: list[float] = field(default_factory=list)
    lengths: list[int] = field(default_factory=list)
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
        for name, values in self.stats.items():
            known = [v for v in values if not math.isnan(v)]
            lines.append(f"{name}: {np.mean(known):.4g}" if known else f"{name}: n/a")
        return "\n".join(lines)


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


def deploy(env_id: str, policy: Callable[[np.ndarray], Any], url: str, address: int,
           motor_type: str, *, period: float, deadline: float | None = None,
           episodes: int = 1, seed: int = 0, max_seconds: float | None = None,
           max_step: float = 0.5, watchdog_url: str | None = None,
           watchdog_timeout: float = 0.25, timeout: float = 0.1, retries: int = 1,
           trace: str | Path | None = None, stop: threading.Event | None = None
           ) -> DeployReport:
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
    env = gym.make(env_id, motor_type=motor_type).unwrapped
    step_seconds = env.core.decimation * fam.constants.OUTER_DT
    horizon = env.core.max_episode_steps * step_seconds if max_seconds is None else max_seconds
    n_periods = max(1, int(math.ceil(horizon / period - 1e-9)))
    client = _client(url, address, fam, max(timeout, SETUP_TIMEOUT), retries)
    link = BusLink(client, fam.twin.passive_mode)
    window = float(client.read_raw("INPOSWIN")) / bridge.cpr
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
    old_term = None
    if threading.current_thread() is threading.main_thread():
        def on_term(signum: int, frame: Any) -> None:
            raise _Terminate()

        old_term = signal.signal(signal.SIGTERM, on_term)
    t_first = time.monotonic()
    loop_time, t0 = 0.0, t_first
    try:
        for ep in range(episodes):
            env.reset(seed=seed + ep)
            client.timeout = max(timeout, SETUP_TIMEOUT)
            bridge.start(link, int(env.core.target[0]))
            client.timeout = timeout
            supervisor.last = np.zeros(act_dim)
            ret, t0 = 0.0, time.monotonic()
            cols: dict[str, list[float]] = {"t": [], "error": [], "direction": []}
            for k in range(n_periods):
                if stop is not None and stop.is_set():
                    raise KeyboardInterrupt
                start = t0 + k * period
                raws = link.read_raws(bridge.reads)
                t_read = time.monotonic()
                obs, error = bridge.observe(raws, float(supervisor.last[0]))
                action = runner(obs, deadline)
                a, written = supervisor.command(np.asarray(action).reshape(-1))
                t_written = time.monotonic()
                watchdog.beat()
                latencies.append(t_written - t_read)
                r = bridge.reward(error, float(a[0])) * period / step_seconds
                ret += r
                cols["t"].append(start - t0)
                cols["error"].append(error)
                cols["direction"].append(bridge.direction)
                rows.append([ep, k, start - t_first, error, *obs[0].tolist(), float(a[0]),
                             *written.values(), r, t_written - t_read])
                report.periods += 1
                late = time.monotonic() - (start + period)
                if late > period:
                    raise Stopped(f"loop overrun: period {k} ended {late * 1e3:.1f} ms late "
                                  "(more than a period)")
                time.sleep(max(0.0, start + period - time.monotonic()))
            loop_time += time.monotonic() - t0
            supervisor.link.passive()
            report.returns.append(ret)
            report.lengths.append(n_periods)
            trace_cols = {key: np.asarray(v) for key, v in cols.items()}
            for name, value in engineering_metrics(env_id, trace_cols, window).items():
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
        w.writerow(["episode", "period", "time_s", "error_turns", *obs_labels, "action",
                    *bridge.writes, "reward", "latency_s"])
        w.writerows(rows)
