"""The MIS/SMC integrated step motor family (MIS17x, 23x, 34x, 43x; SMC66/SMC85; MIS manual).

``REGISTERS`` is the family's register table (``registers.csv`` in this package, every register
of the MIS manual §8.2 at one register number, 32 bits wide); :mod:`.units` holds its counts per
revolution and unit scalings.
"""

from __future__ import annotations

from ...registers.table import RegisterTable, load_packaged_table

__all__ = ["REGISTERS"]

#: the MIS/SMC register table (registers 1 … 253)
REGISTERS: RegisterTable = load_packaged_table(__name__)
