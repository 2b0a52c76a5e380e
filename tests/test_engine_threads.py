"""The wait policy of the threaded steps' thread pool (jvl_gym.engine.threads): waiting
threads sleep instead of spinning, unless the user chose otherwise."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
_OMP = ("OMP_WAIT_POLICY", "GOMP_SPINCOUNT")


def _policy_after_import(**env: str) -> str:
    """``OMP_WAIT_POLICY`` in a new process after ``import jvl_gym`` ('-' when unset), the
    process started with ``env`` and neither OpenMP setting otherwise."""
    base = {k: v for k, v in os.environ.items() if k not in _OMP}
    code = "import os, jvl_gym; print(os.environ.get('OMP_WAIT_POLICY', '-'))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, cwd=ROOT, env={**base, **env})
    return out.stdout.strip().splitlines()[-1]


def test_waiting_threads_sleep_by_default() -> None:
    assert _policy_after_import() == "PASSIVE"


@pytest.mark.parametrize(("env", "policy"), [({"OMP_WAIT_POLICY": "ACTIVE"}, "ACTIVE"),
                                             ({"GOMP_SPINCOUNT": "1000"}, "-")])
def test_the_users_choice_is_kept(env: dict[str, str], policy: str) -> None:
    assert _policy_after_import(**env) == policy


def test_setting_the_policy_keeps_an_existing_one(monkeypatch: pytest.MonkeyPatch) -> None:
    from jvl_gym.engine.threads import WAIT_POLICY, set_wait_policy

    monkeypatch.delenv("GOMP_SPINCOUNT", raising=False)
    monkeypatch.setenv("OMP_WAIT_POLICY", "ACTIVE")
    assert set_wait_policy() == "ACTIVE"
    monkeypatch.delenv("OMP_WAIT_POLICY")
    assert set_wait_policy() == WAIT_POLICY == os.environ["OMP_WAIT_POLICY"]
