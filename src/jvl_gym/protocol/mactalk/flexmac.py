"""FlexMAC codec (manual 5.2.2): W2/W4/R2/R4 headers, register index, number and address forms.

Grammar (manual 5.2.2), every header byte sent three times, every data byte protected::

    WriteWordBlock ::= <HeaderW2Q> | <HeaderW2> <RegNmb> | <HeaderW2> 0 <AddressBlock>
    (same for W4, R2, R4);  W2 = 60h, W4 = E0h, R2 = 70h, R4 = F0h, xxQ = xx + RegIndex
    RegNmb ::= <Nmb> !<Nmb>;  AddressBlock ::= WordDataBlock ::= ByteBlock ByteBlock
    ByteBlock ::= <Byte> !<Byte>;  LongDataBlock ::= 4 ByteBlocks

Header byte: bit 7 word 0 / longword 1; bits 6,5 always 11; bit 4 write 0 / read 1;
bits 3..0 the register index (0: a register number or an address follows).

Decisions, all from the manual's byte examples (``docs/protocol.md``):

* **Byte order.** "Data Format used: Big Endian", but the example writes V_SOLL = 0547H as
  ``47h B8h 05h FAh`` and the address 0412H as ``12h EDh 04h FBh``: low byte first, as in
  MacTalk (docs/model.md §16).
* **Register numbers.** The examples give V_SOLL "register number 09H, address 0412H" and
  P_IST "register number 0EH, address 041CH", while the MAC50–141 table (3.2) numbers them 5
  and 10. Both fit ``FlexMAC number = register number + 4`` and ``address = 0400h + 2·number``;
  this is what :func:`flex_number` and :func:`flex_address` implement.
* **Switch to FastMAC.** The example sends ``07FH ×3`` (read index 15), while the read index
  table lists 14 as "Use FastMAC" and 15 as "Use FlexMAC (NOP)". Both 14 and 15 are decoded as
  :attr:`FlexRead.use_fastmac`; :func:`encode_use_fastmac` sends the example's ``7Fh``.
* **Write index 8 and 9** are "P0" and "P1" in the table; the MAC50–141 has P1..P8 and the
  other pairs are (V1, V2), (A1, A2), (L1, L2), so 8 → P1 and 9 → P2.
* **Read reply.** The manual only says the reply to a read starts with a header byte (bits 6,5
  = 11). The twin answers with the request's header byte three times followed by the protected
  data (2 or 4 bytes, low byte first): :func:`encode_read_reply`.
"""

from __future__ import annotations

from dataclasses import dataclass

from ...registers.errors import echo, echo_hex
from ..errors import FrameError
from .codec16 import protect
from .stream import Malformed, NeedMore, StreamDecoder, decode_one_with

__all__ = [
    "W2",
    "W4",
    "R2",
    "R4",
    "WRITE_INDEX",
    "READ_INDEX",
    "NUMBER_OFFSET",
    "ADDRESS_BASE",
    "flex_number",
    "flex_address",
    "register_of_number",
    "register_of_address",
    "FlexWrite",
    "FlexRead",
    "header_byte",
    "encode_write",
    "encode_read",
    "encode_use_fastmac",
    "encode_read_reply",
    "decode_read_reply",
    "FlexMacDecoder",
    "decode",
]

W2, W4, R2, R4 = 0x60, 0xE0, 0x70, 0xF0
#: FlexMAC register number = MacTalk register number + NUMBER_OFFSET (5.2.2 examples)
NUMBER_OFFSET = 4
#: byte address of FlexMAC register number 0 (5.2.2 examples: 0412h = 0400h + 2·09h)
ADDRESS_BASE = 0x0400

#: write index → (name, MAC50–141 register number, data bytes) (manual 5.2.2 "Write")
WRITE_INDEX: dict[int, tuple[str, int, int]] = {
    1: ("CNTRL_BITS", 36, 2), 2: ("P_SOLL", 3, 4), 3: ("V_SOLL", 5, 2), 4: ("A_SOLL", 6, 2),
    5: ("T_SOLL", 7, 2), 6: ("KVOUT", 13, 2), 7: ("INPOSWIN", 33, 2), 8: ("P1", 49, 4),
    9: ("P2", 51, 4), 10: ("V1", 65, 2), 11: ("V2", 66, 2), 12: ("A1", 73, 2), 13: ("A2", 74, 2),
    14: ("L1", 81, 2), 15: ("L2", 82, 2),
}
#: read index → (name, register number or 0 for a command, data bytes) (manual 5.2.2 "Read")
READ_INDEX: dict[int, tuple[str, int, int]] = {
    1: ("CNTRL_BITS", 36, 2), 2: ("P_FNC", 8, 4), 3: ("P_IST", 10, 4), 4: ("V_IST", 12, 2),
    5: ("V_EXT", 120, 2), 6: ("ANINP", 122, 2), 7: ("I_NOM", 131, 2), 8: ("VF_OUT", 121, 2),
    9: ("I2T", 16, 2), 10: ("UIT", 18, 2), 11: ("FLWERR", 20, 2), 12: ("FNCERR", 24, 2),
    13: ("ERR_STAT", 35, 2), 14: ("Use FastMAC", 0, 2), 15: ("Use FlexMAC (NOP)", 0, 2),
}


