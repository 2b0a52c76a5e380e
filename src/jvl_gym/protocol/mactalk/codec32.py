"""MacTalk of the 32-bit register families (MAC800 serial quick guide §1.3, MIS manual §18.2):
pure functions, bytes in / bytes out, no I/O.

The frames are those of the MAC050–141 MacTalk (:mod:`.codec16`: three sync bytes, every
following byte protected by its complement, ``AAh AAh`` end), with these differences:

* every register is 32 bits wide at **one** register number 1..255; the data are sent low byte
  first ("First byte = LSB", quick guide §1.3.2; MIS §18.2.4);
* the read reply names the register: ``52h×3 00h FFh <regnum> <!regnum> 04h FBh <4 data bytes>
  AAh AAh`` (quick guide §1.3.3: "RegNum … will always be the same as requested"; MIS
  §18.2.2) — a write frame to the master's address 0;
* read block (51h) replies with 128 data bytes (MIS §18.2.3), i.e. 32 registers of 4 bytes
  (decision below);
* 54h is "enter safe mode" and 55h "exit safe mode" (MIS §18.2.5, §18.2.6);
* 53h reads the sample buffer ("The sampled values are read back using the command hex 53
  SMC_READSAMPLE", MIS §8.2.63), one sample per request (decision below);
* program status and command (61h, MIS §18.2.10): the command number and its data after a
  length, every byte protected; the unit answers with 61h to the master's address and 8 status
  bytes (:class:`ProgramReply`);
* group write (59h, MIS §18.2.9): ``59h×3 <group> <sequence> <regnum> <len> <data> AAh AAh``,
  every field protected, never answered.

Grammar::

    read          50h 50h 50h  <addr> <regnum>                    AAh AAh  → reply
    read block    51h 51h 51h  <addr> <regnum>                    AAh AAh  → reply (128 bytes)
    write         52h 52h 52h  <addr> <regnum> <len> <data…>      AAh AAh  → accept
    read sample   53h 53h 53h  <addr>                             AAh AAh  → reply (16 or 0)
    enter safe    54h 54h 54h  <addr>                             AAh AAh  → accept
    exit safe     55h 55h 55h  <addr>                             AAh AAh  → accept
    write flash   56h 56h 56h  <addr>                             AAh AAh  → accept if it failed
    reset         57h 57h 57h  <addr>                             AAh AAh  → none
    group write   59h 59h 59h  <group> <seq> <regnum> <len> <data…> AAh AAh → none
    program       61h 61h 61h  <addr> <len> <command> <data…>     AAh AAh  → program reply
    reply         52h 52h 52h  00h FFh <regnum> <len> <data…>     AAh AAh
    program reply 61h 61h 61h  00h FFh <len> <status…>            AAh AAh
    accept        11h 11h 11h

Decisions where the sources are ambiguous (``docs/protocol.md``, "MacTalk of the 32-bit
families"):

* **Short writes.** A write carries ``Len`` = 4 (quick guide §1.3.2: "Len = 4"; all its
  examples) or 2 (MIS §18.2.4 and §18.2.9: "Len = 2", data ``E8h,17h,03h,FCh`` = 1000). The
  manuals do not say how two bytes fill a 32-bit register. Readings: (a) the value is the
  16-bit number extended to 32 bits as the register's format extends it, sign extension for a
  signed register and zero extension for an unsigned one; (b) always zero extension; (c) only
  the low 16 bits change (as a MAC050–141 LongInt's low word). (a) is chosen: the example's
  register then holds 1000 whatever it held before (not so under (c)), and a 2-byte write of
  −1 to a signed register writes −1 (not 65535, as under (b)). The codec keeps the data bytes;
  :func:`data_value` extends them.
* **Read block size.** MIS §18.2.3 says "64 consecutive registers" and "Len = 128, so 64
  registers is read in each block"; 64 registers of 32 bits are 256 bytes, more than a one-byte
  ``Len`` holds. ``Len`` = 128 is followed: 32 registers of 4 bytes (:data:`BLOCK_REGISTERS`).
* **Read sample buffer.** MIS §8.2.63 names the command 53h but §18.2.1 does not list it
  and no section gives its frames. Readings: (a) the request of the MAC050–141 (manual 5.1:
  ``53h×3 <addr> AAh AAh``, the next sample per request, an empty reply after the last), its
  reply in this dialect's reply frame; (b) a read block of the buffer. (a) is chosen, the one
  frame the MacTalk family already has for it: the reply names the register of the first
  channel (SAMPLE1, as a read reply names the register it answers) and carries one sample,
  the four channels as 32-bit values (16 bytes), or no data after the last of REC_CNT
  samples; the next request starts again at the first.
* **Misprints in the quick guide's examples** (each is a unit test as decided here): §1.3.3
  example 1 sends the register number as ``05h,F6h`` and the reply ``05h,F6h``, whose
  complement is wrong (05h is followed by FAh, as in the block description), and calls the
  value 258h "500" (258h = 600); §1.3.3 example 2 reads register 3 but its reply names register
  5 (the block description: "This will always be the same as requested": 3); §1.3.4 "Setting
  position 100,000 … on motor 8" transmits address ``07h,F8h`` (7; the bytes are followed).

Examples
--------
>>> encode_read(8, 10).hex(" ")
'50 50 50 08 f7 0a f5 aa aa'
>>> decode(bytes.fromhex("52 52 52 00 ff 0a f5 04 fb 08 f7 bd 42 03 fc 00 ff aa aa"))
Reply(register=10, data=b'\\x08\\xbd\\x03\\x00')
"""

