"""The transfer gap of a policy: its return in simulation, behind the link model, and deployed
in real time over a twin's link.

:func:`measure_transfer` runs one policy on the same episodes three ways: the env as it is
(:func:`~.evaluate.run_episodes`), the env behind the link model (``jvl_gym.envs.link``), and
:func:`~.deploy.deploy` over MacTalk on TCP to a twin served in real time by ``jvl-gym serve
--line`` in a process of its own, whose motor sits in the env's machine drawn per episode with
the same seeds (:mod:`.lines`). The k-th episode of
each is seeded ``seed + k``. :func:`kept` says how much of a return the deployment kept.
"""

from __future__ import annotations

import contextlib
import os
import subprocess
import sys
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["Transfer", "kept", "measure_transfer", "served_twin", "served_line"]


def kept(reference: float, deployed: float) -> float:
    """The fraction of ``reference`` that ``deployed`` keeps: ``1 − (reference − deployed) /
    |reference|`` (1: as much; 0.9: 10 % of the reference's magnitude lost; above 1: better),
    the same for returns of either sign."""
    if reference == 0.0:
        return float("nan")
    return float(1.0 - (reference - deployed) / abs(reference))


@dataclass
class Transfer:
    """One policy's returns three ways (module docstring), one per episode each."""

    env_id: str
    link: str
    seed: int
    period: float
    sim: list[float] = field(default_factory=list)
    link_model: list[float] = field(default_factory=list)
    deployed: list[float] = field(default_factory=list)
    reason: str = ""
    rate_hz: float = float("nan")
    latency_mean: float = float("nan")
    latency_max: float = float("nan")
    load: tuple[float, float, float] = (float("nan"),) * 3

    @property
    def kept_of_link_model(self) -> float:
        """:func:`kept` of the deployed mean return against the link model's."""
        return kept(float(np.mean(self.link_model)), float(np.mean(self.deployed)))

    @property
    def kept_of_sim(self) -> float:
        """:func:`kept` of the deployed mean return against the simulation's."""
        return kept(float(np.mean(self.sim)), float(np.mean(self.deployed)))

    def summary(self) -> str:
        """A few lines for the terminal."""
        m = {k: float(np.mean(getattr(self, k))) for k in ("sim", "link_model", "deployed")}
        return (f"{self.env_id} over {self.link} (period {1e3 * self.period:.2f} ms), "
                f"{len(self.deployed)} episodes from seed {self.seed}:\n"
                f"return: simulation {m['sim']:.2f}, link model {m['link_model']:.2f}, "
                f"deployed {m['deployed']:.2f} ({self.reason})\n"
                f"kept: {100 * self.kept_of_link_model:.1f} % of the link model's, "
                f"{100 * self.kept_of_sim:.1f} % of the simulation's\n"
                f"loop: {self.rate_hz:.1f} Hz, latency mean {1e3 * self.latency_mean:.2f} ms, "
                f"max {1e3 * self.latency_max:.2f} ms; load average "
                + " ".join(f"{x:.2f}" for x in self.load))


def served_twin(env_id: str, motor_type: str, address: int, seed: int) -> Any:
    """A MacTalk twin of one motor at ``address`` inside ``env_id``'s machine (:mod:`.lines`),
    its episodes drawn from ``seed``."""
    from ..protocol.mactalk.twin16 import Twin
    from .lines import make_line

    return Twin(make_line(env_id, motor_type, seed), [address])


#: how long a ``jvl-gym serve`` started by :func:`served_line` may take to serve [s] (its
#: first step compiles or loads the compiled code)
SERVE_START_SECONDS = 300.0


@contextlib.contextmanager
def served_line(env_id: str, motor_type: str, address: int, seed: int) -> Iterator[str]:
    """``jvl-gym serve --line ENV_ID --seed SEED`` in a process of its own (as a deployment
    meets it: the twin's clock and the loop do not share an interpreter) on a free local TCP
    port; yields its MacTalk URL and stops the process at the end."""
    cmd = [sys.executable, "-m", "jvl_gym.cli", "serve", "--motor", motor_type,
           "--address", str(address), "--tcp", "127.0.0.1:0", "--line", env_id,
           "--seed", str(seed)]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    try:
        url = None
        deadline = time.monotonic() + SERVE_START_SECONDS
        assert proc.stdout is not None
        while url is None and time.monotonic() < deadline:
            line = proc.stdout.readline()
            if not line:
                break
            if line.startswith("mactalk tcp: "):
                url = line.split(": ", 1)[1].strip()
        if url is None:
            raise RuntimeError(f"jvl-gym serve --line {env_id} did not start serving")
        yield url
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


def measure_transfer(env_id: str, model: str | Path, link: str, *, motor_type: str,
                     episodes: int = 5, seed: int = 0, url: str | None = None,
                     address: int = 1, trace: str | Path | None = None) -> Transfer:
    """The returns of the policy ``model`` on ``episodes`` episodes from ``seed`` three ways
    (module docstring); deployed to ``url`` (a ``jvl-gym serve --line ENV_ID --seed SEED``)
    or, by default, to one started for it (:func:`served_line`), at the link model's period,
    each write held to its latency over MacTalk on TCP (:func:`~.deploy.holds_latency`) and
    rate-limited as the link model has it (its ``max_step``; none when it states none)."""
    from ..envs.link import parse_link
    from ..envs.registration import vector_class
    from .deploy import deploy, holds_latency, link_latency, load_policy, loop_period
    from .evaluate import run_episodes

    cls = vector_class(env_id)
    policy = load_policy(str(model), env_id, len(cls.act_labels),
                         cls.step_seconds(motor_type))
    kwargs = {"motor_type": motor_type}
    period = loop_period(env_id, link, motor_type)
    hold = link_latency(env_id, link, motor_type) if holds_latency(link) else 0.0
    max_step = parse_link(link).max_step or 2.0  # the link model's rate limit (2: none)
    out = Transfer(env_id, link, seed, period)
    out.sim = run_episodes(env_id, policy, seed, episodes, kwargs).returns.tolist()
    out.link_model = run_episodes(env_id, policy, seed, episodes, kwargs,
                                  link=link).returns.tolist()
    with contextlib.ExitStack() as stack:
        if url is None:
            url = stack.enter_context(served_line(env_id, motor_type, address, seed))
        report = deploy(env_id, policy, url, address, motor_type, period=period,
                        episodes=episodes, seed=seed, trace=trace, hold=hold,
                        max_step=max_step)
    out.deployed = list(report.returns)
    out.reason = report.reason
    out.rate_hz, out.latency_mean, out.latency_max = (report.rate_hz, report.latency_mean,
                                                      report.latency_max)
    out.load = os.getloadavg()
    return out
