"""Modbus RTU codec of the MIS/SMC integrated step motors (MIS manual §12): pure functions and
small state objects, bytes in / bytes out, no I/O and no register names.

Frames (MIS manual §12.4, §12.5; the CRC-16 and the exception reply are those of the Modbus
specification the manual refers to, §12.1)::

    read request   <slave> 03h <index hi> <index lo> <count hi> <count lo>       <crc lo> <crc hi>
    read reply     <slave> 03h <bytes = 2·count> <word hi> <word lo> …           <crc lo> <crc hi>
    write request  <slave> 10h <index hi> <index lo> <count hi> <count lo> <bytes = 2·count>
                   <word hi> <word lo> …                                         <crc lo> <crc hi>
    write reply    <slave> 10h <index hi> <index lo> <count hi> <count lo>       <crc lo> <crc hi>
    exception      <slave> <function | 80h> <exception code>                     <crc lo> <crc hi>

Addressing (MIS manual §12.3): every motor register *n* is 32 bits wide and appears as two 16-bit
Modbus words, the **low word first** (at index 2n) and the high word at 2n + 1, each word
big-endian on the wire. A register holding 123456789 (075BCD15h) reads as ``CD 15 07 5B``. Every
register also appears in the alternative window at 40 000 (:class:`AddressMap`, where the two
readings of the manual's text are described). The PDO1/PDO2 remapping registers (MIS manual
§12.6.3, §12.6.4) are 32-bit registers at fixed Modbus indices F200h … F70Eh; :class:`PdoTable`
holds their set-up.

Limits (MIS manual §12.4, §12.5, §12.3): at most 16 words per request; a write covers whole
32-bit registers only (even start index in the 2n window, even word count), so that the two halves
of a register are never updated separately.

Frame timing (Modbus serial line guide, referred to by MIS manual §12.1): a silence of 3.5
character times ends a frame (fixed 1.75 ms above 19 200 baud); :class:`RtuFramer` splits a byte
stream into frames by these silences and, as the frames of the two supported requests have a
length that their first bytes determine, also as soon as a complete frame with a valid CRC has
arrived (which is what makes RTU framing over TCP work without waiting for a silence).

Examples
--------
>>> encode_read_request(42, 2 * 10, 2).hex(" ")
'2a 03 00 14 00 02 82 14'
>>> decode_request(bytes.fromhex("2a 03 00 14 00 02 82 14"))
ReadRequest(slave=42, index=20, count=2)
>>> words_of(123456789)
(52501, 1883)
"""

from __future__ import annotations

import enum
from collections.abc import Sequence
from dataclasses import dataclass, field

from ...registers.errors import echo
from ..errors import FrameError

__all__ = [
    "READ_HOLDING_REGISTERS",
    "WRITE_MULTIPLE_REGISTERS",
    "BROADCAST",
    "MAX_WORDS",
    "MAX_FRAME",
    "ALT_OFFSET",
    "PDO_BASES",
    "PDO_SLOTS",
    "BAUD_RATES",
    "ExceptionCode",
    "ModbusError",
    "ReadRequest",
    "WriteRequest",
    "OtherRequest",
    "Request",
    "ReadResponse",
    "WriteResponse",
    "ExceptionResponse",
    "Response",
    "crc16",
    "append_crc",
    "crc_ok",
    "encode_read_request",
    "encode_write_request",
    "encode_read_response",
    "encode_write_response",
    "encode_exception",
    "decode_request",
    "decode_response",
    "request_length",
    "check_request",
    "whole_registers",
    "ModbusSetup",
    "words_of",
    "value_of",
    "Area",
    "WordRef",
    "AddressMap",
    "PdoTable",
    "SerialFormat",
    "decode_setup",
    "char_time",
    "silence",
    "RtuFramer",
]

