"""The MIS/SMC register table (``registers.csv`` beside this module, MIS manual §8.2).

One row per register number 1 … 253, every register 32 bits wide; numbers the manual leaves
undocumented are ``RESERVED_<n>`` rows. Loaded and validated once (the package's ``REGISTERS``).
"""

from __future__ import annotations

from ...registers.conformance import Conformance, load_packaged_conformance
from ...registers.statements import Statements, load_packaged_statements
from ...registers.table import RegisterTable, load_packaged_table

__all__ = ["TABLE", "CONFORMANCE", "STATEMENTS"]

#: the register table, loaded and validated once (the package's ``REGISTERS``)
TABLE: RegisterTable = load_packaged_table(__package__)

#: what the simulator does with each register and documented bit (``conformance.yaml``)
CONFORMANCE: Conformance = load_packaged_conformance(__package__, TABLE)

#: the manual's statements about the registers, each with its status and tests
#: (``statements.yaml``; empty until the family has one)
STATEMENTS: Statements = load_packaged_statements(__package__, TABLE)
