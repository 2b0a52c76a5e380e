"""User errors of the ``sweep`` and ``fleet`` commands, printed as one line.

A :class:`UserError` says what is wrong, where (file and key), and what to do. :func:`run_cli`
runs a command body and turns a :class:`UserError` (and the missing ``scale`` extra) into one
line on stderr and exit status 2; with ``debug=True`` the exception propagates with its
traceback instead.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TypeVar

import typer

from .extra import MissingExtraError

__all__ = ["UserError", "run_cli"]

T = TypeVar("T")


class UserError(ValueError):
    """Bad input: a malformed sweep or fleet file, an unknown env id, a bad path."""


def run_cli(body: Callable[[], T], prog: str, debug: bool = False) -> T:
    """Run ``body``; a :class:`UserError` or a missing extra becomes one line and exit 2.

    Parameters
    ----------
    body : callable
        The command's work.
    prog : str
        Prefix of the printed line, e.g. ``"jvl-gym sweep"``.
    debug : bool
        Re-raise instead (full traceback).
    """
    try:
        return body()
    except (UserError, MissingExtraError) as exc:
        if debug:
            raise
        typer.echo(f"{prog}: error: {exc}", err=True)
        raise typer.Exit(2) from None
