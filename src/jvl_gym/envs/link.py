"""The link between a controller and its motor, as a wrapper of any jvl_gym env.

A real set-up does not act on every sample in process: the controller reaches the motor over a
bus (MacTalk or Modbus RTU at a baud rate, CANopen PDOs at a SYNC period) or drives its
analogue input through a DAC. :class:`Link` states such a link; :class:`LinkVectorEnv` (native
``gymnasium.vector.VectorEnv``) and :class:`LinkEnv` (``gymnasium.Env``) put an env's policy
behind it:

- **rate**: the policy acts once per link period, ``k`` env steps (the period rounded up to
  whole env steps); the motor keeps the last command it received between;
- **latency**: an action lands ``d`` env steps into the next period (the time from the motor's
  answer to the read, which samples the observation, to the end of the write that carries the
  action); the observation the policy sees is the one sampled at the read, so it is ``d`` steps
  old when the action lands;
- **rate limit** (``max_step``, as the deployment's supervisor has it): each action moves at
  most ``max_step`` from the one sent before (0: no limit);
- **quantisation**: the action goes through the raw format of the register (or the DAC) that
  carries it: ``round(a·counts)/counts``, clipped to [−1, 1];
- **randomisation** (seeded, per copy): a latency jitter, uniform in [0, ``jitter``] seconds
  on each action, and dropped frames, each write (the command is lost: the motor keeps the one
  before) and each read (the policy sees the observation before) lost with probability
  ``drop``.

MacTalk over TCP (``mactalk-tcp``: a MAC with an Ethernet module, or a twin served by ``jvl-gym
serve``) has no line time to count: its period and latency are stated, as a deployment loop
measures them (docs/deploy.md "Policies trained behind the link"); the deployment holds each
write until the stated latency after its read (``jvl-gym deploy`` with the link), so that the
action lands when the model has it land.

On the MacTalk links (the links ``jvl-gym deploy`` runs over) an env whose action has no
register of its own is commanded as the deployment commands it: :data:`BUS_COMMANDS` (one
definition, used by the link model and by the deployment's bridge). Positioning's torque is
velocity mode with the speed command at the speed limit in the action's direction and the
torque limit T_SOLL = |action| of its full scale (:class:`TorqueLimitCommand`); the env's own
analogue torque (AT_MODE) is what a DAC link drives.

The serial links' times come from the real frames: the bytes of the register writes and reads
an action and an observation need, built by the project's own codecs (MacTalk: one write of a
word per action component, answered by an accept, and one read per observed register, answered
by a data reply; Modbus RTU: one Write Multiple Registers of all action components and one Read
Holding Registers of all observed registers, two 16-bit words each, with the t3.5 silence after
every frame, MIS manual §12), at 10 bits a byte on 8N1. A CANopen link exchanges its PDOs at
each SYNC: the RPDO of an action takes effect at the next SYNC, one period late. A DAC updates
once per ``period`` (default: every env step) with no latency; its resolution is ``bits`` over
±``volts`` against the analogue input's ±10 V.

Episodes end on the env step that ends them; a copy of the vector env that ends inside a period
is reset at once and runs the rest of the period in its new episode, under the link's held
command (its reward in those steps is not counted); ``SAME_STEP`` reports the final
observation. ``NEXT_STEP`` reports the end, and the next period returns the first observation
of a new episode with reward 0 (a vector env steps every copy: a copy that ended is reset,
stepped through that period with no command, and reset again).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.vector import AutoresetMode, VectorEnv

__all__ = ["Link", "LinkVectorEnv", "LinkEnv", "parse_link", "make_link_vec", "KINDS",
           "TorqueLimitCommand", "BUS_COMMANDS", "bus_command", "SPEED_LIMIT_RPM",
           "LoadCellObserver", "BUS_OBSERVERS", "bus_observer", "LOADCELL_FULL_SCALE",
           "register_bounds"]

#: the link kinds: serial register links, CANopen PDOs, an analogue input through a DAC
KINDS = ("mactalk", "mactalk32", "mactalk-tcp", "modbus", "canopen", "dac")
#: the links ``jvl-gym deploy`` runs over: MacTalk's registers (:data:`BUS_COMMANDS`)
MACTALK_KINDS = ("mactalk", "mactalk32", "mactalk-tcp")
#: MacTalk over TCP: the control period [s] and the latency [s] (from the answer to the read to
#: the end of the write) of a deployment loop, as measured (docs/deploy.md): the loop held
#: 10 ms periods, its latency a mean of 2 to 4 ms; the stated latency is the write's hold
TCP_PERIOD = 0.010
TCP_LATENCY = 0.004
#: bits per byte of a serial link on 8N1: start, 8 data bits, stop
BITS_PER_BYTE = 10
#: the analogue input's span [V] the action ±1 stands for (±10 V, MAC050–141 manual 4.4.5)
ANALOGUE_VOLTS = 10.0
#: raw counts of the action's full scale on a register link: the analogue-torque scale
#: ±1023 ↔ ±T_SOLL (MAC050–141 manual 4.4.5)
REGISTER_COUNTS = 1023


@dataclass(frozen=True)
class Link:
    """A controller's link to its motor.

    Attributes
    ----------
    kind : str
        One of :data:`KINDS`.
    baud : int
        Baud rate of a serial link (``mactalk``, ``mactalk32``, ``modbus``).
    sync_period : float
        SYNC period of a CANopen link [s].
    bits, volts : int, float
        Resolution and range (±volts) of a DAC.
    period : float
        Update period of a DAC [s] (0: every env step), or the control period of MacTalk over
        TCP (0: :data:`TCP_PERIOD`).
    latency : float
        The latency of MacTalk over TCP [s] (negative: :data:`TCP_LATENCY`).
    counts : int
        Raw counts of the action's full scale on a register link.
    jitter : float
        Extra latency of each action, uniform in [0, jitter] seconds.
    drop : float
        Probability that a frame (a write or a read) is lost.
    max_step : float
        Largest change of the action from the one sent before (the deployment's rate limit,
        ``jvl-gym deploy --max-step``; 0: none).
    """

    kind: str
    baud: int = 19200
    sync_period: float = 0.002
    bits: int = 12
    volts: float = 10.0
    period: float = 0.0
    latency: float = -1.0
    counts: int = REGISTER_COUNTS
    jitter: float = 0.0
    drop: float = 0.0
    max_step: float = 0.0

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"unknown link {self.kind!r}; known: {', '.join(KINDS)}")
        checks = {"baud": self.baud > 0, "sync_period": self.sync_period > 0,
                  "bits": 1 < self.bits <= 24, "volts": self.volts > 0,
                  "period": self.period >= 0, "latency": self.latency >= 0
                  or self.latency == -1.0, "counts": self.counts >= 1,
                  "jitter": self.jitter >= 0, "drop": 0 <= self.drop < 1,
                  "max_step": self.max_step >= 0}
        for name, ok in checks.items():
            value = getattr(self, name)
            if not (ok and math.isfinite(value)):
                raise ValueError(f"link {self.kind}: bad {name} {value!r}")

    # ------------------------------------------------------------------ frames and times
    def frame_bytes(self, n_actions: int, n_registers: int) -> tuple[int, int]:
        """Bytes on the line of one period of a serial link: (those of the reads of
        ``n_registers`` observed registers, those of the writes of ``n_actions`` action
        components), requests and replies, from the codecs' frames."""
        if self.kind == "mactalk":
            from ..protocol.mactalk import codec16 as mt

            read = len(mt.encode_read(1, 1)) + len(mt.encode_data_reply(bytes(4)))
            write = len(mt.encode_write_word(1, 1, 0)) + len(mt.encode_accept())
            return n_registers * read, n_actions * write
        if self.kind == "mactalk32":
            from ..protocol.mactalk import codec32 as mt32

            read = len(mt32.encode_read(1, 1)) + len(mt32.encode_reply(1, bytes(4)))
            write = len(mt32.encode_write_value(1, 1, 0, 4)) + len(mt32.encode_accept())
            return n_registers * read, n_actions * write
        if self.kind == "modbus":
            from ..protocol.modbus import codec as mb

            words = 2 * n_registers
            read = (len(mb.encode_read_request(1, 0, words))
                    + len(mb.encode_read_response(1, [0] * words))) if n_registers else 0
            words = 2 * n_actions
            write = (len(mb.encode_write_request(1, 0, [0] * words))
                     + len(mb.encode_write_response(1, 0, words))) if n_actions else 0
            return read, write
        raise ValueError(f"a {self.kind} link sends no serial frames")

    def times(self, n_actions: int, n_registers: int, step: float) -> tuple[float, float]:
        """(period, latency) [s] of one exchange: an action of ``n_actions`` components after an
        observation of ``n_registers`` registers, on an env of ``step`` seconds a step.

        Serial links: the period is the line time of all frames; the latency runs from the
        motor's answer to the first read (the observation's sample) to the end of the last
        write request. CANopen: one SYNC period each. A DAC: its update period, no latency.
        MacTalk over TCP: the stated period and latency.
        """
        if self.kind == "mactalk-tcp":
            period = self.period or TCP_PERIOD
            latency = TCP_LATENCY if self.latency < 0 else self.latency
            if latency >= period:
                raise ValueError(f"link {self}: the latency ({latency:g} s) must be shorter "
                                 f"than the period ({period:g} s)")
            return period, latency
        if self.kind == "canopen":
            return self.sync_period, self.sync_period
        if self.kind == "dac":
            return (self.period or step), 0.0
        read, write = self.frame_bytes(n_actions, n_registers)
        byte = BITS_PER_BYTE / self.baud
        if self.kind == "modbus":
            from ..protocol.modbus import codec as mb

            gap = mb.silence(mb.SerialFormat(self.baud))
            frames = 2 * bool(n_registers) + 2 * bool(n_actions)
            request = len(mb.encode_read_request(1, 0, 2 * n_registers)) if n_registers else 0
            answer = len(mb.encode_write_response(1, 0, 2 * n_actions)) if n_actions else 0
            period = (read + write) * byte + frames * gap
            latency = period - request * byte - gap * bool(n_registers) - answer * byte - gap
            return period, max(latency, 0.0)
        first_request = len(self._read_request()) if n_registers else 0
        accept = self._accept_bytes() if n_actions else 0
        period = (read + write) * byte
        return period, max(period - (first_request + accept) * byte, 0.0)

    def _read_request(self) -> bytes:
        if self.kind == "mactalk":
            from ..protocol.mactalk import codec16 as mt

            return mt.encode_read(1, 1)
        from ..protocol.mactalk import codec32 as mt32

        return mt32.encode_read(1, 1)

    def _accept_bytes(self) -> int:
        if self.kind == "mactalk":
            from ..protocol.mactalk import codec16 as mt

            return len(mt.encode_accept())
        from ..protocol.mactalk import codec32 as mt32

        return len(mt32.encode_accept())

    def quantise(self, action: np.ndarray) -> np.ndarray:
        """``action`` through the raw format that carries it: the register's ``counts`` per
        full scale, or the DAC's ``bits`` over ±``volts`` against the input's ±10 V; clipped
        to [−1, 1] (and to the DAC's range)."""
        a = np.clip(np.asarray(action, dtype=np.float64), -1.0, 1.0)
        if self.kind == "dac":
            lsb = 2.0 * self.volts / 2**self.bits
            top = min(self.volts, ANALOGUE_VOLTS)
            volts = np.clip(np.round(a * ANALOGUE_VOLTS / lsb) * lsb, -top, top)
            return volts / ANALOGUE_VOLTS
        return np.round(a * self.counts) / self.counts

    def __str__(self) -> str:
        main = {"canopen": f"{self.sync_period * 1e3:g}ms", "dac": f"{self.bits}",
                "mactalk-tcp": f"{(self.period or TCP_PERIOD) * 1e3:g}ms"}.get(
            self.kind, f"{self.baud}")
        extra = "".join(f",{k}={getattr(self, k):g}" for k in ("jitter", "drop", "max_step")
                        if getattr(self, k))
        if self.kind == "mactalk-tcp" and self.latency >= 0:
            extra = f",latency={self.latency:g}" + extra
        return f"{self.kind}:{main}{extra}"


