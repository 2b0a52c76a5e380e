"""Which MacTalk a motor family speaks: the family declares it as data, in its contract
(:attr:`jvl_gym.families.TwinSpec.dialects`, the default first):

=============  =====================================================================
``mactalk16``  MAC050–141 manual 5.1 (:mod:`.codec16`): 16-bit registers, a LongInt at two
               numbers, the read reply without register number
``mactalk32``  MAC800 serial quick guide §1.3, MIS manual §18.2 (:mod:`.codec32`): 32-bit
               registers at one number, the read reply names the register, group write
=============  =====================================================================
"""

from __future__ import annotations

from typing import Any

from ...registers.errors import echo
from . import codec16, codec32

__all__ = ["MACTALK16", "MACTALK32", "DIALECTS", "check_dialect", "dialect_of", "client_class"]

#: MacTalk of the MAC050–141 (manual 5.1)
MACTALK16: str = codec16.DIALECT
#: MacTalk of the 32-bit register families (MAC800 quick guide §1.3, MIS manual §18.2)
MACTALK32: str = codec32.DIALECT
DIALECTS = (MACTALK16, MACTALK32)


def check_dialect(name: str) -> str:
    """``name`` if it is a known dialect; ValueError naming the known ones otherwise."""
    if name not in DIALECTS:
        raise ValueError(f"unknown MacTalk dialect {echo(name)}; known: {', '.join(DIALECTS)}")
    return name


def dialect_of(motors: Any) -> str:
    """The default MacTalk dialect of ``motors``' family (its contract's
    :attr:`~jvl_gym.families.TwinSpec.dialect`), checked."""
    return check_dialect(motors.family.twin.dialect)


def client_class(name: str) -> type:
    """The master of dialect ``name``: :class:`~.client.MacTalkClient` (16-bit) or
    :class:`~.client32.MacTalk32Client` (32-bit), both :class:`~.master.SerialMaster`."""
    check_dialect(name)
    if name == MACTALK32:
        from .client32 import MacTalk32Client

        return MacTalk32Client
    from .client16 import MacTalkClient

    return MacTalkClient
