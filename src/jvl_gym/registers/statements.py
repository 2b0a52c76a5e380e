"""The statements of a family's manual: what each register description says, and whether the
simulator does it.

The conformance matrix (:mod:`.conformance`) gives a status per register; a family's
``statements.yaml`` (beside it) goes one level finer, one entry per normative statement of the
manual's register descriptions and of the chapters they refer to::

    manual: "MIS/SMC integrated step motor user manual"   # the manual the sections refer to
    statements:
      - id: "mis:8.2.13:1"        # <family key>:<section>:<ordinal within the section>
        section: "8.2.13"         # the manual's section
        line: 5123                # the statement's line in the manual's text edition
        registers: [ACTUAL_TORQUE]   # the registers it is about; [] for a chapter's rule
        says: "In passive mode ACTUAL_TORQUE reads 0 %."    # in the project's own words
        status: modelled          # modelled | stored only | not modelled | decision
        tests: [test_file.py::test_name]   # modelled and decision: the tests asserting it
        why: "..."                # stored only and not modelled: why that is faithful enough
        decision: "mis-sim.md#error-output"  # decision: the doc section (docs/families/) that
                                             # gives both readings and the choice

A test named in ``tests`` carries the statement's id in a ``pytest.mark.statements`` marker
(checked by ``tests/test_families_statements.py``). A register's status follows from its
statements (:meth:`Statements.derived_status`): *modelled* when each is modelled or a decision,
*not modelled* when one is not modelled, *stored only* otherwise.

A malformed file raises :class:`StatementError` naming the file and the entry; a family without
the file has no statements (:attr:`Statements.present` is False).
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

from .conformance import (
    MODELLED,
    NOT_MODELLED,
    STORED_ONLY,
    Conformance,
    ConformanceError,
    packaged_yaml,
    parse_test_ids,
)
from .errors import RegisterError
from .table import Access, Format, RegisterTable

__all__ = ["DECISION", "STATUSES", "Statement", "StatementError", "Statements",
           "load_packaged_statements"]

DECISION = "decision"
#: the statuses of a statement
STATUSES = (MODELLED, STORED_ONLY, NOT_MODELLED, DECISION)
_FILE = "statements.yaml"
_KEYS = {"id", "section", "line", "registers", "says", "status", "tests", "why", "decision"}
_SECTION = re.compile(r"[0-9A-Za-z]+(\.[0-9A-Za-z]+)*")
_DECISION = re.compile(r"[\w./-]+\.md#[\w-]+")


class StatementError(ConformanceError):
    """A family's statements file is malformed or does not match its register table."""


@dataclass(frozen=True)
class Statement:
    """One normative statement of the manual.

    Attributes
    ----------
    id : str
        ``<family key>:<section>:<ordinal>``.
    section : str
        The manual's section.
    line : int
        The statement's line in the manual's text edition.
    registers : tuple of str
        The registers it is about (names of the register table); empty for a chapter's rule.
    says : str
        The statement in the project's words.
    status : str
        One of :data:`STATUSES`.
    tests : tuple of str
        The tests asserting it (``file.py::test_name`` in ``tests/``).
    why : str
        Why a *stored only* or *not modelled* statement is so.
    decision : str
        The doc section (``file.md#anchor`` under ``docs/families/``) of a *decision*.
    """

    id: str
    section: str
    line: int
    registers: tuple[str, ...]
    says: str
    status: str
    tests: tuple[str, ...] = ()
    why: str = ""
    decision: str = ""

    @property
    def chapter(self) -> str:
        """The chapter: the section's first number."""
        return self.section.split(".")[0]


def _text(raw: dict, key: str, where: str) -> str:
    value = raw.get(key)
    if value is None or value == "":
        return ""
    if not isinstance(value, str):
        raise StatementError(f"{where}: {key} must be a string (quoted in YAML: '8.2' "
                             f"unquoted is a number), got {value!r}")
    return value.strip()


