"""The generated benchmark page (benchmarks/bench_page.py) and the sections of the bench scripts.

No benchmark is run: the scripts' section writers get made-up figures.
"""

from __future__ import annotations

import datetime as dt
import importlib
import sys
from pathlib import Path

import pytest

BENCH = Path(__file__).resolve().parents[1] / "benchmarks"
WHEN = dt.datetime(2030, 1, 2, 3, 4, tzinfo=dt.timezone.utc)
HOST = {"CPU": "Test CPU 9000", "cores": "2 logical", "Python": "3.x", "numba": "0.x"}


@pytest.fixture
def bench(monkeypatch):
    """Import a module of benchmarks/ (the scripts import each other by plain name)."""
    monkeypatch.syspath_prepend(str(BENCH))
    monkeypatch.setenv("JVL_BENCH_PAGE", "none")

    def load(name: str):
        sys.modules.pop(name, None)
        return importlib.import_module(name)

    return load


def test_page_sections_are_replaced_in_place(bench, tmp_path) -> None:
    bp = bench("bench_page")
    page = tmp_path / "docs" / "benchmarks.md"
    bp.update_section("envs", "envs body 1", page, when=WHEN, host=HOST)
    text = page.read_text()
    assert text.startswith("# Benchmarks") and "generated" in text.lower()
    # known sections in their order, those not run yet as placeholders
    assert text.index("bench:sim begin") < text.index("bench:protocol begin") \
        < text.index("bench:envs begin")
    assert text.count("Not measured on this checkout yet") == 3
    assert "Run 2030-01-02 03:04 UTC by `benchmarks/bench_envs.py`" in text
    assert "Test CPU 9000" in text and "numba 0.x" in text

    bp.update_section("sim", "sim body", page, when=WHEN, host=HOST)
    bp.update_section("envs", "envs body 2", page, when=WHEN, host=HOST)
    bp.update_section("extra", "extra body", page, when=WHEN, host=HOST)
    text = page.read_text()
    assert "sim body" in text and "envs body 2" in text and "envs body 1" not in text
    assert text.count("Not measured on this checkout yet") == 2  # protocol, scaling
    assert text.index("bench:envs end") < text.index("bench:extra begin")
    for key in ("sim", "protocol", "envs", "extra"):
        assert text.count(f"<!-- bench:{key} begin -->") == 1
        assert text.count(f"<!-- bench:{key} end -->") == 1


def test_no_page_when_disabled(bench, tmp_path) -> None:
    bp = bench("bench_page")
    assert bp.page_path() is None
    assert bp.update_section("sim", "x", when=WHEN, host=HOST) is None


def test_machine_description(bench) -> None:
    host = bench("bench_page").machine()
    assert {"CPU", "cores", "Python", "numba", "numpy", "commit", "load average"} <= set(host)
    assert all(isinstance(v, str) and v for v in host.values())


def test_table(bench) -> None:
    t = bench("bench_page").table(["a", "b"], [[1, "x"], ["y", 2.5]])
    assert t.splitlines() == ["| a | b |", "| --- | ---: |", "| 1 | x |", "| y | 2.5 |"]


def test_script_sections(bench, tmp_path) -> None:
    """Each bench script's section renders its figures into the page."""
    sim = bench("bench_sim").section({1: 1.5e6, 64: 2.0e7, 4096: 4.5e7}, 60000.0, 90000.0,
                                     2944.0, 28640.0)
    assert "N = 4096" in sim and "4.5e+07" in sim and "2,944 B" in sim

    proto = bench("bench_protocol")
    total = proto.LoadResult(requests=80000, writes=30000, lost=0, corrupted=0)
    protocol = proto.section(8, 10000, "MAC140", total, 20.0)
    assert "4,000" in protocol and "8 TCP clients" in protocol

    envs = bench("bench_envs")
    rows = [{"env": "jvl_gym/GearSync-v0", "trials": False, "dec": 2, "dt": 1.92e-3,
             "single": 100000.0, "dec1": 150000.0, "copies": 1024, "vector": 1.2e6,
             "vec1": 2.0e6},
            {"env": "jvl_gym/FilterTuning-v0", "trials": True, "dec": 1, "dt": 1.92e-3,
             "single": 300.0, "dec1": 300.0, "copies": 256, "vector": 12000.0,
             "vec1": 12000.0}]
    env_text = envs.section((5000.0, 1e-4), rows)
    assert "| jvl_gym/GearSync-v0 | 2 | 100,000 | 20.0 |" in env_text
    assert "12,000 (256 copies)" in env_text
    assert "not measured" in envs.section(None, rows[:1])

    scaling = bench("bench_scaling").section(
        {1: {1: 2.0e6, 2: 2.0e6}, 16384: {1: 3.0e7, 2: 5.5e7}},
        {1: {1: 150000.0, 2: 150000.0}, 16384: {1: 1.5e6, 2: 2.8e6}})
    assert "| 16,384 | 30,000,000 | 55,000,000 | 1,500,000 | 2,800,000 |" in scaling
    assert "motor-inner-steps/s, 2 threads" in scaling

    bp = bench("bench_page")
    page = tmp_path / "benchmarks.md"
    for key, body in (("sim", sim), ("protocol", protocol), ("envs", env_text),
                      ("scaling", scaling)):
        bp.update_section(key, body, page, when=WHEN, host=HOST)
    text = page.read_text()
    assert "Not measured" not in text and text.count("Run 2030-01-02") == 4
    assert "## Scaling: copies and threads" in text
