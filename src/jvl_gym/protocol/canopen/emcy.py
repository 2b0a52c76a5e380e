"""Emergency messages, the error register and the error history of a node (MIS manual §11.4.1,
§11.4.2).

An EMCY (COB-ID 1014h, default ``80h + node id``) is sent once per error event: when a bit of
the motor's error register (ERR_BITS, §8.2.31) comes on, with the code of that error, and for the
communication errors of the node itself. Its 8 bytes: the CANopen error code (2), the error
register 1001h (1), the low 16 bits of ERR_BITS (2), zeros (3). When every error has gone, an
EMCY with code 0000h ("error reset", DS-301) says so. Each EMCY's code and ERR_BITS word enter
the pre-defined error field 1003h, newest first (sub-index 1 the last); writing 0 to 1003h sub 0
empties it and clears the motor's errors (§11.4.2).

===========  ========================================  ==========================
code         error                                     1001h bit
===========  ========================================  ==========================
1001h        motor error (any other ERR_BITS bit)      7 manufacturer specific
1002h        position error (position limit)           5 device profile specific
1003h        follow error (ERR_BITS bit 1)             5 device profile specific
1004h        low bus voltage (ERR_BITS bit 4)          2 voltage
1010h        homing: unsupported profile               5 device profile specific
8210h        PDO of the wrong length                   4 communication
8130h        node guard fail                           4 communication
===========  ========================================  ==========================

Bit 0 (generic) is set while any error is.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass, field

__all__ = ["Emcy", "MOTOR_ERROR", "POSITION_ERROR", "FOLLOW_ERROR", "LOW_BUS_VOLTAGE",
           "HOMING_PROFILE", "PDO_LENGTH", "NODE_GUARD", "HISTORY"]

MOTOR_ERROR, POSITION_ERROR, FOLLOW_ERROR, LOW_BUS_VOLTAGE = 0x1001, 0x1002, 0x1003, 0x1004
HOMING_PROFILE, PDO_LENGTH, NODE_GUARD = 0x1010, 0x8210, 0x8130
#: entries the error field 1003h keeps (sub-indices 1 and 2, §11.4.1)
HISTORY = 2
_REGISTER_BIT = {MOTOR_ERROR: 7, POSITION_ERROR: 5, FOLLOW_ERROR: 5, LOW_BUS_VOLTAGE: 2,
                 HOMING_PROFILE: 5, PDO_LENGTH: 4, NODE_GUARD: 4}


@dataclass
class Emcy:
    """The emergency state of a node.

    Attributes
    ----------
    history : list of int
        1003h entries, newest first: ERR_BITS low word << 16 | code.
    comm_bits : int
        Bits of 1001h held by communication and profile events until 1003h is cleared.
    """

    history: list[int] = field(default_factory=list)
    comm_bits: int = 0
    last_err: int = 0

    def register(self, err_bits: int, follow: int, low_bus: int, position: int) -> int:
        """The error register 1001h for ERR_BITS ``err_bits`` (the masks name its bits)."""
        reg = self.comm_bits
        if err_bits & follow or err_bits & position:
            reg |= 1 << 5
        if err_bits & low_bus:
            reg |= 1 << 2
        if err_bits & ~(follow | low_bus | position):
            reg |= 1 << 7
        return reg | (1 if reg or err_bits else 0)

    def code_of(self, new_bits: int, follow: int, low_bus: int, position: int) -> int:
        """The error code of newly set ERR_BITS ``new_bits`` (the most specific one)."""
        if new_bits & follow:
            return FOLLOW_ERROR
        if new_bits & low_bus:
            return LOW_BUS_VOLTAGE
        if new_bits & position:
            return POSITION_ERROR
        return MOTOR_ERROR

    def frame(self, code: int, register: int, err_bits: int) -> bytes:
        """The 8 data bytes of an EMCY (and its entry in the history)."""
        if code:
            self.history.insert(0, (err_bits & 0xFFFF) << 16 | code)
            del self.history[HISTORY:]
        return struct.pack("<HBH3x", code, register, err_bits & 0xFFFF)

    def event(self, code: int) -> None:
        """A communication or profile event: its 1001h bit stays until 1003h is cleared."""
        self.comm_bits |= 1 << _REGISTER_BIT[code]

    def clear(self) -> None:
        """1003h sub 0 := 0: the history and the held bits are cleared."""
        self.history.clear()
        self.comm_bits = 0
