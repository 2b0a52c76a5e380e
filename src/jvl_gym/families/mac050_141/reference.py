"""Write the MAC050–141's register reference and mode table (``docs/registers.md``,
``docs/modes.md``).

Run ``python -m jvl_gym.families.mac050_141.reference [OUTPUT]`` from the repository root; the
default output is ``docs/registers.md``, and ``modes.md`` is written beside it.
"""

from __future__ import annotations

import sys
from pathlib import Path

from ...registers.reference import markdown_reference
from .firmware.mode_table import markdown_mode_table, modes_using
from .table import CONFORMANCE, STATEMENTS, TABLE


def main(argv: list[str] | None = None) -> int:
    """Write the reference of the register table to ``argv[0]`` (default docs/registers.md)
    and the mode table to ``modes.md`` beside it."""
    args = sys.argv[1:] if argv is None else argv
    out = Path(args[0]) if args else Path("docs/registers.md")
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(markdown_reference(TABLE, usage=modes_using, conformance=CONFORMANCE,
                                      statements=STATEMENTS), encoding="utf-8")
    (out.parent / "modes.md").write_text(markdown_mode_table(), encoding="utf-8")
    print(f"wrote {out} ({len(TABLE)} registers)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
