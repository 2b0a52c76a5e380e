"""Register layer of jvl_gym: the register table as data, formats and errors (manual 3.1, 3.2).

>>> from jvl_gym.registers import load_table
>>> table = load_table("src/jvl_gym/families/mac050_141/registers.csv")
>>> table.lookup("v_soll").number
5
"""

from __future__ import annotations

from .conformance import (
    Conformance,
    ConformanceError,
    NotModelledWarning,
    load_packaged_conformance,
)
from .errors import (
    ReadOnlyRegisterError,
    RegisterError,
    RegisterRangeError,
    RegisterShapeError,
    UnknownRegisterError,
)
from .formats import (
    from_raw,
    from_word16,
    join_longint,
    join_word32,
    round_half_away,
    saturate_raw,
    split_longint,
    split_word32,
    to_raw,
    to_word16,
)
from .table import (
    FORMAT_CODES,
    Access,
    Format,
    Register,
    RegisterTable,
    TableError,
    format_value_range,
    load_packaged_table,
    load_table,
)

__all__ = [
    "Access",
    "Conformance",
    "ConformanceError",
    "FORMAT_CODES",
    "Format",
    "ReadOnlyRegisterError",
    "Register",
    "RegisterError",
    "RegisterRangeError",
    "RegisterShapeError",
    "RegisterTable",
    "TableError",
    "UnknownRegisterError",
    "from_raw",
    "format_value_range",
    "from_word16",
    "join_longint",
    "join_word32",
    "NotModelledWarning",
    "load_packaged_conformance",
    "load_packaged_table",
    "load_table",
    "round_half_away",
    "saturate_raw",
    "split_longint",
    "split_word32",
    "to_raw",
    "to_word16",
]
