"""The first hour: the README's command lines name commands and options that exist,
the output folders they create are ignored by git, the package metadata has an SPDX license."""

from __future__ import annotations

import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()


def _shell_lines() -> list[str]:
    blocks = re.findall(r"```sh\n(.*?)```", README, re.S)
    lines = []
    for block in blocks:
        for line in block.splitlines():
            line = line.split("  #")[0].strip()
            for part in line.split("&&"):
                if part.strip():
                    lines.append(part.strip())
    return lines


def _command(words: list[str]):
    from tuning.cli import app as tune

    from jvl_gym.cli.main import app as gym_cli

    app = {"jvl-tune": tune, "jvl-gym": gym_cli}[words[0].split("/")[-1]]
    import typer.main

    group = typer.main.get_command(app)
    cmd = group.commands[words[1]]
    sub = getattr(cmd, "commands", None)  # a command group: ``jvl-gym program run``
    return cmd if sub is None else sub[words[2]]


def test_readme_cli_lines_use_existing_commands_and_options():
    lines = [ln for ln in _shell_lines() if re.match(r"(\.venv/bin/)?jvl-(tune|gym) ", ln)]
    assert len(lines) >= 4
    for line in lines:
        words = shlex.split(line)
        cmd = _command(words)
        known = {opt for p in cmd.params for opt in p.opts}
        for word in words[2:]:
            if word.startswith("--"):
                assert word.split("=")[0] in known, (line, word)


def test_readme_make_targets_exist():
    makefile = (ROOT / "Makefile").read_text()
    for line in _shell_lines():
        if line.startswith("make "):
            assert re.search(rf"^{line.split()[1]}:", makefile, re.M), line


def test_readme_says_how_to_reach_the_commands_and_the_rl_extra():
    assert ".venv/bin" in README and "activate" in README
    assert "setup-rl" in README


@pytest.mark.parametrize("folder", ["demo_out", "tune_out", "autotune_out", "runs", "site",
                                    "program_out"])
def test_output_folders_are_ignored(folder):
    out = subprocess.run(["git", "check-ignore", "-q", f"{folder}/x"], cwd=ROOT)
    assert out.returncode == 0, folder


def test_license_is_an_spdx_string():
    if sys.version_info < (3, 11):
        pytest.skip("tomllib")
    import tomllib

    meta = tomllib.loads((ROOT / "pyproject.toml").read_text())
    assert meta["project"]["license"] == "MIT"
    req = [r for r in meta["build-system"]["requires"] if r.startswith("setuptools")][0]
    assert int(re.search(r">=(\d+)", req).group(1)) >= 77