#: function code "Read Holding Registers" (MIS manual §12.4)
READ_HOLDING_REGISTERS = 0x03
#: function code "Write Multiple Registers" (MIS manual §12.5)
WRITE_MULTIPLE_REGISTERS = 0x10
#: the broadcast slave address: writes only, never answered (MIS manual §12.4, §12.5)
BROADCAST = 0
#: most 16-bit words a request may read or write (MIS manual §12.4, §12.5: "16 or lower")
MAX_WORDS = 16
#: longest RTU frame (Modbus serial line guide: 256 bytes)
MAX_FRAME = 256
#: offset of the alternative register window (MIS manual §12.3)
ALT_OFFSET = 40000
#: Modbus index of RX_SETUP[0], TX_SETUP[0] and VALUE[0] of PDO1 and PDO2 (MIS manual §12.6.3,
#: §12.6.4); entry k of each block is at base + 2k
PDO_BASES: dict[int, dict[str, int]] = {
    1: {"rx_setup": 0xF200, "tx_setup": 0xF300, "value": 0xF400},
    2: {"rx_setup": 0xF500, "tx_setup": 0xF600, "value": 0xF700},
}
#: 32-bit registers in each PDO block (MIS manual §12.6: "[0..7]")
PDO_SLOTS = 8
#: baud rate of each value of the baud-rate registers (MIS manual §12.1 lists 0..6; the
#: register BAUD_RATE, §8.2.84, adds 7 = 921600)
BAUD_RATES = (9600, 19200, 38400, 57600, 115200, 230400, 460800, 921600)

_FIXED_T35 = 1.75e-3  # Modbus serial line guide 2.5.1.1: above 19 200 baud
_FIXED_T15 = 0.75e-3


class ExceptionCode(enum.IntEnum):
    """Exception codes of the Modbus specification (MIS manual §12.1 names code 1)."""

    ILLEGAL_FUNCTION = 1  #: any function other than 03h and 10h (MIS manual §12.1)
    ILLEGAL_DATA_ADDRESS = 2  #: no such register, unaligned write, unconfigured PDO entry
    ILLEGAL_DATA_VALUE = 3  #: word count 0 or above 16, byte count ≠ 2·count, bad frame length
    SERVER_DEVICE_FAILURE = 4  #: the register refused the value for another reason
    ACKNOWLEDGE = 5
    SERVER_DEVICE_BUSY = 6
    MEMORY_PARITY_ERROR = 8
    GATEWAY_PATH_UNAVAILABLE = 10
    GATEWAY_TARGET_FAILED = 11


class ModbusError(Exception):
    """A request that is answered with an exception reply (nothing is changed).

    Parameters
    ----------
    code : ExceptionCode
    reason : str
        Human-readable reason (for logs and tests).
    """

    def __init__(self, code: ExceptionCode, reason: str) -> None:
        super().__init__(reason)
        self.code = ExceptionCode(code)
        self.reason = reason

    def __repr__(self) -> str:
        return f"ModbusError({self.code.name}: {self.reason!r})"


# ----------------------------------------------------------------------------- frames
@dataclass(frozen=True)
class ReadRequest:
    """Read Holding Registers (MIS manual §12.4): ``count`` words from Modbus index ``index``."""

    slave: int
    index: int
    count: int


@dataclass(frozen=True)
class WriteRequest:
    """Write Multiple Registers (MIS manual §12.5).

    Attributes
    ----------
    slave, index, count : int
        Header fields as sent.
    byte_count : int
        The "Number of bytes" field as sent (checked against ``count`` by :func:`check_request`).
    words : tuple of int
        The data words (0..65535), in index order.
    """

    slave: int
    index: int
    count: int
    byte_count: int
    words: tuple[int, ...]


@dataclass(frozen=True)
class OtherRequest:
    """A frame with a valid CRC whose function the MIS does not support (MIS manual §12.1:
    exception 1), or whose length does not fit its function (``malformed`` gives the reason)."""

    slave: int
    function: int
    data: bytes = b""
    malformed: str = ""


Request = ReadRequest | WriteRequest | OtherRequest


@dataclass(frozen=True)
class ReadResponse:
    """Reply to a read (MIS manual §12.4): the words read."""

    slave: int
    words: tuple[int, ...]


@dataclass(frozen=True)
class WriteResponse:
    """Reply to a write (MIS manual §12.5): the request's index and count, repeated."""

    slave: int
    index: int
    count: int


@dataclass(frozen=True)
class ExceptionResponse:
    """Exception reply: the function code with bit 7 set and the exception code."""

    slave: int
    function: int
    code: int  #: an :class:`ExceptionCode` when it is one of the specification's


