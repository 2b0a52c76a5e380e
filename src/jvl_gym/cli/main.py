"""``jvl-gym`` command line: ``train``, ``evaluate``, ``compile``, ``sweep``, ``program run``,
``deploy``, ``studio`` (and ``serve`` when available).

Errors are one line on stderr with a non-zero exit status; ``--debug`` shows the traceback
(:class:`jvl_gym.cli.app.App`).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path
from typing import Annotated

import typer

from .app import RL_EXTRA_HINT, App, CliError, writable_dir
from .identified import HELP as IDENTIFIED_HELP
from .identified import identified_kwargs
from .program import program_app

app = App(prog="jvl-gym",
          help="jvl_gym: train and evaluate policies on the MAC motor environments.",
          no_args_is_help=True)


def _check_env_id(env_id: str) -> None:
    """Refuse an env id that jvl_gym does not register (the message lists the known ones)."""
    from ..envs import ENV_IDS

    if env_id not in ENV_IDS:
        raise typer.BadParameter(f"unknown env {env_id!r}; known: {', '.join(ENV_IDS)}")


def _check_family(env_id: str, family: str | None) -> None:
    """Refuse a family key ``env_id`` does not run on (the message lists those it does)."""
    if family is None:
        return
    from ..rl.config import env_families

    known = env_families(env_id)
    if family not in known:
        raise typer.BadParameter(f"{env_id} does not run on family {family!r}; it runs on: "
                                 f"{', '.join(known)}")


def _check_link(link: str) -> None:
    """Refuse link text that ``jvl_gym.envs.link.parse_link`` does not read (one line)."""
    from ..envs.link import parse_link

    try:
        parse_link(link)
    except ValueError as exc:
        raise typer.BadParameter(str(exc)) from None


def _need_rl_extra(command: str) -> None:
    """Raise a one-line error unless torch and stable-baselines3 can be imported."""
    try:
        import stable_baselines3  # noqa: F401
        import torch  # noqa: F401
    except ImportError as exc:
        raise CliError(f"{command} {RL_EXTRA_HINT}") from exc


@app.command()
def train(env_id: Annotated[str, typer.Argument(help="e.g. jvl_gym/GearSync-v0")],
          out: Annotated[Path, typer.Option(help="directory for the model",
                                            callback=writable_dir)] = Path("runs"),
          timesteps: Annotated[int | None, typer.Option(help="override total_timesteps",
                                                        min=1)] = None,
          seed: Annotated[int | None, typer.Option(help="override the config's seed")] = None,
          threads: Annotated[int, typer.Option(help="torch threads", min=1)] = 1,
          config_dir: Annotated[Path | None, typer.Option(help="directory of the RL *.yml")]
          = None,
          family: Annotated[str | None, typer.Option(
              help="motor family key (default: the env's first)")] = None,
          algo: Annotated[str | None, typer.Option(
              help="algorithm of the config (default: its algo, e.g. ppo; or sac)")] = None,
          checkpoint_every: Annotated[int | None, typer.Option(
              help="also save the model every N steps (OUT/<Env>-<family>-<algo>-<steps>.zip)",
              min=1)] = None,
          link: Annotated[str | None, typer.Option(
              help="train behind a link: mactalk:19200, mactalk32:BAUD, modbus:BAUD, "
                   "canopen:2ms, dac:12 (then ,jitter=S ,drop=P)")] = None,
          variant: Annotated[str | None, typer.Option(
              help="train a variant of the config (its variants: e.g. link, nolink; "
                   "OUT/<Env>-<family>-<variant>-<algo>.zip)")] = None,
          identified: Annotated[Path | None, typer.Option(help=IDENTIFIED_HELP)] = None
          ) -> None:
    """Train the configured algorithm (configs/rl/*.yml) on ENV_ID and save the model
    (OUT/<Env>-<family>-<algo>.zip, its training log beside it)."""
    _check_env_id(env_id)
    _check_family(env_id, family)
    env_kwargs, family = identified_kwargs(identified, env_id, family)
    _need_rl_extra("jvl-gym train")
    from ..rl.config import rl_config
    from ..rl.train import train as run

    try:
        rl_config(env_id, config_dir, family=family, algo=algo, variant=variant)
    except KeyError as exc:
        raise typer.BadParameter(f"{exc.args[0]}: add it to configs/rl/*.yml or pick another "
                                 "--family/--algo/--variant") from None
    if link is not None:
        _check_link(link)
    run(env_id, out, timesteps, seed, progress_bar=True, threads=threads,
        config_dir=config_dir, family=family, algo=algo, checkpoint_every=checkpoint_every,
        link=link, variant=variant, env_kwargs=env_kwargs)


@app.command()
def evaluate(env_ids: Annotated[list[str] | None, typer.Argument(
                 help="env ids to evaluate (or --all)")] = None,
             runs: Annotated[Path, typer.Option(help="directory of the models")] = Path("runs"),
             seeds: Annotated[int | None, typer.Option(help="held-out seeds (>= 5)", min=1)]
             = None,
             episodes: Annotated[int | None, typer.Option(help="episodes per seed", min=1)]
             = None,
             config_dir: Annotated[Path | None, typer.Option(help="directory of the RL *.yml")]
             = None,
             family: Annotated[str | None, typer.Option(
                 help="motor family key (default: the env's first)")] = None,
             algo: Annotated[str, typer.Option(help="algorithm of the model")] = "ppo",
             all_: Annotated[bool, typer.Option(
                 "--all", help="every env × family × {trained, baseline, random}: the results "
                 "page")] = False,
             out: Annotated[Path | None, typer.Option(
                 help="with --all: directory for results.md and its plots",
                 callback=writable_dir)] = None,
             max_steps: Annotated[int | None, typer.Option(
                 help="cut the episodes at this many steps", min=1)] = None,
             link: Annotated[str | None, typer.Option(
                 help="evaluate behind a link (as train --link): mactalk:19200 …")] = None,
             identified: Annotated[Path | None, typer.Option(help=IDENTIFIED_HELP)] = None
             ) -> None:
    """Print policy vs baseline (mean ± std over held-out seeds) for each ENV_ID, or with
    --all write the results page (OUT/results.md).

    The model is ``RUNS/<Env>-<family>-<algo>.zip`` (what ``jvl-gym train`` writes), else the
    policy shipped with the package (named on stderr). A missing model is reported in one line
    on stderr (exit status 1) after the table, which then shows the baseline only.
    """
    if all_:
        if env_ids or family is not None or link is not None or identified is not None:
            raise typer.BadParameter("--all evaluates every env and family: give no ENV_IDS, "
                                     "no --family, no --link and no --identified")
        if out is None:
            raise typer.BadParameter("--all needs --out DIR (the directory for results.md)")
        _need_rl_extra("jvl-gym evaluate --all")
        from ..rl import results as res

        rows = res.evaluate_all(runs, seeds, episodes, max_steps, config_dir,
                                progress_bar=True)
        transfer = res.evaluate_transfer(runs, config_dir)  # real time: about a minute
        page = res.write_page(rows, out, runs, max_episode_steps=max_steps,
                              transfer=transfer)
        typer.echo(f"wrote {page}")
        return
    if out is not None:
        raise typer.BadParameter("--out is for --all (the results page)")
    if link is not None:
        _check_link(link)
    if not env_ids:
        raise typer.BadParameter("give ENV_IDS to evaluate, or --all --out DIR")
    from ..rl import evaluate as ev
    from ..rl.train import model_path, shipped_model

    kwargs_of = {}
    for env_id in env_ids:
        _check_env_id(env_id)
        _check_family(env_id, family)
        kwargs_of[env_id], fam = identified_kwargs(identified, env_id, family)
    family = fam
    paths = {env_id: model_path(runs, env_id, family, algo) for env_id in env_ids}
    for env_id, path in paths.items():
        shipped = None if path.exists() else shipped_model(env_id, family, algo)
        if shipped is not None:
            print(f"jvl-gym evaluate: {env_id}: no {path}, using the shipped policy {shipped}",
                  file=sys.stderr)
            paths[env_id] = shipped
    if any(path.exists() for path in paths.values()):
        _need_rl_extra("jvl-gym evaluate (with a model)")
    results = {}
    for env_id, path in paths.items():
        results[env_id] = ev.evaluate(env_id, path if path.exists() else None, seeds, episodes,
                                      config_dir=config_dir, family=family, link=link,
                                      env_kwargs=kwargs_of[env_id])
    typer.echo(ev.format_table(results))
    missing = [env_id for env_id, path in paths.items() if not path.exists()]
    if missing:
        names = ", ".join(f"{env_id} ({paths[env_id]})" for env_id in missing)
        fam = "" if family is None else f" --family {family}"
        print(f"jvl-gym evaluate: no model for {names}: train one with `jvl-gym train "
              f"{missing[0]}{fam} --out {runs}`, or pass --runs DIR", file=sys.stderr)
        raise typer.Exit(1)


@app.command(name="compile")
def compile_(motors_only: Annotated[bool, typer.Option(
                 "--motors-only", help="only the motor arrays, not the environments")] = False,
             motor: Annotated[list[str] | None, typer.Option(
                 help="only the motor array of this motor type's family (repeatable; "
                      "no environments)")] = None,
             workers: Annotated[int | None, typer.Option(
                 help="worker processes (default: the CPU count)")] = None
             ) -> None:
    """Compile the simulator and the environments for this machine now, in parallel
    processes (numba caches the result on disk; otherwise each compiles on first use)."""
    from ..families.config import ConfigError
    from .precompile import compile_all

    if workers is not None and workers < 1:
        raise typer.BadParameter(f"--workers {workers}: give 1 or more")
    start = time.perf_counter()
    try:
        times = compile_all(workers, envs=not (motors_only or motor), motor_types=motor)
    except ConfigError as exc:
        raise CliError(f"--motor: {exc}") from exc
    typer.echo(f"compiled {len(times)} units in {time.perf_counter() - start:.1f} s")


@app.command()
def sweep(config: Annotated[Path, typer.Argument(help="sweep file (configs/sweeps/*.yml)")],
          out: Annotated[Path, typer.Option(help="output directory (run again to resume)",
                                            callback=writable_dir)] = Path("sweep_out"),
          address: Annotated[str | None, typer.Option(
              help="Ray cluster: auto, HOST:PORT or ray://HOST:10001 (default: local Ray)")]
          = None,
          num_cpus: Annotated[int | None, typer.Option(help="CPUs of the local Ray")] = None,
          max_concurrent: Annotated[int | None, typer.Option(help="trials at once")] = None,
          stop_after: Annotated[int | None, typer.Option(
              help="stop once this many trials have finished (run again to resume)")] = None,
          storage: Annotated[str | None, typer.Option(
              help="Ray Tune storage path or URI (default OUT/ray)")] = None,
          verbose: Annotated[bool, typer.Option(help="Ray Tune's own output too")] = False
          ) -> None:
    """Run a hyper-parameter sweep as Ray Tune trials (needs the scale extra)."""
    from ..scale.commands import sweep_command

    sweep_command(config, out, address, num_cpus, max_concurrent, stop_after, storage,
                  verbose)


def _mount_serve() -> None:
    try:
        from . import serve as cli_serve
    except ImportError:
        return
    command = getattr(cli_serve, "serve", None)
    if command is not None:
        app.command(name="serve")(command)


_mount_serve()
app.add_typer(program_app, name="program")


def _mount_deploy() -> None:
    from .deploy import deploy

    app.command(name="deploy")(deploy)


_mount_deploy()


def _mount_studio() -> None:
    from .studio import studio

    app.command(name="studio")(studio)


_mount_studio()

if __name__ == "__main__":
    app()
