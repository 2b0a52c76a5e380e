"""How the threaded steps' thread pool waits (jvl_gym.engine.threads): waiting threads spin a
short while, then sleep, unless the user chose otherwise."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
_OMP = ("OMP_WAIT_POLICY", "GOMP_SPINCOUNT")


def _settings_after_import(**env: str) -> str:
    """``OMP_WAIT_POLICY GOMP_SPINCOUNT`` in a new process after ``import jvl_gym`` ('-' when
    unset), the process started with ``env`` and neither OpenMP setting otherwise."""
    base = {k: v for k, v in os.environ.items() if k not in _OMP}
    code = ("import os, jvl_gym; print(os.environ.get('OMP_WAIT_POLICY', '-'), "
            "os.environ.get('GOMP_SPINCOUNT', '-'))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, cwd=ROOT, env={**base, **env})
    return out.stdout.strip().splitlines()[-1]


def test_waiting_threads_spin_a_short_while_by_default() -> None:
    from jvl_gym.engine.threads import SPIN_COUNT

    assert _settings_after_import() == f"- {SPIN_COUNT}"


@pytest.mark.parametrize(("env", "settings"), [({"OMP_WAIT_POLICY": "ACTIVE"}, "ACTIVE -"),
                                               ({"OMP_WAIT_POLICY": "PASSIVE"}, "PASSIVE -"),
                                               ({"GOMP_SPINCOUNT": "1000"}, "- 1000")])
def test_the_users_choice_is_kept(env: dict[str, str], settings: str) -> None:
    assert _settings_after_import(**env) == settings


def test_setting_the_policy_keeps_an_existing_one(monkeypatch: pytest.MonkeyPatch) -> None:
    from jvl_gym.engine.threads import SPIN_COUNT, set_wait_policy

    monkeypatch.delenv("GOMP_SPINCOUNT", raising=False)
    monkeypatch.setenv("OMP_WAIT_POLICY", "ACTIVE")
    assert set_wait_policy() == "OMP_WAIT_POLICY=ACTIVE"
    monkeypatch.delenv("OMP_WAIT_POLICY")
    assert set_wait_policy() == f"GOMP_SPINCOUNT={SPIN_COUNT}"
    assert os.environ["GOMP_SPINCOUNT"] == str(SPIN_COUNT) and "OMP_WAIT_POLICY" not in os.environ