Response = ReadResponse | WriteResponse | ExceptionResponse


# ----------------------------------------------------------------------------- CRC
def _crc_table() -> tuple[int, ...]:
    table = []
    for byte in range(256):
        crc = byte
        for _ in range(8):
            crc = (crc >> 1) ^ 0xA001 if crc & 1 else crc >> 1
        table.append(crc)
    return tuple(table)


_CRC_TABLE = _crc_table()


def crc16(data: bytes | bytearray | memoryview) -> int:
    """CRC-16/MODBUS of ``data`` (polynomial A001h reflected, initial FFFFh, no final XOR).

    >>> hex(crc16(b"123456789"))
    '0x4b37'
    """
    crc = 0xFFFF
    for b in bytes(data):
        crc = (crc >> 8) ^ _CRC_TABLE[(crc ^ b) & 0xFF]
    return crc


def append_crc(body: bytes | bytearray) -> bytes:
    """``body`` followed by its CRC, low byte first (MIS manual §12.4 "CRC1, CRC2")."""
    return bytes(body) + crc16(body).to_bytes(2, "little")


def crc_ok(frame: bytes | bytearray) -> bool:
    """True if ``frame`` (at least 4 bytes) ends with the CRC of the bytes before it."""
    return len(frame) >= 4 and crc16(frame[:-2]) == int.from_bytes(frame[-2:], "little")


# ----------------------------------------------------------------------------- encoding
def _check(value: int, lo: int, hi: int, what: str) -> int:
    if not isinstance(value, int) or isinstance(value, bool) or not lo <= value <= hi:
        raise ValueError(f"{what} must be an integer {lo}..{hi}, got {echo(value)}")
    return value


def encode_read_request(slave: int, index: int, count: int) -> bytes:
    """Read Holding Registers request (MIS manual §12.4). ``count`` is not limited here, so that
    tests can send requests the motor refuses; the motor's limit is :data:`MAX_WORDS`."""
    _check(slave, 0, 255, "slave address")
    _check(index, 0, 0xFFFF, "Modbus index")
    _check(count, 0, 0xFFFF, "word count")
    return append_crc(bytes((slave, READ_HOLDING_REGISTERS)) + index.to_bytes(2, "big")
                      + count.to_bytes(2, "big"))


def encode_write_request(slave: int, index: int, words: Sequence[int],
                         count: int | None = None) -> bytes:
    """Write Multiple Registers request (MIS manual §12.5): ``words`` (0..65535 each) from
    ``index``. ``count`` (default: ``len(words)``) may be given to build inconsistent frames."""
    _check(slave, 0, 255, "slave address")
    _check(index, 0, 0xFFFF, "Modbus index")
    data = b"".join(_check(w, 0, 0xFFFF, "word").to_bytes(2, "big") for w in words)
    if len(data) > 0xFF:
        raise ValueError(f"{len(words)} words do not fit the byte-count field")
    n = len(words) if count is None else _check(count, 0, 0xFFFF, "word count")
    return append_crc(bytes((slave, WRITE_MULTIPLE_REGISTERS)) + index.to_bytes(2, "big")
                      + n.to_bytes(2, "big") + bytes((len(data),)) + data)


def encode_read_response(slave: int, words: Sequence[int]) -> bytes:
    """Read reply (MIS manual §12.4): byte count, then each word big-endian."""
    data = b"".join(_check(w, 0, 0xFFFF, "word").to_bytes(2, "big") for w in words)
    return append_crc(bytes((_check(slave, 0, 255, "slave address"), READ_HOLDING_REGISTERS,
                             len(data))) + data)


def encode_write_response(slave: int, index: int, count: int) -> bytes:
    """Write reply (MIS manual §12.5): the request's index and count, repeated."""
    return append_crc(bytes((_check(slave, 0, 255, "slave address"), WRITE_MULTIPLE_REGISTERS))
                      + _check(index, 0, 0xFFFF, "Modbus index").to_bytes(2, "big")
                      + _check(count, 0, 0xFFFF, "word count").to_bytes(2, "big"))


