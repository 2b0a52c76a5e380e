"""The statements of every family (``families/<key>/statements.yaml``): each names tests that
exist and carry its id (``pytest.mark.statements``), every marker id is a statement, every
decision's doc section exists, every register has a statement, and no register the conformance
matrix calls *modelled* has a statement that is *not modelled*. A family without the file is
left alone. Each rule is shown to fire on a made-up file and test tree."""

from __future__ import annotations

import sys
import textwrap
from functools import cache
from pathlib import Path
from typing import Any

import pytest

from jvl_gym.families import family
from jvl_gym.registers import Conformance
from jvl_gym.registers.reference import markdown_reference_32
from jvl_gym.registers.statements import (
    DECISION,
    StatementError,
    Statements,
    load_packaged_statements,
)
from statement_markers import (
    Markers,
    anchors,
    decision_problems,
    named_test_problems,
    scan_markers,
    slug,
    unknown_ids,
)

TESTS = Path(__file__).resolve().parent
DOCS = TESTS.parent / "docs" / "families"
KEYS = ("mac050_141", "mac800", "mis")


@cache
def _markers() -> Markers:
    return scan_markers(TESTS)


def _statements(key: str) -> Statements:
    st = family(key).statements
    assert st is not None
    return st


def _with_file(key: str) -> Statements:
    st = _statements(key)
    if not st.present:
        pytest.skip(f"{st.source} does not exist yet")
    return st


# --- the families' files ----------------------------------------------------------------------
def test_the_markers_are_readable() -> None:
    bad = _markers().problems
    assert not bad, "\n".join(bad)


@pytest.mark.parametrize("key", KEYS)
def test_every_named_test_exists_and_carries_the_statement_id(key: str) -> None:
    bad = named_test_problems(_statements(key), _markers())
    assert not bad, "\n".join(bad)


def test_every_marker_id_is_a_statement() -> None:
    bad = unknown_ids([_statements(k) for k in KEYS], _markers())
    assert not bad, "\n".join(bad)


@pytest.mark.parametrize("key", KEYS)
def test_every_decision_names_a_doc_section_that_exists(key: str) -> None:
    bad = decision_problems(_statements(key), DOCS)
    assert not bad, "\n".join(bad)


@pytest.mark.parametrize("key", KEYS)
def test_every_register_has_a_statement(key: str) -> None:
    missing = _with_file(key).uncovered()
    assert not missing, f"{len(missing)} registers have no statement: {', '.join(missing)}"


@pytest.mark.parametrize("key", KEYS)
def test_no_register_is_modelled_while_one_of_its_statements_is_not(key: str) -> None:
    conformance = family(key).conformance
    assert conformance is not None
    bad = _statements(key).conflicts(conformance)
    assert not bad, "\n".join(bad)


# --- the loader, on made-up files -------------------------------------------------------------
TABLE = family("mis").table
CONFORMANCE = family("mis").conformance


def _s(sid: str = "mis:8.2.13:1", **kw: Any) -> dict[str, Any]:
    out: dict[str, Any] = {"id": sid, "section": sid.split(":")[1], "line": 10,
                           "registers": ["ACTUAL_TORQUE"], "says": "It reads 0 in passive mode.",
                           "status": "modelled", "tests": ["test_a.py::test_one"]}
    out.update(kw)
    return {k: v for k, v in out.items() if v is not None}


def _load(*statements: dict[str, Any], key: str = "mis") -> Statements:
    return Statements(key, TABLE, {"manual": "MIS manual", "statements": list(statements)},
                      "<made up>")


