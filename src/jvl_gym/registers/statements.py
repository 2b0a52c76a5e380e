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
        bit: 3                    # optional, with one register: the statement is about this
                                  # bit (0 … 31) of it; or value: 11, one documented value
        says: "In passive mode ACTUAL_TORQUE reads 0 %."    # in the project's own words
        status: modelled          # modelled | stored only | not modelled | decision
        tests: [test_file.py::test_name]   # modelled and decision: the tests asserting it
        why: "..."                # stored only and not modelled: why that is faithful enough
        decision: "mis-sim.md#error-output"  # decision: the doc section (docs/families/) that
                                             # gives both readings and the choice

A test named in ``tests`` carries the statement's id in a ``pytest.mark.statements`` marker
(checked by ``tests/test_families_statements.py``). A register's status follows from its
statements about the whole register (:meth:`Statements.derived_status`; those about a bit or a
value where it has no other): *modelled* when each is modelled or a decision, *partly
modelled* when some are and some are not modelled, *not modelled* when one is not modelled and
none is modelled, *stored only* otherwise. A statement about a bit or a value is held
against the conformance matrix's entry of that bit or value (its register's where the matrix
documents none): the two never disagree on whether it is modelled
(:meth:`Statements.conflicts`).

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
    PARTLY_MODELLED,
    STORED_ONLY,
    Conformance,
    ConformanceError,
    packaged_yaml,
    parse_test_ids,
)
from .errors import RegisterError, echo
from .table import Access, Format, RegisterTable

__all__ = ["DECISION", "STATUSES", "Statement", "StatementError", "Statements",
           "load_packaged_statements"]

DECISION = "decision"
#: the statuses of a statement
STATUSES = (MODELLED, STORED_ONLY, NOT_MODELLED, DECISION)
_FILE = "statements.yaml"
_KEYS = {"id", "section", "line", "registers", "bit", "value", "says", "status", "tests", "why",
         "decision"}
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
    bit, value : int or None
        The bit (0 … 31) or the documented value of its one register the statement is about;
        None for a statement about whole registers.
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
    bit: int | None = None
    value: int | None = None

    @property
    def about_part(self) -> bool:
        """Whether the statement is about one bit or one value of its register."""
        return self.bit is not None or self.value is not None

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
                             f"unquoted is a number), got {echo(value)}")
    return value.strip()


