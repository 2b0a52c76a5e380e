"""The register table of one motor family, kept as data (manual 3.2, docs/model.md §4).

Each motor family keeps its table in its own package
(``jvl_gym/families/<family>/registers.csv``, loaded with :func:`load_table` or
:func:`load_packaged_table`). One row per register number. A LongInt register N (manual
3.1: "registers of the format LongInt take up two register numbers, corresponding to two
words") is a ``LongInt`` row N holding the whole 32-bit value and a ``LongIntHigh`` row N+1 named
``<NAME>_HI`` for the high word, so that every number has exactly one row. Numbers the manual
leaves undocumented are ``RESERVED_<n>`` rows with access ``reserved``.

Tables whose registers are 32 bits wide at one register number use the formats ``Int32``,
``Word32``, ``Fixed16`` and ``Fixed24``: one row per number, no high-word row; on a 16-bit
protocol such a value travels as two words, low word first
(:func:`jvl_gym.registers.formats.split_word32`).

The CSV is loaded once and validated; a malformed table raises :class:`TableError` naming the
file, row and problem.
"""

from __future__ import annotations

import csv
import difflib
import enum
import io
import math
from collections.abc import Iterator
from dataclasses import dataclass
from functools import cached_property
from importlib import resources
from os import PathLike
from pathlib import Path

import numpy as np

from .errors import RegisterError, UnknownRegisterError, echo

__all__ = [
    "Format",
    "Access",
    "Register",
    "RegisterTable",
    "TableError",
    "load_table",
    "load_packaged_table",
    "FORMAT_CODES",
    "FORMAT_SCALE",
    "FORMAT_RAW_RANGE",
    "FORMATS_32_ONE_NUMBER",
    "format_value_range",
    "is_signed",
]

#: highest register number of the MAC50–141 (index length of the arrays is this + 1)
MAC050_141_LAST = 164


class Format(str, enum.Enum):
    """Data formats of manual 3.1, the high word of a LongInt, and the 32-bit formats at one
    register number used by tables with 32-bit registers."""

    WORD = "Word"  #: 16 bit unsigned, 0 … 65535
    INTEGER = "Integer"  #: 16 bit signed, −32767 … +32767
    LONGINT = "LongInt"  #: 32 bit signed, takes two register numbers (low word first)
    LONGINT_HIGH = "LongIntHigh"  #: second register number of a LongInt (high word)
    FIXED4 = "Fixed4"  #: 16 bit signed, unit 1/4096, ±7.999756
    FIXED8 = "Fixed8"  #: 16 bit signed, unit 1/256, ±127.996
    INT32 = "Int32"  #: 32 bit signed at one register number, −2**31 … 2**31−1
    WORD32 = "Word32"  #: 32 bit unsigned at one register number, 0 … 2**32−1
    FIXED16 = "Fixed16"  #: 32 bit signed at one number, unit 1/65536, −32768 … 32767.9999847
    FIXED24 = "Fixed24"  #: 32 bit signed at one number, unit 1/16777216, −128 … 127.99999994


class Access(str, enum.Enum):
    """Who may write a register."""

    RW = "rw"  #: parameter or data the user may write
    RO = "ro"  #: computed by the firmware; a user write is refused
    RESERVED = "reserved"  #: number not documented in the manual


#: format → code used by the compiled kernels (0 means reserved)
FORMAT_CODES: dict[Format, int] = {
    Format.WORD: 1,
    Format.INTEGER: 2,
    Format.LONGINT: 3,
    Format.LONGINT_HIGH: 4,
    Format.FIXED4: 5,
    Format.FIXED8: 6,
    Format.INT32: 7,
    Format.WORD32: 8,
    Format.FIXED16: 9,
    Format.FIXED24: 10,
}

#: raw = value · scale (manual 3.1: Fixed4 unit 1/4096, Fixed8 unit 1/256; Fixed16 unit
#: 1/65536, Fixed24 unit 1/16777216)
FORMAT_SCALE: dict[Format, int] = {Format.FIXED4: 4096, Format.FIXED8: 256,
                                   Format.FIXED16: 2**16, Format.FIXED24: 2**24}

#: formats holding a 32-bit value at a single register number (two 16-bit words on the line)
FORMATS_32_ONE_NUMBER: frozenset[Format] = frozenset(
    {Format.INT32, Format.WORD32, Format.FIXED16, Format.FIXED24})

