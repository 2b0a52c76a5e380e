"""The register groups of the manuals.

MAC050–141 manual 3.2 categorises the registers by number range (Main Control 1–15, Error
handling 16–35, …); a family whose public ``constants`` module names such ranges in
``REGISTER_GROUPS`` (title, first, last) is grouped by them. Otherwise the section column of the
register table names the group: the MAC800 register overview (§1.2) gives each row its group
("1.2 Main Control"), which is taken as it is; the MIS manual lists its registers in one
overview (§8.2.1) and describes each in its own section §8.2.N, so the MIS registers form one
group per section prefix ("8.2") plus the few rows documented elsewhere (§12.1 Modbus).
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from typing import Any

from ..registers import Access, Format, Register, RegisterTable

__all__ = ["register_groups", "visible", "family_ranges"]

_SECTION = re.compile(r"^\s*(?P<number>\d+(?:\.\d+)*)\s*(?P<title>.*)$")


def visible(reg: Register) -> bool:
    """Whether the register view lists ``reg``: every documented register; the high word of a
    LongInt is shown with its low word."""
    return reg.access != Access.RESERVED and reg.format != Format.LONGINT_HIGH


def _section_group(reg: Register) -> str:
    m = _SECTION.match(reg.section)
    if m is None:
        return reg.section or "Registers"
    title = m["title"].strip().strip('"').strip()
    if title:
        return f"{m['number']} {title}"
    parts = m["number"].split(".")
    return f"§{'.'.join(parts[:-1]) if len(parts) > 2 else m['number']}"


def register_groups(table: RegisterTable, ranges: Sequence[tuple[str, int, int]] | None = None
                    ) -> list[tuple[str, list[Register]]]:
    """The registers of ``table`` shown by the register view, grouped.

    Parameters
    ----------
    table : RegisterTable
        The family's register table.
    ranges : sequence of (title, first, last), optional
        The manual's groups by register number (``constants.REGISTER_GROUPS``); without them
        the section column names the groups.

    Returns
    -------
    list of (str, list of Register)
        Group title and its registers, in the order of their first register.
    """
    groups: dict[str, list[Register]] = {}
    for reg in table:
        if not visible(reg):
            continue
        title = None
        for name, first, last in ranges or ():
            if first <= reg.number <= last:
                title = name
                break
        groups.setdefault(title or _section_group(reg), []).append(reg)
    return list(groups.items())


def family_ranges(constants: Any) -> list[tuple[str, int, int]] | None:
    """``REGISTER_GROUPS`` of a family's ``constants`` module, or None."""
    ranges = getattr(constants, "REGISTER_GROUPS", None)
    return [(str(t), int(a), int(b)) for t, a, b in ranges] if ranges else None