def parse_link(text: str | Link) -> Link:
    """A :class:`Link` from its text: ``KIND:VALUE[,key=value...]``.

    ``mactalk:19200``, ``mactalk32:115200``, ``modbus:19200`` (baud); ``canopen:2ms`` (SYNC
    period, ``ms`` or seconds); ``mactalk-tcp:10ms`` (control period); ``dac:12`` (bits;
    ``dac:12:5`` ±5 V); then any of ``jitter=SECONDS``, ``drop=P``, ``counts=N``,
    ``period=SECONDS``, ``latency=SECONDS`` (MacTalk over TCP), ``max_step=A``. Raises
    ValueError with one line on bad text.
    """
    if isinstance(text, Link):
        return text
    head, *pairs = str(text).strip().split(",")
    kind, _, value = head.partition(":")
    kind = kind.strip().lower()
    if kind not in KINDS:
        raise ValueError(f"link {text!r}: unknown kind {kind!r}; known: {', '.join(KINDS)} "
                         "(e.g. mactalk:19200, canopen:2ms, dac:12)")
    fields: dict[str, Any] = {}
    try:
        if kind == "canopen" and value:
            fields["sync_period"] = _seconds(value)
        elif kind == "mactalk-tcp" and value:
            fields["period"] = _seconds(value)
        elif kind == "dac" and value:
            bits, _, volts = value.partition(":")
            fields["bits"] = int(bits)
            if volts:
                fields["volts"] = float(volts)
        elif value:
            fields["baud"] = int(value)
        for pair in pairs:
            key, _, v = pair.partition("=")
            key = key.strip()
            if key not in ("jitter", "drop", "counts", "period", "latency", "max_step"):
                raise ValueError(f"unknown key {key!r} (jitter, drop, counts, period, latency, "
                                 "max_step)")
            fields[key] = int(v) if key == "counts" else _seconds(v)
        made = Link(kind, **fields)
        made.times(1, 1, 1e-3)  # a stated latency longer than its period
        return made
    except ValueError as exc:
        raise ValueError(f"link {text!r}: {exc}") from None


