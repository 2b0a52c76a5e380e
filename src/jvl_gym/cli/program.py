"""``jvl-gym program``: run a stored program on a simulated motor with an I/O script.

``jvl-gym program run PROGRAM.txt --motor MIS232 --seconds 5 --io script.yaml --out DIR``
stores the program in the motor, runs it from power-on with the script's inputs, sensors and
load, and writes ``DIR/trace.csv`` and ``DIR/trace.png``. The motor's family declares
``Capability.PROGRAMS`` and its record's ``programs`` module does the work. A malformed program,
an unknown motor or a motor without stored programs, or a malformed I/O script is one line on
stderr and exit status 2.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Any

import typer

from ..families import UnsupportedOperation
from .app import CliError, writable_dir

__all__ = ["program_app"]

program_app = typer.Typer(help="Stored programs of the motors that run them.",
                          no_args_is_help=True)


class UsageError(CliError):
    """A bad argument or input file: exit status 2."""

    exit_code = 2


#: the simulated time a run may take [s]
SECONDS_RANGE = (0.001, 3600.0)


def _seconds(value: float) -> float:
    """Option callback of ``--seconds``: a finite time in :data:`SECONDS_RANGE`."""
    lo, hi = SECONDS_RANGE
    if not (math.isfinite(value) and lo <= value <= hi):
        raise typer.BadParameter(f"{value} is no simulated time: give seconds from {lo:g} to "
                                 f"{hi:g}")
    return value


def _traced(m: Any, registers: list[str], where: str) -> list[str]:
    """The names of the registers ``--register`` gives (each a name or a number) of the motor
    ``m``; a usage error naming the first it has not and ``where`` its registers are listed."""
    from ..registers import RegisterError

    names = []
    for text in registers:
        key: str | int = int(text) if text.strip().lstrip("+-").isdigit() else text
        try:
            names.append(m.table.lookup(key).name)
        except RegisterError as exc:
            raise UsageError(f"--register {text}: {exc}; give a register name or number of "
                             f"the motor ({where})") from None
    return names


@program_app.command("run")
def run(program: Annotated[Path, typer.Argument(help="program text file (one command a line)")],
        motor: Annotated[str | None, typer.Option(
            help="motor type (default: the first of the first family with stored "
                 "programs)")] = None,
        seconds: Annotated[float, typer.Option(help="simulated time [s], 0.001 … 3600",
                                               callback=_seconds)] = 5.0,
        io: Annotated[Path | None, typer.Option(help="I/O script (YAML): inputs over time, "
                                                     "sensors, load, registers")] = None,
        register: Annotated[list[str] | None, typer.Option(
            help="another register to trace (repeat)")] = None,
        out: Annotated[Path, typer.Option(help="output directory",
                                          callback=writable_dir)] = Path("program_out"),
        seed: Annotated[int, typer.Option(help="noise seed")] = 0) -> None:
    """Run PROGRAM on a simulated motor and write its trace (CSV and plot) to OUT."""
    from .. import MotorArray
    from ..families import Capability, families_with, family_of_motor
    from ..registers import RegisterError

    runners = families_with(Capability.PROGRAMS)
    if motor is None:
        motor = runners[0].motor_types()[0]
    try:
        text = program.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise UsageError(f"cannot read the program {program}: {exc}; give a text file") from None
    try:
        fam = family_of_motor(motor)
        fam.require(Capability.PROGRAMS)
    except UnsupportedOperation as exc:
        types = ", ".join(t for f in runners for t in f.motor_types())
        raise UsageError(f"--motor {motor}: {exc}; give a motor type that runs stored programs "
                         f"({types})") from None
    except (ValueError, KeyError, OSError) as exc:
        raise UsageError(f"--motor {motor}: {exc}") from None
    progs = fam.programs
    assert progs is not None  # a family declaring PROGRAMS states its programs module
    try:
        m: Any = MotorArray(motor, seed=seed)  # its family runs programs: store_program …
    except (ValueError, KeyError, OSError) as exc:
        raise UsageError(f"--motor {motor}: {exc}") from None
    traced = _traced(m, register or [], f"{motor}: docs/families/{fam.key}-registers.md")
    try:
        m.store_program(text)
    except progs.ProgramError as exc:
        raise UsageError(f"{program}: {exc}") from None
    try:
        script = progs.load_io_script(io)
        trace = progs.run_bench(m, seconds, script, traced)
    except progs.IoScriptError as exc:
        raise UsageError(f"{io}: {exc}") from None
    except RegisterError as exc:
        raise UsageError(f"{exc}") from None
    out.mkdir(parents=True, exist_ok=True)
    progs.write_csv(trace, out / "trace.csv")
    progs.plot_trace(trace, out / "trace.png", f"{program.name} on {motor}")
    s = m.program_status(0)
    typer.echo(f"{program.name}: {seconds:g} s on {motor}, program {s.name} at line {s.line}; "
               f"wrote {out / 'trace.csv'} and {out / 'trace.png'}")
