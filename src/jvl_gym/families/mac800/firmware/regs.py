"""Register numbers used by the compiled MAC800 firmware, read from the family's register table
(``registers.csv``, MAC800 register overview §1.2) at import: every register is a module
constant named as in the table (``R.MODE_REG``), a compile-time constant, each number stated
once (in the table)."""

from __future__ import annotations

from ..table import TABLE as _TABLE

_NUMBERS = _TABLE.numbers_by_name()
globals().update(_NUMBERS)
LAST = _TABLE.last


def _consecutive(*names: str) -> bool:
    """Whether registers ``names`` stand at consecutive numbers in this order (the firmware
    indexes these groups from their first register)."""
    first = _NUMBERS[names[0]]
    return [_NUMBERS[n] for n in names] == list(range(first, first + len(names)))


assert _consecutive(*(f"KFF{k}" for k in range(5, -1, -1)))
assert _consecutive(*(f"KVFX{k}" for k in range(6, 0, -1)))
assert _consecutive(*(f"KVFY{k}" for k in range(5, -1, -1)))
assert _consecutive(*(f"KVB{k}" for k in range(4, -1, -1)))
assert _consecutive("IA_SOLL", "IB_SOLL", "IC_SOLL", "IA_IST", "IB_IST", "IC_IST")
assert _consecutive("UA_VAL", "UB_VAL", "UC_VAL", "EMK_A", "EMK_B", "EMK_C")
