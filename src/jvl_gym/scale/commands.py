"""The body of ``jvl-gym sweep`` (the typer command calls it) and what ``jvl-tune fleet``
(:func:`tuning.fleet.fleet_command`) shares with it.

It checks for Ray first (without the ``scale`` extra they print one line saying how to
install it and exit with status 1), then read and validate their file, then run. Errors are
:class:`jvl_gym.cli.app.CliError` (one line, ``--debug`` for the traceback).
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import typer

from .errors import UserError, run_cli
from .extra import require_ray

__all__ = ["sweep_command", "say", "out_dir"]


def say(prog: str) -> Callable[[str], None]:
    def say(line: str) -> None:
        typer.echo(f"[{prog}] {line}", err=True)

    return say


def out_dir(out: Path) -> Path:
    if out.exists() and not out.is_dir():
        raise UserError(f"--out {out}: exists and is not a directory; give a directory")
    return out


def sweep_command(config: Path, out: Path, address: str | None = None,
                  num_cpus: int | None = None, max_concurrent: int | None = None,
                  stop_after: int | None = None, storage: str | None = None,
                  verbose: bool = False) -> None:
    """``jvl-gym sweep``: run (or resume) a sweep file; exit 1 if a trial failed or the sweep
    was interrupted before every trial finished (not when ``stop_after`` stopped it).

    Parameters
    ----------
    config : Path
        Sweep file (:mod:`jvl_gym.scale.sweep_spec`).
    out : Path
        Output directory (also what a resumed sweep reads).
    address, num_cpus, max_concurrent, stop_after, storage, verbose
        See :func:`jvl_gym.scale.sweep.run_sweep`.
    """
    def body() -> None:
        require_ray()
        try:
            import stable_baselines3  # noqa: F401
            import torch  # noqa: F401
        except ImportError as exc:
            from ..cli.app import RL_EXTRA_HINT

            raise UserError(f"jvl-gym sweep {RL_EXTRA_HINT}") from exc
        from .sweep import run_sweep
        from .sweep_spec import load_sweep

        spec = load_sweep(config)
        for name, value in (("--num-cpus", num_cpus), ("--max-concurrent", max_concurrent),
                            ("--stop-after", stop_after)):
            if value is not None and value < 1:
                raise UserError(f"{name} {value}: give a positive integer")
        outcome = run_sweep(spec, out_dir(out), address, num_cpus, max_concurrent,
                            stop_after, storage, progress=say("sweep"), verbose=verbose)
        if outcome.failed or (stop_after is None and not outcome.complete):
            raise typer.Exit(1)  # a trial failed, or the sweep was interrupted

    run_cli(body)
