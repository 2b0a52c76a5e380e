"""MacTalk protocol codec (manual 5.1): pure functions, bytes in / bytes out, no I/O.

Grammar (manual 5.1)::

    message := <readsync> <address> <startreg> <endsync>
             | <readblocksync> <address> <startreg> <endsync>
             | <writesync> <address> <startreg> <datalength> <datablock> <endsync>
             | <readsamplebuffersync> <address> <endsync>
             | <gosafemodesync> <address> <endsync>
             | <goinitmodesync> <address> <endsync>
             | <writeparmflashsync> <address> <endsync>
             | <resetsync> <address> <endsync>
             | <accept>
    readsync 50h 50h 50h ... resetsync 57h 57h 57h;  endsync AAh AAh;  accept 11h 11h 11h
    address  := <unitaddr> <!unitaddr>   master 0, units 01h..FEh, broadcast FFh (3.2.156)
    startreg := <regnr> <!regnr>         regnr 01h..FFh
    datalength := <dl> <!dl>;  dataword := <databyte> <!databyte>

Every field after the sync bytes is *protected*: the byte is followed by its complement.

Decisions where the manual is ambiguous (``docs/protocol.md``, docs/model.md §16):

* **Byte order.** The text says "big-endian", but both byte examples of 5.1 send the low byte
  first (4711h is sent as 11h, 47h; 3322h as 22h, 33h), as do the MAC800 quick guide ("first
  byte = LSB") and the MIS manual. The examples are followed: little-endian, and a LongInt is
  sent low word first.
* **Length rule.** The grammar says ``dl`` is the "number of dataword in datablock", but the
  read reply example carries ``04h`` with four data bytes and the write example ``02h`` with two
  data bytes: ``dl`` counts data *bytes*, as in the examples.
* **LongInt reply rule** (5.1 example): a unit does not know whether a register is a LongInt,
  so a read of register N always returns four bytes: register N (low word) then N+1.
* **Reply frames.** The read reply of the example is ``52h 52h 52h 00h FFh 04h FBh <data>
  AAh AAh``: a write frame addressed to the master (00h) *without* ``startreg``. A write frame
  addressed to 00h is therefore decoded as a :class:`DataReply`, any other as a request.
* **Write lengths.** A write request carries 2 bytes (one 16-bit word to register N) or 4 bytes
  (a 32-bit value to register N, the MAC800 rule); other lengths are rejected here.

Examples
--------
>>> encode_read(0x13, 7).hex(" ")
'50 50 50 13 ec 07 f8 aa aa'
>>> decode(bytes.fromhex("52 52 52 10 ef 08 f7 02 fd 22 dd 33 cc aa aa"))
Request(command=<Command.WRITE: 82>, address=16, register=8, data=b'"3')
"""

from __future__ import annotations

import enum
import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field

from ...registers.errors import echo, echo_hex
from ..errors import FrameError
from .stream import Malformed, NeedMore, StreamDecoder, decode_all_with, decode_one_with

__all__ = [
    "DIALECT",
    "Command",
    "Request",
    "DataReply",
    "Accept",
    "Frame",
    "MASTER",
    "BROADCAST",
    "ACCEPT",
    "END",
    "WRITE_LENGTHS",
    "protect",
    "encode_read",
    "encode_read_block",
    "encode_write",
    "encode_write_word",
    "encode_write_long",
    "encode_read_sample_buffer",
    "encode_go_safe_mode",
    "encode_go_init_mode",
    "encode_write_flash",
    "encode_reset",
    "encode_accept",
    "encode_data_reply",
    "encode",
    "words_to_bytes",
    "bytes_to_words",
    "long_to_bytes",
    "bytes_to_long",
    "MacTalkDecoder",
    "decode",
    "decode_all",
]

#: address of the master (manual 5.1 ``masteraddr``)
MASTER = 0x00
#: broadcast address (manual 5.1 ``broadcastaddr``)
#: the name of this dialect (the MAC050–141's MacTalk, manual 5.1) in a family's ``family.yaml``
DIALECT = "mactalk16"
BROADCAST = 0xFF
#: the accept message (manual 5.1 ``accept := 11h,11h,11h``)
ACCEPT = b"\x11\x11\x11"
#: end sync (manual 5.1 ``endsync := 0AAh 0AAh``)
END = b"\xaa\xaa"
#: data lengths (bytes) a write request may carry: one word or one 32-bit value
WRITE_LENGTHS = (2, 4)
_ACCEPT_BYTE = 0x11
_END_BYTE = 0xAA


