"""The J1939 node of one MIS motor (MIS manual §11.8): address claim with its NAME and access to
the MAC registers by DM14/DM15/DM16 as the transfer table of §11.8.7 shows.

Read: DM14 read → DM15 proceed, DM16 with the register's bytes, DM15 operation completed; the
tool closes with a DM14 operation complete (no answer). Write: DM14 write → DM15 proceed; the
tool sends the DM16 within 1000 ms → DM15 operation completed (the register written) or
operation failed (refused). Any malformed or refused request is answered with DM15 operation
failed (§11.8.7 "Failed read operation").

Decisions where the manual is silent (``docs/protocol.md``, "J1939"):

* A request is malformed if it is not 8 bytes, its command is not read, write or operation
  complete, its pointer type is not direct (0, §11.8.5: "Direct spatial addressing"), its
  pointer extension is not 80h, its length not 1, 2 or 4, or its pointer not a register of the
  table (1 … 512 in the manual; reserved registers fail). A DM16 that does not follow a proceed
  of a write, or whose length is not the requested one, fails; so does one after 1000 ms.
* A read of 1 or 2 bytes gives the register's low bytes; a write of 1 or 2 bytes is extended as
  the register's format extends it (signed or not), as the 32-bit MacTalk's short writes.
* DM15 fields the manual leaves open: the length of a proceed echoes the request's, an
  operation completed or failed carries length 0 (nothing more is to be transferred); the error
  indicator is FFFFFFh (no code; the manual names none), EDCP extension FFh, seed FFFFh (no
  key: "Key/user level: NA"), reserved bits 1.
* Address claim (SAE J1939/81): the claim (PGN 60928, the 64-bit NAME) is sent at start and
  on a request for PGN 60928 to our address or to all; a claim of our address by a node of
  lower NAME (the higher priority) makes the motor give the address up: "arbitrary address
  capable", it claims the next free address of 129 … 247 (§11.8.3: "Negotiable address support
  129 – 247"), else (or when none is free) it sends "cannot claim" (the claim from the null
  address 254) and answers a request for PGN 60928 with it again; a claim of our address with a
  higher NAME is answered by our claim again; a claim of our address with our own NAME is our
  claim heard back (a bus such as python-can's ``udp_multicast`` loops frames back) and is
  ignored.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ...families import Capability
from ...registers import RegisterError
from .frames import (
    COMPLETED,
    FAILED,
    GLOBAL,
    MAC_REGISTERS,
    NULL_ADDRESS,
    OPERATION_COMPLETE,
    PGN_ADDRESS_CLAIMED,
    PGN_DM14,
    PGN_DM15,
    PGN_DM16,
    PGN_REQUEST,
    PROCEED,
    READ,
    WRITE,
    Dm14,
    Dm15,
    Dm16,
    Name,
    can_id,
    split_id,
)

__all__ = ["J1939Device", "Frame", "WRITE_TIMEOUT_S", "NEGOTIABLE"]

WRITE_TIMEOUT_S = 1.0  #: §11.8.7: "Timeout 1000 milliseconds"
NEGOTIABLE = range(129, 248)  #: §11.8.3


@dataclass(frozen=True)
class Frame:
    """A CAN frame: 29-bit identifier and data (python-can's ``Message`` fields)."""

    arbitration_id: int
    data: bytes


class J1939Device:
    """The J1939 side of motor ``index`` of a motor array (module docstring).

    Parameters
    ----------
    motors : MotorArray
        Registers by number (``read_raw``, ``write_raw``, ``table``).
    index : int
    address : int
        Node address 1 … 252 (§11.8.3; factory default 5).
    name : Name or None
        The NAME; None: the one the motors' family states (``Family.j1939_name``, MIS manual
        §11.8.4).

    Raises
    ------
    UnsupportedOperation
        The motors' family declares no J1939 interface.
    """

    def __init__(self, motors: Any, index: int = 0, address: int = 5,
                 name: Name | None = None) -> None:
        motors.family.require(Capability.J1939)
        if not 1 <= address <= 252:
            raise ValueError(f"J1939 node address must be 1 … 252 (§11.8.3), got {address}")
        self.m = motors
        self.i = index
        self.address = address
        self.name = Name.from_value(motors.family.j1939_name) if name is None else name
        self.others: dict[int, int] = {}  # address → NAME value of other nodes
        self.pending: tuple[int, int, int, float] | None = None  # (tool, register, length, t)

    # ------------------------------------------------------------------ address claim
    def claim(self) -> list[Frame]:
        """The address claim (PGN 60928, broadcast, from our address; from the null address
        254 it is "cannot claim")."""
        return [Frame(can_id(PGN_ADDRESS_CLAIMED, self.address, GLOBAL), self.name.to_bytes())]

    def _claimed(self, source: int, data: bytes) -> list[Frame]:
        other = int.from_bytes(bytes(data[:8]), "little")
        if source == self.address and other == self.name.value():
            return []  # our own claim, heard back (a bus that loops frames back)
        self.others[source] = other
        if source != self.address or self.address == NULL_ADDRESS:
            return []
        if self.name.value() < other:
            return self.claim()  # we win: claim again
        taken = set(self.others)
        free = [a for a in NEGOTIABLE if a not in taken] if self.name.arbitrary_address else []
        self.address = free[0] if free else NULL_ADDRESS
        return self.claim()

    # ------------------------------------------------------------------ frames in
    def handle(self, identifier: int, data: bytes, now: float = 0.0) -> list[Frame]:
        """One received frame → the frames to send (``now``: seconds, for the write time-out)."""
        _, pgn, source, dest = split_id(identifier)
        if pgn == PGN_ADDRESS_CLAIMED:
            return self._claimed(source, data)
        if dest not in (self.address, GLOBAL):
            return []
        if pgn == PGN_REQUEST and len(data) >= 3 and int.from_bytes(
                bytes(data[:3]), "little") == PGN_ADDRESS_CLAIMED:
            return self.claim()  # from 254 ("cannot claim") if the address was lost
        if self.address == NULL_ADDRESS or dest != self.address:
            return []
        if pgn == PGN_DM14:
            return self._dm14(source, bytes(data), now)
        if pgn == PGN_DM16:
            return self._dm16(source, bytes(data), now)
        return []

    def _reply(self, pgn: int, tool: int, payload: bytes) -> Frame:
        return Frame(can_id(pgn, self.address, tool), payload)

    def _failed(self, tool: int) -> list[Frame]:
        self.pending = None
        return [self._reply(PGN_DM15, tool, Dm15(0, FAILED).to_bytes())]

    def _register(self, req: Dm14) -> int | None:
        """The register a request points to, or None if it is malformed."""
        if (req.pointer_type != 0 or req.extension != MAC_REGISTERS
                or req.length not in (1, 2, 4) or req.pointer not in self.m.table):
            return None
        reg = self.m.table.lookup(req.pointer)
        return None if reg.access.value == "reserved" else reg.number

    def _dm14(self, tool: int, data: bytes, now: float) -> list[Frame]:
        if len(data) != 8:
            return self._failed(tool)
        req = Dm14.from_bytes(data)
        if req.command == OPERATION_COMPLETE:
            self.pending = None
            return []
        reg = self._register(req) if req.command in (READ, WRITE) else None
        if reg is None:
            return self._failed(tool)
        proceed = self._reply(PGN_DM15, tool, Dm15(req.length, PROCEED).to_bytes())
        if req.command == WRITE:
            self.pending = (tool, reg, req.length, now)
            return [proceed]
        value = int(self.m.read_raw(reg)[self.i]) & 0xFFFFFFFF
        return [proceed,
                self._reply(PGN_DM16, tool, Dm16(value.to_bytes(4, "little")[:req.length])
                            .to_bytes()),
                self._reply(PGN_DM15, tool, Dm15(0, COMPLETED).to_bytes())]

    def _dm16(self, tool: int, data: bytes, now: float) -> list[Frame]:
        pending = self.pending
        if pending is None or pending[0] != tool or now - pending[3] > WRITE_TIMEOUT_S:
            return self._failed(tool)
        _, reg, length, _ = pending
        try:
            msg = Dm16.from_bytes(data)
        except ValueError:
            return self._failed(tool)
        if len(msg.data) != length:
            return self._failed(tool)
        fmt = self.m.table.lookup(reg).format
        signed = getattr(fmt, "value", str(fmt)) not in ("Word32", "Word")
        value = int.from_bytes(msg.data, "little", signed=signed)
        try:
            self.m.write_raw(reg, value, index=self.i)
        except (RegisterError, ValueError):
            return self._failed(tool)
        self.pending = None
        return [self._reply(PGN_DM15, tool, Dm15(0, COMPLETED).to_bytes())]
