"""User errors of the ``sweep`` and ``fleet`` commands, printed as one line.

A :class:`UserError` says what is wrong, where (file and key), and what to do. :func:`run_cli`
runs a command body and turns a :class:`UserError`, and the missing ``scale`` extra, into a
:class:`jvl_gym.cli.app.CliError`: the command-line application prints it as one line on stderr
and exits with status 1 (``--debug`` lets it through with its traceback).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar

import yaml

from .extra import MissingExtraError

__all__ = ["UserError", "run_cli", "read_yaml", "file_mapping", "file_number", "file_integer",
           "file_flag"]

T = TypeVar("T")


class UserError(ValueError):
    """Bad input: a malformed sweep or fleet file, an unknown env id, a bad path."""


def file_mapping(value: Any, where: str, allowed: set[str]) -> dict[str, Any]:
    """``value`` of the file key ``where`` as a mapping whose keys are all in ``allowed``
    (None: an empty one); UserError naming the key and the allowed keys otherwise."""
    if value is None:
        return {}
    if not isinstance(value, dict):
        raise UserError(f"{where}: expected a mapping with keys {sorted(allowed)}")
    unknown = set(value) - allowed
    if unknown:
        raise UserError(f"{where}: unknown keys {sorted(unknown)}; allowed: {sorted(allowed)}")
    return value


def file_number(value: Any, where: str, low: float | None = None,
                positive: bool = False) -> float:
    """``value`` of the file key ``where`` as a finite real number (an int or float, not a bool
    or a string), at least ``low`` or above 0 when ``positive``; UserError naming key and
    value otherwise."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise UserError(f"{where}: expected a finite number, got {value!r}")
    if positive and not value > 0:
        raise UserError(f"{where}: expected a number > 0, got {value!r}")
    if low is not None and not value >= low:
        raise UserError(f"{where}: expected a number >= {low}, got {value!r}")
    return float(value)


def file_integer(value: Any, where: str, low: int = 0) -> int:
    """``value`` of the file key ``where`` as an integer >= ``low`` (not a bool, a float such as
    1.5 or 1.0, or a string); UserError naming key and value otherwise."""
    if isinstance(value, bool) or not isinstance(value, int) or value < low:
        raise UserError(f"{where}: expected an integer >= {low}, got {value!r}")
    return value


def file_flag(value: Any, where: str) -> bool:
    """``value`` of the file key ``where`` as true or false (not a string such as "false", not
    a number); UserError naming key and value otherwise."""
    if not isinstance(value, bool):
        raise UserError(f"{where}: expected true or false, got {value!r}")
    return value


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
    from ..cli.app import CliError

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
