"""Register numbers used by the compiled firmware, taken from the register table.

Every register of the one register table (``jvl_gym.registers``) is a module constant here,
named as in the table (``R.MODE_REG``), read at import time, so the kernel sees the numbers as
compile-time constants and no number is written twice.
"""

from __future__ import annotations

from ..table import TABLE as _TABLE

globals().update(_TABLE.numbers_by_name())

#: raw storage bounds by register number (int64 arrays of length 165)
RAW_MIN = _TABLE.raw_min_array
RAW_MAX = _TABLE.raw_max_array
