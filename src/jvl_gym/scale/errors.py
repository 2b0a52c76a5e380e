"""User errors of the ``sweep`` and ``fleet`` commands, printed as one line.

A :class:`UserError` says what is wrong, where (file and key), and what to do. :func:`run_cli`
runs a command body and turns a :class:`UserError`, and the missing ``scale`` extra, into a
:class:`jvl_gym.cli_app.CliError`: the command-line application prints it as one line on stderr
and exits with status 1 (``--debug`` lets it through with its traceback).
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar

import yaml

from .extra import MissingExtraError

__all__ = ["UserError", "run_cli", "read_yaml"]

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


def read_yaml(path: Path) -> Any:
    """The YAML document of the file ``path``; a syntax error is a :class:`UserError` naming
    the file and line."""
    try:
        return yaml.safe_load(path.read_text())
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        line = f" line {mark.line + 1}" if mark is not None else ""
        raise UserError(f"{path}:{line} is not valid YAML ({getattr(exc, 'problem', exc)}); "
                        "fix the syntax") from None