#: the speed limit of Positioning's torque over MacTalk [rpm]: the scale of the env's speed
#: observation and the speed of its firmware baseline
SPEED_LIMIT_RPM = 3000.0


def register_bounds(table: Any, names: Sequence[str]) -> dict[str, tuple[int, int]]:
    """Raw (stored integer) range of each register of ``names`` in ``table``: the bounds the
    link model and the deployment's supervisor hold every command within."""
    out = {}
    for name in names:
        reg = table.lookup(name)
        out[name] = (int(np.ceil(reg.minimum * reg.scale - 1e-9)),
                     int(np.floor(reg.maximum * reg.scale + 1e-9)))
    return out


class TorqueLimitCommand:
    """Positioning's torque action over MacTalk's registers: velocity mode (MAC050–141 manual
    4.4.2) with the speed command V_SOLL at the speed limit in the action's direction and the
    torque limit T_SOLL = |action| × its full scale. The velocity loop saturates at T_SOLL, so
    the torque follows the action while the motor is below the speed limit. The acceleration
    A_SOLL is set to its largest value at the start: velocity mode ramps its speed reference at
    A_SOLL, and at the default (160) the ramp, not T_SOLL, would set the torque (a reversal
    of the action would take the ramp's time to reverse the torque).

    Parameters
    ----------
    fam : Family
        The motor's family (its register table, velocity mode and speed unit).
    speed_limit : float
        The speed command's magnitude [rpm].
    """

    env_id = "jvl_gym/Positioning-v0"
    writes = ("T_SOLL", "V_SOLL")

    def __init__(self, fam: Any, speed_limit: float = SPEED_LIMIT_RPM) -> None:
        self.mode = int(fam.task.VELOCITY_MODE)
        self.passive = int(fam.twin.passive_mode)
        self.bounds = register_bounds(fam.table, self.writes)
        self.a_max = int(register_bounds(fam.table, ("A_SOLL",))["A_SOLL"][1])
        lo, hi = self.bounds["V_SOLL"]
        self.v_limit = int(min(abs(round(fam.task.rpm_to_v_soll(speed_limit))), hi, -lo))
        self.t_full = int(self.bounds["T_SOLL"][1])

    def registers(self, actions: np.ndarray) -> dict[str, np.ndarray]:
        """The raw registers of each action (rows of ``actions``, (N, 1)): T_SOLL and
        V_SOLL, (N,) each."""
        a = np.asarray(actions, dtype=np.float64)[:, 0]
        return {"T_SOLL": np.round(np.abs(a) * self.t_full).astype(np.int64),
                "V_SOLL": np.where(a >= 0, self.v_limit, -self.v_limit).astype(np.int64)}

    def start_registers(self) -> dict[str, int]:
        """The registers an episode starts with: no torque, no speed, the largest
        acceleration (class docstring)."""
        return {"T_SOLL": 0, "V_SOLL": 0, "A_SOLL": self.a_max}

    def start(self, motors: Any, idx: np.ndarray) -> None:
        """Begin an episode of the motors ``idx`` as the deployment does: passive (the
        family's passive mode, reached through a stop), then :meth:`start_registers`."""
        motors.write("MODE_REG", self.passive, index=idx)
        motors.write_raw_many(self.start_registers(), index=idx)

    def write(self, motors: Any, idx: np.ndarray, actions: np.ndarray) -> None:
        """Command the motors ``idx`` with ``actions`` (N, 1): the registers, and velocity
        mode on a motor not yet in it (the first command after :meth:`start`, once the stop
        to passive is done)."""
        motors.write_raw_many(self.registers(actions), index=idx)
        off = idx[motors.read_raw("MODE_REG")[idx] != self.mode]
        if off.size:
            motors.write("MODE_REG", self.mode, index=off)


