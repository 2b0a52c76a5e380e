"""Which MacTalk a unit on a line speaks, from its reply to one read (MAC050–141 manual 5.1,
MAC800 serial quick guide §1.3.3, MIS manual §18.2.2).

A read request has the same bytes in both dialects (``50h×3 <addr> <!addr> <reg> <!reg> AAh
AAh``); the replies differ after ``52h×3 00h FFh``: the 16-bit reply goes on with its datalength
(``04h``, two words), the 32-bit reply with the register number it answers ("always the same
as requested"). Asking for a register other than 4 therefore tells the two apart, and a line
with motors of several families can be scanned with one request per address.
"""

from __future__ import annotations

from typing import Any

from ..errors import NoAnswerError
from . import codec16 as mt
from . import codec32 as m32
from .dialect import MACTALK16, MACTALK32
from .master import SerialMaster

__all__ = ["DialectProbe", "PROBE_REGISTER"]

#: the register the probe reads: MODE_REG in every family (MAC050–141 manual 3.2.2, MAC800
#: quick guide 1.2, MIS manual §8.2.3); any number but 4, the 16-bit reply's datalength
PROBE_REGISTER = 2


class DialectProbe(SerialMaster):
    """Reads register :data:`PROBE_REGISTER` of a unit and reports the dialect of its reply
    (the parameters of :class:`~.master.SerialMaster`)."""

    def _read_reply(self, deadline: float) -> bytes:
        head = self._read_exact(3, deadline)
        if len(head) < 3 or head != bytes((m32.Command.WRITE,)) * 3:
            return head
        head += self._read_exact(4, deadline)
        if len(head) < 7:
            return head
        if head[5] == PROBE_REGISTER:  # the 32-bit reply names the register, then Len
            head += self._read_exact(2, deadline)
            if len(head) < 9:
                return head
            return head + self._read_exact(2 * head[7] + 2, deadline)
        return head + self._read_exact(2 * head[5] + 2, deadline)

    def _decode(self, raw: bytes) -> Any:
        if len(raw) > 5 and raw[5] == PROBE_REGISTER:
            frame = m32.decode(raw)
            return (MACTALK32, frame) if isinstance(frame, m32.Reply) else frame
        frame = mt.decode(raw)
        return (MACTALK16, frame) if isinstance(frame, mt.DataReply) else frame

    def _kind(self, frame: Any) -> str:
        return "data" if isinstance(frame, tuple) else "other"

    def dialect(self, address: int) -> str | None:
        """The dialect of the unit at ``address``, None if no unit answers there."""
        self.address = address
        try:
            return self.transact(mt.encode_read(address, PROBE_REGISTER),
                                 f"READ {PROBE_REGISTER}")[0]
        except NoAnswerError:
            return None
