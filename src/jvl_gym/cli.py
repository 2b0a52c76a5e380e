"""``jvl-gym`` command line: ``train``, ``evaluate``, ``sweep`` (and ``serve`` when available)."""

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


@app.command()
def sweep(config: Annotated[Path, typer.Argument(help="sweep file (configs/sweeps/*.yml)")],
          out: Annotated[Path, typer.Option(help="output directory (run again to resume)")]
          = Path("sweep_out"),
          address: Annotated[str | None, typer.Option(
              help="Ray cluster: auto, HOST:PORT or ray://HOST:10001 (default: local Ray)")]
          = None,
          num_cpus: Annotated[int | None, typer.Option(help="CPUs of the local Ray")] = None,
          max_concurrent: Annotated[int | None, typer.Option(help="trials at once")] = None,
          stop_after: Annotated[int | None, typer.Option(
              help="stop once this many trials have finished (run again to resume)")] = None,
          storage: Annotated[str | None, typer.Option(
              help="Ray Tune storage path or URI (default OUT/ray)")] = None,
          verbose: Annotated[bool, typer.Option(help="Ray Tune's own output too")] = False,
          debug: Annotated[bool, typer.Option(help="tracebacks instead of one-line errors")]
          = False) -> None:
    """Run a hyper-parameter sweep as Ray Tune trials (needs the scale extra)."""
    from .scale.commands import sweep_command

    sweep_command(config, out, address, num_cpus, max_concurrent, stop_after, storage,
                  verbose, debug)


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
