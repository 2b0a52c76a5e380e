"""Register layer of jvl_gym: the register table as data, formats and errors (manual 3.1, 3.2).

>>> from jvl_gym.registers import MAC050_141
>>> MAC050_141.lookup("v_soll").number
5
"""

from __future__ import annotations

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
    MAC050_141,
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
    "FORMAT_CODES",
    "Format",
    "MAC050_141",
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
    "load_packaged_table",
    "load_table",
    "round_half_away",
    "saturate_raw",
    "split_longint",
    "split_word32",
    "to_raw",
    "to_word16",
]
