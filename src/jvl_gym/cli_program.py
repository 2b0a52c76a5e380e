"""``jvl-gym program``: run a stored program on a simulated motor with an I/O script.

``jvl-gym program run PROGRAM.txt --motor MIS232 --seconds 5 --io script.yaml --out DIR``
stores the program in the motor, runs it from power-on with the script's inputs, sensors and
load, and writes ``DIR/trace.csv`` and ``DIR/trace.png``. A malformed program, an unknown motor
or a motor without stored programs, or a malformed I/O script is one line on stderr and exit
status 2.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from .cli_app import CliError

__all__ = ["program_app"]

program_app = typer.Typer(help="Stored programs of the motors that run them (MIS/SMC).",
                          no_args_is_help=True)


class UsageError(CliError):
    """A bad argument or input file: exit status 2."""

    exit_code = 2


@program_app.command("run")
def run(program: Annotated[Path, typer.Argument(help="program text file (one command a line)")],
        motor: Annotated[str, typer.Option(help="motor type, e.g. MIS232")] = "MIS232",
        seconds: Annotated[float, typer.Option(help="simulated time [s]", min=0.001,
                                               max=3600.0)] = 5.0,
        io: Annotated[Path | None, typer.Option(help="I/O script (YAML): inputs over time, "
                                                     "sensors, load, registers")] = None,
        register: Annotated[list[str] | None, typer.Option(
            help="another register to trace (repeat)")] = None,
        out: Annotated[Path, typer.Option(help="output directory")] = Path("program_out"),
        seed: Annotated[int, typer.Option(help="noise seed")] = 0) -> None:
    """Run PROGRAM on a simulated motor and write its trace (CSV and plot) to OUT."""
    from . import MotorArray
    from .registers import RegisterError

    try:
        text = program.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise UsageError(f"cannot read the program {program}: {exc}; give a text file") from None
    try:
        m = MotorArray(motor, seed=seed)
    except (ValueError, KeyError, OSError) as exc:
        raise UsageError(f"--motor {motor}: {exc}") from None
    if not hasattr(m, "store_program"):
        raise UsageError(f"--motor {motor}: this motor type does not run stored programs; give "
                         "an MIS/SMC type such as MIS232")
    from .families.mis.program.bench import (
        IoScriptError,
        load_io_script,
        plot_trace,
        run_bench,
        write_csv,
    )
    from .families.mis.program.format import ProgramError

    try:
        m.store_program(text)
    except ProgramError as exc:
        raise UsageError(f"{program}: {exc}") from None
    try:
        script = load_io_script(io)
        trace = run_bench(m, seconds, script, register or ())
    except IoScriptError as exc:
        raise UsageError(f"{io}: {exc}") from None
    except RegisterError as exc:
        raise UsageError(f"{exc}") from None
    out.mkdir(parents=True, exist_ok=True)
    write_csv(trace, out / "trace.csv")
    plot_trace(trace, out / "trace.png", f"{program.name} on {motor}")
    s = m.program_status(0)
    typer.echo(f"{program.name}: {seconds:g} s on {motor}, program {s.name} at line {s.line}; "
               f"wrote {out / 'trace.csv'} and {out / 'trace.png'}")