def _statement(raw: Any, key: str, table: RegisterTable, where: str) -> Statement:
    if not isinstance(raw, dict):
        raise StatementError(f"{where}: expected a mapping, got {raw!r}")
    unknown = set(raw) - _KEYS
    if unknown:
        raise StatementError(f"{where}: unknown keys {sorted(unknown)}")
    sid, section = _text(raw, "id", where), _text(raw, "section", where)
    where = f"{where} ({sid})" if sid else where
    if not _SECTION.fullmatch(section):
        raise StatementError(f"{where}: section must be a manual section such as '8.2.13', "
                             f"got {raw.get('section')!r}")
    if not re.fullmatch(rf"{re.escape(key)}:{re.escape(section)}:[1-9][0-9]*", sid):
        raise StatementError(f"{where}: id must be '{key}:{section}:<ordinal>' (family "
                             f"{key}, section {section}), got {raw.get('id')!r}")
    line = raw.get("line")
    if isinstance(line, bool) or not isinstance(line, int) or line < 1:
        raise StatementError(f"{where}: line must be a line number ≥ 1, got {line!r}")
    names = raw.get("registers")
    if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
        raise StatementError(f"{where}: registers must be a list of register names ([] for "
                             f"a chapter's statement), got {names!r}")
    registers = []
    for name in names:
        try:
            reg = table.lookup(name)
        except RegisterError as exc:
            raise StatementError(f"{where}: {exc}") from exc
        if reg.format == Format.LONGINT_HIGH:  # a LongInt's high word is its register's
            reg = table.lookup(reg.number - 1)
        registers.append(reg.name)
    says = _text(raw, "says", where)
    if not says:
        raise StatementError(f"{where}: says what the manual states")
    status = raw.get("status")
    if status not in STATUSES:
        raise StatementError(f"{where}: status must be one of {list(STATUSES)}, got "
                             f"{status!r}")
    tests = parse_test_ids(raw.get("tests"), where, StatementError)
    why, decision = _text(raw, "why", where), _text(raw, "decision", where)
    if status in (MODELLED, DECISION) and not tests:
        raise StatementError(f"{where}: a {status} statement names the tests asserting it")
    if status in (STORED_ONLY, NOT_MODELLED) and not why:
        raise StatementError(f"{where}: a {status} statement says why")
    if status == DECISION and not decision:
        raise StatementError(f"{where}: a decision names its doc section ('file.md#anchor')")
    if decision and not _DECISION.fullmatch(decision):
        raise StatementError(f"{where}: decision must be 'file.md#anchor', got {decision!r}")
    return Statement(sid, section, line, tuple(dict.fromkeys(registers)), says, status, tests,
                     why, decision)