class Command(enum.IntEnum):
    """Sync byte of each MacTalk message (manual 5.1); sent three times."""

    READ = 0x50  #: read one register (reply: 4 data bytes, LongInt rule)
    READ_BLOCK = 0x51  #: read a block of registers
    WRITE = 0x52  #: write a register; also the sync of a data reply to the master
    READ_SAMPLE_BUFFER = 0x53  #: read the next sample of the sample buffer
    GO_SAFE_MODE = 0x54  #: go to SAFE_MODE (4.4.16)
    GO_INIT_MODE = 0x55  #: go to INIT_MODE (leaves SAFE_MODE)
    WRITE_FLASH = 0x56  #: write parameters to flash, then reset (no accept)
    RESET = 0x57  #: software reset (no accept)


_SYNC_BYTES = frozenset(int(c) for c in Command)
_WITH_REGISTER = (Command.READ, Command.READ_BLOCK, Command.WRITE)


@dataclass(frozen=True)
class Request:
    """A message from the master to a unit (manual 5.1).

    Attributes
    ----------
    command : Command
    address : int
        Unit address 0..255 (255 = broadcast).
    register : int or None
        ``startreg`` (1..255) for READ, READ_BLOCK and WRITE, else None.
    data : bytes
        The data bytes of a WRITE (2 or 4, low byte first), else ``b""``.
    """

    command: Command
    address: int
    register: int | None = None
    data: bytes = b""


@dataclass(frozen=True)
class DataReply:
    """Data sent by a unit to the master: a write frame to address 00h without ``startreg``
    (manual 5.1, read example). ``data`` holds the data bytes, low byte first."""

    data: bytes
    address: int = MASTER


@dataclass(frozen=True)
class Accept:
    """The accept message ``11h 11h 11h`` (manual 5.1)."""

    raw: bytes = field(default=ACCEPT, repr=False)


Frame = Request | DataReply | Accept


# ----------------------------------------------------------------------------- encoding
def _byte(value: int, what: str) -> int:
    if not isinstance(value, int) or not 0 <= value <= 0xFF:
        raise ValueError(f"{what} must be an integer 0..255, got {echo(value)}")
    return value


def protect(data: bytes | Iterable[int]) -> bytes:
    """Each byte followed by its complement (manual 5.1 ``<x> <!x>``).

    >>> protect(b"\\x13").hex(" ")
    '13 ec'
    """
    out = bytearray()
    for b in bytes(data):
        out += bytes((b, b ^ 0xFF))
    return bytes(out)


def _unit_address(address: int) -> int:
    _byte(address, "address")
    return address


def _register(register: int) -> int:
    if not isinstance(register, int) or not 1 <= register <= 0xFF:
        raise ValueError("register number must be 1..255 (regnr := 01h..0FFh), "
                         f"got {echo(register)}")
    return register


def _message(command: Command, address: int, body: bytes = b"") -> bytes:
    return bytes((command,)) * 3 + protect((_unit_address(address),)) + body + END


def encode_read(address: int, register: int) -> bytes:
    """Read register ``register`` of unit ``address`` (manual 5.1 ``readsync``)."""
    return _message(Command.READ, address, protect((_register(register),)))


def encode_read_block(address: int, register: int) -> bytes:
    """Read the block of registers starting at ``register`` (manual 5.1 ``readblocksync``)."""
    return _message(Command.READ_BLOCK, address, protect((_register(register),)))


def encode_write(address: int, register: int, data: bytes) -> bytes:
    """Write ``data`` (2 or 4 bytes, low byte first) to ``register`` (manual 5.1 ``writesync``).

    ``<datalength>`` counts data *bytes*, as in the manual's examples (the grammar's "number of
    dataword" contradicts the examples, which are followed; docs/model.md §16).
    """
    if address == MASTER:
        raise ValueError("address 0 is the master; a write to it is a data reply "
                         "(use encode_data_reply)")
    data = bytes(data)
    if len(data) not in WRITE_LENGTHS:
        raise ValueError(f"a write carries 2 or 4 data bytes, got {len(data)}")
    return _message(Command.WRITE, address,
                    protect((_register(register), len(data))) + protect(data))


def words_to_bytes(words: Sequence[int]) -> bytes:
    """16-bit words to bytes, low byte first (manual 5.1 examples)."""
    out = bytearray()
    for w in words:
        if not isinstance(w, int) or not 0 <= w <= 0xFFFF:
            raise ValueError(f"words must be integers 0..65535, got {echo(w)}")
        out += w.to_bytes(2, "little")
    return bytes(out)


def bytes_to_words(data: bytes) -> list[int]:
    """Bytes (low byte first) to 16-bit words; ``len(data)`` must be even."""
    if len(data) % 2:
        raise ValueError(f"an even number of bytes is needed, got {len(data)}")
    return [int.from_bytes(data[i:i + 2], "little") for i in range(0, len(data), 2)]


