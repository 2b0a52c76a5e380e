"""The MAC800 integrated servo motor family (MAC800 register overview and serial quick guide).

``REGISTERS`` is the family's register table (``registers.csv`` in this package, every register
of the overview at one register number, 32 bits wide); :mod:`.units` holds its sample rate,
counts per revolution and unit scalings.
"""

from __future__ import annotations

from ...registers.table import RegisterTable, load_packaged_table

__all__ = ["REGISTERS"]

#: the MAC800 register table (registers 1 … 206)
REGISTERS: RegisterTable = load_packaged_table(__name__)