def _statement(raw: Any, key: str, table: RegisterTable, where: str) -> Statement:
    if not isinstance(raw, dict):
        raise StatementError(f"{where}: expected a mapping, got {echo(raw)}")
    unknown = set(raw) - _KEYS
    if unknown:
        raise StatementError(f"{where}: unknown keys {sorted(unknown)}")
    sid, section = _text(raw, "id", where), _text(raw, "section", where)
    where = f"{where} ({sid})" if sid else where
    if not _SECTION.fullmatch(section):
        raise StatementError(f"{where}: section must be a manual section such as '8.2.13', "
                             f"got {echo(raw.get('section'))}")
    if not re.fullmatch(rf"{re.escape(key)}:{re.escape(section)}:[1-9][0-9]*", sid):
        raise StatementError(f"{where}: id must be '{key}:{section}:<ordinal>' (family "
                             f"{key}, section {section}), got {echo(raw.get('id'))}")
    line = raw.get("line")
    if isinstance(line, bool) or not isinstance(line, int) or line < 1:
        raise StatementError(f"{where}: line must be a line number ≥ 1, got {echo(line)}")
    names = raw.get("registers")
    if not isinstance(names, list) or not all(isinstance(n, str) for n in names):
        raise StatementError(f"{where}: registers must be a list of register names ([] for "
                             f"a chapter's statement), got {echo(names)}")
    registers = []
    for name in names:
        try:
            reg = table.lookup(name)
        except RegisterError as exc:
            raise StatementError(f"{where}: {exc}") from exc
        if reg.format == Format.LONGINT_HIGH:  # a LongInt's high word is its register's
            reg = table.lookup(reg.number - 1)
        registers.append(reg.name)
    bit, value = raw.get("bit"), raw.get("value")
    for name, part, top in (("bit", bit, 31), ("value", value, None)):
        if part is None:
            continue
        if isinstance(part, bool) or not isinstance(part, int) or part < 0 or (
                top is not None and part > top):
            raise StatementError(f"{where}: {name} must be a whole number"
                                 + (f" 0 … {top}" if top is not None else " ≥ 0")
                                 + f", got {echo(part)}")
        if len(registers) != 1:
            raise StatementError(f"{where}: a statement about a {name} names its one register, "
                                 f"got {echo(names)}")
    if bit is not None and value is not None:
        raise StatementError(f"{where}: a statement is about a bit or a value, not both")
    says = _text(raw, "says", where)
    if not says:
        raise StatementError(f"{where}: says what the manual states")
    status = raw.get("status")
    if status not in STATUSES:
        raise StatementError(f"{where}: status must be one of {list(STATUSES)}, got "
                             f"{echo(status)}")
    tests = parse_test_ids(raw.get("tests"), where, StatementError)
    why, decision = _text(raw, "why", where), _text(raw, "decision", where)
    if status in (MODELLED, DECISION) and not tests:
        raise StatementError(f"{where}: a {status} statement names the tests asserting it")
    if status in (STORED_ONLY, NOT_MODELLED) and not why:
        raise StatementError(f"{where}: a {status} statement says why")
    if status == DECISION and not decision:
        raise StatementError(f"{where}: a decision names its doc section ('file.md#anchor')")
    if decision and not _DECISION.fullmatch(decision):
        raise StatementError(f"{where}: decision must be 'file.md#anchor', got {echo(decision)}")
    return Statement(sid, section, line, tuple(dict.fromkeys(registers)), says, status, tests,
                     why, decision, bit, value)


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
        """A register's status from its statements about the whole register (from those about
        its bits and values where it has none): *modelled* when each is modelled or a
        decision, *partly modelled* when some are modelled and some not, *not modelled* when
        one is not modelled and none modelled, *stored only* otherwise; None when no statement
        is about it."""
        about = self._of.get(name, [])
        whole = [s for s in about if not s.about_part]
        statuses = {s.status for s in (whole or about)}
        if not statuses:
            return None
        if statuses <= {MODELLED, DECISION}:
            return MODELLED
        if NOT_MODELLED in statuses:
            return PARTLY_MODELLED if statuses & {MODELLED, DECISION} else NOT_MODELLED
        return STORED_ONLY

    def uncovered(self) -> list[str]:
        """Registers of the table (reserved rows and a LongInt's high word aside) about which
        no statement is."""
        return [r.name for r in self.table if r.access != Access.RESERVED
                and r.format != Format.LONGINT_HIGH and r.name not in self._of]

    def conflicts(self, conformance: Conformance) -> list[str]:
        """Where the statements and the conformance matrix disagree, one line each: a register
        the matrix calls *modelled* while a statement about the whole register is *not
        modelled* (it is *partly modelled*); a register the matrix calls *partly modelled*
        with no statement about it, or a part of it, not modelled; a bit or a value whose
        statement is *not modelled* while the matrix's entry of it (its register's where it
        documents none) is *modelled*, or *modelled* while the matrix's entry of it is *not
        modelled*."""
        out = []
        for name, statements in self._of.items():
            entry = conformance.entry(self.table.lookup(name))
            if entry is None:
                continue
            bad = [s.id for s in statements if not s.about_part and s.status == NOT_MODELLED]
            if entry.status == MODELLED and bad:
                out.append(f"{name}: modelled in {conformance.source}, but not modelled in "
                           f"{', '.join(bad)} (partly modelled, then)")
            if entry.status == PARTLY_MODELLED and not any(
                    s.status == NOT_MODELLED for s in statements):
                out.append(f"{name}: partly modelled in {conformance.source}, but no statement "
                           "about it is not modelled")
            for s in statements:
                if not s.about_part:
                    continue
                what, number = ("bit", s.bit) if s.bit is not None else ("value", s.value)
                parts = entry.bits if s.bit is not None else entry.values
                part = parts.get(number)
                status = part.status if part is not None else entry.status
                place = f"{name} {what} {number}" if part is not None else name
                if s.status == NOT_MODELLED and status == MODELLED:
                    out.append(f"{name} {what} {number}: {place} modelled in "
                               f"{conformance.source}, but {s.id} is not modelled")
                elif s.status == MODELLED and part is not None and status == NOT_MODELLED:
                    out.append(f"{name} {what} {number}: not modelled in {conformance.source}, "
                               f"but {s.id} is modelled")
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
            out.setdefault(self.chapter_of(s), dict.fromkeys(STATUSES, 0))[s.status] += 1
        return dict(sorted(out.items(), key=lambda kv: (not kv[0].isdigit(),
                                                         int(kv[0]) if kv[0].isdigit() else 0,
                                                         kv[0])))

    def chapter_of(self, statement: Statement) -> str:
        """The chapter of ``statement``: its section's first number; for a section that is no
        number (a register without a section of its own, ``reg35``), the chapter of its first
        register's section in the register table."""
        if statement.section[0].isdigit() or not statement.registers:
            return statement.chapter
        section = self.table.lookup(statement.registers[0]).section
        chapter = section.split(".")[0].split()[0] if section else ""
        return chapter if chapter.isdigit() else statement.chapter

    def derived_counts(self) -> dict[str, int]:
        """Registers per derived status (registers with statements)."""
        out = dict.fromkeys((MODELLED, PARTLY_MODELLED, STORED_ONLY, NOT_MODELLED), 0)
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