from __future__ import annotations

import enum
import re
from dataclasses import dataclass

from ...registers.errors import echo, echo_hex
from ..errors import FrameError
from .codec16 import ACCEPT, END, MASTER, Accept, _Reader, protect
from .stream import Malformed, StreamDecoder, decode_all_with, decode_one_with

__all__ = [
    "DIALECT",
    "Command",
    "Request",
    "GroupWrite",
    "Reply",
    "ProgramReply",
    "Accept",
    "Frame",
    "MASTER",
    "BROADCAST",
    "ACCEPT",
    "END",
    "WRITE_LENGTHS",
    "READ_LENGTH",
    "BLOCK_REGISTERS",
    "BLOCK_LENGTH",
    "encode_read",
    "encode_read_block",
    "encode_write",
    "encode_write_value",
    "encode_read_sample",
    "encode_enter_safe_mode",
    "encode_exit_safe_mode",
    "encode_write_flash",
    "encode_reset",
    "encode_group_write",
    "encode_reply",
    "encode_program",
    "encode_program_reply",
    "encode_accept",
    "encode",
    "value_bytes",
    "data_value",
    "MacTalk32Decoder",
    "decode",
    "decode_all",
]

#: broadcast address (MIS §8.2.88: MY_ADDR 255 = broadcast)
#: the name of this dialect (the 32-bit register families' MacTalk) in a family's ``family.yaml``
DIALECT = "mactalk32"
BROADCAST = 0xFF
#: data lengths (bytes) a write or group write may carry (MIS §18.2.4; quick guide §1.3.2)
WRITE_LENGTHS = (2, 4)
#: data bytes of a read reply ("The length will always be 4", quick guide §1.3.3, MIS §18.2.2)
READ_LENGTH = 4
#: data bytes of a read-block reply (MIS §18.2.3: "Len = 128")
BLOCK_LENGTH = 128
#: registers of a read-block reply: 128 bytes of 32-bit registers (decision, see above)
BLOCK_REGISTERS = BLOCK_LENGTH // 4
_ACCEPT_BYTE = 0x11