def long_to_bytes(value: int) -> bytes:
    """A 32-bit value (signed or unsigned) to 4 bytes, low byte first (low word first)."""
    if not isinstance(value, int) or not -(2**31) <= value <= 2**32 - 1:
        raise ValueError(f"value must fit in 32 bits, got {echo(value)}")
    return (value & 0xFFFFFFFF).to_bytes(4, "little")


def bytes_to_long(data: bytes, signed: bool = True) -> int:
    """4 bytes, low byte first, to a 32-bit integer."""
    if len(data) != 4:
        raise ValueError(f"4 bytes are needed, got {len(data)}")
    return int.from_bytes(data, "little", signed=signed)


def encode_write_word(address: int, register: int, word: int) -> bytes:
    """Write one 16-bit word (0..65535) to ``register``: ``dl`` = 2."""
    return encode_write(address, register, words_to_bytes([word]))


def encode_write_long(address: int, register: int, value: int) -> bytes:
    """Write a 32-bit value to ``register`` (and N+1 for a LongInt): ``dl`` = 4."""
    return encode_write(address, register, long_to_bytes(value))


def encode_read_sample_buffer(address: int) -> bytes:
    """Read the next sample of the sample buffer (manual 5.1 ``readsamplebuffersync``)."""
    return _message(Command.READ_SAMPLE_BUFFER, address)


def encode_go_safe_mode(address: int) -> bytes:
    """Go to safe mode (manual 5.1 ``gosafemodesync``, 4.4.16)."""
    return _message(Command.GO_SAFE_MODE, address)


def encode_go_init_mode(address: int) -> bytes:
    """Go to init mode (manual 5.1 ``goinitmodesync``); this is how SAFE_MODE is left."""
    return _message(Command.GO_INIT_MODE, address)


def encode_write_flash(address: int) -> bytes:
    """Write parameters to flash and reset (manual 5.1 ``writeparmflashsync``; no accept)."""
    return _message(Command.WRITE_FLASH, address)


def encode_reset(address: int) -> bytes:
    """Software reset (manual 5.1 ``resetsync``; no accept)."""
    return _message(Command.RESET, address)


def encode_accept() -> bytes:
    """The accept message ``11h 11h 11h`` (manual 5.1)."""
    return ACCEPT


def encode_data_reply(data: bytes) -> bytes:
    """A data reply to the master: ``52h×3 00h FFh <dl> <data> AAh AAh`` (manual 5.1 example)."""
    data = bytes(data)
    if len(data) > 0xFF:
        raise ValueError(f"a reply carries at most 255 data bytes, got {len(data)}")
    return _message(Command.WRITE, MASTER, protect((len(data),)) + protect(data))


def encode(frame: Frame) -> bytes:
    """Encode any decoded frame back to bytes (inverse of :func:`decode`)."""
    if isinstance(frame, Accept):
        return ACCEPT
    if isinstance(frame, DataReply):
        return encode_data_reply(frame.data)
    if frame.command == Command.WRITE:
        return encode_write(frame.address, _register(frame.register or 0), frame.data)
    if frame.command in _WITH_REGISTER:
        return _message(frame.command, frame.address, protect((_register(frame.register or 0),)))
    return _message(frame.command, frame.address)


# ----------------------------------------------------------------------------- decoding
_NeedMore = NeedMore
_Bad = Malformed


def _is_start(buf: bytes | bytearray, k: int) -> bool:
    """Could a frame start at ``k``: three identical sync bytes, or a prefix of them at the end."""
    b0 = buf[k]
    if b0 not in _SYNC_BYTES and b0 != _ACCEPT_BYTE:
        return False
    tail = buf[k:k + 3]
    return all(b == b0 for b in tail)


class _Reader:
    def __init__(self, buf: bytes | bytearray) -> None:
        self.buf = buf
        self.pos = 0

    def take(self, n: int) -> bytes:
        if self.pos + n > len(self.buf):
            raise _NeedMore
        out = bytes(self.buf[self.pos:self.pos + n])
        self.pos += n
        return out

    def protected(self, what: str) -> int:
        b, c = self.take(2)
        if c != b ^ 0xFF:
            raise _Bad(f"bad complement in {what}: {b:02X}h followed by {c:02X}h "
                       f"(expected {b ^ 0xFF:02X}h)", "bad_complement")
        return b

    def data(self, n: int, what: str) -> bytes:
        out = bytearray()
        for k in range(n):
            b, c = self.take(2)
            if b == c == _END_BYTE:
                raise _Bad(f"wrong length: datalength {n} announces {n} data bytes but the end "
                           f"sync AAh AAh follows after {k}", "wrong_length")
            if c != b ^ 0xFF:
                raise _Bad(f"bad complement in {what} byte {k}: {b:02X}h followed by {c:02X}h "
                           f"(expected {b ^ 0xFF:02X}h)", "bad_complement")
            out.append(b)
        return bytes(out)

    def end(self, after: str) -> None:
        e = self.take(2)
        if e != END:
            raise _Bad(f"missing end sync after {after}: expected AAh AAh, got "
                       f"{e[0]:02X}h {e[1]:02X}h (wrong length?)", "bad_end")