def encode_exception(slave: int, function: int, code: int) -> bytes:
    """Exception reply: ``<slave> <function | 80h> <code> <crc>`` (Modbus specification; MIS
    manual §12.1 "Exception replies")."""
    return append_crc(bytes((_check(slave, 0, 255, "slave address"),
                             _check(function, 0, 255, "function") | 0x80,
                             _check(int(code), 0, 255, "exception code"))))


# ----------------------------------------------------------------------------- decoding
def request_length(head: bytes | bytearray) -> int | None:
    """Length of the request frame that starts with ``head`` if its function fixes it: 8 for a
    read (MIS manual §12.4), 9 + byte count for a write (§12.5, needs 7 bytes); else None."""
    if len(head) < 2:
        return None
    if head[1] == READ_HOLDING_REGISTERS:
        return 8
    if head[1] == WRITE_MULTIPLE_REGISTERS and len(head) >= 7:
        return 9 + head[6]
    return None


def decode_request(frame: bytes | bytearray) -> Request:
    """Decode one complete request frame (MIS manual §12.4, §12.5).

    A frame whose CRC is right but whose length does not fit its function decodes as an
    :class:`OtherRequest` with ``malformed`` set (answered with exception 3).

    Raises
    ------
    FrameError
        ``too_short`` (under 4 bytes), ``too_long`` (over 256) or ``bad_crc``: the frame is
        discarded without a reply.
    """
    frame = bytes(frame)
    if len(frame) < 4:
        raise FrameError(f"Modbus frame of {len(frame)} bytes: at least 4 needed", "too_short",
                         data=frame)
    if len(frame) > MAX_FRAME:
        raise FrameError(f"Modbus frame of {len(frame)} bytes: at most {MAX_FRAME}", "too_long",
                         data=frame)
    if not crc_ok(frame):
        got = int.from_bytes(frame[-2:], "little")
        raise FrameError(f"bad CRC: frame carries {got:04X}h, bytes give "
                         f"{crc16(frame[:-2]):04X}h", "bad_crc", data=frame)
    slave, function, body = frame[0], frame[1], frame[2:-2]
    if function == READ_HOLDING_REGISTERS:
        if len(body) != 4:
            return OtherRequest(slave, function, body, f"read request with {len(body)} data "
                                "bytes (4 expected)")
        return ReadRequest(slave, int.from_bytes(body[0:2], "big"),
                           int.from_bytes(body[2:4], "big"))
    if function == WRITE_MULTIPLE_REGISTERS:
        if len(body) < 5 or len(body) != 5 + body[4]:
            return OtherRequest(slave, function, body, f"write request with {len(body)} data "
                                "bytes that do not match its byte count")
        data = body[5:]
        if len(data) % 2:
            return OtherRequest(slave, function, body, f"odd byte count {len(data)}")
        words = tuple(int.from_bytes(data[k:k + 2], "big") for k in range(0, len(data), 2))
        return WriteRequest(slave, int.from_bytes(body[0:2], "big"),
                            int.from_bytes(body[2:4], "big"), body[4], words)
    return OtherRequest(slave, function, body)


def check_request(req: Request) -> None:
    """Structural checks of the Modbus specification on a decoded request.

    Raises
    ------
    ModbusError
        ILLEGAL_FUNCTION for other functions (MIS manual §12.1); ILLEGAL_DATA_VALUE for a word
        count of 0 or above :data:`MAX_WORDS` (MIS manual §12.4, §12.5), a byte count other than
        2·count, or a frame whose length does not fit its function.
    """
    if isinstance(req, OtherRequest):
        if req.function in (READ_HOLDING_REGISTERS, WRITE_MULTIPLE_REGISTERS):
            raise ModbusError(ExceptionCode.ILLEGAL_DATA_VALUE, req.malformed)
        raise ModbusError(ExceptionCode.ILLEGAL_FUNCTION,
                          f"function {req.function:02X}h is not supported (03h and 10h only)")
    if not 1 <= req.count <= MAX_WORDS:
        raise ModbusError(ExceptionCode.ILLEGAL_DATA_VALUE,
                          f"{req.count} words requested: 1..{MAX_WORDS} allowed")
    if isinstance(req, WriteRequest) and not req.byte_count == 2 * req.count == 2 * len(
            req.words):
        raise ModbusError(ExceptionCode.ILLEGAL_DATA_VALUE,
                          f"byte count {req.byte_count} with {len(req.words)} words for a word "
                          f"count of {req.count}")


