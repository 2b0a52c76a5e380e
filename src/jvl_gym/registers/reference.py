"""Markdown register references of register tables (``docs/registers.md``, ``docs/families``).

The pages are written by the families' generators: ``python -m
jvl_gym.families.mac050_141.reference`` and ``python -m jvl_gym.families.reference``.
"""

from __future__ import annotations

from collections.abc import Callable

from .conformance import REGISTER_STATUSES, STATUSES, Conformance
from .statements import STATUSES as STATEMENT_STATUSES
from .statements import Statements
from .table import FORMAT_SCALE, Access, Format, RegisterTable

__all__ = ["markdown_reference", "markdown_reference_32"]


def _fmt_value(x: float, fmt: Format) -> str:
    if fmt in FORMAT_SCALE:
        return f"{x:g}"
    return str(int(x))


def _fmt_value_32(x: float, fmt: Format) -> str:
    if fmt in FORMAT_SCALE:
        return f"{x:.12g}"  # Fixed16/Fixed24 ends: 32767.9999847, 127.99999994
    return str(int(x))


def _cell(text: str) -> str:
    return text.replace("|", "\\|")


#: the command that writes the MAC050–141 reference
MAC_GENERATOR = "python -m jvl_gym.families.mac050_141.reference"


def _conformance_lines(conformance: Conformance | None) -> list[str]:
    """The paragraph on the conformance column, with the counts per status."""
    if conformance is None:
        return []
    counts = conformance.counts()
    bits = conformance.bit_counts()
    return [
        f"Conformance (`{conformance.source}`): whether the simulator models the register "
        "(the tests that exercise it are named there), models it but for statements the "
        "statements file names (partly), only stores it (kept and read back, no effect), or "
        "does not model it; a write of a value other than the default to a register or bit "
        "it does not model warns (`NotModelledWarning`). Registers: "
        + ", ".join(f"{counts[s]} {s}" for s in REGISTER_STATUSES)
        + "; documented bits and values: "
        + ", ".join(f"{bits[s]} {s}" for s in STATUSES) + ".",
        ""]


def _given(statements: Statements | None) -> Statements | None:
    """``statements`` when the family has a statements file, None otherwise."""
    return statements if statements is not None and statements.present else None


def _statement_counts(statements: Statements | None) -> list[str]:
    """The paragraph and table of the statement counts: per status, per chapter and derived
    per register."""
    if statements is None:
        return []
    head = " | ".join(STATEMENT_STATUSES)
    lines = [
        f"Statements (`{statements.source}`, from the {statements.manual}): each normative "
        "statement of the manual, with whether the simulator does it (*modelled*: the named "
        "tests assert it; *decision*: the manual reads two ways, the family's doc gives the "
        "choice and the tests assert it), only stores the register, or does not do it, and "
        "why. Every statement is listed under [Statements](#statements). Per chapter:",
        "",
        f"| chapter | {head} | all |",
        "|---|" + "---:|" * (len(STATEMENT_STATUSES) + 1)]
    for chapter, counts in (*statements.chapter_counts().items(), ("all", statements.counts())):
        name = "all" if chapter == "all" else f"§{chapter}"
        lines.append(f"| {name} | " + " | ".join(str(counts[k]) for k in STATEMENT_STATUSES)
                     + f" | {sum(counts.values())} |")
    derived = statements.derived_counts()
    lines += [
        "",
        "The *statements* column derives a register's status from its statements: modelled "
        "when each is modelled or a decision, partly modelled when some are modelled and "
        "some not, not modelled when one is not modelled and none is, stored only "
        "otherwise. Registers: " + ", ".join(f"{n} {k}" for k, n in derived.items())
        + f", {len(statements.uncovered())} without a statement.",
        ""]
    return lines


def _statement_cell(statements: Statements, name: str) -> str:
    status = statements.derived_status(name)
    return "" if status is None else f"{status} ({len(statements.of_register(name))})"


def _statement_list(statements: Statements | None) -> list[str]:
    """The section listing every statement, by register in the table's order, then the
    chapters' statements."""
    if statements is None:
        return []
    lines = ["", "## Statements", "",
             "| register | id | section | says | status | tests |",
             "|---|---|---|---|---|---|"]
    groups = [(r.name, statements.of_register(r.name)) for r in statements.table]
    for name, group in (*groups, ("(chapter)", statements.chapter_statements())):
        for s in group:
            status = s.status + (f": {s.why}" if s.why else "") + (
                f" (`{s.decision}`)" if s.decision else "")
            tests = ", ".join(f"`{t}`" for t in s.tests)
            lines.append(f"| {name} | {s.id} | {s.section} | {_cell(s.says)} | "
                         f"{_cell(status)} | {_cell(tests)} |")
    return lines