class Statements:
    """A family's statements, checked against its register table.

    Parameters
    ----------
    key : str
        The family key (the ids' prefix).
    table : RegisterTable
        The family's register table.
    data : dict or None
        The parsed ``statements.yaml``; None: the family has no statements file.
    source : str
        Where the data came from (error messages).
    """

    def __init__(self, key: str, table: RegisterTable, data: Any, source: str) -> None:
        self.key = key
        self.table = table
        self.source = source
        #: whether the family has a statements file
        self.present = data is not None
        self.manual = ""
        self.statements: tuple[Statement, ...] = ()
        #: statement id → statement
        self.by_id: dict[str, Statement] = {}
        self._of: dict[str, list[Statement]] = {}
        if data is None:
            return
        if not isinstance(data, dict) or not isinstance(data.get("statements"), list):
            raise StatementError(f"{source}: expected a mapping with 'manual' and a list "
                                 "'statements'")
        unknown = set(data) - {"manual", "statements"}
        if unknown:
            raise StatementError(f"{source}: unknown keys {sorted(unknown)}")
        self.manual = _text(data, "manual", source)
        if not self.manual:
            raise StatementError(f"{source}: manual names the manual the sections refer to")
        out: dict[str, Statement] = {}
        for n, raw in enumerate(data["statements"], start=1):
            s = _statement(raw, key, table, f"{source} statement {n}")
            if s.id in out:
                raise StatementError(f"{source} statement {n}: id {s.id} listed twice")
            out[s.id] = s
        self.statements = tuple(out.values())
        self.by_id = out
        for s in self.statements:
            for name in s.registers:
                self._of.setdefault(name, []).append(s)

    def __iter__(self) -> Iterator[Statement]:
        return iter(self.statements)

    def __len__(self) -> int:
        return len(self.statements)

    def of_register(self, name: str) -> list[Statement]:
        """The statements about register ``name`` (a table name), in file order."""
        return list(self._of.get(name, []))

    def chapter_statements(self) -> list[Statement]:
        """The statements about no register (a chapter's rules)."""
        return [s for s in self.statements if not s.registers]

    def derived_status(self, name: str) -> str | None:
        """A register's status from its statements: *modelled* when each is modelled or a
        decision, *not modelled* when one is not modelled, *stored only* otherwise; None when
        no statement is about it."""
        statuses = {s.status for s in self._of.get(name, [])}
        if not statuses:
            return None
        if statuses <= {MODELLED, DECISION}:
            return MODELLED
        return NOT_MODELLED if NOT_MODELLED in statuses else STORED_ONLY

    def uncovered(self) -> list[str]:
        """Registers of the table (reserved rows and a LongInt's high word aside) about which
        no statement is."""
        return [r.name for r in self.table if r.access != Access.RESERVED
                and r.format != Format.LONGINT_HIGH and r.name not in self._of]

    def conflicts(self, conformance: Conformance) -> list[str]:
        """Registers the conformance matrix calls *modelled* while one of their statements is
        *not modelled*: one line each, naming those statements."""
        out = []
        for name, statements in self._of.items():
            entry = conformance.entry(self.table.lookup(name))
            bad = [s.id for s in statements if s.status == NOT_MODELLED]
            if entry is not None and entry.status == MODELLED and bad:
                out.append(f"{name}: modelled in {conformance.source}, but not modelled in "
                           f"{', '.join(bad)}")
        return out

    def counts(self) -> dict[str, int]:
        """Statements per status."""
        out = dict.fromkeys(STATUSES, 0)
        for s in self.statements:
            out[s.status] += 1
        return out

    def chapter_counts(self) -> dict[str, dict[str, int]]:
        """Chapter → statements per status, chapters in the manual's order."""
        out: dict[str, dict[str, int]] = {}
        for s in self.statements:
            out.setdefault(s.chapter, dict.fromkeys(STATUSES, 0))[s.status] += 1
        return dict(sorted(out.items(), key=lambda kv: (not kv[0].isdigit(),
                                                         int(kv[0]) if kv[0].isdigit() else 0,
                                                         kv[0])))

    def derived_counts(self) -> dict[str, int]:
        """Registers per derived status (registers with statements)."""
        out = dict.fromkeys((MODELLED, STORED_ONLY, NOT_MODELLED), 0)
        for name in self._of:
            out[self.derived_status(name) or NOT_MODELLED] += 1
        return out


def load_packaged_statements(package: str, table: RegisterTable,
                             key: str | None = None) -> Statements:
    """Load the ``statements.yaml`` of a family package (beside its ``conformance.yaml``).

    Parameters
    ----------
    package : str
        Dotted name of the family package.
    table : RegisterTable
        The family's register table.
    key : str, optional
        The family key the ids start with; default: the package's last name.

    Returns
    -------
    Statements
        Empty (``present`` False) when the package has no statements file.
    """
    data, source = packaged_yaml(package, _FILE, StatementError, required=False)
    return Statements(key or package.rsplit(".", 1)[-1], table, data, source)