def decode_response(frame: bytes | bytearray) -> Response:
    """Decode one complete reply frame (MIS manual §12.4, §12.5, exception replies).

    Raises
    ------
    FrameError
        ``too_short``, ``bad_crc``, ``wrong_length`` or ``bad_function``.
    """
    frame = bytes(frame)
    if len(frame) < 5:
        raise FrameError(f"Modbus reply of {len(frame)} bytes: at least 5 needed", "too_short",
                         data=frame)
    if not crc_ok(frame):
        raise FrameError("bad CRC", "bad_crc", data=frame)
    slave, function, body = frame[0], frame[1], frame[2:-2]
    if function & 0x80:
        if len(body) != 1:
            raise FrameError("exception reply of wrong length", "wrong_length", data=frame)
        code = body[0]
        known = code in ExceptionCode._value2member_map_
        return ExceptionResponse(slave, function & 0x7F, ExceptionCode(code) if known else code)
    if function == READ_HOLDING_REGISTERS:
        if len(body) < 1 or len(body) != 1 + body[0] or body[0] % 2:
            raise FrameError("read reply whose byte count does not fit", "wrong_length",
                             data=frame)
        data = body[1:]
        return ReadResponse(slave, tuple(int.from_bytes(data[k:k + 2], "big")
                                         for k in range(0, len(data), 2)))
    if function == WRITE_MULTIPLE_REGISTERS:
        if len(body) != 4:
            raise FrameError("write reply of wrong length", "wrong_length", data=frame)
        return WriteResponse(slave, int.from_bytes(body[0:2], "big"),
                             int.from_bytes(body[2:4], "big"))
    raise FrameError(f"reply with function {function:02X}h", "bad_function", data=frame)


# ----------------------------------------------------------------------------- 32-bit values
def words_of(value: int) -> tuple[int, int]:
    """The two Modbus words of a 32-bit register value: (low word, high word), as they appear at
    indices 2n and 2n + 1 (MIS manual §12.3). Negative values are taken in two's complement."""
    v = int(value) & 0xFFFFFFFF
    return v & 0xFFFF, v >> 16


def value_of(low: int, high: int) -> int:
    """The signed 32-bit register value of its (low, high) Modbus words (MIS manual §12.3)."""
    v = ((high & 0xFFFF) << 16) | (low & 0xFFFF)
    return v - 2**32 if v & 0x80000000 else v


# ----------------------------------------------------------------------------- addressing
class Area(enum.Enum):
    """What a Modbus word belongs to."""

    REGISTER = "register"  #: a motor register (MIS manual §12.3)
    RX_SETUP = "rx_setup"  #: PDOn_RX_SETUP[k] (MIS manual §12.6.3, §12.6.4)
    TX_SETUP = "tx_setup"  #: PDOn_TX_SETUP[k]
    VALUE = "value"  #: PDOn_VALUE[k]


@dataclass(frozen=True)
class WordRef:
    """One 16-bit Modbus word: the low or high half of a 32-bit register.

    Attributes
    ----------
    area : Area
    number : int
        Motor register number (REGISTER) or PDO entry k (0..7).
    high : bool
        True for the upper 16 bits.
    pdo : int
        PDO set (1 or 2), 0 for motor registers.
    """

    area: Area
    number: int
    high: bool
    pdo: int = 0

    @property
    def target(self) -> tuple[Area, int, int]:
        """The 32-bit register this word belongs to."""
        return self.area, self.pdo, self.number