@pytest.mark.parametrize("bad, match", [
    (_s(status="maybe"), r"statement 2 \(mis:8\.2\.13:1\): status must be one of"),
    (_s(status="not modelled", tests=None), r"\(mis:8\.2\.13:1\): a not modelled statement "
                                            "says why"),
    (_s(status="stored only"), "a stored only statement says why"),
    (_s(tests=None), "a modelled statement names the tests"),
    (_s(status=DECISION, tests=None, decision="mis-sim.md#x"),
     "a decision statement names the tests"),
    (_s(status=DECISION), r"a decision names its doc section"),
    (_s(status=DECISION, decision="mis-sim.md"), "decision must be 'file.md#anchor'"),
    (_s(tests=["test_a.py"]), "tests must be a list of 'file.py::test_name'"),
    (_s("mac800:8.2.13:1"), r"id must be 'mis:8\.2\.13:<ordinal>'"),
    (_s("mis:8.2.13:1", section="8.2.14"), r"id must be 'mis:8\.2\.14:<ordinal>'"),
    (_s("mis:8.2.13:0"), "id must be"),
    (_s(section="§8.2"), "section must be a manual section"),
    (_s("mis:8.2:1", section=8.2), "section must be a string"),
    (_s(line=0), "line must be a line number"),
    (_s(line="5123"), "line must be a line number"),
    (_s(registers=["NO_SUCH_REGISTER"]), r"\(mis:8\.2\.13:1\): .*NO_SUCH_REGISTER"),
    (_s(registers="ACTUAL_TORQUE"), "registers must be a list"),
    (_s(says=""), "says what the manual states"),
    (_s(note="x"), r"unknown keys \['note'\]"),
    (_s(bit=32), r"bit must be a whole number 0 … 31, got 32"),
    (_s(bit=True), r"bit must be a whole number"),
    (_s(value=-1), r"value must be a whole number ≥ 0, got -1"),
    (_s(bit=1, registers=["ACTUAL_TORQUE", "V_SOLL"]), "a statement about a bit names its one "
                                                       "register"),
    (_s(bit=1, value=2), "about a bit or a value, not both"),
    (["not", "a", "mapping"], "statement 2: expected a mapping"),
])
def test_a_malformed_statement_is_refused_naming_the_file_and_entry(bad: Any,
                                                                     match: str) -> None:
    good = _s("mis:8.2.12:1", registers=["V_SOLL"])
    _load(good)  # the good one alone loads
    with pytest.raises(StatementError, match=rf"<made up> .*{match}"):
        _load(good, bad)


def test_a_duplicate_id_or_a_malformed_file_is_refused() -> None:
    with pytest.raises(StatementError, match=r"statement 2: id mis:8\.2\.13:1 listed twice"):
        _load(_s(), _s(says="Again."))
    for data, match in (([], "expected a mapping"),
                        ({"statements": []}, "manual names the manual"),
                        ({"manual": "m", "statements": {}}, "a list 'statements'"),
                        ({"manual": "m", "statements": [], "extra": 1}, "unknown keys")):
        with pytest.raises(StatementError, match=match):
            Statements("mis", TABLE, data, "<made up>")


