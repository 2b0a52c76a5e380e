"""Register numbers the compiled MIS firmware uses, read from the register table at import.

Every register of the table is a module constant named as in the table (``R.MODE_REG``): the
kernel sees them as compile-time constants, and no register number is written twice.
"""

from __future__ import annotations

from ..table import TABLE as _TABLE

globals().update(_TABLE.numbers_by_name())
