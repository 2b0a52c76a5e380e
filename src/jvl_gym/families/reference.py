"""Generate the Markdown register references of the motor families (``docs/families/``).

Run ``python -m jvl_gym.families.reference [OUTPUT_DIR]`` from the repository root; the default
output directory is ``docs/families``. It writes ``mac800-registers.md`` and
``mis-registers.md``.
"""

from __future__ import annotations

import sys
from pathlib import Path

from ..registers.reference import markdown_reference_32
from . import family

__all__ = ["FAMILY_REFERENCES", "family_references"]

_GENERATOR = "python -m jvl_gym.families.reference"

#: output file name → (family key, title, source note)
FAMILY_REFERENCES: dict[str, tuple[str, str, str]] = {
    "mac800-registers.md": (
        "mac800", "MAC800",
        "Source: the MAC800 register overview (§1.2) and serial quick guide (§1.3). Sections "
        "are the overview's sub-tables. Derivations, OCR repairs and chosen values: "
        "[MAC800: register table and units](mac800.md)."),
    "mis-registers.md": (
        "mis", "MIS/SMC step motors",
        "Source: the MIS manual, register list §8.2 (overview §8.2.1, detail sections §8.2.2 … "
        "§8.2.131). Where the overview and a detail section disagree, the choice and both "
        "readings are in [MIS/SMC: register table and units](mis.md)."),
}


def family_references() -> dict[str, str]:
    """Render every family's register reference.

    Returns
    -------
    dict of str to str
        Output file name → Markdown text.
    """
    return {name: markdown_reference_32(family(key).table, title, note, _GENERATOR,
                                        family(key).conformance, family(key).statements)
            for name, (key, title, note) in FAMILY_REFERENCES.items()}


def main(argv: list[str] | None = None) -> int:
    """Write the references to ``argv[0]`` (default ``docs/families``)."""
    args = sys.argv[1:] if argv is None else argv
    out = Path(args[0]) if args else Path("docs/families")
    out.mkdir(parents=True, exist_ok=True)
    for name, text in family_references().items():
        (out / name).write_text(text, encoding="utf-8")
        print(f"wrote {out / name}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
