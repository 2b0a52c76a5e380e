"""Shared fixtures and helpers of the test suite."""

from __future__ import annotations

import os
from collections.abc import Iterator

import pytest

os.environ.setdefault("MPLBACKEND", "Agg")

try:  # no hypothesis example may fail for the wall-clock time it took: a busy machine (two
    # cores shared by several test runs) takes several times the default 200 ms deadline
    from hypothesis import settings

    settings.register_profile("jvl_gym", deadline=None)
    settings.load_profile("jvl_gym")
except ImportError:  # hypothesis is a test extra; the tests that use it import it themselves
    pass


#: the browser of the Chromium tests: Debian's package (playwright cannot download its own here)
CHROMIUM = "/usr/bin/chromium"
#: a web site's name that the test browser resolves to this machine, as DNS rebinding would
FOREIGN_HOST = "evil.example"
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                 "--disable-background-networking", "--disable-component-update",
                 "--disable-sync", f"--host-resolver-rules=MAP {FOREIGN_HOST} 127.0.0.1"]


@pytest.fixture(scope="session")
def browser_type_launch_args(browser_type_launch_args: dict) -> dict:
    """How every Chromium test's browser starts. pytest-playwright launches one browser per test
    process and keeps it for the session, so whichever module asks first fixes the arguments for
    all: they are stated here once, for every module alike."""
    return {**browser_type_launch_args, "executable_path": CHROMIUM, "args": CHROMIUM_ARGS}


@pytest.fixture(scope="session")
def local_ray() -> Iterator[None]:
    """A local Ray of 2 CPUs, started by the first test that asks for it and shared by every
    later one in the same process (the Ray tests of several modules)."""
    ray = pytest.importorskip("ray")
    from jvl_gym.scale.ray_session import connect

    connect(num_cpus=2)  # as the commands start theirs
    yield
    ray.shutdown()
