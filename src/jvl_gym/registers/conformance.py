"""The conformance matrix of a motor family: what the simulator does with each register.

Each family keeps, beside its register table, a ``conformance.yaml`` saying for every register,
and for every bit or value the manual documents, one of:

- ``modelled``: the simulator does what the manual says; ``tests`` names the tests
  (``test_file.py::test_name`` in ``tests/``) that exercise it;
- ``stored only``: the register is kept and read back (and saved in flash) but has no effect
  on the simulation; ``why`` says why that is faithful enough;
- ``not modelled``: the manual's behaviour is absent; ``why`` says why. Writing a value other
  than the default to such a register, or setting or clearing such a bit, warns once per
  register (:class:`NotModelledWarning`) and is still stored and read back;
- ``partly modelled`` (a register only): the simulator does what the manual says of it but for
  the statements of the family's ``statements.yaml`` that are *not modelled* (a rule, a range,
  a bit or a value); ``tests`` names the tests of what is modelled. Writing it does not warn
  (its not-modelled bits and values, listed as such, do).

The file's layout::

    reserved: {status: not modelled, why: ...}   # every RESERVED_<n> row of the table
    registers:
      NAME:                                      # every other row (a LongInt's _HI row
        status: modelled                         # shares its register's entry)
        tests: [test_file.py::test_name, ...]
        section: "8.2.24"                        # optional: the table's section otherwise
        bits:                                    # optional: documented bits (0 … 31)
          22: {name: In target position, status: modelled, tests: [...]}
        values:                                  # optional: documented values of a code
          11: {name: Stop, status: modelled, tests: [...]}

A malformed file raises :class:`ConformanceError` naming the file and the entry.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from importlib import resources
from typing import Any

import numpy as np
import yaml

from .errors import RegisterError, echo
from .table import Access, Format, Register, RegisterTable

__all__ = ["MODELLED", "STORED_ONLY", "NOT_MODELLED", "PARTLY_MODELLED", "STATUSES",
           "REGISTER_STATUSES", "Conformance",
           "ConformanceError", "Entry", "NotModelledWarning", "load_packaged_conformance",
           "packaged_yaml", "parse_test_ids"]

MODELLED = "modelled"
STORED_ONLY = "stored only"
NOT_MODELLED = "not modelled"
PARTLY_MODELLED = "partly modelled"
#: the statuses of a bit or a value
STATUSES = (MODELLED, STORED_ONLY, NOT_MODELLED)
#: the statuses of a register
REGISTER_STATUSES = (MODELLED, PARTLY_MODELLED, STORED_ONLY, NOT_MODELLED)
_FILE = "conformance.yaml"
#: libyaml's safe loader where PyYAML has it (ten times faster: the files are read on import)
_LOADER = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


class ConformanceError(RegisterError):
    """A family's conformance file is malformed or does not match its register table."""


class NotModelledWarning(UserWarning):
    """A register or bit the simulator does not model was given a value other than its
    default: the value is stored and read back, but the simulated motor ignores it."""


@dataclass(frozen=True)
class Entry:
    """The conformance of one register, bit or value.

    Attributes
    ----------
    status : str
        ``"modelled"``, ``"stored only"`` or ``"not modelled"``.
    tests : tuple of str
        Test ids (``file.py::name`` in ``tests/``) of a modelled entry.
    why : str
        Why the entry is stored only or not modelled (may be given for a modelled one too).
    name : str
        The manual's name of a bit or value (``""`` for a register).
    section : str
        Manual section.
    bits, values : dict
        Bit number (0 … 31) or documented value → its :class:`Entry` (registers only).
    """

    status: str
    tests: tuple[str, ...] = ()
    why: str = ""
    name: str = ""
    section: str = ""
    bits: dict[int, Entry] = field(default_factory=dict)
    values: dict[int, Entry] = field(default_factory=dict)


def parse_test_ids(raw: Any, where: str, error: type[ConformanceError] = ConformanceError
             ) -> tuple[str, ...]:
    """The test ids of an entry (``file.py::test_name`` in ``tests/``; none if ``raw`` is
    empty), or ``error`` naming ``where``."""
    tests = raw or []
    if not isinstance(tests, list) or not all(isinstance(t, str) and "::" in t for t in tests):
        raise error(f"{where}: tests must be a list of 'file.py::test_name'")
    return tuple(tests)


def packaged_yaml(package: str, filename: str, error: type[ConformanceError] = ConformanceError,
                  required: bool = True) -> tuple[Any, str]:
    """The parsed YAML file ``filename`` of a family package, and its source name.

    Parameters
    ----------
    package : str
        Dotted name of the family package.
    filename : str
        File name inside the package.
    error : type
        The error raised (naming the file) when the file is not valid YAML.
    required : bool
        False: a missing file gives ``None`` as its data.

    Returns
    -------
    tuple
        The parsed data and ``"<package as a path>/<filename>"``.
    """
    source = f"{package.replace('.', '/')}/{filename}"
    path = resources.files(package).joinpath(filename)
    if not required and not path.is_file():
        return None, source
    try:
        return yaml.load(path.read_text(encoding="utf-8"), Loader=_LOADER), source
    except yaml.YAMLError as exc:
        raise error(f"{source}: not valid YAML ({exc})") from exc


