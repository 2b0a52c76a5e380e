"""Generate the Markdown register reference (``docs/registers.md``) from a register table.

Run ``python -m jvl_gym.registers.reference [OUTPUT]`` from the repository root; the default
output is ``docs/registers.md``.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from pathlib import Path

from .table import FORMAT_SCALE, MAC050_141, Access, Format, RegisterTable

__all__ = ["markdown_reference"]


def _fmt_value(x: float, fmt: Format) -> str:
    if fmt in FORMAT_SCALE:
        return f"{x:g}"
    return str(int(x))


def _cell(text: str) -> str:
    return text.replace("|", "\\|")


def markdown_reference(table: RegisterTable, title: str = "MAC50/95/140/141",
                       usage: Callable[[str], list[str]] | None = None) -> str:
    """Render a register table as a Markdown document.

    Parameters
    ----------
    table : RegisterTable
        The table to document.
    title : str
        Motor family shown in the heading.
    usage : callable, optional
        ``usage(name) -> [mode names]``: adds a column with the modes that read the register.

    Returns
    -------
    str
        Markdown with one table row per register number: number, name, format, range, unit,
        access, default, section, description.
    """
    lines = [
        f"# Register reference: {title}",
        "",
        f"Generated from `{table.source}` by `python -m jvl_gym.registers.reference`; "
        "do not edit by hand.",
        "",
        "Values are in user units (Fixed4/Fixed8 as real numbers; raw = value·4096 / value·256, "
        "manual 3.1). A LongInt register N holds the low word and N+1 (`<NAME>_HI`) the high "
        "word. Access: `rw` user-writable, `ro` computed by the firmware (writes are refused), "
        "`reserved` undocumented.",
        "",
        "| no. | name | format | range | unit | access | default | section | description |"
        + (" modes |" if usage else ""),
        "|---:|---|---|---|---|---|---:|---|---|" + ("---|" if usage else ""),
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
            + (f" {', '.join(usage(r.name))} |" if usage else ""))
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    """Write the reference of :data:`MAC050_141` to ``argv[0]`` (default docs/registers.md)."""
    args = sys.argv[1:] if argv is None else argv
    out = Path(args[0]) if args else Path("docs/registers.md")
    out.parent.mkdir(parents=True, exist_ok=True)
    from ..firmware.mode_table import markdown_mode_table, modes_using

    out.write_text(markdown_reference(MAC050_141, usage=modes_using), encoding="utf-8")
    (out.parent / "modes.md").write_text(markdown_mode_table(), encoding="utf-8")
    print(f"wrote {out} ({len(MAC050_141)} registers)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