@dataclass(frozen=True)
class AddressMap:
    """Modbus index → 32-bit register and word half (MIS manual §12.3, §12.6.3, §12.6.4).

    Windows, checked in this order; a request must lie inside one window:

    * **PDO blocks**: ``base + 2k`` (low word) and ``base + 2k + 1`` (high word) of entry k
      (0..7) of each block of :data:`PDO_BASES`.
    * **Alternative window**, from ``alt_offset`` (40 000) up: see below.
    * **2n window** below ``alt_offset``: index 2n is the low word of register n, 2n + 1 its high
      word (MIS manual §12.3 example: P_IST = register 10 at indices 20, 21).

    The manual gives the alternative window as "the motor register *n* can be read at Modbus
    register index 2n, 2n + 1 or at register index 40000 + n, 40000 + n + 1" (§12.3). Taken
    literally, index 40000 + n + 1 would be both the high word of register n and the low word of
    register n + 1. Two readings:

    * ``"register"`` (default, the literal one): the start index selects the register,
      n = index − 40 000, and the request's words run in (low, high) pairs through registers n,
      n + 1, …; "40000 + n, 40000 + n + 1" are the two words of the frame. Every start index is
      aligned; a write still needs an even word count.
    * ``"word"``: the window is the 2n window shifted by 40 000 (register n at 40 000 + 2n and
      40 000 + 2n + 1), i.e. the text's "n" read as the Modbus index 2n.

    Parameters
    ----------
    alt_offset : int or None
        Start of the alternative window (None: no alternative window).
    alt_reading : {"register", "word"}
    pdo_bases : dict
        Set → {"rx_setup", "tx_setup", "value"} → Modbus index of entry 0 (empty: no PDOs).
    """

    alt_offset: int | None = ALT_OFFSET
    alt_reading: str = "register"
    pdo_bases: dict[int, dict[str, int]] = field(default_factory=lambda: dict(PDO_BASES))

    def __post_init__(self) -> None:
        if self.alt_reading not in ("register", "word"):
            raise ValueError(f"alt_reading is 'register' or 'word', got {echo(self.alt_reading)}")

    def index_of(self, number: int, alt: bool = False) -> int:
        """Modbus index of the low word of motor register ``number`` (2n, or the alternative
        window's index with ``alt``)."""
        if not alt:
            return 2 * number
        if self.alt_offset is None:
            raise ValueError("no alternative window")
        return self.alt_offset + (number if self.alt_reading == "register" else 2 * number)

    def _pdo_block(self, index: int) -> tuple[int, Area, int] | None:
        for pdo, blocks in self.pdo_bases.items():
            for name, base in blocks.items():
                if base <= index < base + 2 * PDO_SLOTS:
                    return pdo, Area(name), base
        return None

    def resolve(self, index: int, count: int) -> list[WordRef]:
        """The words of a request of ``count`` words from Modbus index ``index``.

        Raises
        ------
        ModbusError
            ILLEGAL_DATA_ADDRESS if the request runs past 65535 or out of its window.
        """
        last = index + count - 1
        if count < 1 or last > 0xFFFF:
            raise ModbusError(ExceptionCode.ILLEGAL_DATA_ADDRESS,
                              f"{count} words from index {index} run past 65535")
        block = self._pdo_block(index)
        if block is not None:
            pdo, area, base = block
            if last >= base + 2 * PDO_SLOTS:
                raise ModbusError(ExceptionCode.ILLEGAL_DATA_ADDRESS,
                                  f"words {index}..{last} run past PDO{pdo} {area.value}[7]")
            return [WordRef(area, (i - base) // 2, bool((i - base) % 2), pdo)
                    for i in range(index, last + 1)]
        if any(self._pdo_block(i) is not None for i in range(index, last + 1)):
            raise ModbusError(ExceptionCode.ILLEGAL_DATA_ADDRESS,
                              f"words {index}..{last} run into a PDO block")
        alt = self.alt_offset
        if alt is not None and index >= alt:
            if self.alt_reading == "register":
                n0 = index - alt
                return [WordRef(Area.REGISTER, n0 + j // 2, bool(j % 2)) for j in range(count)]
            return [WordRef(Area.REGISTER, (i - alt) // 2, bool((i - alt) % 2))
                    for i in range(index, last + 1)]
        if alt is not None and last >= alt:
            raise ModbusError(ExceptionCode.ILLEGAL_DATA_ADDRESS,
                              f"words {index}..{last} run into the window at {alt}")
        return [WordRef(Area.REGISTER, i // 2, bool(i % 2)) for i in range(index, last + 1)]


def whole_registers(refs: Sequence[WordRef]) -> list[tuple[Area, int, int]]:
    """The 32-bit registers written by ``refs``, which must come in (low, high) pairs of the same
    register (MIS manual §12.3: whole 32-bit values, even index).

    Raises
    ------
    ModbusError
        ILLEGAL_DATA_ADDRESS for an odd start or an odd word count.
    """
    if len(refs) % 2:
        raise ModbusError(ExceptionCode.ILLEGAL_DATA_ADDRESS,
                          f"a write of {len(refs)} words: whole 32-bit registers (an even "
                          "number of words) only")
    out = []
    for lo, hi in zip(refs[0::2], refs[1::2]):
        if lo.high or not hi.high or lo.target != hi.target:
            raise ModbusError(ExceptionCode.ILLEGAL_DATA_ADDRESS,
                              "an unaligned write: the first word must be the low word of a "
                              "register (even index)")
        out.append(lo.target)
    return out


@dataclass
class PdoTable:
    """Set-up of one PDO set (MIS manual §12.6): the motor registers that PDOn_VALUE[k] reads
    (TX) and writes (RX). Not saved to flash: :meth:`clear` at every power-on (§12.6.1).

    Attributes
    ----------
    rx, tx : list of int
        Motor register numbers of the active entries; entry k is active for k < len(...).
    """

    rx: list[int] = field(default_factory=list)
    tx: list[int] = field(default_factory=list)

    def clear(self) -> None:
        """Forget the set-up (power-on, MIS manual §12.6.1)."""
        self.rx.clear()
        self.tx.clear()

    def setup_word_value(self, area: Area, k: int) -> int:
        """Value read from RX_SETUP[k] / TX_SETUP[k]: the register number, 0 if inactive."""
        table = self.rx if area == Area.RX_SETUP else self.tx
        return table[k] if k < len(table) else 0

    def configure(self, area: Area, first: int, numbers: Sequence[int]) -> None:
        """Write a list of register numbers to RX_SETUP[0] or TX_SETUP[0] (MIS manual §12.6.1):
        the number of values written is the number of active entries.

        Raises
        ------
        ModbusError
            ILLEGAL_DATA_ADDRESS if the write does not start at entry 0; ILLEGAL_DATA_VALUE for
            a negative register number.
        """
        if first != 0:
            raise ModbusError(ExceptionCode.ILLEGAL_DATA_ADDRESS,
                              f"a PDO set-up write to entry {first}: it must start at entry 0 "
                              "and carry the whole list (MIS manual §12.6.1)")
        for n in numbers:
            if n < 0:
                raise ModbusError(ExceptionCode.ILLEGAL_DATA_VALUE,
                                  f"register number {n} in a PDO set-up")
        table = self.rx if area == Area.RX_SETUP else self.tx
        table[:] = list(numbers)

    def target(self, k: int, write: bool) -> int:
        """Motor register behind PDOn_VALUE[k] for a read or a write.

        Raises
        ------
        ModbusError
            ILLEGAL_DATA_ADDRESS if entry k is not configured (MIS manual §12.6.2).
        """
        table = self.rx if write else self.tx
        if k >= len(table):
            raise ModbusError(ExceptionCode.ILLEGAL_DATA_ADDRESS,
                              f"PDO VALUE[{k}] is not configured for "
                              f"{'writing' if write else 'reading'} (MIS manual §12.6.2)")
        return table[k]


# ----------------------------------------------------------------------------- timing
@dataclass(frozen=True)
class SerialFormat:
    """Serial character format (MIS manual §12.1, register 121 bits 3:2 and 5).

    Attributes
    ----------
    baud : int
    parity : str
        ``"N"``, ``"O"`` or ``"E"``.
    stop_bits : int
        1 or 2.
    """

    baud: int = 19200
    parity: str = "N"
    stop_bits: int = 1

    @property
    def bits(self) -> int:
        """Bits per character: start, 8 data bits, parity, stop bits."""
        return 1 + 8 + (self.parity != "N") + self.stop_bits


@dataclass(frozen=True)
class ModbusSetup:
    """The Modbus set-up register decoded (MIS manual §12.1 table; see :func:`decode_setup`)."""

    rs485: bool
    rs422: bool
    parity: str
    stop_bits: int


def decode_setup(value: int) -> ModbusSetup:
    """Decode the Modbus set-up register (MIS manual §12.1): bit 0 Modbus RTU on the RS-485
    (MacTalk) channel, bits 3:2 parity (0 none, 1 odd, 2 even, 3 reserved → none), bit 5 two stop
    bits, bit 8 Modbus on the RS-422 channel. (The register description of MIS manual §8.2.66
    gives an older layout with bit 1 RTU/ASCII and bit 4 7/8 data bits; §12.1 is followed.)"""
    parity = {0: "N", 1: "O", 2: "E"}.get((value >> 2) & 3, "N")
    return ModbusSetup(bool(value & 1), bool(value & (1 << 8)), parity,
                       2 if value & (1 << 5) else 1)


def char_time(fmt: SerialFormat) -> float:
    """Seconds per character at ``fmt``."""
    return fmt.bits / fmt.baud


def silence(fmt: SerialFormat, chars: float = 3.5) -> float:
    """Silence of ``chars`` character times [s]: 3.5 ends a frame, 1.5 is the longest gap inside
    one. Above 19 200 baud the Modbus serial line guide fixes t3.5 = 1.75 ms, t1.5 = 0.75 ms."""
    if fmt.baud > 19200 and chars in (3.5, 1.5):
        return _FIXED_T35 if chars == 3.5 else _FIXED_T15
    return chars * char_time(fmt)


class RtuFramer:
    """Split a received byte stream into RTU request frames (MIS manual §12.4, §12.5).

    A frame ends

    * at a silence of 3.5 characters (:func:`silence`): the bytes held then are the frame, and
      as they did not complete a frame with a valid CRC they are reported as a
      :class:`FrameError` (``bad_crc`` or ``too_short``);
    * as soon as the held bytes are a complete read or write request (length fixed by its first
      bytes, :func:`request_length`) with a valid CRC, or as soon as all the held bytes end with
      a valid CRC and are not a read or write request still short of its length (requests of
      other functions, replies of other slaves).

    More than 256 bytes without a frame are reported (``too_long``) and dropped. Gaps of 1.5 to
    3.5 characters inside a frame are not treated specially.

    Parameters
    ----------
    fmt : SerialFormat
        Baud rate and character format that fix the silence.
    """

    def __init__(self, fmt: SerialFormat | None = None) -> None:
        self.fmt = fmt or SerialFormat()
        self._buf = bytearray()
        self._last: float | None = None
        #: frames and errors produced so far
        self.frames = 0
        self.errors = 0

    @property
    def pending(self) -> bytes:
        """Bytes held back (a frame not yet complete)."""
        return bytes(self._buf)

    def _error(self, data: bytes) -> FrameError:
        self.errors += 1
        try:
            decode_request(data)
        except FrameError as exc:
            return exc
        return FrameError(f"{len(data)} bytes ended by a silence before the length their "
                          "function needs", "truncated", data=data)

    def flush(self) -> list[bytes | FrameError]:
        """A silence of 3.5 characters: whatever is held is a bad frame, reported and dropped."""
        if not self._buf:
            return []
        data = bytes(self._buf)
        self._buf.clear()
        return [self._error(data)]

    def feed(self, data: bytes, now: float) -> list[bytes | FrameError]:
        """Add ``data`` received at time ``now`` [s]; return the complete frames (bytes with a
        valid CRC) and the errors, in stream order."""
        out: list[bytes | FrameError] = []
        if self._last is not None and now - self._last >= silence(self.fmt):
            out += self.flush()
        self._last = now
        for b in data:
            self._buf.append(b)
            n = request_length(self._buf)
            if n is not None and len(self._buf) == n and crc_ok(self._buf):
                out.append(bytes(self._buf))
                self._buf.clear()
                self.frames += 1
            elif len(self._buf) > MAX_FRAME:
                out.append(self._error(bytes(self._buf)))
                self._buf.clear()
        n = request_length(self._buf)
        if (n is None or len(self._buf) > n) and crc_ok(self._buf):
            out.append(bytes(self._buf))
            self._buf.clear()
            self.frames += 1
        return out
