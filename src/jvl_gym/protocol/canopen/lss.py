"""Layer setting services of a node (MIS manual §11.7): node id and bit rate over the bus.

The master sends on COB-ID 7E5h, the node answers on 7E4h, always 8 bytes (other lengths are
ignored):

======  ==========================================================================
04h     switch mode global: byte 1 = 1 configuration mode, 0 back to waiting (no answer)
40h–43h switch mode selective: vendor id, product code, revision, serial number; when all
        four match 1018h the node enters configuration mode and answers 44h
11h     configure node id (1 … 127; else error code 1)
13h     configure bit timing: table 0, rate 0–4, 6–8 (§11.7.4; else error code 1)
17h     store configuration: the node id and bit rate into their registers and the motor's
        flash (error code 2 if the motor refuses)
5Ah–5Eh inquire vendor id, product code, revision, serial number, node id
======  ==========================================================================

Services other than switch mode are answered in configuration mode only. A configured node id
is taken at the next reset (node or communication, §11.7.6: "After a reset, the device now works
with the new settings").
"""

from __future__ import annotations

import struct
from typing import Any

from canopen.sdo import SdoAbortedError

__all__ = ["LssSlave", "LSS_MASTER_COB", "LSS_SLAVE_COB", "BIT_RATES"]

LSS_MASTER_COB, LSS_SLAVE_COB = 0x7E5, 0x7E4
#: bit-rate codes of the CiA table (§11.7.4) → kbit/s; 5 is reserved
BIT_RATES = {0: 1000, 1: 800, 2: 500, 3: 250, 4: 125, 6: 50, 7: 20, 8: 10}


class LssSlave:
    """The LSS state of ``node`` (a :class:`~.slave.CanopenSlave`)."""

    def __init__(self, node: Any) -> None:
        self.node = node
        self.configuration = False
        self.pending: int | None = None
        self.pending_rate: int | None = None
        self._selective: list[int] = []

    def _answer(self, *values: int) -> None:
        self.node.send(LSS_SLAVE_COB, bytes(values) + bytes(8 - len(values)))
        self.node.stats["LSS"] += 1

    def _identity(self, k: int) -> int:
        return int(self.node.read_value(0x1018, k)) & 0xFFFFFFFF

    def on_request(self, data: bytes) -> None:
        """One LSS request."""
        if len(data) != 8:
            return
        cs = data[0]
        arg = struct.unpack_from("<L", data, 1)[0]
        if cs == 0x04:
            self.configuration = data[1] == 1
            return
        if 0x40 <= cs <= 0x43:
            k = cs - 0x40
            if k == 0:
                self._selective = []
            if len(self._selective) == k:
                self._selective.append(arg)
            if k == 3 and self._selective == [self._identity(j) for j in range(1, 5)]:
                self.configuration = True
                self._answer(0x44)
            return
        if not self.configuration:
            return
        if cs == 0x11:
            ok = 1 <= data[1] <= 127
            if ok:
                self.pending = data[1]
            self._answer(0x11, 0 if ok else 1, 0)
        elif cs == 0x13:
            ok = data[1] == 0 and data[2] in BIT_RATES
            if ok:
                self.pending_rate = data[2]
            self._answer(0x13, 0 if ok else 1, 0)
        elif cs == 0x17:
            self._answer(0x17, 0 if self._store() else 2, 0)
        elif 0x5A <= cs <= 0x5D:
            self._answer(cs, *struct.pack("<L", self._identity(cs - 0x5A + 1)))
        elif cs == 0x5E:
            self._answer(0x5E, self.node.node_id)

    def _store(self) -> bool:
        node = self.node
        try:
            if self.pending is not None:
                node.set_node_id(self.pending)
            if self.pending_rate is not None:
                node.reg_write(node.facts.baud, self.pending_rate, sdo=False)
                image = dict(node.m.flash_image(node.i)) or node.register_image()
                image[node.facts.baud] = self.pending_rate
                node.m.load_flash_image(node.i, image)
        except (ValueError, SdoAbortedError) as exc:  # the motor's refusal
            node.refuse(f"LSS store configuration: {exc}")
            return False
        return True