#: hard raw range of each format (manual 3.1); LongIntHigh is an unsigned 16-bit word
FORMAT_RAW_RANGE: dict[Format, tuple[int, int]] = {
    Format.WORD: (0, 65535),
    Format.INTEGER: (-32767, 32767),
    Format.LONGINT: (-(2**31), 2**31 - 1),
    Format.LONGINT_HIGH: (0, 65535),
    Format.FIXED4: (-32767, 32767),
    Format.FIXED8: (-32767, 32767),
    Format.INT32: (-(2**31), 2**31 - 1),
    Format.WORD32: (0, 2**32 - 1),
    Format.FIXED16: (-(2**31), 2**31 - 1),
    Format.FIXED24: (-(2**31), 2**31 - 1),
}


def is_signed(fmt: object) -> bool:
    """Whether a register of format ``fmt`` holds a signed number (all but Word and Word32)."""
    return fmt not in (Format.WORD32, Format.WORD)


def format_value_range(fmt: Format) -> tuple[float, float]:
    """Exact range of a format in user units: the raw range divided by the scale.

    Parameters
    ----------
    fmt : Format
        A data format.

    Returns
    -------
    (float, float)
        Smallest and largest value, e.g. ``(-32768.0, 32767.9999847412109375)`` for Fixed16 and
        ``(-128.0, 127.999999940395355224609375)`` for Fixed24 (both exact in float64).
    """
    lo, hi = FORMAT_RAW_RANGE[fmt]
    scale = FORMAT_SCALE.get(fmt, 1)
    return lo / scale, hi / scale


_COLUMNS = ("number", "name", "format", "min", "max", "unit", "access", "default", "section",
            "description")
#: optional trailing columns: MacTalk name where it differs from ``name``; "yes"/"no" whether the
#: register is meant for the normal user
_EXTRA_COLUMNS = ("alias", "user")


def _round_half_away(x: float) -> int:
    return int(math.copysign(math.floor(abs(x) + 0.5), x))


class TableError(RegisterError):
    """The register table file is malformed."""


@dataclass(frozen=True)
class Register:
    """One register of the table (manual 3.2.N).

    Attributes
    ----------
    number : int
        Register number N (manual section 3.2.N).
    name : str
        Name as in the manual (``<NAME>_HI`` for a LongInt's high word).
    format : Format
        Data format (manual 3.1).
    minimum, maximum : float
        Range in user units (Fixed formats as real numbers).
    unit : str
        Unit of one user unit, e.g. ``"1/16 count/sample"``; ``""`` if dimensionless.
    access : Access
        ``rw``, ``ro`` or ``reserved``.
    default : float
        ROM default in user units.
    section : str
        Manual section, e.g. ``"3.2.13"``.
    description : str
        One line.
    alias : str
        MacTalk name where it differs from ``name``, else ``""``.
    user : bool
        False for registers the manual marks as not for the normal user (changing them may
        damage the motor), True otherwise.
    """

    number: int
    name: str
    format: Format
    minimum: float
    maximum: float
    unit: str
    access: Access
    default: float
    section: str
    description: str
    alias: str = ""
    user: bool = True

    @cached_property
    def scale(self) -> int:
        """Raw units per user unit: 4096 for Fixed4, 256 for Fixed8, 65536 for Fixed16,
        16777216 for Fixed24, 1 otherwise."""
        return FORMAT_SCALE.get(self.format, 1)

    @cached_property
    def raw_min(self) -> int:
        """Smallest stored integer, ``round(minimum · scale)``."""
        return _round_half_away(self.minimum * self.scale)

    @cached_property
    def raw_max(self) -> int:
        """Largest stored integer, ``round(maximum · scale)``."""
        return _round_half_away(self.maximum * self.scale)

    @property
    def words(self) -> int:
        """Number of 16-bit words the value occupies: 2 for LongInt (two register numbers) and
        for the 32-bit formats at one number (Int32, Word32, Fixed16, Fixed24), 1 otherwise."""
        return 2 if self.format == Format.LONGINT or self.format in FORMATS_32_ONE_NUMBER else 1

    @property
    def numbers(self) -> int:
        """Number of register numbers the register occupies: 2 for LongInt, 1 otherwise."""
        return 2 if self.format == Format.LONGINT else 1

    @property
    def default_raw(self) -> int:
        """The ROM default as a stored integer."""
        return _round_half_away(self.default * self.scale)

    @property
    def fmt_code(self) -> int:
        """Format code of :data:`FORMAT_CODES` (0 for reserved rows)."""
        return 0 if self.access == Access.RESERVED else FORMAT_CODES[self.format]

    @property
    def range_text(self) -> str:
        """The range with its unit, for messages and documentation."""
        unit = f" {self.unit}" if self.unit else ""
        return f"{_num(self.minimum)} … {_num(self.maximum)}{unit}"


