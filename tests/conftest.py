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


@pytest.fixture(scope="session")
def local_ray() -> Iterator[None]:
    """A local Ray of 2 CPUs, started by the first test that asks for it and shared by every
    later one in the same process (the Ray tests of several modules)."""
    ray = pytest.importorskip("ray")
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False,
             object_store_memory=256 * 1024 * 1024)
    yield
    ray.shutdown()
