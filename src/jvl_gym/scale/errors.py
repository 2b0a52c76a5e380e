"""User errors of the ``sweep`` and ``fleet`` commands, printed as one line.

A :class:`UserError` says what is wrong, where (file and key), and what to do. :func:`run_cli`
runs a command body and turns a :class:`UserError`, and the missing ``scale`` extra, into a
:class:`jvl_gym.cli_app.CliError`: the command-line application prints it as one line on stderr
and exits with status 1 (``--debug`` lets it through with its traceback).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TypeVar

from .extra import MissingExtraError

__all__ = ["UserError", "run_cli"]

T = TypeVar("T")


class UserError(ValueError):
    """Bad input: a malformed sweep or fleet file, an unknown env id, a bad path."""


def run_cli(body: Callable[[], T]) -> T:
    """Run ``body``; a :class:`UserError` or a missing extra becomes a ``CliError``.

    Parameters
    ----------
    body : callable
        The command's work.

    Returns
    -------
    object
        What ``body`` returns.
    """
    from ..cli_app import CliError

    try:
        return body()
    except (UserError, MissingExtraError) as exc:
        raise CliError(str(exc)) from exc