def _parse(buf: bytes | bytearray) -> tuple[Frame, int]:
    """Parse one frame at the start of ``buf``; raises _NeedMore or _Bad."""
    r = _Reader(buf)
    b0 = r.take(1)[0]
    if b0 == _ACCEPT_BYTE:
        rest = r.take(2)
        if rest != b"\x11\x11":
            raise _Bad(f"incomplete accept: 11h followed by {echo_hex(rest)} "
                       "(expected 11h 11h 11h)", "bad_sync")
        return Accept(), 3
    if b0 not in _SYNC_BYTES:
        raise _Bad(f"unknown sync byte {b0:02X}h (MacTalk syncs are 50h..57h, accept 11h)",
                   "unknown_sync")
    rest = r.take(2)
    if rest[0] != b0 or rest[1] != b0:
        raise _Bad(f"sync bytes differ: {b0:02X}h {rest[0]:02X}h {rest[1]:02X}h (expected "
                   f"three times {b0:02X}h)", "bad_sync")
    cmd = Command(b0)
    address = r.protected("address")
    if cmd == Command.WRITE and address == MASTER:
        dl = r.protected("datalength")
        data = r.data(dl, "data")
        r.end(f"{dl} data bytes")
        return DataReply(data), r.pos
    register = None
    if cmd in _WITH_REGISTER:
        register = r.protected("register number")
        if register == 0:
            raise _Bad("register number 0 is not allowed (regnr := 01h..0FFh)", "bad_register")
    if cmd == Command.WRITE:
        dl = r.protected("datalength")
        if dl not in WRITE_LENGTHS:
            raise _Bad(f"wrong length: a write carries 2 or 4 data bytes, datalength is {dl}",
                       "wrong_length")
        data = r.data(dl, "data")
        r.end(f"{dl} data bytes")
        return Request(cmd, address, register, data), r.pos
    r.end("the register number" if register is not None else "the address")
    return Request(cmd, address, register), r.pos


#: a possible frame start: a sync or accept byte twice more, or up to the end of the buffer
_START = re.compile(rb"([\x11\x50-\x57])(?:\1\1|\1\Z|\Z)")
#: a run of one byte value at the start of the buffer, by value
_RUNS = {b: re.compile(re.escape(bytes((b,))) + b"+") for b in range(256)}


def _next_start(buf: bytearray) -> int:
    """Where a frame could start after a malformed one at ``buf[0]`` (``_is_start``), skipping
    in one step the inside of a run of one sync byte: a frame at ``j`` of a run of ``m`` bytes
    ``b`` has the address byte and its complement equal (``b``, ``b``) unless ``j >= m − 4``,
    so it is malformed too. Linear in the bytes skipped."""
    k = 1
    if buf[0] in _SYNC_BYTES:
        run = _RUNS[buf[0]].match(buf)
        assert run is not None
        k = max(1, run.end() - 4)
    found = _START.search(buf, k)
    return found.start() if found else len(buf)


class MacTalkDecoder(StreamDecoder):
    """Streaming MacTalk decoder: feed arbitrary byte chunks, get frames and errors.

    Malformed input yields one :class:`FrameError` per bad frame (or run of garbage) with a
    precise reason; the decoder then resynchronises on the next possible sync (three identical
    sync bytes ``50h..57h`` or ``11h``). A frame that is still incomplete is kept until more bytes
    arrive; :meth:`flush` (call it after an inter-character timeout or at end of stream)
    reports it as truncated.

    Examples
    --------
    >>> d = MacTalkDecoder()
    >>> [e.reason for e in d.feed(bytes.fromhex("00 50 50 50 13 ec"))]
    ['unknown sync byte 00h (MacTalk syncs are 50h..57h, accept 11h)']
    >>> d.feed(bytes.fromhex("07 f8 aa aa"))
    [Request(command=<Command.READ: 80>, address=19, register=7, data=b'')]
    """

    def _parse(self, buf: bytearray) -> tuple[Frame, int]:
        return _parse(buf)

    def _is_start(self, k: int) -> bool:
        return _is_start(self._buf, k)

    def _next_start(self) -> int:
        return _next_start(self._buf)


def decode_all(data: bytes) -> list[Frame | FrameError]:
    """Decode a complete byte string: all frames and errors, a trailing partial frame reported
    as truncated."""
    return decode_all_with(MacTalkDecoder(), data)


def decode(data: bytes) -> Frame:
    """Decode exactly one frame; raise :class:`FrameError` with the reason otherwise."""
    frame: Frame = decode_one_with(MacTalkDecoder(), data)
    return frame
