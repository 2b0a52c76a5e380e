"""Field types of the program commands: how one dialogue field is written, read and stored.

Each field of a §9.7 dialogue (MIS manual) is one ``key=value`` of a program line. A field type
parses the value's text (raising :class:`FieldError` with what is wrong), prints it back in its
canonical form, and packs it into the program's flash bytes (:mod:`.binary`).

Values: whole numbers for counts, milliseconds and RPM/s; velocities in RPM with up to two
decimals (the 0.01 RPM of V_SOLL, §8.2.5); ``register1`` … ``register3`` for the three position
registers of the user memory (P1, P2, P3: the §9.7.27 dialogue names register 51 "Position Reg
2"); registers by name or number (§9.7.26: "Simple list with short firmware names" or a number).
"""

from __future__ import annotations

import re
import struct
from abc import ABC, abstractmethod
from dataclasses import dataclass

from ....registers.errors import echo
from ..table import TABLE
from ..units import COUNTS_PER_REV

__all__ = ["FieldError", "Field", "Int", "Choice", "Velocity", "Source", "RegisterField",
           "Value", "Pattern", "Text", "Hex", "Expression", "POSITION_REGISTERS", "INPUT_NAMES",
           "OPERATORS"]

#: the user memory's position registers 1–3 of the move, save and set position dialogues
POSITION_REGISTERS = ("P1", "P2", "P3")
#: the inputs a condition may test (§9.7.11: inputs 1–8, Motor Error, In Position)
INPUT_NAMES = ("1", "2", "3", "4", "5", "6", "7", "8", "error", "in_position")
#: comparison operators of §9.7.17, §9.7.18, §9.7.27
OPERATORS = ("=", "!=", "<", ">", "<=", ">=")

_INT = re.compile(r"[+-]?[0-9]+\Z")
_DECIMAL = re.compile(r"[+-]?[0-9]+(\.[0-9]{1,2})?\Z")
_I32 = (-(2**31), 2**31 - 1)


class FieldError(ValueError):
    """A field value is malformed or out of range (the message says which and why)."""


def _int(text: str, lo: int, hi: int) -> int:
    if len(text) > 24 or not _INT.match(text):
        raise FieldError(f"{echo(text)} is not a whole number")
    v = int(text)
    if not lo <= v <= hi:
        raise FieldError(f"{v} is outside {lo} … {hi}")
    return v


@dataclass(frozen=True)
class Field(ABC):
    """A field type: ``parse`` text → value, ``show`` value → text, ``pack`` and ``unpack``
    for the flash bytes (each field type defines all but ``show``)."""

    @abstractmethod
    def parse(self, text: str) -> object:
        """The value of the field's text; :class:`FieldError` if malformed or out of range."""

    def show(self, value: object) -> str:
        return str(value)

    @abstractmethod
    def pack(self, value: object) -> bytes:
        """The value's bytes in the program's flash image."""

    @abstractmethod
    def unpack(self, data: bytes, k: int) -> tuple[object, int]:
        """The value stored at byte ``k`` of ``data`` and the index after it."""


@dataclass(frozen=True)
class Int(Field):
    """A whole number in ``lo … hi`` (counts, ms, RPM/s, a line number), stored as int32."""

    lo: int = _I32[0]
    hi: int = _I32[1]

    def parse(self, text: str) -> int:
        return _int(text, self.lo, self.hi)

    def pack(self, value: object) -> bytes:
        return struct.pack("<i", value)

    def unpack(self, data: bytes, k: int) -> tuple[int, int]:
        v = struct.unpack_from("<i", data, k)[0]
        if not self.lo <= v <= self.hi:
            raise FieldError(f"{v} is outside {self.lo} … {self.hi}")
        return v, k + 4


@dataclass(frozen=True)
class Choice(Field):
    """One of a few words (a dialogue's radio buttons), stored as its index."""

    options: tuple[str, ...] = ()

    def parse(self, text: str) -> str:
        if text not in self.options:
            raise FieldError(f"{echo(text)} is not one of {', '.join(self.options)}")
        return text

    def pack(self, value: object) -> bytes:
        return bytes([self.options.index(str(value))])

    def unpack(self, data: bytes, k: int) -> tuple[str, int]:
        if data[k] >= len(self.options):
            raise FieldError(f"choice code {data[k]} is not defined")
        return self.options[data[k]], k + 1