def markdown_reference(table: RegisterTable, title: str = "MAC50/95/140/141",
                       usage: Callable[[str], list[str]] | None = None,
                       generator: str = MAC_GENERATOR,
                       conformance: Conformance | None = None,
                       statements: Statements | None = None) -> str:
    """Render a register table as a Markdown document.

    Parameters
    ----------
    table : RegisterTable
        The table to document.
    title : str
        Motor family shown in the heading.
    usage : callable, optional
        ``usage(name) -> [mode names]``: adds a column with the modes that read the register.
    generator : str
        The command that writes the page (named in its header).
    conformance : Conformance, optional
        The family's conformance matrix: adds a column with each register's status.
    statements : Statements, optional
        The family's statements: when it has a statements file, adds their counts, a column
        with each register's status derived from them and the list of every statement.

    Returns
    -------
    str
        Markdown with one table row per register number: number, name, format, range, unit,
        access, default, section, description (and the optional columns).
    """
    statements = _given(statements)
    lines = [
        f"# Register reference: {title}",
        "",
        f"Generated from `{table.source}` by `{generator}`; "
        "do not edit by hand.",
        "",
        "Values are in user units (Fixed4/Fixed8 as real numbers; raw = value·4096 / value·256, "
        "manual 3.1). A LongInt register N holds the low word and N+1 (`<NAME>_HI`) the high "
        "word. Access: `rw` user-writable, `ro` computed by the firmware (writes are refused), "
        "`reserved` undocumented.",
        "",
        *_conformance_lines(conformance),
        *_statement_counts(statements),
        "| no. | name | format | range | unit | access | default | section | description |"
        + (" modes |" if usage else "") + (" conformance |" if conformance else "")
        + (" statements |" if statements else ""),
        "|---:|---|---|---|---|---|---:|---|---|" + ("---|" if usage else "")
        + ("---|" if conformance else "") + ("---|" if statements else ""),
    ]
    for r in table:
        if r.access == Access.RESERVED:
            rng = default = ""
        else:
            rng = f"{_fmt_value(r.minimum, r.format)} … {_fmt_value(r.maximum, r.format)}"
            default = _fmt_value(r.default, r.format)
        lines.append(
            f"| {r.number} | {r.name} | {r.format.value} | {rng} | {_cell(r.unit)} | "
            f"{r.access.value} | {default} | {r.section} | {_cell(r.description)} |"
            + (f" {', '.join(usage(r.name))} |" if usage else "")
            + (f" {_cell(conformance.cell(r))} |" if conformance else "")
            + (f" {_statement_cell(statements, r.name)} |" if statements else ""))
    lines += _statement_list(statements)
    return "\n".join(lines) + "\n"


def markdown_reference_32(table: RegisterTable, title: str, source_note: str,
                          generator: str, conformance: Conformance | None = None,
                          statements: Statements | None = None) -> str:
    """Render a table of 32-bit registers (one register number each) as a Markdown document.

    Parameters
    ----------
    table : RegisterTable
        The table to document.
    title : str
        Motor family shown in the heading.
    source_note : str
        One paragraph naming the source document and where its decisions are recorded.
    generator : str
        The command that writes the document (named in its header).
    conformance : Conformance, optional
        The family's conformance matrix: adds a column with each register's status.
    statements : Statements, optional
        The family's statements: when it has a statements file, adds their counts, a column
        with each register's status derived from them and the list of every statement.

    Returns
    -------
    str
        Markdown with one table row per register number: number, name, MacTalk name, format,
        range, unit, access, default, whether the register is for the normal user, section and
        description.
    """
    statements = _given(statements)
    lines = [
        f"# Register reference: {title}",
        "",
        f"Generated from `{table.source}` by `{generator}`; do not edit by hand.",
        "",
        source_note,
        "",
        "Every register is 32 bits wide at one register number: `Int32` signed, `Word32` "
        "unsigned, `Fixed16` and `Fixed24` signed fixed point with unit 1/65536 and 1/16777216 "
        "(values here as real numbers). Access: `rw` user-writable, `ro` computed by the "
        "firmware (writes are refused), `reserved` undocumented. *user* `no` marks registers "
        "not meant for the normal user.",
        "",
        *_conformance_lines(conformance),
        *_statement_counts(statements),
        "| no. | name | MacTalk name | format | range | unit | access | default | user | section "
        "| description |" + (" conformance |" if conformance else "")
        + (" statements |" if statements else ""),
        "|---:|---|---|---|---|---|---|---:|---|---|---|" + ("---|" if conformance else "")
        + ("---|" if statements else ""),
    ]
    for r in table:
        if r.access == Access.RESERVED:
            rng = default = user = ""
        else:
            rng = f"{_fmt_value_32(r.minimum, r.format)} … {_fmt_value_32(r.maximum, r.format)}"
            default = _fmt_value_32(r.default, r.format)
            user = "yes" if r.user else "no"
        lines.append(
            f"| {r.number} | {r.name} | {_cell(r.alias)} | {r.format.value} | {rng} | "
            f"{_cell(r.unit)} | {r.access.value} | {default} | {user} | {_cell(r.section)} | "
            f"{_cell(r.description)} |" + (f" {_cell(conformance.cell(r))} |" if conformance
                                           else "")
            + (f" {_statement_cell(statements, r.name)} |" if statements else ""))
    lines += _statement_list(statements)
    return "\n".join(lines) + "\n"