#: the load cell's force at +10 V on the analogue input [N] (GearSync's references are
#: 10–25 N and a web breaks at 3 × its reference: 75 N at most)
LOADCELL_FULL_SCALE = 100.0
#: the analogue input's counts at +10 V (ANINP, MAC050–141 manual 3.2.122)
ANINP_FULL = 1023


class LoadCellObserver:
    """GearSync's tension channels as a controller over MacTalk computes them: from the load
    cell on the analogue input, read as ANINP (1023 counts for :data:`LOADCELL_FULL_SCALE`,
    0.1 N a count), once a period: the tension error, its rate since the last read and the
    leaky integral of the error, kept by the controller (the env computes them every step
    from the load cell's unquantised reading). The deployment's bridge and the link model
    observe through it alike.

    Parameters
    ----------
    n : int
        Copies.
    tau : float
        The leaky integral's time constant [s] (the env's).
    """

    env_id = "jvl_gym/GearSync-v0"

    def __init__(self, n: int, tau: float) -> None:
        self.tau = float(tau)
        self.previous = np.full(n, np.nan)
        self.integral = np.zeros(n)

    @staticmethod
    def tension_of(aninp: np.ndarray) -> np.ndarray:
        """The tension [N] of an ANINP reading."""
        return np.asarray(aninp, dtype=np.float64) / ANINP_FULL * LOADCELL_FULL_SCALE

    @staticmethod
    def aninp_of(tension: np.ndarray) -> np.ndarray:
        """The ANINP reading of a tension [N] (the load cell on 0..10 V)."""
        volts = np.clip(np.asarray(tension, dtype=np.float64) / LOADCELL_FULL_SCALE, -1.0, 1.0)
        return np.round(volts * ANINP_FULL)

    def reset(self, idx: np.ndarray) -> None:
        """A new episode of the copies ``idx``: no reading before, no integral."""
        self.previous[idx] = np.nan
        self.integral[idx] = 0.0

    def observe(self, idx: np.ndarray, tension: np.ndarray, ref: np.ndarray, period: float
                ) -> np.ndarray:
        """The channels (M, 3) of the copies ``idx`` at a read of ``tension`` [N] (the
        quantised reading), against the references ``ref`` [N], ``period`` s after the last
        read: the error, the rate (0.1 s of its change), the integral × 10 (as the env
        scales them)."""
        tension = np.asarray(tension, dtype=np.float64)
        before = np.where(np.isnan(self.previous[idx]), tension, self.previous[idx])
        self.previous[idx] = tension
        e = (tension - ref) / ref
        self.integral[idx] += period * (e - self.integral[idx] / self.tau)
        return np.stack([e, (tension - before) / ref * (0.1 / period),
                         self.integral[idx] * 10.0], axis=1)

    def link_observation(self, env: Any, idx: np.ndarray, obs: np.ndarray, period: float
                         ) -> None:
        """Replace the tension channels of ``obs`` rows ``idx`` (the env's, from the load
        cell's unquantised reading) by those read through ANINP (in place)."""
        from .compiled import OBS_BOUND

        ref = np.asarray(env.tension_ref, dtype=np.float64)[idx]
        measured = ref * (1.0 + obs[idx, 0].astype(np.float64))
        chans = self.observe(idx, self.tension_of(self.aninp_of(measured)), ref, period)
        obs[idx, 0:3] = np.clip(chans, -OBS_BOUND, OBS_BOUND)