def _entry(raw: Any, where: str, section: str, nested: bool) -> Entry:
    if not isinstance(raw, dict):
        raise ConformanceError(f"{where}: expected a mapping, got {echo(raw)}")
    allowed = {"status", "tests", "why", "name", "section"} | (set() if nested else
                                                                {"bits", "values"})
    unknown = set(raw) - allowed
    if unknown:
        raise ConformanceError(f"{where}: unknown keys {sorted(unknown)}")
    status = raw.get("status")
    allowed_statuses = STATUSES if nested else REGISTER_STATUSES
    if status not in allowed_statuses:
        raise ConformanceError(f"{where}: status must be one of {list(allowed_statuses)}, got "
                               f"{echo(status)}")
    tests = parse_test_ids(raw.get("tests"), where)
    why = str(raw.get("why") or "")
    if status in (MODELLED, PARTLY_MODELLED) and not tests:
        raise ConformanceError(f"{where}: a {status} entry names its tests")
    if status in (STORED_ONLY, NOT_MODELLED) and not why:
        raise ConformanceError(f"{where}: a {status} entry says why")
    subs: dict[str, dict[int, Entry]] = {"bits": {}, "values": {}}
    for key in ("bits", "values"):
        for k, sub in (raw.get(key) or {}).items():
            if not isinstance(k, int) or (key == "bits" and not 0 <= k <= 31):
                raise ConformanceError(f"{where}: {key} key {echo(k)} is not a "
                                       f"{'bit number 0 … 31' if key == 'bits' else 'value'}")
            subs[key][k] = _entry(sub, f"{where} {key[:-1]} {k}", section, True)
    return Entry(status, tests, why, str(raw.get("name") or ""),
                 str(raw.get("section") or section), subs["bits"], subs["values"])


class Conformance:
    """A family's conformance matrix, checked against its register table.

    Parameters
    ----------
    table : RegisterTable
        The family's register table.
    data : dict
        The parsed ``conformance.yaml``.
    source : str
        Where the data came from (error messages).
    """

    def __init__(self, table: RegisterTable, data: Any, source: str) -> None:
        if not isinstance(data, dict) or not isinstance(data.get("registers"), dict):
            raise ConformanceError(f"{source}: expected a mapping with 'registers'")
        self.source = source
        self.table = table
        reserved = data.get("reserved")
        self.reserved = None if reserved is None else _entry(reserved, f"{source} reserved",
                                                             "", True)
        self.entries: dict[int, Entry] = {}
        for name, raw in data["registers"].items():
            try:
                reg = table.lookup(str(name))
            except RegisterError as exc:
                raise ConformanceError(f"{source}: {exc}") from exc
            if reg.number in self.entries:
                raise ConformanceError(f"{source}: {reg.name} listed twice")
            self.entries[reg.number] = _entry(raw, f"{source} {reg.name}", reg.section, False)
        #: register number → (mask of the not-modelled bits, whole register not modelled)
        self.warn_rules: dict[int, tuple[int, bool]] = {}
        for num, e in self.entries.items():
            mask = 0
            for bit, sub in e.bits.items():
                if sub.status == NOT_MODELLED:
                    mask |= 1 << bit
            whole = e.status == NOT_MODELLED
            if (mask or whole) and table.lookup(num).access == Access.RW:
                self.warn_rules[num] = (mask, whole)

    def entry(self, reg: Register) -> Entry | None:
        """The entry that covers ``reg`` (a LongInt's high word: its register's; a reserved
        row: the ``reserved`` entry), or None when the matrix has none."""
        if reg.access == Access.RESERVED:
            return self.entries.get(reg.number, self.reserved)
        if reg.format == Format.LONGINT_HIGH:
            return self.entries.get(reg.number - 1)
        return self.entries.get(reg.number)

    def missing(self) -> list[str]:
        """Registers of the table without an entry (names)."""
        return [reg.name for reg in self.table if self.entry(reg) is None]

    def counts(self) -> dict[str, int]:
        """Registers per status (a LongInt's high word and the reserved rows not counted)."""
        out = dict.fromkeys(REGISTER_STATUSES, 0)
        for e in self.entries.values():
            out[e.status] += 1
        return out

    def bit_counts(self) -> dict[str, int]:
        """Documented bits and values per status."""
        out = dict.fromkeys(STATUSES, 0)
        for e in self.entries.values():
            for sub in (*e.bits.values(), *e.values.values()):
                out[sub.status] += 1
        return out

    def cell(self, reg: Register) -> str:
        """One Markdown-ready line for ``reg``: its status, tests or reason, and the bits and
        values that are not modelled."""
        e = self.entry(reg)
        if e is None:
            return ""
        text = e.status
        if e.why and e.status != MODELLED:
            text += f": {e.why}"
        partial = [f"{kind} {k}" for kind, subs in (("bit", e.bits), ("value", e.values))
                   for k, sub in subs.items() if sub.status == NOT_MODELLED]
        if partial:
            text += f" (not modelled: {', '.join(partial)})"
        return text

    def not_modelled_change(self, num: int, default: int, raw: Any) -> bool:
        """Whether stored integers ``raw`` of register ``num`` differ from ``default`` where
        the register or one of its bits is not modelled."""
        rule = self.warn_rules.get(num)
        if rule is None:
            return False
        mask, whole = rule

        diff = np.asarray(raw, dtype=np.int64) ^ default
        return bool(np.any(diff != 0) if whole else np.any(diff & mask))


def load_packaged_conformance(package: str, table: RegisterTable) -> Conformance:
    """Load the ``conformance.yaml`` of a family package (beside its ``registers.csv``).

    Parameters
    ----------
    package : str
        Dotted name of the family package.
    table : RegisterTable
        The family's register table.
    """
    data, source = packaged_yaml(package, _FILE)
    return Conformance(table, data, source)