def flex_number(register: int) -> int:
    """FlexMAC register number of a MAC50–141 register (5.2.2 examples: V_SOLL 5 → 09h)."""
    n = register + NUMBER_OFFSET
    if not 1 <= register or n > 0xFF:
        raise ValueError(f"register {register} has no FlexMAC number (1..{0xFF - NUMBER_OFFSET})")
    return n


def flex_address(register: int) -> int:
    """FlexMAC byte address of a MAC50–141 register (5.2.2 examples: V_SOLL → 0412h)."""
    return ADDRESS_BASE + 2 * flex_number(register)


def register_of_number(nmb: int) -> int | None:
    """MAC50–141 register of a FlexMAC register number, or None if it maps to none."""
    reg = nmb - NUMBER_OFFSET
    return reg if reg >= 1 else None


def register_of_address(address: int) -> int | None:
    """MAC50–141 register at a FlexMAC byte address, or None (odd or outside the registers)."""
    off = address - ADDRESS_BASE
    if off < 0 or off % 2:
        return None
    return register_of_number(off // 2)


@dataclass(frozen=True)
class FlexWrite:
    """A decoded FlexMAC write message. Exactly one of index, number, address is set."""

    long: bool
    data: bytes
    index: int | None = None
    number: int | None = None
    address: int | None = None

    @property
    def register(self) -> int | None:
        """The MAC50–141 register written, or None if the target maps to no register."""
        if self.index is not None:
            return WRITE_INDEX[self.index][1]
        if self.number is not None:
            return register_of_number(self.number)
        return register_of_address(self.address or 0)


@dataclass(frozen=True)
class FlexRead:
    """A decoded FlexMAC read message. Exactly one of index, number, address is set."""

    long: bool
    index: int | None = None
    number: int | None = None
    address: int | None = None

    @property
    def use_fastmac(self) -> bool:
        """Read index 14 or 15: switch the receive protocol to FastMAC (see module notes)."""
        return self.index in (14, 15)

    @property
    def register(self) -> int | None:
        """The MAC50–141 register read, or None (a command, or no register there)."""
        if self.index is not None:
            return READ_INDEX[self.index][1] or None
        if self.number is not None:
            return register_of_number(self.number)
        return register_of_address(self.address or 0)

    @property
    def header(self) -> int:
        """The header byte of this message."""
        return header_byte(read=True, long=self.long, index=self.index or 0)


FlexMessage = FlexWrite | FlexRead


def header_byte(read: bool, long: bool, index: int = 0) -> int:
    """Header byte (manual 5.2.2): bit 7 longword, bits 6,5 = 11, bit 4 read, bits 3..0 index."""
    if not 0 <= index <= 15:
        raise ValueError(f"register index must be 0..15, got {echo(index)}")
    return (0x80 if long else 0) | 0x60 | (0x10 if read else 0) | index


def _target(index: int | None, number: int | None, address: int | None) -> tuple[int, bytes]:
    given = [x is not None for x in (index, number, address)]
    if sum(given) != 1:
        raise ValueError("give exactly one of index, number, address")
    if index is not None:
        if not 1 <= index <= 15:
            raise ValueError(f"register index must be 1..15, got {index}")
        return index, b""
    if number is not None:
        if not 1 <= number <= 0xFF:
            raise ValueError(f"register number must be 1..255, got {number}")
        return 0, protect((number,))
    assert address is not None
    if not 0 <= address <= 0xFFFF:
        raise ValueError(f"address must be 0..FFFFh, got {address}")
    return 0, protect((0,)) + protect(address.to_bytes(2, "little"))


def encode_write(value: int, *, long: bool = False, index: int | None = None,
                 number: int | None = None, address: int | None = None) -> bytes:
    """A write message: header ×3, target, data (2 or 4 protected bytes, low byte first).

    >>> encode_write(0x0547, index=3).hex(" ")
    '63 63 63 47 b8 05 fa'
    """
    idx, target = _target(index, number, address)
    if idx:
        want = WRITE_INDEX[idx][2] == 4
        if want != long:
            raise ValueError(f"write index {idx} ({WRITE_INDEX[idx][0]}) is a "
                             f"{'longword' if want else 'word'}")
    n = 4 if long else 2
    lo = -(2 ** (8 * n - 1))
    if not isinstance(value, int) or not lo <= value < 2 ** (8 * n):
        raise ValueError(f"value {echo(value)} does not fit in {8 * n} bits")
    head = header_byte(read=False, long=long, index=idx)
    return bytes((head,)) * 3 + target + protect((value % 2 ** (8 * n)).to_bytes(n, "little"))


def encode_read(*, long: bool = False, index: int | None = None, number: int | None = None,
                address: int | None = None) -> bytes:
    """A read message: header ×3 and target (manual 5.2.2).

    >>> encode_read(long=True, index=3).hex(" ")
    'f3 f3 f3'
    """
    idx, target = _target(index, number, address)
    return bytes((header_byte(read=True, long=long, index=idx),)) * 3 + target


def encode_use_fastmac() -> bytes:
    """Switch the receive protocol to FastMAC: ``07FH ×3`` as in the manual's example."""
    return bytes((0x7F,)) * 3


def encode_read_reply(header: int, data: bytes) -> bytes:
    """Reply to a read (twin decision): the request's header ×3 and the protected data."""
    return bytes((header,)) * 3 + protect(data)


def decode_read_reply(data: bytes, long: bool) -> tuple[int, bytes]:
    """Decode a read reply → (header byte, data bytes); raise :class:`FrameError`."""
    n = 4 if long else 2
    if len(data) != 3 + 2 * n:
        raise FrameError(f"wrong length: a {'longword' if long else 'word'} read reply has "
                         f"{3 + 2 * n} bytes, got {len(data)}", "wrong_length", 0, data)
    h = data[0]
    if data[1] != h or data[2] != h or h & 0x60 != 0x60:
        raise FrameError(f"bad reply header {data[:3].hex(' ').upper()}", "bad_header", 0, data)
    out = bytearray()
    for k in range(n):
        b, c = data[3 + 2 * k], data[4 + 2 * k]
        if c != b ^ 0xFF:
            raise FrameError(f"bad complement in reply byte {k}: {b:02X}h followed by {c:02X}h "
                             f"(expected {b ^ 0xFF:02X}h)", "bad_complement", 0, data)
        out.append(b)
    return h, bytes(out)


_NeedMore = NeedMore
_Bad = Malformed


def _parse(buf: bytearray) -> tuple[FlexMessage, int]:
    pos = 0

    def take(n: int) -> bytes:
        nonlocal pos
        if pos + n > len(buf):
            raise _NeedMore
        out = bytes(buf[pos:pos + n])
        pos += n
        return out

    def protected(what: str) -> int:
        b, c = take(2)
        if c != b ^ 0xFF:
            raise _Bad(f"bad complement in {what}: {b:02X}h followed by {c:02X}h "
                       f"(expected {b ^ 0xFF:02X}h)", "bad_complement")
        return b

    h = take(1)[0]
    if h & 0x60 != 0x60:
        raise _Bad(f"{h:02X}h is not a FlexMAC header (bits 6,5 must be 11)", "bad_header")
    rest = take(2)
    if rest[0] != h or rest[1] != h:
        raise _Bad(f"header bytes differ: {h:02X}h {rest[0]:02X}h {rest[1]:02X}h (expected "
                   f"three times {h:02X}h)", "bad_sync")
    long, read, index = bool(h & 0x80), bool(h & 0x10), h & 0x0F
    number = address = None
    if index == 0:
        number = protected("register number")
        if number == 0:
            lo = protected("address low byte")
            hi = protected("address high byte")
            address, number = lo | hi << 8, None
    elif not read:
        want = WRITE_INDEX[index][2] == 4
        if want != long:
            raise _Bad(f"format mismatch: write index {index} ({WRITE_INDEX[index][0]}) is a "
                       f"{'longword' if want else 'word'} but the header {h:02X}h says "
                       f"{'longword' if long else 'word'}", "bad_format")
    elif index not in (14, 15) and (READ_INDEX[index][2] == 4) != long:
        want = READ_INDEX[index][2] == 4
        raise _Bad(f"format mismatch: read index {index} ({READ_INDEX[index][0]}) is a "
                   f"{'longword' if want else 'word'} but the header {h:02X}h says "
                   f"{'longword' if long else 'word'}", "bad_format")
    idx = index or None
    if read:
        return FlexRead(long, idx, number, address), pos
    data = bytes(protected(f"data byte {k}") for k in range(4 if long else 2))
    return FlexWrite(long, data, idx, number, address), pos


class FlexMacDecoder(StreamDecoder):
    """Streaming decoder of FlexMAC messages sent to the motor (manual 5.2.2).

    Same contract as :class:`~jvl_gym.protocol.mactalk.MacTalkDecoder`: frames and
    :class:`FrameError` objects in stream order, resynchronisation on the next byte with bits
    6,5 = 11 repeated three times, :meth:`flush` reports a truncated message.
    """

    def _parse(self, buf: bytearray) -> tuple[FlexMessage, int]:
        return _parse(buf)

    def _is_start(self, k: int) -> bool:
        b = self._buf[k]
        return b & 0x60 == 0x60 and all(x == b for x in self._buf[k:k + 3])

    def _truncated(self, data: bytes) -> str:
        return f"truncated FlexMAC message: {echo_hex(data)}"


def decode(data: bytes) -> FlexMessage:
    """Decode exactly one FlexMAC message; raise :class:`FrameError` otherwise."""
    message: FlexMessage = decode_one_with(FlexMacDecoder(), data, "message")
    return message
