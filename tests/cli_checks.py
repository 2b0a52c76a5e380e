"""What the command-line tests check of every command: its exit status and a one-line error."""

from __future__ import annotations

from typing import Any

import pytest


def run_cli(app: Any, args: list[str], capsys: Any) -> tuple[Any, str, str]:
    """Run the typer ``app`` with ``args``; its exit code, stdout and stderr."""
    with pytest.raises(SystemExit) as info:
        app(args)
    out, err = capsys.readouterr()
    return info.value.code, out, err


def one_line_error(code: Any, err: str) -> str:
    """The one line of an error exit (non-zero status, no traceback)."""
    assert code not in (0, None)
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert "Traceback" not in err
    return lines[0]