def _num(x: float) -> str:
    return str(int(x)) if float(x).is_integer() else f"{x:g}"


class RegisterTable:
    """The register table of one motor family.

    Parameters
    ----------
    registers : iterable of Register
        All rows, one per number 1 … last; validated on construction.
    source : str
        Where the rows came from (for error messages).

    Attributes
    ----------
    registers : tuple of Register
        Rows ordered by number.
    names : tuple of str
        Register names in number order.
    raw_min_array, raw_max_array, default_raw_array : numpy.ndarray
        int64 arrays indexed by register number (index 0 unused = 0; LongIntHigh and reserved
        rows 0). A LongInt's entry is its whole 32-bit value.
    fmt_code_array : numpy.ndarray
        int8 array indexed by register number: 0 reserved, 1 Word, 2 Integer, 3 LongInt,
        4 LongIntHigh, 5 Fixed4, 6 Fixed8, 7 Int32, 8 Word32, 9 Fixed16, 10 Fixed24.
    """

    def __init__(self, registers: tuple[Register, ...] | list[Register], source: str = "<rows>"):
        regs = tuple(sorted(registers, key=lambda r: r.number))
        _validate(regs, source)
        self.source = source
        self.registers: tuple[Register, ...] = regs
        self.names: tuple[str, ...] = tuple(r.name for r in regs)
        self._by_name = {r.name.upper(): r for r in regs}
        self._by_number = {r.number: r for r in regs}
        size = regs[-1].number + 1
        self.raw_min_array = np.zeros(size, dtype=np.int64)
        self.raw_max_array = np.zeros(size, dtype=np.int64)
        self.default_raw_array = np.zeros(size, dtype=np.int64)
        self.fmt_code_array = np.zeros(size, dtype=np.int8)
        for r in regs:
            self.fmt_code_array[r.number] = r.fmt_code
            if r.access == Access.RESERVED or r.format == Format.LONGINT_HIGH:
                continue
            self.raw_min_array[r.number] = r.raw_min
            self.raw_max_array[r.number] = r.raw_max
            self.default_raw_array[r.number] = r.default_raw
        self._freeze()

    def _freeze(self) -> None:
        """Make the per-number arrays read-only."""
        for arr in (self.raw_min_array, self.raw_max_array, self.default_raw_array,
                    self.fmt_code_array):
            arr.flags.writeable = False

    def __setstate__(self, state: dict) -> None:
        """Unpickle (a pickled motor array or env carries its table): the arrays read-only
        again, since pickle restores them writable and numba types a read-only array apart,
        so every compiled step that reads one would compile a second time."""
        self.__dict__.update(state)
        self._freeze()

    @property
    def last(self) -> int:
        """Highest register number."""
        return self.registers[-1].number

    def numbers_by_name(self) -> dict[str, int]:
        """Register number by name, for every register: the compile-time constants of a
        family's firmware (its ``firmware/regs.py`` defines one module constant per register,
        so that each number stays stated once, in the table)."""
        return {r.name: r.number for r in self.registers}

    def data_write_limits(self, *excluded: int) -> tuple[np.ndarray, np.ndarray]:
        """Raw ``(low, high)`` of every read-write register by number, both 0 for the others
        and for the ``excluded`` numbers (a mode request, a command): what a compiled task may
        store directly, saturated to the register's range. Shape (last + 1,) int64 each."""
        low = np.zeros(self.last + 1, dtype=np.int64)
        high = np.zeros(self.last + 1, dtype=np.int64)
        for r in self.registers:
            if r.access == Access.RW and r.number not in excluded:
                low[r.number], high[r.number] = r.raw_min, r.raw_max
        return low, high

    def lookup(self, key: str | int) -> Register:
        """Return a register by name (case-insensitive) or number.

        Parameters
        ----------
        key : str or int
            Register name (``"v_soll"``, ``"V_SOLL"``) or number (``5``).

        Returns
        -------
        Register

        Raises
        ------
        UnknownRegisterError
            If no register has that name or number; the message lists up to three close names.
        """
        if isinstance(key, (bool, np.bool_)):
            raise UnknownRegisterError(f"register key must be a name or number, got {echo(key)}")
        if isinstance(key, (int, np.integer)):
            reg = self._by_number.get(int(key))
            if reg is None:
                raise UnknownRegisterError(
                    f"no register number {int(key)} (valid: 1 … {self.last})")
            return reg
        if isinstance(key, str):
            reg = self._by_name.get(key.strip().upper())
            if reg is None:
                close = difflib.get_close_matches(key.strip().upper(), list(self._by_name), n=3,
                                                  cutoff=0.5)
                hint = f"; did you mean {', '.join(close)}?" if close else ""
                raise UnknownRegisterError(f"no register named {echo(key)}{hint}")
            return reg
        raise UnknownRegisterError(f"register key must be a name or number, got {echo(key)}")

    def __iter__(self) -> Iterator[Register]:
        return iter(self.registers)

    @property
    def wide_registers(self) -> bool:
        """Whether every register is 32 bits wide at one number (the MAC800 and MIS tables),
        as against 16-bit registers with LongInts at two numbers (MAC050–141 manual 3.1)."""
        return all(reg.format in FORMATS_32_ONE_NUMBER for reg in self.registers)

    def __len__(self) -> int:
        return len(self.registers)

    def __contains__(self, key: object) -> bool:
        if isinstance(key, Register):
            return self._by_number.get(key.number) == key
        if isinstance(key, (bool, np.bool_)):
            return False
        if isinstance(key, (int, np.integer)):
            return int(key) in self._by_number
        if isinstance(key, str):
            return key.strip().upper() in self._by_name
        return False

    def __repr__(self) -> str:
        return f"RegisterTable({len(self)} registers from {self.source})"