#: the register command of each env whose action has no register of its own, on MacTalk
BUS_COMMANDS: dict[str, Any] = {TorqueLimitCommand.env_id: TorqueLimitCommand}


#: the observers of an env whose observation a controller computes from what it reads
BUS_OBSERVERS: dict[str, Any] = {LoadCellObserver.env_id: LoadCellObserver}


def bus_observer(env_id: str, link: Link, n: int) -> Any:
    """The observer of ``env_id`` on ``link`` (:data:`BUS_OBSERVERS`), or None."""
    if link.kind not in MACTALK_KINDS or env_id not in BUS_OBSERVERS:
        return None
    from . import gear_sync as gs

    return BUS_OBSERVERS[env_id](n, gs._INTEGRAL_TAU)


def bus_command(env_id: str, link: Link, fam: Any) -> Any:
    """The register command of ``env_id`` on ``link`` (:data:`BUS_COMMANDS`), or None: the
    env's own action (a link that is not MacTalk, or an env whose action is a register's)."""
    if link.kind not in MACTALK_KINDS or env_id not in BUS_COMMANDS:
        return None
    return BUS_COMMANDS[env_id](fam)


def _seconds(text: str) -> float:
    """Seconds from ``"2ms"`` or ``"0.002"``."""
    text = text.strip()
    return float(text[:-2]) / 1e3 if text.endswith("ms") else float(text)