class Command(enum.IntEnum):
    """Sync byte of each command (MIS §18.2.1); sent three times."""

    READ = 0x50  #: read one register (reply 52h with the register number, 4 bytes)
    READ_BLOCK = 0x51  #: read 32 registers (reply 52h, 128 bytes)
    WRITE = 0x52  #: write a register (accept); also the sync of the reply to the master
    READ_SAMPLE = 0x53  #: the next sample of the sample buffer (reply 52h; MIS §8.2.63)
    ENTER_SAFE_MODE = 0x54  #: enter safe mode (accept; MIS §18.2.5)
    EXIT_SAFE_MODE = 0x55  #: exit safe mode (accept; MIS §18.2.6)
    WRITE_FLASH = 0x56  #: registers to flash, then reset (accept only if it failed; §18.2.7)
    RESET = 0x57  #: reset the controller (no reply; MIS §18.2.8)
    GROUP_WRITE = 0x59  #: write a register of every unit of a group (no reply; MIS §18.2.9)
    PROGRAM = 0x61  #: program status and command (reply 61h with 8 status bytes; MIS §18.2.10)


_SYNC_BYTES = frozenset(int(c) for c in Command)
_WITH_REGISTER = (Command.READ, Command.READ_BLOCK, Command.WRITE)


@dataclass(frozen=True)
class Request:
    """A command from the master to one unit (or to all, address FFh).

    Attributes
    ----------
    command : Command
        Any command but :attr:`Command.GROUP_WRITE` (:class:`GroupWrite`).
    address : int
        Unit address 1..255 (255 = broadcast).
    register : int or None
        Register number 1..255 for READ, READ_BLOCK and WRITE, else None.
    data : bytes
        The data of a WRITE (2 or 4 bytes, low byte first); of a PROGRAM the command number and
        its data (1 … 5 bytes); else ``b""``.
    """

    command: Command
    address: int
    register: int | None = None
    data: bytes = b""


@dataclass(frozen=True)
class GroupWrite:
    """A group write (MIS §18.2.9): every unit whose group id is ``group`` writes ``data`` to
    ``register``, unless ``sequence`` is the sequence of the last group write it received.

    Attributes
    ----------
    group, sequence : int
        0..255.
    register : int
        1..255.
    data : bytes
        2 or 4 bytes, low byte first.
    """

    group: int
    sequence: int
    register: int
    data: bytes


@dataclass(frozen=True)
class Reply:
    """A unit's data for the master: the register it was asked for and its data (4 bytes for a
    read, 128 for a read block), low byte first (quick guide §1.3.3; MIS §18.2.2, §18.2.3)."""

    register: int
    data: bytes


@dataclass(frozen=True)
class ProgramReply:
    """A unit's answer to a program command (MIS §18.2.10): program state, program pointer
    (16 bit), stack pointer, program checksum (16 bit), inputs, outputs — 8 bytes."""

    data: bytes


Frame = Request | GroupWrite | Reply | ProgramReply | Accept