def _validate(regs: tuple[Register, ...], source: str) -> None:
    """Check the table invariants, raising :class:`TableError` on the first violation."""
    if not regs:
        raise TableError(f"{source}: empty register table")
    numbers = [r.number for r in regs]
    dup = sorted({n for n in numbers if numbers.count(n) > 1})
    if dup:
        raise TableError(f"{source}: duplicate register numbers {dup}")
    missing = sorted(set(range(1, numbers[-1] + 1)) - set(numbers))
    if missing or numbers[0] != 1:
        raise TableError(f"{source}: register numbers missing: {missing or [1]}")
    seen: dict[str, int] = {}
    for r in regs:
        key = r.name.upper()
        if not r.name or key in seen:
            raise TableError(f"{source}: register {r.number}: name {echo(r.name)} is empty or "
                             f"already used by register {seen.get(key)}")
        seen[key] = r.number
    for i, r in enumerate(regs):
        where = f"{source}: register {r.number} {r.name}"
        if r.access == Access.RESERVED:
            if r.name.upper() != f"RESERVED_{r.number}":
                raise TableError(f"{where}: reserved rows must be named RESERVED_{r.number}")
            continue
        if r.name.upper().startswith("RESERVED_"):
            raise TableError(f"{where}: a RESERVED_ row must have access 'reserved'")
        for label, v in (("min", r.minimum), ("max", r.maximum), ("default", r.default)):
            if not math.isfinite(v):
                raise TableError(f"{where}: {label} is not a finite number")
        if r.minimum > r.maximum:
            raise TableError(f"{where}: min {r.minimum} > max {r.maximum}")
        lo, hi = FORMAT_RAW_RANGE[r.format]
        if r.raw_min < lo or r.raw_max > hi:
            raise TableError(f"{where}: range {r.range_text} exceeds the {r.format.value} "
                             f"format (raw {lo} … {hi}, manual 3.1)")
        if r.scale == 1 and not (float(r.minimum).is_integer() and float(r.maximum).is_integer()
                                 and float(r.default).is_integer()):
            raise TableError(f"{where}: {r.format.value} min/max/default must be integers")
        if not (r.minimum <= r.default <= r.maximum):
            raise TableError(f"{where}: default {r.default} outside {r.range_text}")
        if r.format == Format.LONGINT:
            nxt = regs[i + 1] if i + 1 < len(regs) else None
            if (nxt is None or nxt.format != Format.LONGINT_HIGH
                    or nxt.name.upper() != f"{r.name.upper()}_HI" or nxt.access != r.access):
                raise TableError(f"{where}: a LongInt must be followed by its LongIntHigh row "
                                 f"{r.name}_HI (register {r.number + 1}) with the same access")
            if nxt.default != (r.default_raw >> 16) & 0xFFFF:
                raise TableError(f"{where}: default of {nxt.name} must be the high word of the "
                                 f"default ({(r.default_raw >> 16) & 0xFFFF})")
        if r.format == Format.LONGINT_HIGH:
            prev = regs[i - 1] if i > 0 else None
            if prev is None or prev.format != Format.LONGINT:
                raise TableError(f"{where}: a LongIntHigh row must follow its LongInt row")