def test_a_packaged_file_loads_and_a_missing_one_is_empty(tmp_path: Path,
                                                          monkeypatch: pytest.MonkeyPatch) -> None:
    for name in ("fam_with", "fam_without", "fam_broken"):
        (tmp_path / name).mkdir()
        (tmp_path / name / "__init__.py").write_text("")
    (tmp_path / "fam_with" / "statements.yaml").write_text(textwrap.dedent("""\
        manual: "MIS manual"
        statements:
          - id: "fam_with:8.2.13:1"
            section: "8.2.13"
            line: 5123
            registers: [actual_torque]
            says: "In passive mode ACTUAL_TORQUE reads 0 %."
            status: not modelled
            why: "the closed loop keeps its torque"
        """))
    (tmp_path / "fam_broken" / "statements.yaml").write_text("manual: [unclosed\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    st = load_packaged_statements("fam_with", TABLE)
    assert st.present and st.source == "fam_with/statements.yaml"
    assert [s.registers for s in st] == [("ACTUAL_TORQUE",)]
    assert st.derived_status("ACTUAL_TORQUE") == "not modelled"
    empty = load_packaged_statements("fam_without", TABLE)
    assert not empty.present and len(empty) == 0 and empty.counts()["modelled"] == 0
    assert empty.derived_status("ACTUAL_TORQUE") is None
    with pytest.raises(StatementError, match="fam_broken/statements.yaml: not valid YAML"):
        load_packaged_statements("fam_broken", TABLE)
    for name in ("fam_with", "fam_without", "fam_broken"):
        sys.modules.pop(name, None)


# --- the rules, each shown to fire --------------------------------------------------------------
def _tree(tmp_path: Path) -> Markers:
    (tmp_path / "test_a.py").write_text(textwrap.dedent("""\
        import pytest
        from pytest import mark

        pytestmark = [pytest.mark.slow, pytest.mark.statements("mis:5.1:1")]


        @pytest.mark.statements("mis:8.2.13:1", "mis:8.2.13:2")
        def test_one():
            pass


        @mark.statements("mis:8.2.12:1")
        @pytest.mark.parametrize("x", [1, 2])
        def test_two(x):
            pass


        def test_unmarked():
            pass


        def helper():
            pass


        @pytest.mark.statements("mis:8.2.14:1")
        class TestGroup:
            pytestmark = pytest.mark.statements("mis:8.2.14:2")

            @pytest.mark.statements("mis:8.2.14:3")
            def test_method(self):
                pass


        @pytest.mark.statements(IDS)
        def test_bad_marker():
            pass
        """))
    (tmp_path / "helpers.py").write_text("@pytest.mark.statements('mis:1:1')\ndef test_x(): ...\n")
    return scan_markers(tmp_path)


def test_the_scan_finds_every_test_and_the_ids_of_its_markers(tmp_path: Path) -> None:
    m = _tree(tmp_path)
    module = {"mis:5.1:1"}
    assert m.tests == {
        "test_a.py::test_one": frozenset(module | {"mis:8.2.13:1", "mis:8.2.13:2"}),
        "test_a.py::test_two": frozenset(module | {"mis:8.2.12:1"}),
        "test_a.py::test_unmarked": frozenset(module),
        "test_a.py::TestGroup::test_method": frozenset(
            module | {"mis:8.2.14:1", "mis:8.2.14:2", "mis:8.2.14:3"}),
        "test_a.py::test_bad_marker": frozenset(module)}
    assert m.problems == ["test_a.py:35: a statements marker takes the ids as string literals, "
                          "got IDS"]


def test_a_named_test_that_is_missing_or_lacks_the_id_is_reported(tmp_path: Path) -> None:
    m = _tree(tmp_path)
    good = _load(_s(tests=["test_a.py::test_one"]),
                 _s("mis:8.2.14:2", registers=["V_SOLL"],
                    tests=["test_a.py::TestGroup::test_method"]))
    assert named_test_problems(good, m) == []
    bad = _load(_s(tests=["test_a.py::test_one", "test_a.py::test_gone", "test_b.py::test_one"]),
                _s("mis:8.2.13:3", tests=["test_a.py::test_two"]))
    assert named_test_problems(bad, m) == [
        "mis:8.2.13:1: test test_a.py::test_gone does not exist",
        "mis:8.2.13:1: test test_b.py::test_one does not exist",
        "mis:8.2.13:3: test test_a.py::test_two does not carry the id in its statements marker"]


def test_a_marker_id_in_no_statements_file_is_reported(tmp_path: Path) -> None:
    m = Markers({"test_a.py::test_one": frozenset({"mis:8.2.13:1", "mis:8.2.13:9"}),
                 "test_a.py::test_two": frozenset({"mls:8.2.13:1", "mac800:1.2:1"})})
    mis = _load(_s())
    mac800 = Statements("mac800", family("mac800").table, None, "<none>")  # no file: left alone
    assert unknown_ids([mis, mac800], m) == [
        "test_a.py::test_one: marker id 'mis:8.2.13:9' is in no statement of <made up>",
        "test_a.py::test_two: marker id 'mls:8.2.13:1' is of no family (mis, mac800)"]


def test_slugs_are_the_anchors_mkdocs_makes() -> None:
    assert slug("Decisions where the manual is ambiguous") == (
        "decisions-where-the-manual-is-ambiguous")
    assert slug("Firmware (`firmware/`)") == "firmware-firmware"
    assert slug("Error output: §5.6.1 *or* §8.2.78?") == "error-output-561-or-8278"
    assert slug("ACTUAL_TORQUE in [passive mode](#modes)") == "actual_torque-in-passive-mode"


def test_a_decision_whose_doc_section_is_missing_is_reported(tmp_path: Path) -> None:
    (tmp_path / "fam.md").write_text(textwrap.dedent("""\
        # Family
        ## Error output
        ```
        # not a heading
        ```
        ## Error output
        """))
    assert anchors(tmp_path / "fam.md") == {"family", "error-output", "error-output_1"}
    st = _load(*(_s(f"mis:8.2.13:{n}", status=DECISION, decision=d) for n, d in enumerate(
        ("fam.md#error-output", "fam.md#error-output_1", "fam.md#not-a-heading",
         "other.md#error-output"), start=1)))
    assert decision_problems(st, tmp_path) == [
        "mis:8.2.13:3: fam.md has no heading with the anchor #not-a-heading",
        "mis:8.2.13:4: decision page other.md does not exist"]


def test_a_register_without_a_statement_is_reported() -> None:
    st = _load(_s(registers=["ACTUAL_TORQUE", "V_SOLL"]),
               _s("mis:5.1:1", registers=[]))
    missing = st.uncovered()
    assert "ACTUAL_TORQUE" not in missing and "V_SOLL" not in missing
    assert "P_SOLL" in missing and not any(n.startswith("RESERVED_") for n in missing)
    assert len(missing) == sum(1 for r in TABLE if r.access.value != "reserved") - 2
    assert [s.id for s in st.chapter_statements()] == ["mis:5.1:1"]


def test_a_registers_status_derives_from_its_statements() -> None:
    def derived(*statuses: str) -> str | None:
        extra = {"stored only": {"why": "w", "tests": None}, "not modelled": {"why": "w"},
                 DECISION: {"decision": "mis-sim.md#x"}}
        st = _load(*(_s(f"mis:8.2.13:{n}", status=s, **extra.get(s, {}))
                     for n, s in enumerate(statuses, start=1)))
        return st.derived_status("ACTUAL_TORQUE")

    assert derived("modelled", DECISION) == "modelled"
    assert derived("modelled", "stored only") == "stored only"
    assert derived("modelled", "stored only", "not modelled") == "partly modelled"
    assert derived(DECISION, "not modelled") == "partly modelled"
    assert derived("stored only", "not modelled") == "not modelled"


def test_a_modelled_register_with_a_not_modelled_statement_is_reported() -> None:
    assert CONFORMANCE is not None
    modelled = next(CONFORMANCE.table.lookup(n).name for n, e in CONFORMANCE.entries.items()
                    if e.status == "modelled")
    st = _load(_s(registers=[modelled]),
               _s("mis:8.2.13:2", registers=[modelled], status="not modelled", why="w"))
    assert st.conflicts(CONFORMANCE) == [
        f"{modelled}: modelled in {CONFORMANCE.source}, but not modelled in mis:8.2.13:2 "
        "(partly modelled, then)"]
    assert _load(_s(registers=[modelled])).conflicts(CONFORMANCE) == []
    partly = Conformance(TABLE, {"registers": {modelled: {"status": "partly modelled",
                                                          "tests": ["test_a.py::test_one"]}}},
                         "<p>")
    assert st.conflicts(partly) == []
    assert _load(_s(registers=[modelled])).conflicts(partly) == [
        f"{modelled}: partly modelled in <p>, but no statement about it is not modelled"]
    stored = Conformance(TABLE, {"registers": {modelled: {"status": "stored only",
                                                          "why": "w"}}}, "<c>")
    assert st.conflicts(stored) == []


def test_a_bit_or_value_statement_is_held_against_its_conformance_entry() -> None:
    conformance = Conformance(TABLE, {"registers": {"MODE_REG": {
        "status": "modelled", "tests": ["test_a.py::test_one"],
        "values": {1: {"name": "Velocity", "status": "modelled", "tests": ["test_a.py::test_one"]},
                   32: {"name": "CSP", "status": "not modelled", "why": "w"}}}}}, "<c>")
    not_modelled = {"status": "not modelled", "why": "w", "tests": None}
    # a value the matrix documents as not modelled: the register stays modelled
    st = _load(_s("mis:8.2.3:1", registers=["MODE_REG"]),
               _s("mis:8.2.3:2", registers=["MODE_REG"], value=32, **not_modelled))
    assert st.conflicts(conformance) == []
    assert st.derived_status("MODE_REG") == "modelled"
    # a value the matrix calls modelled, a statement not modelled
    st = _load(_s("mis:8.2.3:1", registers=["MODE_REG"], value=1, **not_modelled))
    assert st.conflicts(conformance) == [
        "MODE_REG value 1: MODE_REG value 1 modelled in <c>, but mis:8.2.3:1 is not modelled"]
    # a value the matrix does not document: held against the register's entry
    st = _load(_s("mis:8.2.3:1", registers=["MODE_REG"], value=2, **not_modelled))
    assert st.conflicts(conformance) == [
        "MODE_REG value 2: MODE_REG modelled in <c>, but mis:8.2.3:1 is not modelled"]
    assert st.derived_status("MODE_REG") == "not modelled"  # its only statement
    # a statement modelled where the matrix says the value is not
    st = _load(_s("mis:8.2.3:1", registers=["MODE_REG"], value=32))
    assert st.conflicts(conformance) == [
        "MODE_REG value 32: not modelled in <c>, but mis:8.2.3:1 is modelled"]


def test_a_statement_of_a_register_without_a_section_counts_in_its_register_s_chapter() -> None:
    table = family("mac800").table
    st = Statements("mac800", table, {"manual": "MAC800 overview", "statements": [
        _s("mac800:reg2:1", registers=["MODE_REG"]), _s("mac800:1.3.1:1", registers=[])]},
        "<made up>")
    assert table.lookup("MODE_REG").section.startswith("1.2")
    assert list(st.chapter_counts()) == ["1"]
    assert sum(st.chapter_counts()["1"].values()) == 2


# --- the reference page -----------------------------------------------------------------------
def test_the_reference_page_lists_the_statements_and_their_counts() -> None:
    st = _load(_s(registers=["ACTUAL_TORQUE", "V_SOLL"]),
               _s("mis:8.2.13:2", status="not modelled", why="no | pipe", tests=None),
               _s("mis:5.1:1", registers=[], status=DECISION, decision="mis-sim.md#x"))
    plain = markdown_reference_32(TABLE, "MIS", "note", "gen", CONFORMANCE)
    assert markdown_reference_32(TABLE, "MIS", "note", "gen", CONFORMANCE,
                                 Statements("mis", TABLE, None, "<none>")) == plain
    md = markdown_reference_32(TABLE, "MIS", "note", "gen", CONFORMANCE, st)
    assert "| chapter | modelled | stored only | not modelled | decision | all |" in md
    assert "| §5 | 0 | 0 | 0 | 1 | 1 |" in md
    assert "| §8 | 1 | 0 | 1 | 0 | 2 |" in md
    assert "| all | 1 | 0 | 1 | 1 | 3 |" in md
    assert "Registers: 1 modelled, 1 partly modelled, 0 stored only, 0 not modelled," in md
    rows = {ln.split(" | ")[1]: ln for ln in md.splitlines() if ln.startswith("| ")
            and ln[2].isdigit()}
    assert rows["ACTUAL_TORQUE"].endswith("| partly modelled (2) |")
    assert rows["V_SOLL"].endswith("| modelled (1) |")
    assert rows["P_SOLL"].endswith("|  |")
    assert ("| ACTUAL_TORQUE | mis:8.2.13:2 | 8.2.13 | It reads 0 in passive mode. | "
            "not modelled: no \\| pipe |  |") in md
    assert ("| V_SOLL | mis:8.2.13:1 | 8.2.13 | It reads 0 in passive mode. | modelled | "
            "`test_a.py::test_one` |") in md
    assert "| (chapter) | mis:5.1:1 | 5.1 |" in md
    assert "decision (`mis-sim.md#x`)" in md


def test_the_mac050_141_page_shows_the_statements_column_too() -> None:
    from jvl_gym.registers.reference import markdown_reference

    table = family("mac050_141").table
    st = Statements("mac050_141", table, {"manual": "MAC manual", "statements": [
        _s("mac050_141:3.2.3:1", registers=["P_SOLL_HI"])]}, "<made up>")
    assert st.statements[0].registers == ("P_SOLL",)  # a LongInt's high word is its register's
    md = markdown_reference(table, statements=st)
    rows = {ln.split(" | ")[1]: ln for ln in md.splitlines() if ln.startswith("| ")
            and ln[2].isdigit()}
    assert rows["P_SOLL"].endswith("| modelled (1) |") and rows["P_SOLL_HI"].endswith("|  |")
    assert "| P_SOLL | mac050_141:3.2.3:1 | 3.2.3 |" in md
    assert markdown_reference(table) == markdown_reference(
        table, statements=Statements("mac050_141", table, None, "<none>"))


@pytest.mark.parametrize("key", KEYS)
def test_every_registers_conformance_status_is_its_derived_status(key: str) -> None:
    """The conformance matrix's status of each register is the one its statements give
    (:meth:`Statements.derived_status`): the two files never tell different stories."""
    st = _with_file(key)
    conformance = family(key).conformance
    assert conformance is not None
    bad = []
    for reg in st.table:
        derived = st.derived_status(reg.name)
        entry = conformance.entry(reg)
        if derived is None or entry is None:
            continue
        if entry.status != derived:
            bad.append(f"{reg.name}: {entry.status} in {conformance.source}, {derived} by its "
                       "statements")
    assert not bad, f"{len(bad)} registers disagree:\n" + "\n".join(bad)