def observed_registers(labels: Sequence[str]) -> int:
    """The registers a controller reads for an observation of ``labels``: one per component
    but the previous action, which it knows."""
    return sum(not label.startswith("previous") for label in labels)


class LinkVectorEnv(VectorEnv):
    """A native jvl_gym vector env behind a :class:`Link` (module docstring).

    Parameters
    ----------
    env : MotorVectorEnv
        The env, in ``AutoresetMode.DISABLED`` (:func:`make_link_vec` builds one).
    link : Link or str
        The link (:func:`parse_link`).
    autoreset_mode : AutoresetMode or str
        The wrapper's own autoreset mode (``NEXT_STEP``, ``SAME_STEP`` or ``DISABLED``).
    command : object, optional
        The register command the held action goes through (:data:`BUS_COMMANDS`; default:
        :func:`bus_command` of the env on the link).
    """

    def __init__(self, env: Any, link: Link | str,
                 autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP,
                 command: Any = "default") -> None:
        if env.autoreset_mode != AutoresetMode.DISABLED:
            raise ValueError("LinkVectorEnv wraps an env in AutoresetMode.DISABLED "
                             "(make_link_vec builds one)")
        self.env = env
        self.link = parse_link(link)
        if isinstance(command, str) and command == "default":
            command = bus_command(_env_id(env), self.link, env.fam)
        #: the register command of the held action, or None (the env's own action)
        self.command = command
        #: the observer of what the controller reads, or None (the env's own observation)
        self.observer = bus_observer(_env_id(env), self.link, env.num_envs)
        self.num_envs = env.num_envs
        self.single_observation_space = env.single_observation_space
        self.single_action_space = env.single_action_space
        self.observation_space = env.observation_space
        self.action_space = env.action_space
        self.autoreset_mode = _mode(autoreset_mode)
        self.metadata = {**env.metadata, "autoreset_mode": self.autoreset_mode}
        self.render_mode = env.render_mode
        step = float(env.decimation * env.fam.constants.OUTER_DT)
        n_act = len(env.act_labels)
        period, latency = self.link.times(n_act, observed_registers(env.obs_labels), step)
        #: env step [s], the link's period and latency [s], and both in env steps
        self.step_seconds = step
        self.period_seconds, self.latency_seconds = period, latency
        self.period_steps = max(1, math.ceil(period / step - 1e-9))
        self.latency_steps = int(round(latency / step))
        self.jitter_steps = int(round(self.link.jitter / step))
        if env.max_episode_steps < self.period_steps:
            raise ValueError(f"the link's period ({self.period_steps} env steps) is longer "
                             f"than an episode ({env.max_episode_steps} steps)")
        n = self.num_envs
        depth = (self.latency_steps + self.jitter_steps) // self.period_steps + 2
        self._held = np.zeros((n, n_act))
        self._sent = np.zeros((n, n_act))
        self._due = np.full((n, depth), np.iinfo(np.int64).max, dtype=np.int64)
        self._queued = np.zeros((n, depth, n_act))
        self._clock = np.zeros(n, dtype=np.int64)
        self._seen = np.zeros((n, len(env.obs_labels)), dtype=np.float32)
        self._rngs: list[np.random.Generator] = [np.random.default_rng() for _ in range(n)]
        self._autoreset = np.zeros(n, dtype=bool)

    # ------------------------------------------------------------------ gymnasium API
    def reset(self, *, seed: int | Sequence[int | None] | None = None,
              options: dict[str, Any] | None = None) -> tuple[np.ndarray, dict[str, Any]]:
        """Reset the env (as its ``reset``) and the link of the copies reset: no command
        held (0), nothing in flight, the link's generator seeded with the copy's seed."""
        obs, info = self.env.reset(seed=seed, options=options)
        mask = None if not options else options.get("reset_mask")
        idx = np.arange(self.num_envs) if mask is None else np.flatnonzero(mask)
        seeds = _seeds(seed, self.num_envs)
        for i in idx:
            if seeds[i] is not None:
                self._rngs[i] = np.random.default_rng([seeds[i], 0x4C494E4B])
        self._restart(idx, obs)
        self._autoreset[idx] = False
        return obs.copy(), info

    def step(self, actions: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray,
                                          dict[str, Any]]:
        """One link period: the actions are sent (quantised, late, maybe lost), the motor
        runs ``period_steps`` env steps, the next observation is read (maybe lost)."""
        a = np.asarray(actions, dtype=np.float64)
        if a.shape != self._held.shape:
            self.env._refuse_action(a)
        if not np.isfinite(a).all():
            raise ValueError("action must be finite")
        n = self.num_envs
        if self.autoreset_mode == AutoresetMode.DISABLED and self._autoreset.any():
            raise RuntimeError("AutoresetMode.DISABLED: reset the finished copies (reset_mask) "
                               "before stepping")
        info: dict[str, Any] = {}
        fresh = self._autoreset.copy()
        if self.autoreset_mode == AutoresetMode.NEXT_STEP and fresh.any():
            obs, _ = self.env.reset(options={"reset_mask": fresh})
            self._restart(np.flatnonzero(fresh), obs)
            self._autoreset[:] = False
            if fresh.all():
                z = np.zeros(n, dtype=bool)
                return self._seen.copy(), np.zeros(n), z, z.copy(), info
        if self.link.max_step:  # the supervisor's rate limit, on the action before
            step = self.link.max_step
            a = np.where(fresh[:, None], a, np.clip(a, self._sent - step, self._sent + step))
        self._sent[~fresh] = np.clip(a, -1.0, 1.0)[~fresh]
        self._send(self.link.quantise(a), ~fresh)
        reward = np.zeros(n)
        terminated = np.zeros(n, dtype=bool)
        truncated = np.zeros(n, dtype=bool)
        ended = np.zeros(n, dtype=bool)
        final = np.full(n, None, dtype=object)
        for _ in range(self.period_steps):
            self._land()
            obs, r, term, trunc, step_info = self.env.step(self._held.copy())
            counted = ~ended & ~fresh
            reward += np.where(counted, r, 0.0)
            now = (term | trunc) & counted
            if now.any():
                terminated |= term & now
                truncated |= trunc & now
                _merge_end(info, step_info, now)
                for i in np.flatnonzero(now):
                    final[i] = obs[i].copy()
                ended |= now
            done = term | trunc
            if done.any():  # reset at once: the rest of the period runs the new episode
                obs, _ = self.env.reset(options={"reset_mask": done})
                self._restart(np.flatnonzero(done), obs, keep_clock=True)
        if fresh.any():  # NEXT_STEP: the copies that ended start their episode from here
            obs, _ = self.env.reset(options={"reset_mask": fresh})
            self._restart(np.flatnonzero(fresh), obs)
        read = np.array([rng.random() >= self.link.drop if self.link.drop else True
                         for rng in self._rngs])
        got = read | ended | fresh
        if self.observer is not None:
            # (a copy reset at the period's end was observed by its reset)
            self.observer.link_observation(self.env, np.flatnonzero(got & ~fresh), obs,
                                           self.period_steps * self.step_seconds)
        self._seen[got] = obs[got]
        if self.autoreset_mode == AutoresetMode.SAME_STEP and ended.any():
            info.update({"final_obs": final, "_final_obs": ended.copy(),
                         "final_info": {}, "_final_info": ended.copy()})
        elif self.autoreset_mode != AutoresetMode.SAME_STEP and ended.any():
            # NEXT_STEP / DISABLED: the copy shows its last observation until it is reset
            for i in np.flatnonzero(ended):
                self._seen[i] = final[i]
        self._autoreset = ended.copy() if self.autoreset_mode != AutoresetMode.SAME_STEP \
            else np.zeros(n, dtype=bool)
        return self._seen.copy(), reward, terminated, truncated, info

    def render(self) -> Any:
        """The env's scope images."""
        return self.env.render()

    def close(self, **kwargs: Any) -> None:
        """Close the env."""
        self.env.close()

    @property
    def unwrapped(self) -> Any:
        return self.env

    # ------------------------------------------------------------------ the link
    def _restart(self, idx: np.ndarray, obs: np.ndarray, keep_clock: bool = False) -> None:
        self._held[idx] = 0.0
        self._sent[idx] = 0.0
        if self.command is not None and len(idx):
            self.command.start(self.env.motors, np.asarray(idx))
        self._due[idx] = np.iinfo(np.int64).max
        if not keep_clock:
            self._clock[idx] = 0
        if self.observer is not None and len(idx):
            idx = np.asarray(idx)
            self.observer.reset(idx)
            self.observer.link_observation(self.env, idx, obs,
                                           self.period_steps * self.step_seconds)
        self._seen[idx] = obs[idx]

    def _send(self, actions: np.ndarray, mask: np.ndarray) -> None:
        """Queue each copy's action to land ``latency (+ jitter)`` steps from now, unless its
        frame is lost."""
        for i in np.flatnonzero(mask):
            rng = self._rngs[i]
            delay = self.latency_steps
            if self.jitter_steps:
                delay += int(rng.integers(0, self.jitter_steps + 1))
            if self.link.drop and rng.random() < self.link.drop:
                continue
            slot = int(np.argmax(self._due[i]))
            self._due[i, slot] = self._clock[i] + delay
            self._queued[i, slot] = actions[i]

    def _land(self) -> None:
        """Apply the latest action that has landed by now on each copy; count a step."""
        landed = self._due <= self._clock[:, None]
        if landed.any():
            for i in np.flatnonzero(landed.any(axis=1)):
                slots = np.flatnonzero(landed[i])
                last = slots[np.argmax(self._due[i, slots])]
                self._held[i] = self._queued[i, last]
                self._due[i, slots] = np.iinfo(np.int64).max
            if self.command is not None:
                idx = np.flatnonzero(landed.any(axis=1))
                self.command.write(self.env.motors, idx, self._held[idx])
        self._clock += 1


