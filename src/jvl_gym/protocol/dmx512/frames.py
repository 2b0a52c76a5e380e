"""DMX512 packets on a byte stream (MIS manual §13.1.10; the DMX512 standard's packet: a break,
the start code, then up to 512 slots of one byte).

A serial line carries the break as a line condition, which a byte stream (a TCP connection, a
pty) cannot. The stream uses the POSIX encoding of a break in received data (termios ``PARMRK``):
a break is the three bytes ``FFh 00h 00h`` (:data:`BREAK`) and a data byte FFh is sent as
``FFh FFh``; ``FFh`` followed by any other byte is a framing error and drops the packet. A
packet ends at the next break or after its 512th slot. Start code 0 is dimmer data; the motor
uses only those ("Only DMX packets with type zero will be used", §13.1.10).
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["BREAK", "SLOTS", "DmxPacket", "DmxDecoder", "encode_packet"]

BREAK = b"\xff\x00\x00"  #: a break on the byte stream (PARMRK)
SLOTS = 512  #: slots of a packet at most


@dataclass(frozen=True)
class DmxPacket:
    """One packet: its start code and slot values (slot 1 first; a DMX address *a* is
    ``slots[a - 1]``)."""

    start_code: int
    slots: bytes


def encode_packet(slots: bytes, start_code: int = 0) -> bytes:
    """A break, the start code and ``slots`` (1 … 512 bytes), FFh doubled.

    >>> encode_packet(bytes([255, 7])).hex(" ")
    'ff 00 00 00 ff ff 07'
    """
    slots = bytes(slots)
    if not 1 <= len(slots) <= SLOTS:
        raise ValueError(f"a DMX512 packet has 1 … 512 slots, got {len(slots)}")
    if not 0 <= start_code <= 255:
        raise ValueError(f"start code must be 0 … 255, got {start_code}")
    body = bytes([start_code]) + slots
    return BREAK + body.replace(b"\xff", b"\xff\xff")


class DmxDecoder:
    """Bytes of the stream in, complete packets out (module docstring).

    Attributes
    ----------
    errors : int
        Framing errors and data before the first break (dropped).
    """

    def __init__(self) -> None:
        self._data = bytearray()  # the bytes of the packet being received (start code first)
        self._in_packet = False
        self._pending = b""  # an FFh (and 00h) that may begin a break
        self.errors = 0

    def feed(self, chunk: bytes) -> list[DmxPacket]:
        """Received bytes → the packets they complete."""
        out: list[DmxPacket] = []
        buf = self._pending + bytes(chunk)
        self._pending = b""
        k = 0
        while k < len(buf):
            b = buf[k]
            if b != 0xFF:
                self._byte(b, out)
                k += 1
                continue
            if k + 1 >= len(buf):
                self._pending = buf[k:]
                break
            nxt = buf[k + 1]
            if nxt == 0xFF:
                self._byte(0xFF, out)
                k += 2
            elif nxt == 0x00:
                if k + 2 >= len(buf):
                    self._pending = buf[k:]
                    break
                if buf[k + 2] == 0x00:
                    self._break(out)
                else:
                    self._error()
                k += 3
            else:
                self._error()
                k += 2
        return out

    def flush(self) -> list[DmxPacket]:
        """The end of the stream: a packet being received is complete."""
        out: list[DmxPacket] = []
        self._pending = b""
        self._break(out)
        self._in_packet = False
        return out

    def _byte(self, b: int, out: list[DmxPacket]) -> None:
        if not self._in_packet:
            self.errors += 1
            return
        self._data.append(b)
        if len(self._data) == SLOTS + 1:
            out.append(DmxPacket(self._data[0], bytes(self._data[1:])))
            self._data.clear()
            self._in_packet = False

    def _break(self, out: list[DmxPacket]) -> None:
        if self._in_packet and len(self._data) > 1:
            out.append(DmxPacket(self._data[0], bytes(self._data[1:])))
        self._data.clear()
        self._in_packet = True

    def _error(self) -> None:
        self.errors += 1
        self._data.clear()
        self._in_packet = False