# ----------------------------------------------------------------------------- encoding
def _byte(value: int, what: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= 0xFF:
        raise ValueError(f"{what} must be an integer 0..255, got {echo(value)}")
    return value


def _register(register: int | None) -> int:
    if isinstance(register, bool) or not isinstance(register, int) or not 1 <= register <= 0xFF:
        raise ValueError(f"register number must be 1..255 (MIS §18.2: 'numbered 1-255'), "
                         f"got {echo(register)}")
    return register


def _unit(address: int) -> int:
    _byte(address, "address")
    if address == MASTER:
        raise ValueError("address 0 is the master's; a frame to it is a reply (encode_reply)")
    return address


def _write_data(data: bytes) -> bytes:
    data = bytes(data)
    if len(data) not in WRITE_LENGTHS:
        raise ValueError(f"a write carries 2 or 4 data bytes (MIS §18.2.4), got {len(data)}")
    return data


def _message(command: Command, fields: bytes, data: bytes = b"") -> bytes:
    return bytes((command,)) * 3 + protect(fields) + protect(data) + END


def encode_read(address: int, register: int) -> bytes:
    """Read register ``register`` of unit ``address`` (quick guide §1.3.3; MIS §18.2.2)."""
    return _message(Command.READ, bytes((_unit(address), _register(register))))


def encode_read_block(address: int, register: int) -> bytes:
    """Read the 32 registers from ``register`` on (MIS §18.2.3)."""
    return _message(Command.READ_BLOCK, bytes((_unit(address), _register(register))))


def encode_write(address: int, register: int, data: bytes) -> bytes:
    """Write 2 or 4 data bytes (low byte first) to ``register`` (quick guide §1.3.2; MIS
    §18.2.4)."""
    data = _write_data(data)
    return _message(Command.WRITE, bytes((_unit(address), _register(register), len(data))), data)


def value_bytes(value: int, length: int = 4) -> bytes:
    """``value`` as ``length`` (2 or 4) bytes, low byte first: a signed or unsigned number that
    fits (−2**31 … 2**32 − 1 for 4 bytes, −2**15 … 2**16 − 1 for 2).

    >>> value_bytes(230000).hex(" ")
    '70 82 03 00'
    """
    if length not in WRITE_LENGTHS:
        raise ValueError(f"length must be 2 or 4, got {echo(length)}")
    bits = 8 * length
    if isinstance(value, bool) or not isinstance(value, int) or not (
            -(2 ** (bits - 1)) <= value < 2**bits):
        raise ValueError(f"value must fit in {bits} bits, got {echo(value)}")
    return (value & (2**bits - 1)).to_bytes(length, "little")


def data_value(data: bytes, signed: bool = True) -> int:
    """The number in ``data`` (low byte first), extended as a signed (``signed``) or unsigned
    register extends it (the short-write decision above).

    >>> data_value(bytes.fromhex("e8 03")), data_value(bytes.fromhex("ff ff"), signed=False)
    (1000, 65535)
    """
    return int.from_bytes(bytes(data), "little", signed=signed)


def encode_write_value(address: int, register: int, value: int, length: int = 4) -> bytes:
    """Write the number ``value`` in ``length`` (4 or 2) bytes to ``register``."""
    return encode_write(address, register, value_bytes(value, length))


def encode_read_sample(address: int) -> bytes:
    """Read the next sample of the sample buffer (MIS §8.2.63; the frame is a decision,
    see above)."""
    return _message(Command.READ_SAMPLE, bytes((_unit(address),)))


def encode_enter_safe_mode(address: int) -> bytes:
    """Enter safe mode (MIS §18.2.5)."""
    return _message(Command.ENTER_SAFE_MODE, bytes((_unit(address),)))


def encode_exit_safe_mode(address: int) -> bytes:
    """Exit safe mode (MIS §18.2.6)."""
    return _message(Command.EXIT_SAFE_MODE, bytes((_unit(address),)))


def encode_write_flash(address: int) -> bytes:
    """Write the registers to flash, then reset (MIS §18.2.7)."""
    return _message(Command.WRITE_FLASH, bytes((_unit(address),)))


def encode_reset(address: int) -> bytes:
    """Reset the controller (MIS §18.2.8)."""
    return _message(Command.RESET, bytes((_unit(address),)))


def encode_group_write(group: int, sequence: int, register: int, data: bytes) -> bytes:
    """Group write (MIS §18.2.9): ``data`` (2 or 4 bytes) to ``register`` of every unit of
    ``group``; change ``sequence`` for every new write."""
    data = _write_data(data)
    fields = bytes((_byte(group, "group"), _byte(sequence, "sequence"), _register(register),
                    len(data)))
    return _message(Command.GROUP_WRITE, fields, data)


def encode_reply(register: int, data: bytes) -> bytes:
    """A unit's reply to the master: ``52h×3 00h FFh <regnum> <len> <data> AAh AAh`` (quick
    guide §1.3.3; MIS §18.2.2, §18.2.3)."""
    data = bytes(data)
    if len(data) > 0xFF:
        raise ValueError(f"a reply carries at most 255 data bytes, got {len(data)}")
    return _message(Command.WRITE, bytes((MASTER, _register(register), len(data))), data)


def encode_program(address: int, command: int, data: bytes = b"") -> bytes:
    """Program status and command (MIS §18.2.10): ``command`` (0 … 7) and its data bytes
    (e.g. start and end address of command 4, 16 bits each, low byte first)."""
    body = bytes((_byte(command, "program command"),)) + bytes(data)
    if len(body) > 5:
        raise ValueError(f"a program command carries at most 4 data bytes, got {len(data)}")
    return _message(Command.PROGRAM, bytes((_unit(address), len(body))), body)


def encode_program_reply(data: bytes) -> bytes:
    """A unit's answer to a program command: 8 status bytes (MIS §18.2.10)."""
    data = bytes(data)
    if len(data) != 8:
        raise ValueError(f"the program status is 8 bytes, got {len(data)}")
    return _message(Command.PROGRAM, bytes((MASTER, len(data))), data)


def encode_accept() -> bytes:
    """The accept ``11h 11h 11h``."""
    return ACCEPT


def encode(frame: Frame) -> bytes:
    """Encode any decoded frame back to bytes (inverse of :func:`decode`)."""
    if isinstance(frame, Accept):
        return ACCEPT
    if isinstance(frame, Reply):
        return encode_reply(frame.register, frame.data)
    if isinstance(frame, ProgramReply):
        return encode_program_reply(frame.data)
    if isinstance(frame, GroupWrite):
        return encode_group_write(frame.group, frame.sequence, frame.register, frame.data)
    if frame.command == Command.PROGRAM:
        return encode_program(frame.address, frame.data[0], frame.data[1:])
    if frame.command == Command.WRITE:
        return encode_write(frame.address, _register(frame.register), frame.data)
    if frame.command in _WITH_REGISTER:
        return _message(frame.command, bytes((_unit(frame.address), _register(frame.register))))
    if frame.command == Command.GROUP_WRITE:
        raise ValueError("a group write is a GroupWrite frame")
    return _message(frame.command, bytes((_unit(frame.address),)))


# ----------------------------------------------------------------------------- decoding
def _register_field(r: _Reader, what: str = "register number") -> int:
    register = r.protected(what)
    if register == 0:
        raise Malformed("register number 0 is not allowed (registers are numbered 1-255)",
                        "bad_register")
    return register


def _write_length(r: _Reader) -> int:
    n = r.protected("length")
    if n not in WRITE_LENGTHS:
        raise Malformed(f"wrong length: a write carries 2 or 4 data bytes, Len is {n}",
                        "wrong_length")
    return n


def _parse(buf: bytes | bytearray) -> tuple[Frame, int]:
    """Parse one frame at the start of ``buf``; raises NeedMore or Malformed."""
    r = _Reader(buf)
    b0 = r.take(1)[0]
    if b0 == _ACCEPT_BYTE:
        rest = r.take(2)
        if rest != b"\x11\x11":
            raise Malformed(f"incomplete accept: 11h followed by {echo_hex(rest)} "
                            "(expected 11h 11h 11h)", "bad_sync")
        return Accept(), 3
    if b0 not in _SYNC_BYTES:
        raise Malformed(f"unknown sync byte {b0:02X}h (the 32-bit MacTalk syncs are 50h..57h, "
                        "59h, 61h, accept 11h)", "unknown_sync")
    rest = r.take(2)
    if rest[0] != b0 or rest[1] != b0:
        raise Malformed(f"sync bytes differ: {b0:02X}h {rest[0]:02X}h {rest[1]:02X}h "
                        f"(expected three times {b0:02X}h)", "bad_sync")
    cmd = Command(b0)
    if cmd == Command.GROUP_WRITE:
        group = r.protected("group")
        sequence = r.protected("sequence")
        register = _register_field(r)
        n = _write_length(r)
        data = r.data(n, "data")
        r.end(f"{n} data bytes")
        return GroupWrite(group, sequence, register, data), r.pos
    address = r.protected("address")
    if cmd == Command.WRITE and address == MASTER:
        register = _register_field(r)
        n = r.protected("length")
        data = r.data(n, "data")
        r.end(f"{n} data bytes")
        return Reply(register, data), r.pos
    if cmd == Command.PROGRAM:
        n = r.protected("length")
        if address == MASTER:
            data = r.data(n, "status")
            r.end(f"{n} status bytes")
            return ProgramReply(data), r.pos
        if not 1 <= n <= 5:
            raise Malformed(f"wrong length: a program command carries 1 … 5 bytes, Len is {n}",
                            "wrong_length")
        data = r.data(n, "data")
        r.end(f"{n} data bytes")
        return Request(cmd, address, None, data), r.pos
    if address == MASTER:
        raise Malformed(f"{cmd.name} addressed to 00h, the master's address", "bad_address")
    if cmd in _WITH_REGISTER:
        register = _register_field(r)
        if cmd == Command.WRITE:
            n = _write_length(r)
            data = r.data(n, "data")
            r.end(f"{n} data bytes")
            return Request(cmd, address, register, data), r.pos
        r.end("the register number")
        return Request(cmd, address, register), r.pos
    r.end("the address")
    return Request(cmd, address), r.pos


#: a possible frame start: a sync or accept byte twice more, or up to the end of the buffer
_START = re.compile(rb"([\x11\x50-\x57\x59\x61])(?:\1\1|\1\Z|\Z)")
_RUNS = {b: re.compile(re.escape(bytes((b,))) + b"+") for b in _SYNC_BYTES}


def _is_start(buf: bytes | bytearray, k: int) -> bool:
    b0 = buf[k]
    if b0 not in _SYNC_BYTES and b0 != _ACCEPT_BYTE:
        return False
    return all(b == b0 for b in buf[k:k + 3])


def _next_start(buf: bytearray) -> int:
    """Where a frame could start after a malformed one at ``buf[0]``; the inside of a run of one
    sync byte is skipped in one step (a frame starting in it would have a field equal to its
    complement), as in :func:`.codec16._next_start`."""
    k = 1
    if buf[0] in _SYNC_BYTES:
        run = _RUNS[buf[0]].match(buf)
        assert run is not None
        k = max(1, run.end() - 4)
    found = _START.search(buf, k)
    return found.start() if found else len(buf)


class MacTalk32Decoder(StreamDecoder):
    """Streaming decoder of the 32-bit MacTalk: feed byte chunks, get frames and
    :class:`~.errors.FrameError` objects (one per bad frame or run of garbage, then a
    resynchronisation on the next possible sync); :meth:`flush` reports a held-back partial
    frame as truncated.

    Examples
    --------
    >>> d = MacTalk32Decoder()
    >>> d.feed(bytes.fromhex("50 50 50 08 f7 23"))
    []
    >>> d.feed(bytes.fromhex("dc aa aa"))
    [Request(command=<Command.READ: 80>, address=8, register=35, data=b'')]
    """

    def _parse(self, buf: bytearray) -> tuple[Frame, int]:
        return _parse(buf)

    def _is_start(self, k: int) -> bool:
        return _is_start(self._buf, k)

    def _next_start(self) -> int:
        return _next_start(self._buf)


def decode_all(data: bytes) -> list[Frame | FrameError]:
    """All frames and errors of a complete byte string (a trailing partial frame: truncated)."""
    return decode_all_with(MacTalk32Decoder(), data)


def decode(data: bytes) -> Frame:
    """Decode exactly one frame; raise :class:`~.errors.FrameError` with the reason otherwise."""
    frame: Frame = decode_one_with(MacTalk32Decoder(), data)
    return frame

