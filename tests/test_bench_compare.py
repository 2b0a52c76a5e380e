"""benchmarks/bench_compare.py: the fixed reference and the table of ratios.

No benchmark is run: the report gets made-up figures.
"""

from __future__ import annotations

import importlib
import sys
from pathlib import Path

import pytest

BENCH = Path(__file__).resolve().parents[1] / "benchmarks"


@pytest.fixture
def compare(monkeypatch):
    monkeypatch.syspath_prepend(str(BENCH))
    sys.modules.pop("bench_compare", None)
    return importlib.import_module("bench_compare")


def test_reference_file_names_a_revision_of_the_repository(compare) -> None:
    revision = compare.read_reference(compare.REFERENCE_FILE.read_text())
    assert compare.commit_of(revision).startswith(revision[:7])


def test_reference_text(compare) -> None:
    text = "# why\n# how\nabc1234\n"
    assert compare.read_reference(text) == "abc1234"
    moved = compare.with_reference(text, "def5678901")
    assert moved == "# why\n# how\ndef5678901\n"
    assert compare.read_reference(moved) == "def5678901"
    with pytest.raises(ValueError, match="names no revision"):
        compare.read_reference("# only a comment\n\n")


def test_unknown_revision_is_refused(compare) -> None:
    with pytest.raises(ValueError, match="not a revision"):
        compare.commit_of("no-such-revision-anywhere")


def test_report_gives_both_ratios(compare) -> None:
    best = {"reference": {"a": 100.0, "b": 200.0}, "previous": {"a": 50.0, "b": 400.0},
            "this": {"a": 110.0, "b": 200.0}}
    lines = compare.report(best, {"reference": "ref abc1234", "previous": "HEAD~1 def5678"})
    assert "ref abc1234" in lines[0] and "HEAD~1 def5678" in lines[0]
    assert lines[1].split()[-2:] == ["1.100", "2.200"]
    assert lines[2].split()[-2:] == ["1.000", "0.500"]
    assert compare.below(best) == []
    assert compare.below(best, "previous") == ["b"]
    best["this"]["b"] = 199.0
    assert compare.below(best) == ["b"]


def test_report_without_a_separate_previous_revision(compare) -> None:
    best = {"reference": {"a": 100.0}, "this": {"a": 90.0}}
    lines = compare.report(best, {"reference": "ref abc1234"})
    assert lines[1].split()[-1] == "0.900" and len(lines[1].split()) == 4
