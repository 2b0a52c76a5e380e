"""A deployment in motor time, beside its link model: the traces that compare them step by step.

:func:`deployed_trace` runs what ``jvl-gym deploy`` runs each period (the bridge's read and
observation, the policy, the supervisor's bounds, the bridge's registers and reward) against the
env's machine in process (:mod:`.lines`, the motor ``jvl-gym serve --line`` serves), stepped by
the link model's period and latency in outer samples instead of by the wall clock: the write
lands the link model's latency after the read, as a deployment that holds its writes
(``jvl-gym deploy`` over ``mactalk-tcp``) lands it. :func:`link_trace` runs the same policy on
the env behind the link model (:class:`~jvl_gym.envs.link.LinkEnv`). Both give one row per
period: the observation the policy saw, the action, the registers of the command and the
reward, so a test (or an engineer) compares them period by period, free of the machine's load.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

__all__ = ["MachineClient", "deployed_trace", "link_trace"]


class MachineClient:
    """A MacTalk client's register access, on a machine in process (a twin's motor backend:
    :class:`~.lines.EnvMachine`) with no line between.

    Parameters
    ----------
    machine : EnvMachine
        The machine (one motor).
    """

    def __init__(self, machine: Any) -> None:
        self.machine = machine
        self.table = machine.m.table

    def write(self, name: str, value: float) -> None:
        """Write ``name`` in user units (as the client does: its stored integer)."""
        reg = self.table.lookup(name)
        self.machine.write_raw(name, int(round(value * reg.scale)))

    def pause(self, seconds: float) -> None:
        """Let ``seconds`` of motor time pass (whole outer samples, at least one): the wait of
        a client that polls the motor."""
        dt = float(self.machine.env.fam.constants.OUTER_DT)
        self.machine.step(max(1, int(round(seconds / dt))))

    def read_raw(self, name: str) -> int:
        """The stored integer of ``name``."""
        return int(np.asarray(self.machine.read_raw(name)).reshape(-1)[0])


def _rows() -> dict[str, list[Any]]:
    return {"obs": [], "action": [], "registers": [], "reward": []}


def deployed_trace(env_id: str, policy: Callable[[np.ndarray], Any], link: str,
                   motor_type: str, seed: int, periods: int, max_step: float = 0.5
                   ) -> dict[str, np.ndarray]:
    """One deployed episode of ``periods`` periods from ``seed``, in motor time (module
    docstring): rows ``obs`` (P, K), ``action`` (P, A) (bounded by the supervisor),
    ``registers`` (P, W) (the command written, in the bridge's ``writes`` order) and
    ``reward`` (P,) (the bridge's)."""
    import gymnasium as gym

    import jvl_gym  # noqa: F401

    from ..families import family_of_motor
    from .deploy import BRIDGES, BusLink, PeriodReward, link_latency, loop_period
    from .lines import make_line
    from .supervisor import Limits, Supervisor

    fam = family_of_motor(motor_type)
    env = gym.make(env_id, motor_type=motor_type).unwrapped
    core = env.core
    outer = int(core.decimation)
    step = float(core.decimation * fam.constants.OUTER_DT)
    period = loop_period(env_id, link, motor_type)
    k_steps = int(round(period / step))
    d_steps = int(round(link_latency(env_id, link, motor_type) / step))
    machine = make_line(env_id, motor_type, seed)
    bus = BusLink(MachineClient(machine), fam.twin.passive_mode)
    bridge = BRIDGES[env_id](fam)
    bridge.prepare(bus)
    n_act = len(core.act_labels)
    sup = Supervisor(bus, Limits((-1.0,) * n_act, (1.0,) * n_act, max_step),
                     bridge.to_registers, bridge.bounds)
    env.reset(seed=seed)
    bridge.start(bus, core)
    sup.bounds.update(bridge.bounds)
    rows = _rows()
    rewards = PeriodReward(bridge, float(k_steps))
    for k in range(periods + 1):  # the read after the last period closes it
        raws = bus.read_raws(bridge.reads)
        obs = bridge.observe(raws, sup.last, period)
        if rewards.open:
            r, failed = rewards.close()
            rows["reward"].append(r)
            if failed:
                break
        if k == periods:
            break
        action = np.asarray(policy(obs)).reshape(-1)
        machine.step(d_steps * outer)
        a, written = sup.command(action)
        machine.step((k_steps - d_steps) * outer)
        rewards.begin(a)
        rows["obs"].append(obs[0].copy())
        rows["action"].append(a.copy())
        rows["registers"].append([written[name] for name in bridge.writes])
    return {key: np.asarray(value, dtype=np.float64) for key, value in rows.items()}


def link_trace(env_id: str, policy: Callable[[np.ndarray], Any], link: str, motor_type: str,
               seed: int, periods: int, **env_kwargs: Any) -> dict[str, np.ndarray]:
    """The same policy's episode from ``seed`` on the env behind ``link``: rows ``obs``,
    ``action`` (as the link carries it: rate-limited, quantised), ``registers`` (the link
    model's register command of the action, when it has one; else empty rows) and
    ``reward``, one per period. ``env_kwargs`` go to the env (GearSync's line has no load
    cell noise: ``loadcell_noise=0.0``)."""
    import gymnasium as gym

    import jvl_gym  # noqa: F401

    from ..envs.link import LinkEnv

    env = LinkEnv(gym.make(env_id, motor_type=motor_type, **env_kwargs), link)
    command = env.core.command
    obs, _ = env.reset(seed=seed)
    rows = _rows()
    for _ in range(periods):
        action = np.asarray(policy(obs[None])).reshape(-1)
        rows["obs"].append(np.asarray(obs, dtype=np.float64).copy())
        obs, r, term, trunc, _ = env.step(action)
        q = env.link.quantise(env.core._sent[0])  # as sent: rate-limited, quantised
        rows["action"].append(q)
        rows["registers"].append([] if command is None else
                                 [int(v[0]) for v in command.registers(q[None]).values()])
        rows["reward"].append(r)
        if term or trunc:
            break
    return {key: np.asarray(value, dtype=np.float64) for key, value in rows.items()}
