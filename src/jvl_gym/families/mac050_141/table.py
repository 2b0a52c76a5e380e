"""The MAC050–141 register table (``registers.csv`` beside this module, manual 3.2).

One row per register number (a LongInt as a ``LongInt`` row and its ``_HI`` row, numbers the
manual leaves undocumented as ``RESERVED_<n>``), loaded and validated once.
"""

from __future__ import annotations

from pathlib import Path

from ...registers.conformance import Conformance, load_packaged_conformance
from ...registers.statements import Statements, load_packaged_statements
from ...registers.table import RegisterTable, load_table

__all__ = ["TABLE", "CONFORMANCE", "STATEMENTS"]

#: the register table of the MAC50, MAC95, MAC140 and MAC141
TABLE: RegisterTable = load_table(Path(__file__).with_name("registers.csv"),
                                  source="jvl_gym/families/mac050_141/registers.csv")

#: what the simulator does with each register and documented bit (``conformance.yaml``)
CONFORMANCE: Conformance = load_packaged_conformance(__package__, TABLE)

#: the manual's statements about the registers, each with its status and tests
#: (``statements.yaml``; empty until the family has one)
STATEMENTS: Statements = load_packaged_statements(__package__, TABLE)
