"""J1939 frames of the MIS (MIS manual §11.8.4–§11.8.6): 29-bit identifiers, the NAME field,
and the memory access messages DM14 (request), DM15 (response) and DM16 (binary data).

Identifier (SAE J1939/21): priority (3 bits), data page, PDU format PF, PDU specific PS (the
destination address when PF < 240), source address. PGNs: address claimed 60928 (EE00h),
request 59904 (EA00h), DM14 55552 (D900h), DM15 55296 (D800h), DM16 55040 (D700h).

DM14 (8 bytes, §11.8.6): length (11 bits: byte 0 and bits 5–7 of byte 1), pointer type (bit 4),
command (bits 1–3), bit 0 reserved = 1; pointer (bytes 2–4, low byte first), pointer extension
(byte 5), key/user level (bytes 6–7). DM15: length, status (bits 1–3: 0 proceed, 4 operation
completed, 5 operation failed), error indicator (bytes 2–4), EDCP extension (byte 5), seed
(bytes 6–7). DM16: data length 1–4 (byte 0), data (low byte first), unused bytes FFh.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["PGN_ADDRESS_CLAIMED", "PGN_REQUEST", "PGN_DM14", "PGN_DM15", "PGN_DM16",
           "GLOBAL", "NULL_ADDRESS", "can_id", "split_id", "Name", "Dm14", "Dm15",
           "Dm16", "READ", "WRITE", "OPERATION_COMPLETE", "PROCEED", "COMPLETED", "FAILED",
           "MAC_REGISTERS"]

PGN_ADDRESS_CLAIMED = 60928
PGN_REQUEST = 59904
PGN_DM14, PGN_DM15, PGN_DM16 = 55552, 55296, 55040
GLOBAL = 255  #: destination "all"
NULL_ADDRESS = 254  #: source of a node that could not claim an address
#: DM14 commands the MIS takes (§11.8.5: "Read (1) / Write (2) / Operation Complete (4)")
READ, WRITE, OPERATION_COMPLETE = 1, 2, 4
#: DM15 status (§11.8.6)
PROCEED, COMPLETED, FAILED = 0, 4, 5
#: pointer extension of the MAC registers (§11.8.5: "Identifier for Mac registers (80h)")
MAC_REGISTERS = 0x80


def can_id(pgn: int, source: int, destination: int = GLOBAL, priority: int = 6) -> int:
    """The 29-bit identifier of a message of ``pgn`` (PDU1: the destination in PS)."""
    pf = (pgn >> 8) & 0xFF
    ps = destination if pf < 240 else pgn & 0xFF
    return (priority & 7) << 26 | (pgn >> 16 & 1) << 24 | pf << 16 | ps << 8 | source & 0xFF


def split_id(identifier: int) -> tuple[int, int, int, int]:
    """(priority, pgn, source, destination) of an identifier (destination 255 for PDU2)."""
    priority = identifier >> 26 & 7
    dp = identifier >> 24 & 1
    pf = identifier >> 16 & 0xFF
    ps = identifier >> 8 & 0xFF
    if pf < 240:
        return priority, dp << 16 | pf << 8, identifier & 0xFF, ps
    return priority, dp << 16 | pf << 8 | ps, identifier & 0xFF, GLOBAL


@dataclass(frozen=True)
class Name:
    """The 64-bit NAME of a J1939 node (§11.8.4 table)."""

    identity: int
    manufacturer: int
    ecu_instance: int
    function_instance: int
    function: int
    vehicle_system: int
    vehicle_system_instance: int
    industry_group: int
    arbitrary_address: bool

    def value(self) -> int:
        """The NAME as a 64-bit number (byte 0 lowest; the lower NAME wins a claim)."""
        return (self.identity & 0x1FFFFF | (self.manufacturer & 0x7FF) << 21
                | (self.ecu_instance & 7) << 32 | (self.function_instance & 0x1F) << 35
                | (self.function & 0xFF) << 40 | (self.vehicle_system & 0x7F) << 49
                | (self.vehicle_system_instance & 0xF) << 56 | (self.industry_group & 7) << 60
                | int(self.arbitrary_address) << 63)

    def to_bytes(self) -> bytes:
        return self.value().to_bytes(8, "little")

    @classmethod
    def from_bytes(cls, data: bytes) -> Name:
        """The NAME of the 8 bytes ``data`` (byte 0 lowest)."""
        return cls.from_value(int.from_bytes(bytes(data[:8]), "little"))

    @classmethod
    def from_value(cls, v: int) -> Name:
        """The NAME of the 64-bit number ``v`` (:meth:`value`)."""
        return cls(v & 0x1FFFFF, v >> 21 & 0x7FF, v >> 32 & 7, v >> 35 & 0x1F, v >> 40 & 0xFF,
                   v >> 49 & 0x7F, v >> 56 & 0xF, v >> 60 & 7, bool(v >> 63 & 1))


@dataclass(frozen=True)
class Dm14:
    """A memory access request."""

    length: int
    command: int
    pointer: int
    extension: int = MAC_REGISTERS
    pointer_type: int = 0
    key: int = 0xFFFF

    def to_bytes(self) -> bytes:
        b1 = ((self.length >> 8 & 7) << 5 | (self.pointer_type & 1) << 4
              | (self.command & 7) << 1 | 1)
        return (bytes([self.length & 0xFF, b1]) + self.pointer.to_bytes(3, "little")
                + bytes([self.extension]) + self.key.to_bytes(2, "little"))

    @classmethod
    def from_bytes(cls, data: bytes) -> Dm14:
        d = bytes(data)
        return cls(d[0] | (d[1] >> 5) << 8, d[1] >> 1 & 7, int.from_bytes(d[2:5], "little"),
                   d[5], d[1] >> 4 & 1, int.from_bytes(d[6:8], "little"))


@dataclass(frozen=True)
class Dm15:
    """A memory access response."""

    length: int
    status: int
    error: int = 0xFFFFFF
    edcp: int = 0xFF
    seed: int = 0xFFFF

    def to_bytes(self) -> bytes:
        b1 = (self.length >> 8 & 7) << 5 | 1 << 4 | (self.status & 7) << 1 | 1
        return (bytes([self.length & 0xFF, b1]) + self.error.to_bytes(3, "little")
                + bytes([self.edcp]) + self.seed.to_bytes(2, "little"))

    @classmethod
    def from_bytes(cls, data: bytes) -> Dm15:
        d = bytes(data)
        return cls(d[0] | (d[1] >> 5) << 8, d[1] >> 1 & 7, int.from_bytes(d[2:5], "little"),
                   d[5], int.from_bytes(d[6:8], "little"))


@dataclass(frozen=True)
class Dm16:
    """Binary data: 1–4 bytes, low byte first."""

    data: bytes

    def to_bytes(self) -> bytes:
        return bytes([len(self.data)]) + self.data + b"\xff" * (7 - len(self.data))

    @classmethod
    def from_bytes(cls, data: bytes) -> Dm16:
        d = bytes(data)
        n = d[0]
        if not 1 <= n <= 4 or n + 1 > len(d):
            raise ValueError(f"DM16 data length {n} is not 1 … 4")
        return cls(d[1:1 + n])
