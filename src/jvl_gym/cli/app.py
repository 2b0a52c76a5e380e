"""The Typer application class of ``jvl-gym`` and ``jvl-tune``: errors as one line.

Every error a command meets (a bad option, an unknown motor, a malformed file, a refused
register write, a missing extra) is printed as one line on stderr, ``<prog>: error: <what>``,
and the process exits non-zero (2 for a usage error, 1 otherwise). ``--debug`` anywhere on the
command line, or ``JVL_DEBUG=1``, lets the exception through with its traceback.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
from pathlib import Path
from typing import Any

import typer
from typer.exceptions import TyperException

__all__ = ["App", "CliError", "one_line", "writable_dir", "writable_dir_arg", "writable_file",
           "RL_EXTRA_HINT"]

#: what to do when the RL extra (torch, stable-baselines3) is missing
RL_EXTRA_HINT = ("needs the RL extra (torch, stable-baselines3): run `make setup-rl` or "
                 "`.venv/bin/pip install -e '.[rl]'`")


class CliError(TyperException):
    """An error a command words completely (what, where, what to do): printed as it is."""


def one_line(exc: BaseException | str) -> str:
    """The message of ``exc`` on one line (the lines of a multi-line message joined by '; ')."""
    lines = [ln.strip() for ln in str(exc).splitlines() if ln.strip()]
    text = "; ".join(lines).replace(":;", ":")
    if not text or isinstance(exc, (OSError, KeyError, TypeError, AttributeError)):
        text = f"{type(exc).__name__}: {text}" if text else type(exc).__name__
    return text


def writable_dir(value: Path | None) -> Path | None:
    """Option callback of an output directory (``--out``): one that exists and is writable,
    or that can be created in a writable directory (checked before any work starts; nothing
    is created here). None (not given) passes.

    Raises
    ------
    typer.BadParameter
        The path is a file, or no file can be made where the directory would be.
    """
    if value is None:
        return None
    probe = value.absolute()
    while not probe.exists() and probe != probe.parent:
        probe = probe.parent
    if probe == value.absolute() and not probe.is_dir():
        raise typer.BadParameter(f"{value} exists and is not a directory; give a directory")
    try:
        if not probe.is_dir():
            raise OSError(f"{probe} is not a directory")
        tempfile.TemporaryFile(dir=probe).close()  # what the run would do: make a file there
    except OSError as exc:
        raise typer.BadParameter(f"{value} cannot be written ({exc.strerror or exc} in "
                                 f"{probe}); give a writable directory") from None
    return value


def writable_dir_arg(text: str) -> Path:
    """argparse ``type`` of an output directory (``--out`` of ``python -m`` entry points):
    :func:`writable_dir`, its refusal as argparse's one-line usage error.

    Raises
    ------
    argparse.ArgumentTypeError
        What :func:`writable_dir` refuses.
    """
    try:
        path = writable_dir(Path(text))
    except typer.BadParameter as exc:
        raise argparse.ArgumentTypeError(exc.message) from None
    assert path is not None
    return path


def writable_file(value: Path | None) -> Path | None:
    """Option callback of an output file (``--out FILE``): not a directory, and in a directory
    :func:`writable_dir` accepts (checked before any work starts; nothing is created here).
    None (not given) passes.

    Raises
    ------
    typer.BadParameter
        The path is a directory, or its directory cannot be written.
    """
    if value is None:
        return None
    if value.is_dir():
        raise typer.BadParameter(f"{value} is a directory; give a file name")
    try:
        writable_dir(value.absolute().parent)
    except typer.BadParameter as exc:
        raise typer.BadParameter(f"{value} cannot be written: {exc.message}") from None
    return value


class App(typer.Typer):
    """A :class:`typer.Typer` whose errors are one line on stderr with a non-zero exit status.

    Parameters
    ----------
    prog : str
        Program name used in the messages (``"jvl-tune"``).
    **kwargs
        Passed to :class:`typer.Typer`.
    """

    def __init__(self, *, prog: str, **kwargs: Any) -> None:
        super().__init__(pretty_exceptions_enable=False, **kwargs)
        self.prog = prog

    def __call__(self, args: list[str] | None = None, prog_name: str | None = None,
                 **extra: Any) -> Any:
        """Run the command line ``args`` (default ``sys.argv[1:]``) and exit."""
        argv = list(sys.argv[1:] if args is None else args)
        debug = "--debug" in argv or os.environ.get("JVL_DEBUG", "") not in ("", "0")
        argv = [a for a in argv if a != "--debug"]
        if not argv:
            argv = ["--help"]
        command = self._command_path(argv)
        try:
            code = super().__call__(args=argv, prog_name=prog_name or self.prog,
                                    standalone_mode=False, **extra)
        except typer.Abort:
            print(f"{self.prog}: aborted", file=sys.stderr)
            sys.exit(130)
        except TyperException as exc:  # usage errors (exit status 2) and CliError
            if debug:
                raise
            usage = f" (see {command} --help)" if exc.exit_code == 2 else ""
            print(f"{command}: error: {one_line(exc.format_message())}{usage}", file=sys.stderr)
            sys.exit(exc.exit_code)
        except KeyboardInterrupt:
            sys.exit(130)
        except Exception as exc:
            if debug:
                raise
            print(f"{command}: error: {one_line(exc)} (--debug shows the traceback)",
                  file=sys.stderr)
            sys.exit(1)
        sys.exit(code if isinstance(code, int) else 0)

    def _command_path(self, argv: list[str]) -> str:
        """The program and the subcommand names that ``argv`` begins with
        (``"jvl-gym program run"``), as the messages name the command."""
        words = [self.prog]
        command: Any = typer.main.get_command(self)
        for arg in argv:
            command = getattr(command, "commands", {}).get(arg)
            if command is None:
                break
            words.append(arg)
        return " ".join(words)
