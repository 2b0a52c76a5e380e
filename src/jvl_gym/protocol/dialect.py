"""Which MacTalk a motor family speaks: the family declares it as data.

A family's public ``constants`` module names its dialect in :data:`DIALECT_CONSTANT`
(``MACTALK_DIALECT``):

=============  =====================================================================
``mactalk16``  MAC050–141 manual 5.1 (:mod:`.mactalk`): 16-bit registers, a LongInt at two
               numbers, the read reply without register number
``mactalk32``  MAC800 serial quick guide §1.3, MIS manual §18.2 (:mod:`.mactalk32`): 32-bit
               registers at one number, the read reply names the register, group write
=============  =====================================================================

A family that names none speaks ``mactalk16``, the MacTalk of the first family.
"""

from __future__ import annotations

import importlib
from typing import Any

__all__ = ["MACTALK16", "MACTALK32", "DIALECTS", "DIALECT_CONSTANT", "DEFAULT_DIALECT",
           "check_dialect", "dialect_of"]

#: MacTalk of the MAC050–141 (manual 5.1)
MACTALK16 = "mactalk16"
#: MacTalk of the 32-bit register families (MAC800 quick guide §1.3, MIS manual §18.2)
MACTALK32 = "mactalk32"
DIALECTS = (MACTALK16, MACTALK32)
#: name of the constant in a family's ``constants`` module
DIALECT_CONSTANT = "MACTALK_DIALECT"
#: the dialect of a family that declares none
DEFAULT_DIALECT = MACTALK16


def check_dialect(name: str) -> str:
    """``name`` if it is a known dialect; ValueError naming the known ones otherwise."""
    if name not in DIALECTS:
        raise ValueError(f"unknown MacTalk dialect {name!r}; known: {', '.join(DIALECTS)}")
    return name


def dialect_of(motors: Any) -> str:
    """The MacTalk dialect of ``motors``' family: ``MACTALK_DIALECT`` of the ``constants``
    module beside the module of its array class (``jvl_gym.families.<key>.constants``), or
    :data:`DEFAULT_DIALECT` if the family has no such module or constant."""
    package = type(motors).__module__.rpartition(".")[0]
    if not package:
        return DEFAULT_DIALECT
    try:
        constants = importlib.import_module(f"{package}.constants")
    except ModuleNotFoundError as exc:
        if exc.name != f"{package}.constants":
            raise
        return DEFAULT_DIALECT
    return check_dialect(getattr(constants, DIALECT_CONSTANT, DEFAULT_DIALECT))