@dataclass(frozen=True)
class Velocity(Field):
    """A velocity in RPM with up to two decimals (0 … 3000 RPM; 0: keep V_SOLL, §9.7.4),
    held as V_SOLL units of 0.01 RPM."""

    def parse(self, text: str) -> int:
        if len(text) > 24 or not _DECIMAL.match(text):
            raise FieldError(f"{echo(text)} is not a velocity in RPM (at most two decimals)")
        whole, _, frac = text.lstrip("+-").partition(".")
        units = int(whole) * 100 + int((frac + "00")[:2])
        if text.startswith("-") or units > 300000:
            raise FieldError(f"{text} RPM is outside 0 … 3000 RPM")
        return units

    def show(self, value: object) -> str:
        v = int(value)  # type: ignore[call-overload]
        return f"{v // 100}" if v % 100 == 0 else f"{v // 100}.{v % 100:02d}".rstrip("0")

    def pack(self, value: object) -> bytes:
        return struct.pack("<i", value)

    def unpack(self, data: bytes, k: int) -> tuple[int, int]:
        v = struct.unpack_from("<i", data, k)[0]
        if not 0 <= v <= 300000:
            raise FieldError(f"velocity {v} is outside 0 … 300000 (0.01 RPM)")
        return v, k + 4


@dataclass(frozen=True)
class Source(Field):
    """Counts entered directly or ``register1`` … ``register3`` (P1, P2, P3): an int, or the
    string ``"registerK"``."""

    lo: int = _I32[0]

    def parse(self, text: str) -> int | str:
        if text in ("register1", "register2", "register3"):
            return text
        if text.startswith("register"):
            raise FieldError(f"{echo(text)}: the user memory has register1, register2, register3")
        return _int(text, self.lo, _I32[1])

    def pack(self, value: object) -> bytes:
        if isinstance(value, str):
            return struct.pack("<Bi", int(value[-1]), 0)
        return struct.pack("<Bi", 0, value)

    def unpack(self, data: bytes, k: int) -> tuple[int | str, int]:
        which, v = struct.unpack_from("<Bi", data, k)
        if which > 3 or (which and v) or v < self.lo:
            raise FieldError(f"bad position source {which}/{v}")
        return (f"register{which}" if which else v), k + 5


@dataclass(frozen=True)
class RegisterField(Field):
    """A register by name or number, printed by name; ``writable``: only read-write ones
    (§9.7.16: "user-accessible registers"). Held as its number."""

    writable: bool = False

    def parse(self, text: str) -> int:
        try:
            reg = TABLE.lookup(int(text) if _INT.match(text) else text)
        except (KeyError, ValueError, LookupError) as exc:
            raise FieldError(f"{echo(text)} is not an MIS register (§8.2)") from exc
        if reg.access.value == "reserved":
            raise FieldError(f"register {reg.number} is reserved")
        if self.writable and reg.access.value != "rw":
            raise FieldError(f"{reg.name} (register {reg.number}) is read-only")
        return reg.number

    def show(self, value: object) -> str:
        return TABLE.lookup(int(value)).name  # type: ignore[call-overload]

    def pack(self, value: object) -> bytes:
        return struct.pack("<H", value)

    def unpack(self, data: bytes, k: int) -> tuple[int, int]:
        num = struct.unpack_from("<H", data, k)[0]
        return self.parse(str(num)), k + 2


@dataclass(frozen=True)
class Value(Field):
    """A register value: native units (a whole number) or, for a register in counts, ``rev``
    (``1.5rev`` = 614400 counts) and, for one in 0.01 RPM, ``rpm`` (§9.7.16: "native motor
    units or generic engineering units"). Held as the native int32."""

    def parse(self, text: str) -> int:
        for suffix, per in (("rev", COUNTS_PER_REV), ("rpm", 100)):
            if text.endswith(suffix):
                num = text[: -len(suffix)]
                try:
                    x = float(num)
                except ValueError:
                    raise FieldError(f"{echo(text)} is not a number of {suffix}") from None
                if len(num) > 24 or not re.fullmatch(r"[+-]?[0-9]+(\.[0-9]+)?", num):
                    raise FieldError(f"{echo(text)} is not a number of {suffix}")
                v = round(x * per)
                if not _I32[0] <= v <= _I32[1]:
                    raise FieldError(f"{text} is outside 32 bits")
                return v
        return _int(text, *_I32)

    def pack(self, value: object) -> bytes:
        return struct.pack("<i", value)

    def unpack(self, data: bytes, k: int) -> tuple[int, int]:
        return struct.unpack_from("<i", data, k)[0], k + 4


@dataclass(frozen=True)
class Pattern(Field):
    """Levels of several inputs or outputs: ``1:high,3:low`` (others "Don't care",
    §9.7.9, §9.7.12). Held as a tuple of (name, level) in the order of ``names``."""

    names: tuple[str, ...] = INPUT_NAMES

    def parse(self, text: str) -> tuple[tuple[str, str], ...]:
        got: dict[str, str] = {}
        for item in text.split(","):
            name, sep, level = item.partition(":")
            if not sep or name not in self.names or level not in ("high", "low"):
                raise FieldError(f"{echo(item)} is not NAME:high or NAME:low with NAME in "
                                 f"{', '.join(self.names)}")
            if name in got:
                raise FieldError(f"{name} is given twice")
            got[name] = level
        return tuple((n, got[n]) for n in self.names if n in got)

    def show(self, value: object) -> str:
        return ",".join(f"{n}:{lv}" for n, lv in value)  # type: ignore[attr-defined]

    def pack(self, value: object) -> bytes:
        high = low = 0
        for n, lv in value:  # type: ignore[attr-defined]
            bit = 1 << self.names.index(n)
            if lv == "high":
                high |= bit
            else:
                low |= bit
        return struct.pack("<HH", high, low)

    def unpack(self, data: bytes, k: int) -> tuple[tuple[tuple[str, str], ...], int]:
        high, low = struct.unpack_from("<HH", data, k)
        if high & low or (high | low) >> len(self.names) or not high | low:
            raise FieldError("bad level pattern")
        out = tuple((n, "high" if high >> j & 1 else "low")
                    for j, n in enumerate(self.names) if (high | low) >> j & 1)
        return out, k + 4