def _env_id(env: Any) -> str:
    """The id of a native vector env, from its class (:mod:`.registration`)."""
    from .registration import ENV_IDS, vector_class

    for env_id in ENV_IDS:
        if vector_class(env_id) is type(env):
            return env_id
    return ""


def _mode(mode: AutoresetMode | str) -> AutoresetMode:
    """An autoreset mode from itself, its value (``"SameStep"``) or its name
    (``"same_step"``)."""
    if isinstance(mode, str) and mode.upper() in AutoresetMode.__members__:
        return AutoresetMode[mode.upper()]
    return AutoresetMode(mode)


def _seeds(seed: int | Sequence[int | None] | None, n: int) -> list[int | None]:
    if seed is None:
        return [None] * n
    if isinstance(seed, (int, np.integer)):
        return [int(seed) + i for i in range(n)]
    return list(seed)


def _merge_end(info: dict[str, Any], step_info: dict[str, Any], now: np.ndarray) -> None:
    """Copy the end info (reason, episode statistics) of the copies ``now`` into ``info``."""
    for key, values in step_info.items():
        if key.startswith("_") or not isinstance(values, np.ndarray):
            continue
        if key not in info:
            info[key] = np.zeros_like(values)
            info["_" + key] = np.zeros(now.size, dtype=bool)
            if values.dtype == object:
                info[key].fill("")
        info[key][now] = values[now]
        info["_" + key] |= now


