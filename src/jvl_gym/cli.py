"""``jvl-gym`` command line: ``train``, ``evaluate``, ``compile`` (and ``serve`` when
available)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

app = typer.Typer(help="jvl_gym: train and evaluate policies on the MAC motor environments.",
                  no_args_is_help=True)


@app.command()
def train(env_id: Annotated[str, typer.Argument(help="e.g. jvl_gym/GearSync-v0")],
          out: Annotated[Path, typer.Option(help="directory for the model")] = Path("runs"),
          timesteps: Annotated[int | None, typer.Option(help="override total_timesteps")] = None,
          seed: Annotated[int | None, typer.Option(help="override the config's seed")] = None,
          threads: Annotated[int, typer.Option(help="torch threads")] = 1,
          config_dir: Annotated[Path | None, typer.Option(help="directory of the RL *.yml")]
          = None) -> None:
    """Train the configured algorithm (configs/rl/*.yml) on ENV_ID and save the model."""
    from .rl.train import train as run

    run(env_id, out, timesteps, seed, progress_bar=True, threads=threads,
        config_dir=config_dir)


@app.command()
def evaluate(env_ids: Annotated[list[str], typer.Argument(help="env ids to evaluate")],
             runs: Annotated[Path, typer.Option(help="directory of the models")] = Path("runs"),
             seeds: Annotated[int | None, typer.Option(help="held-out seeds (>= 5)")] = None,
             episodes: Annotated[int | None, typer.Option(help="episodes per seed")] = None,
             config_dir: Annotated[Path | None, typer.Option(help="directory of the RL *.yml")]
             = None) -> None:
    """Print policy vs baseline (mean ± std over held-out seeds) for each ENV_ID."""
    from .rl.evaluate import evaluate as run
    from .rl.evaluate import format_table
    from .rl.train import model_path

    results = {}
    for env_id in env_ids:
        path = model_path(runs, env_id)
        results[env_id] = run(env_id, path if path.exists() else None, seeds, episodes,
                              config_dir=config_dir)
    typer.echo(format_table(results))


@app.command(name="compile")
def compile_(motors_only: Annotated[bool, typer.Option(
                 "--motors-only", help="only the motor array, not the environments")] = False,
             workers: Annotated[int | None, typer.Option(help="worker processes")] = None
             ) -> None:
    """Compile the simulator and the environments for this machine now (numba caches the
    result on disk; otherwise each compiles on first use)."""
    from .precompile import compile_all

    for job, seconds in compile_all(workers, envs=not motors_only).items():
        typer.echo(f"{job}: {seconds:.1f} s")


def _mount_serve() -> None:
    try:
        from . import cli_serve
    except ImportError:
        return
    command = getattr(cli_serve, "serve", None)
    if command is not None:
        app.command(name="serve")(command)


_mount_serve()

if __name__ == "__main__":
    app()
