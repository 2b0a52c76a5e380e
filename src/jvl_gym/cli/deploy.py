"""``jvl-gym deploy``: run a policy in real time against a twin (``jvl-gym serve``) or a motor
over MacTalk, behind the safety supervisor (:mod:`jvl_gym.rl.deploy`,
:mod:`jvl_gym.rl.supervisor`).

Examples
--------
``jvl-gym serve --motor MAC140 --address 19 --tcp 127.0.0.1:5000`` and then
``jvl-gym deploy jvl_gym/Positioning-v0 --policy runs/Positioning-v0-mac050_141-ppo.zip
--url socket://127.0.0.1:5000 --address 19 --link mactalk:19200 --trace deploy.csv``
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated

import typer

from ..envs.link import parse_link
from ..rl.deploy import holds_latency, link_latency, loop_period
from .app import CliError
from .identified import HELP as IDENTIFIED_HELP
from .identified import identified_kwargs

#: the supervisor's rate limit when neither --max-step nor the link states one
DEFAULT_MAX_STEP = 0.5

__all__ = ["deploy", "loop_period"]


def deploy(env_id: Annotated[str, typer.Argument(help="e.g. jvl_gym/Positioning-v0")],
           policy: Annotated[str, typer.Option(help="an SB3 .zip, or 'zero'")] = "zero",
           url: Annotated[str, typer.Option(
               help="the motor's MacTalk port: socket://127.0.0.1:5000, /dev/ttyUSB0 …")]
           = "socket://127.0.0.1:5000",
           address: Annotated[int, typer.Option(help="the motor's address (MYADDR)")] = 1,
           motor: Annotated[str | None, typer.Option(
               help="motor type (its family; default: the env's)")] = None,
           link: Annotated[str, typer.Option(
               help="the link model the period follows (jvl-gym train --link)")]
           = "mactalk:19200",
           period: Annotated[float | None, typer.Option(
               help="control period [s] (default: the link's)")] = None,
           deadline: Annotated[float | None, typer.Option(
               help="time the policy has for an action [s] (default: the period)")] = None,
           episodes: Annotated[int, typer.Option(min=1)] = 1,
           seed: Annotated[int, typer.Option(help="seed of the first episode")] = 0,
           max_step: Annotated[float | None, typer.Option(
               help="rate limit: largest change of the command per period (default: the "
               "link's max_step, else 0.5)")] = None,
           watchdog_timeout: Annotated[float, typer.Option(
               help="seconds without a heartbeat before the watchdog stops the motor")] = 0.25,
           watchdog_url: Annotated[str | None, typer.Option(
               help="the watchdog's own connection (default: --url)")] = None,
           timeout: Annotated[float, typer.Option(help="the client's answer time-out [s]")]
           = 0.1,
           trace: Annotated[Path | None, typer.Option(help="CSV of every period")] = None,
           line_time: Annotated[bool, typer.Option(
               "--line-time", help="hold each write until the link model's latency after the "
               "read: the serial line's time, which a twin over TCP does not take (always on "
               "a mactalk-tcp link: its stated latency)")] = False,
           identified: Annotated[Path | None, typer.Option(
               help=IDENTIFIED_HELP + "; the motor type is that motor's")] = None
           ) -> None:
    """Run POLICY on the motor in real time, bounded and watched by the safety supervisor;
    print the episodes' return and metrics, the loop's rate and latency, and why it stopped."""
    from ..envs import ENV_IDS
    from ..rl.deploy import BRIDGES, load_policy
    from ..rl.deploy import deploy as run

    if env_id not in ENV_IDS:
        raise typer.BadParameter(f"unknown env {env_id!r}; known: {', '.join(ENV_IDS)}")
    if env_id not in BRIDGES:
        raise typer.BadParameter(f"{env_id}: deploy knows how {', '.join(BRIDGES)} reaches "
                                 "a motor")
    for name, value in (("--period", period), ("--deadline", deadline),
                        ("--max-step", max_step), ("--watchdog-timeout", watchdog_timeout),
                        ("--timeout", timeout)):
        if value is not None and not (value > 0 and math.isfinite(value)):
            raise typer.BadParameter(f"{name} must be a number > 0, got {value}")
    from ..envs.registration import vector_class

    cls = vector_class(env_id)
    env_kwargs, _ = identified_kwargs(identified, env_id)
    if env_kwargs is not None and motor is not None and motor != env_kwargs["motor_type"]:
        raise CliError(f"--identified: {identified} is a {env_kwargs['motor_type']}, not "
                       f"--motor {motor}")
    motor_type = (env_kwargs["motor_type"] if env_kwargs is not None
                  else motor or cls._default_type())
    try:
        step = period if period is not None else loop_period(env_id, link, motor_type)
        if max_step is None:
            max_step = parse_link(link).max_step or DEFAULT_MAX_STEP
        pol = load_policy(policy, env_id, len(cls.act_labels), cls.step_seconds(motor_type))
    except (ValueError, FileNotFoundError) as exc:
        raise CliError(str(exc)) from None
    try:
        report = run(env_id, pol, url, address, motor_type, period=step, deadline=deadline,
                     episodes=episodes, seed=seed, max_step=max_step,
                     watchdog_url=watchdog_url, watchdog_timeout=watchdog_timeout,
                     timeout=timeout, trace=trace,
                     hold=link_latency(env_id, link, motor_type)
                     if line_time or holds_latency(link) else 0.0, env_kwargs=env_kwargs)
    except ValueError as exc:  # a bridge that does not run on the motor's family
        raise CliError(str(exc)) from None
    typer.echo(f"period {1e3 * step:.2f} ms ({'--period' if period is not None else link})")
    typer.echo(report.summary())
    if report.reason != "done":
        raise typer.Exit(1)