def make_link_vec(env_id: str, num_envs: int, link: Link | str,
                  autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP,
                  **env_kwargs: Any) -> LinkVectorEnv:
    """The native vector env of ``env_id`` behind ``link``."""
    from .registration import vector_class

    link = parse_link(link)
    env = vector_class(env_id)(num_envs, autoreset_mode=AutoresetMode.DISABLED, **env_kwargs)
    return LinkVectorEnv(env, link, autoreset_mode)


class LinkEnv(gym.Env):
    """A single jvl_gym env behind a :class:`Link`: the vector link over the env's one-copy
    core, so a single env seeded ``s`` equals copy ``i`` of a vector env seeded ``s − i``.

    Parameters
    ----------
    env : MotorEnv
        The single env.
    link : Link or str
        The link.
    """

    def __init__(self, env: Any, link: Link | str) -> None:
        self.env = env
        self.core = LinkVectorEnv(env.unwrapped.core, link, AutoresetMode.DISABLED)
        self.link = self.core.link
        self.observation_space = env.observation_space
        self.action_space = env.action_space
        self.metadata = env.metadata
        self.render_mode = env.render_mode
        self._ended = False

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None
              ) -> tuple[np.ndarray, dict[str, Any]]:
        super().reset(seed=seed)
        obs, _ = self.core.reset(seed=None if seed is None else [seed], options=options)
        self._ended = False
        return obs[0], {}

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        if self._ended:
            raise RuntimeError("LinkEnv: the episode has ended; call reset() before step()")
        a = np.asarray(action)
        if a.shape != self.action_space.shape or a.dtype.kind not in "fiu":
            self.core.env._refuse_action(a, self.action_space.shape)
        obs, reward, term, trunc, info = self.core.step(a[None])
        out: dict[str, Any] = {}
        if term[0] or trunc[0]:
            self._ended = True
            out = {k: (str(v[0]) if v.dtype == object else float(v[0]))
                   for k, v in info.items() if not k.startswith("_")}
        return obs[0].copy(), float(reward[0]), bool(term[0]), bool(trunc[0]), out

    def render(self) -> Any:
        return self.env.render()

    def close(self) -> None:
        self.env.close()