def _parse_rows(text: str, source: str) -> list[Register]:
    reader = csv.DictReader(io.StringIO(text))
    if tuple(reader.fieldnames or ()) not in (_COLUMNS, _COLUMNS + _EXTRA_COLUMNS):
        raise TableError(f"{source}: columns must be {','.join(_COLUMNS)} "
                         f"[,{','.join(_EXTRA_COLUMNS)}], got {','.join(reader.fieldnames or ())}")
    rows: list[Register] = []
    for line, row in enumerate(reader, start=2):
        try:
            fmt = Format(row["format"].strip())
        except ValueError:
            raise TableError(f"{source} line {line}: unknown format {echo(row['format'])} "
                             f"(known: {', '.join(f.value for f in Format)})") from None
        try:
            access = Access(row["access"].strip())
        except ValueError:
            raise TableError(f"{source} line {line}: unknown access {echo(row['access'])} "
                             f"(known: {', '.join(a.value for a in Access)})") from None
        try:
            number = int(row["number"])
            vals = [float(row[k]) if row[k].strip() else 0.0 for k in ("min", "max", "default")]
        except ValueError as exc:
            raise TableError(f"{source} line {line}: {exc}") from None
        user_text = (row.get("user") or "yes").strip().lower()
        if user_text not in ("yes", "no"):
            raise TableError(f"{source} line {line}: column user must be 'yes' or 'no', "
                             f"got {echo(row.get('user'))}")
        rows.append(Register(
            number=number, name=row["name"].strip(), format=fmt, minimum=vals[0],
            maximum=vals[1], unit=row["unit"].strip(), access=access, default=vals[2],
            section=row["section"].strip(), description=row["description"].strip(),
            alias=(row.get("alias") or "").strip(), user=user_text == "yes"))
    return rows


def load_table(path: str | PathLike[str], source: str | None = None) -> RegisterTable:
    """Load and validate a register table CSV.

    Parameters
    ----------
    path : str or os.PathLike
        CSV with columns ``number,name,format,min,max,unit,access,default,section,description``
        and optionally ``alias,user``.
    source : str, optional
        How errors and the reference page name the table (default: ``path``).

    Returns
    -------
    RegisterTable

    Raises
    ------
    TableError
        If a row is malformed or a table invariant is violated (unique names and numbers,
        every number 1 … last present, each LongInt followed by its ``_HI`` row, defaults within
        range, known formats).
    """
    p = Path(path)
    name = source if source is not None else str(p)
    return RegisterTable(_parse_rows(p.read_text(encoding="utf-8"), name), source=name)


def load_packaged_table(package: str, filename: str = "registers.csv") -> RegisterTable:
    """Load and validate a register table shipped inside a package.

    Parameters
    ----------
    package : str
        Dotted name of the package holding the CSV, e.g. ``"jvl_gym.families.mac800"``.
    filename : str
        CSV file name inside that package.

    Returns
    -------
    RegisterTable
        Its ``source`` is ``"<package>/<filename>"`` with the package's dots as slashes.

    Raises
    ------
    TableError
        As :func:`load_table`.
    """
    text = resources.files(package).joinpath(filename).read_text(encoding="utf-8")
    source = f"{package.replace('.', '/')}/{filename}"
    return RegisterTable(_parse_rows(text, source), source=source)
