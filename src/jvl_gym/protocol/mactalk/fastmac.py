"""FastMAC codec (manual 5.2.1): one-byte commands, the toggle bit, the status byte.

Command byte (manual 5.2.1.4)::

    bit 7     toggle bit, switched for every new command (5.2.1.3)
    bits 6,5  mode: 00 init, 01 velocity, 10 position, 11 command mode
    bits 4..0 init/velocity/position mode: the register to activate (group + number);
              command mode: a command number 0..31

Status byte, sent by the motor (manual 5.2.1.6)::

    bit 7 toggle of the last accepted command; bit 6 DEC_FLAG; bit 5 ACC_FLAG; bit 4 IN_POS;
    bit 3 receive protocol (0 FastMAC, 1 FlexMAC); bit 2 framing error; bit 1 available;
    bit 0 follow / function / I2T / UIT error

Bits 6,5 of a status byte are never 11 (DEC_FLAG and ACC_FLAG exclude each other), so a byte with
11 there is a FlexMAC header (5.2.2).

**The register code.** The text of 5.2.1.4 gives the groups as P ``00XXX``, V ``01XXX``,
A ``100XX``, T ``101XX``, L ``110XX``, Z ``111XX``. The byte example of 5.2.1.5 contradicts it:
``05DH`` "Position_mode: Activate P6" has bits 4..0 = ``11101``, ``093H`` "Activate V4" has
``10011``, ``003H`` "Activate A4" has ``00011``. Seven of the example's bytes fit one code,
``EXAMPLE_CODE``: P ``11XXX``, V ``10XXX``, A ``000XX`` (and, by the text's order, T ``001XX``,
L ``010XX``, Z ``011XX``; these three are not pinned down by any example). One byte fits no
code together with the others: ``081H`` "Activate T2" has ``00001``, which is A2 in the example
code (T2 would be ``085H``). As for the byte order (docs/model.md §16), the examples are followed:
:data:`EXAMPLE_CODE` is the default and :data:`TABLE_CODE` (the text) is available. Also note
``062H``, commented "Set P_IST = 0", is command 02h (P_SOLL = 0) by the command table; P_IST = 0
is command 03h.

The number field counts from 0: ``XXX = 000`` is register 1 (5.2.1.4 "register number 1 ... 8").
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

from ...registers.errors import echo
from ..errors import FrameError

__all__ = [
    "Mode",
    "FastCommand",
    "GROUP_SIZES",
    "TABLE_CODE",
    "EXAMPLE_CODE",
    "DEFAULT_CODE",
    "FastMacByte",
    "encode_activate",
    "encode_command",
    "decode_byte",
    "Status",
    "encode_status",
    "decode_status",
    "FastMacReceiver",
    "EXAMPLE_SEQUENCE",
]

TOGGLE = 0x80


class Mode(enum.IntEnum):
    """Mode bits 6,5 of a FastMAC command (manual 5.2.1.4) and the MODE_REG they select."""

    INIT = 0  #: MODE_REG 0
    VELOCITY = 1  #: MODE_REG 1
    POSITION = 2  #: MODE_REG 2
    COMMAND = 3  #: keep the mode, bits 4..0 are a command


class FastCommand(enum.IntEnum):
    """The 32 command-mode commands (manual 5.2.1.4, command mode)."""

    NOP = 0x00
    RESET_ERROR = 0x01
    P_SOLL_ZERO = 0x02  #: P_SOLL = 0, IN_POS = 0
    P_IST_ZERO = 0x03
    P_FNC_ZERO = 0x04  #: P_FNC = 0, IN_POS = 0
    V_SOLL_ZERO = 0x05
    T_SOLL_ZERO = 0x06
    IN_POS_ZERO = 0x07
    REL_P7_FNC = 0x08  #: P_FNC = (FLWERR − P7)·16
    REL_P8_FNC = 0x09  #: P_FNC = (FLWERR − P8)·16
    RAPID_COMM = 0x0A  #: one byte per command
    SAFE_COMM = 0x0B  #: two identical bytes per command
    SET1 = 0x0C  #: use P1, V1, A1, T1, L1, Z1; IN_POS = 0
    SET2 = 0x0D
    SET3 = 0x0E
    SET4 = 0x0F
    HOME = 0x10  #: home search with HOME_MODE's high byte
    MOVE_REL_P7 = 0x11  #: P_SOLL = P_IST + P7 − FLWERR
    MOVE_REL_P8 = 0x12  #: P_SOLL = P_IST + P8 − FLWERR
    TRANSMIT_SLOWLY = 0x13
    ABSOLUTE = 0x14  #: RELPOSPSOLL = 0, RELPOSPFNC = 0
    RELATIVE_P_SOLL = 0x15  #: RELPOSPSOLL = 1, RELPOSPFNC = 0
    RELATIVE_P_FNC = 0x16  #: RELPOSPSOLL = 0, RELPOSPFNC = 1
    NOP_17 = 0x17
    NOP_18 = 0x18
    NOP_19 = 0x19
    NOP_1A = 0x1A
    NOP_1B = 0x1B
    NOP_1C = 0x1C
    TRANSMIT_MYADDR = 0x1D
    USE_FASTMAC = 0x1E  #: i.e. NOP
    USE_FLEXMAC = 0x1F


#: registers per group (manual 5.2.1.1)
GROUP_SIZES: dict[str, int] = {"P": 8, "V": 8, "A": 4, "T": 4, "L": 4, "Z": 4}

#: group → (prefix, prefix length in bits) of the text of manual 5.2.1.4
TABLE_CODE: dict[str, tuple[int, int]] = {
    "P": (0b00, 2), "V": (0b01, 2), "A": (0b100, 3), "T": (0b101, 3), "L": (0b110, 3),
    "Z": (0b111, 3),
}
#: group → (prefix, prefix length) that reproduces the byte example of manual 5.2.1.5
EXAMPLE_CODE: dict[str, tuple[int, int]] = {
    "P": (0b11, 2), "V": (0b10, 2), "A": (0b000, 3), "T": (0b001, 3), "L": (0b010, 3),
    "Z": (0b011, 3),
}
DEFAULT_CODE = EXAMPLE_CODE

#: the byte sequence of manual 5.2.1.5 with its comments
EXAMPLE_SEQUENCE: tuple[tuple[int, str], ...] = (
    (0xE0, "Command_mode: NOP: synchronise toggle bit"),
    (0x62, "Set P_IST = 0"),
    (0x81, "Init_mode: Activate T2"),
    (0x03, "Init_mode: Activate A4"),
    (0x93, "Init_mode: Activate V4"),
    (0x5D, "Position_mode: Activate P6. IN_POS = 0."),
    (0xDE, "Position_mode: Activate P7. IN_POS = 0."),
    (0x52, "Position_mode: Activate V3"),
    (0xDC, "Position_mode: Activate P5. IN_POS = 0."),
)


@dataclass(frozen=True)
class FastMacByte:
    """One decoded FastMAC command byte.

    Attributes
    ----------
    toggle : int
        Bit 7 (0 or 1).
    mode : Mode
    group, number : str or None, int or None
        The activated register (e.g. ``"P"``, 6) in init/velocity/position mode.
    command : FastCommand or None
        The command in command mode.
    """

    toggle: int
    mode: Mode
    group: str | None = None
    number: int | None = None
    command: FastCommand | None = None

    @property
    def register(self) -> str | None:
        """Name of the activated register, e.g. ``"P6"``."""
        return None if self.group is None else f"{self.group}{self.number}"


def _toggle(toggle: int) -> int:
    if toggle not in (0, 1):
        raise ValueError(f"toggle must be 0 or 1, got {echo(toggle)}")
    return toggle << 7


def encode_activate(mode: Mode | int, register: str, toggle: int,
                    code: dict[str, tuple[int, int]] = DEFAULT_CODE) -> int:
    """Command byte activating ``register`` (``"P6"``, ``"V4"``…) in init, velocity or position
    mode (manual 5.2.1.4)."""
    mode = Mode(mode)
    if mode == Mode.COMMAND:
        raise ValueError("command mode carries a command, not a register (use encode_command)")
    group, num = register[:1].upper(), register[1:]
    if group not in GROUP_SIZES or not num.isdigit() or not 1 <= int(num) <= GROUP_SIZES[group]:
        raise ValueError(f"no FastMAC register {echo(register)} (P1..P8, V1..V8, A/T/L/Z1..4)")
    prefix, bits = code[group]
    payload = (prefix << (5 - bits)) | (int(num) - 1)
    return _toggle(toggle) | (mode << 5) | payload


def encode_command(command: FastCommand | int, toggle: int) -> int:
    """Command-mode byte (mode bits 11) for ``command`` 0..31 (manual 5.2.1.4)."""
    return _toggle(toggle) | (Mode.COMMAND << 5) | FastCommand(command)


def decode_byte(byte: int, code: dict[str, tuple[int, int]] = DEFAULT_CODE) -> FastMacByte:
    """Decode one FastMAC command byte (every byte value is a valid command)."""
    if not 0 <= byte <= 0xFF:
        raise ValueError(f"a byte is 0..255, got {echo(byte)}")
    toggle, mode, payload = byte >> 7, Mode((byte >> 5) & 3), byte & 0x1F
    if mode == Mode.COMMAND:
        return FastMacByte(toggle, mode, command=FastCommand(payload))
    for group, (prefix, bits) in code.items():
        if payload >> (5 - bits) == prefix:
            return FastMacByte(toggle, mode, group, (payload & ((1 << (5 - bits)) - 1)) + 1)
    raise AssertionError("the code does not cover all 32 payloads")  # pragma: no cover


@dataclass(frozen=True)
class Status:
    """The FastMAC status byte (manual 5.2.1.6)."""

    toggle: int = 0
    dec_flag: bool = False
    acc_flag: bool = False
    in_pos: bool = False
    flexmac: bool = False
    framing_error: bool = False
    error: bool = False


def encode_status(s: Status) -> int:
    """Status byte of ``s`` (manual 5.2.1.6)."""
    if s.dec_flag and s.acc_flag:
        raise ValueError("DEC_FLAG and ACC_FLAG cannot both be set (bits 6,5 = 11 is a "
                         "FlexMAC header, manual 5.2.2)")
    return (_toggle(s.toggle) | (s.dec_flag << 6) | (s.acc_flag << 5) | (s.in_pos << 4)
            | (s.flexmac << 3) | (s.framing_error << 2) | int(s.error))


def decode_status(byte: int) -> Status:
    """Decode a status byte; a byte with bits 6,5 = 11 is a FlexMAC header, not a status."""
    if not 0 <= byte <= 0xFF:
        raise ValueError(f"a byte is 0..255, got {echo(byte)}")
    if byte & 0x60 == 0x60:
        raise FrameError(f"{byte:02X}h has bits 6,5 = 11: a FlexMAC header byte, not a "
                         "FastMAC status byte (manual 5.2.2)", "bad_header", 0, bytes((byte,)))
    return Status(byte >> 7, bool(byte & 0x40), bool(byte & 0x20), bool(byte & 0x10),
                  bool(byte & 0x08), bool(byte & 0x04), bool(byte & 0x01))


class FastMacReceiver:
    """The motor's receive side of FastMAC (manual 5.2.1.3, 5.2.1.4): toggle and safe pairs.

    A byte is a *new* command when its toggle bit differs from the last accepted command's (the
    first byte after power-on is always accepted: the 5.2.1.5 example starts with a NOP "to
    synchronise the toggle bit"); a byte with the same toggle is a repetition and ignored. In safe
    communication (command 0Bh) a command must arrive as two identical bytes; a pair of differing
    bytes is reported as a :class:`FrameError` and the second byte starts a new pair.

    Parameters
    ----------
    code : dict
        Register code, :data:`EXAMPLE_CODE` (default) or :data:`TABLE_CODE`.
    """

    def __init__(self, code: dict[str, tuple[int, int]] = DEFAULT_CODE) -> None:
        self.code = code
        self.safe = False
        self.last_toggle: int | None = None
        self._pending: int | None = None
        self._offset = 0

    def feed(self, byte: int) -> FastMacByte | FrameError | None:
        """One received byte → a new command, an error, or None (repeat / first of a pair)."""
        offset = self._offset
        self._offset += 1
        if self.safe:
            if self._pending is None:
                self._pending = byte
                return None
            first, self._pending = self._pending, None
            if first != byte:
                self._pending = byte
                return FrameError(f"safe FastMAC needs two identical bytes: {first:02X}h then "
                                  f"{byte:02X}h (manual 5.2.1.4)", "bad_safe_pair", offset - 1,
                                  bytes((first,)))
        toggle = byte >> 7
        if toggle == self.last_toggle:
            return None
        self.last_toggle = toggle
        cmd = decode_byte(byte, self.code)
        if cmd.command == FastCommand.SAFE_COMM:
            self.safe, self._pending = True, None
        elif cmd.command == FastCommand.RAPID_COMM:
            self.safe, self._pending = False, None
        return cmd
