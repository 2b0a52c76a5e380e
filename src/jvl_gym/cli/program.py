"""``jvl-gym program``: run a stored program on a simulated motor with an I/O script.

``jvl-gym program run PROGRAM.txt --motor MIS232 --seconds 5 --io script.yaml --out DIR``
stores the program in the motor, runs it from power-on with the script's inputs, sensors and
load, and writes ``DIR/trace.csv`` and ``DIR/trace.png``. The motor's family declares
``Capability.PROGRAMS`` and its record's ``programs`` module does the work. A malformed program,
a file larger than any program the motor holds, an I/O script larger than
:data:`MAX_IO_SCRIPT_BYTES` (each refused by its size, unread), an unknown motor or a motor
without stored programs, or a malformed I/O script is one line on stderr and exit status 2. An
error or Ctrl-C during the run stops the program and puts the motor in its family's passive
mode before the command ends.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Any

import typer

from ..families import UnsupportedOperation
from .app import CliError, one_line, writable_dir

__all__ = ["program_app", "MAX_IO_SCRIPT_BYTES"]

program_app = typer.Typer(help="Stored programs of the motors that run them.",
                          no_args_is_help=True)


class UsageError(CliError):
    """A bad argument or input file: exit status 2."""

    exit_code = 2


#: the simulated time a run may take [s]
SECONDS_RANGE = (0.001, 3600.0)
#: the largest I/O script ``--io`` reads [bytes]: a larger file is refused by its size, unread
#: (a script of thousands of timed inputs is far smaller)
MAX_IO_SCRIPT_BYTES = 1 << 20


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


def _read_text(path: Path, limit: int, refusal: Any, what: str) -> str:
    """The text of the file ``path`` (``what`` it is: "the program"): refused by its size before
    it is read when it is larger than ``limit`` bytes (``refusal(size)`` says why), and read no
    further than that for a file whose size the system does not give (a pipe, a device)."""
    try:
        size = path.stat().st_size
        why = refusal(size)
        if why is not None:
            raise UsageError(f"{path}: {why}; nothing was read")
        with path.open("rb") as fh:
            data = fh.read(limit + 1)
        why = refusal(len(data)) if len(data) > limit else None
        if why is not None:
            raise UsageError(f"{path}: more than {limit} bytes: {why}")
        return data.decode("utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise UsageError(f"cannot read {what} {path}: {exc}; give a text file") from None


def _io_script_size_refusal(size: int) -> str | None:
    """Why an I/O script of ``size`` bytes is not read (None: it is)."""
    if size <= MAX_IO_SCRIPT_BYTES:
        return None
    return f"{size} bytes is more than an I/O script may have ({MAX_IO_SCRIPT_BYTES} bytes)"


def _read_io_script(path: Path) -> Any:
    """The YAML document of the I/O script ``path`` (refused by its size, unread, above
    :data:`MAX_IO_SCRIPT_BYTES`); one-line UsageError if it is not YAML."""
    import yaml

    text = _read_text(path, MAX_IO_SCRIPT_BYTES, _io_script_size_refusal, "the I/O script")
    try:
        document = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise UsageError(f"{path}: io script: {one_line(exc)}") from None
    if isinstance(document, str):  # a mapping is checked by the family's load_io_script
        raise UsageError(f"{path}: io script: the top level is a mapping (registers, inputs, "
                         "sensors, load, load_inertia), not text")
    return document


#: simulated time [s] the stop after an interrupted run may take (the deceleration ramp)
STOP_SECONDS = 30.0


def _stop(m: Any, fam: Any) -> None:
    """Stop motor 0's program and put the motor in its family's passive mode, the way the
    family does it (the MIS decelerates in stop mode first, MIS manual §5.11.2), stepping the
    simulation until MODE_REG reads passive (at most :data:`STOP_SECONDS`)."""
    m.program_stop(0)
    passive = fam.twin.passive_mode
    if passive is None:
        return
    m.write("MODE_REG", passive, index=0)
    chunk = max(int(m.OUTER_HZ // 100), 1)
    for _ in range(int(STOP_SECONDS * m.OUTER_HZ) // chunk):
        if int(m.read_raw("MODE_REG")[0]) == passive:
            return
        m.step(chunk)


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
    """Run PROGRAM from power-on on a simulated motor; write its trace (CSV and plot) to OUT."""
    from .. import MotorArray
    from ..families import Capability, families_with, family_of_motor
    from ..registers import RegisterError

    runners = families_with(Capability.PROGRAMS)
    if motor is None:
        motor = runners[0].motor_types()[0]
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
    text = _read_text(program, progs.MAX_TEXT_BYTES, progs.text_size_refusal, "the program")
    document = _read_io_script(io) if io is not None else None
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
        script = progs.load_io_script(document)
    except progs.IoScriptError as exc:
        raise UsageError(f"{io}: {exc}") from None
    try:
        trace = progs.run_bench(m, seconds, script, traced)
    except KeyboardInterrupt:
        at = float(m.time[0])
        _stop(m, fam)
        typer.echo(f"{program.name}: interrupted at {at:.3f} s; the program is stopped and the "
                   "motor passive; nothing was written", err=True)
        raise typer.Exit(130) from None
    except BaseException as exc:
        _stop(m, fam)
        if isinstance(exc, RegisterError):
            raise UsageError(f"{exc}") from None
        raise
    out.mkdir(parents=True, exist_ok=True)
    progs.write_csv(trace, out / "trace.csv")
    progs.plot_trace(trace, out / "trace.png", f"{program.name} on {motor}")
    s = m.program_status(0)
    typer.echo(f"{program.name}: {seconds:g} s on {motor}, program {s.name} at line {s.line}; "
               f"wrote {out / 'trace.csv'} and {out / 'trace.png'}")
