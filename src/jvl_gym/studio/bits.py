"""Bit registers in words: the bit names come from the register table's descriptions.

A register whose description starts with a title containing "bits" followed by a colon and a
list of ``<bit> <name>`` items (``"Status/error bits: 0 I2T 1 FLW 2 FNC …"``, MAC050–141
manual 3.2.35; ``"Error bits: 0 general 1 follow error …"``, MIS manual §8.2.31) is a bit
register; ``<first>-<last> <name>`` names a field of several bits. The Motors view shows the
error, warning and status registers among them (title naming "error", "warn" or "status").
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from ..registers import Access, Register, RegisterTable

__all__ = ["BitField", "bit_fields", "status_registers", "words", "bit_of"]

_HEAD = re.compile(r"^\s*(?P<title>[^:;]*\bbits\b[^:;]*):\s*(?P<list>.*)$", re.IGNORECASE)
_ITEM = re.compile(r"(?:^|\s)(?P<lo>\d{1,2})(?:-(?P<hi>\d{1,2}))?\s+(?P<name>.+?)"
                   r"(?=\s+\d{1,2}(?:-\d{1,2})?\s+\S|$)")
_KINDS = ("error", "warn", "status")


@dataclass(frozen=True)
class BitField:
    """One named bit, or field of bits, of a register.

    Attributes
    ----------
    first, last : int
        Lowest and highest bit number (equal for a single bit).
    name : str
        The name the table gives it.
    """

    first: int
    last: int
    name: str

    @property
    def mask(self) -> int:
        """The field's bits as an integer mask."""
        return ((1 << (self.last - self.first + 1)) - 1) << self.first


def bit_fields(reg: Register) -> list[BitField]:
    """The named bits of ``reg`` from its description (empty if it is no bit register)."""
    m = _HEAD.match(reg.description)
    if m is None:
        return []
    text = m["list"].split(";")[0]
    out = []
    for item in _ITEM.finditer(text):
        lo = int(item["lo"])
        hi = int(item["hi"]) if item["hi"] else lo
        if lo <= hi < 64:
            out.append(BitField(lo, hi, item["name"].strip().rstrip(",.")))
    return out


def status_registers(table: RegisterTable) -> list[Register]:
    """The error, warning and status bit registers of ``table``, in register order."""
    out = []
    for reg in table:
        if reg.access == Access.RESERVED:
            continue
        m = _HEAD.match(reg.description)
        if m and any(k in m["title"].lower() for k in _KINDS) and bit_fields(reg):
            out.append(reg)
    return out


def words(reg: Register, raw: int) -> list[str]:
    """The names of the bits (fields) of ``reg`` set in ``raw``; a set bit the table does not
    name is ``"bit <n>"``."""
    raw = int(raw) & 0xFFFFFFFF
    named = 0
    out = []
    for f in bit_fields(reg):
        named |= f.mask
        if raw & f.mask:
            out.append(f.name)
    rest = raw & ~named
    out.extend(f"bit {k}" for k in range(32) if rest >> k & 1)
    return out


def bit_of(reg: Register, prefix: str) -> int | None:
    """The number of the single bit of ``reg`` whose name is ``prefix`` or ``prefix``
    followed by ``"BIT"`` (case-insensitive); None if there is none."""
    want = {prefix.upper(), prefix.upper() + "BIT"}
    for f in bit_fields(reg):
        if f.first == f.last and f.name.split()[0].upper() in want:
            return f.first
    return None