@dataclass(frozen=True)
class Text(Field):
    """Free text (a remark), up to 255 bytes of UTF-8 without line breaks."""

    def parse(self, text: str) -> str:
        if "\n" in text or "\r" in text or len(text.encode()) > 255:
            raise FieldError("a remark is one line of at most 255 bytes")
        return text

    def show(self, value: object) -> str:
        return str(value)

    def pack(self, value: object) -> bytes:
        b = str(value).encode()
        return bytes([len(b)]) + b

    def unpack(self, data: bytes, k: int) -> tuple[str, int]:
        n = data[k]
        return self.parse(bytes(data[k + 1:k + 1 + n]).decode()), k + 1 + n


_FIRST = re.compile(r"\s*()([A-Za-z_][A-Za-z0-9_]*|[+-]?[0-9]+)")
@dataclass(frozen=True)
class Hex(Field):
    """Bytes written as hexadecimal digits (``0a1b…``), 1 … 64 bytes."""

    def parse(self, text: str) -> str:
        if not re.fullmatch(r"([0-9a-fA-F]{2}){1,64}", text):
            raise FieldError(f"{echo(text)} is not 1 … 64 bytes of hexadecimal digits")
        return text.lower()

    def pack(self, value: object) -> bytes:
        b = bytes.fromhex(str(value))
        return bytes([len(b)]) + b

    def unpack(self, data: bytes, k: int) -> tuple[str, int]:
        n = data[k]
        return self.parse(bytes(data[k + 1:k + 1 + n]).hex()), k + 1 + n


_TERM = re.compile(r"\s*([+\-*/])?\s*([A-Za-z_][A-Za-z0-9_]*|[+-]?[0-9]+)")


@dataclass(frozen=True)
class Expression(Field):
    """A calculator expression (§9.7.25): operands joined by ``+ - * /``, evaluated left to
    right. An operand is a register by its short firmware name or an integer constant (§9.7.26:
    "If you wish to enter a constant, you simply enter the digits"). Held as a tuple of
    (operator, kind, value): operator ``""`` for the first term, kind ``"reg"`` (value: the
    register number) or ``"const"``."""

    def parse(self, text: str) -> tuple[tuple[str, str, int], ...]:
        terms: list[tuple[str, str, int]] = []
        k = 0
        s = text.strip()
        while k < len(s):
            m = (_TERM if terms else _FIRST).match(s, k)
            if m is None or (terms and m.group(1) is None):
                raise FieldError(f"expression {echo(text)}: expected "
                                 f"{'an operator and ' if terms else ''}an operand at "
                                 f"character {k + 1}")
            op, arg = m.group(1) or "", m.group(2)
            if _INT.match(arg):
                terms.append((op, "const", _int(arg, *_I32)))
            else:
                terms.append((op, "reg", RegisterField().parse(arg)))
            k = m.end()
            while k < len(s) and s[k] == " ":
                k += 1
        if not terms:
            raise FieldError("the expression is empty")
        if len(terms) > 16:
            raise FieldError("at most 16 operands")
        return tuple(terms)

    def show(self, value: object) -> str:
        out = []
        for op, kind, v in value:  # type: ignore[attr-defined]
            arg = TABLE.lookup(v).name if kind == "reg" else str(v)
            out.append(f"{op}{arg}")
        return "".join(out)

    def pack(self, value: object) -> bytes:
        out = bytes([len(value)])  # type: ignore[arg-type]
        for op, kind, v in value:  # type: ignore[attr-defined]
            out += struct.pack("<BBi", "_+-*/".index(op or "_"), kind == "reg", v)
        return out

    def unpack(self, data: bytes, k: int) -> tuple[tuple[tuple[str, str, int], ...], int]:
        n = data[k]
        k += 1
        terms = []
        for j in range(n):
            op, is_reg, v = struct.unpack_from("<BBi", data, k)
            k += 6
            if op > 4 or (op == 0) != (j == 0) or is_reg > 1:
                raise FieldError("bad expression term")
            terms.append(("_+-*/"[op].strip("_"), "reg" if is_reg else "const",
                          RegisterField().parse(str(v)) if is_reg else v))
        if not terms:
            raise FieldError("the expression is empty")
        return tuple(terms), k
