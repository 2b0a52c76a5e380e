"""The program in the motor's flash: the compact binary form of the commands (MIS manual §9.7.24:
"MacTalk programs are sent to the motor in a compact, binary format").

JVL does not publish its binary format; this one is the simulator's own. An instruction is the
command's index in :data:`.commands.SPECS` (one byte) and its fields packed in the dialogue's
order (:mod:`.fields`); a level output (``set_output`` without a pulse) stores ``pulse_ms`` 0.
The program flash holds 3072 bytes (MIS manual, technical data: "Program Storage Flash 3072
Bytes"). The program checksum of the program status command (§18.2.10) is the 16-bit sum of the
program bytes.
"""

from __future__ import annotations

import struct
from collections.abc import Sequence

from .commands import SPECS, Command
from .fields import FieldError

__all__ = ["FLASH_BYTES", "encode_command", "decode_command", "encode_program",
           "decode_program", "checksum"]

FLASH_BYTES = 3072  #: program storage of the MIS (technical data)
_KEYWORDS = list(SPECS)


def encode_command(cmd: Command) -> bytes:
    """One instruction's bytes."""
    out = bytes([_KEYWORDS.index(cmd.keyword)])
    for key, (ftype, _) in cmd.spec.fields.items():
        out += ftype.pack(cmd.values.get(key, 0))
    return out


def _decode_at(data: bytes, k: int) -> tuple[Command, int]:
    if k >= len(data) or data[k] >= len(_KEYWORDS):
        raise FieldError(f"no instruction code at byte {k}")
    keyword = _KEYWORDS[data[k]]
    k += 1
    values: dict[str, object] = {}
    try:
        for key, (ftype, _) in SPECS[keyword].fields.items():
            values[key], k = ftype.unpack(data, k)
    except (IndexError, UnicodeDecodeError, ValueError, struct.error) as exc:
        raise FieldError(f"{keyword}: {exc}") from None
    if keyword == "set_output":
        if str(values["state"]).endswith("_pulse") != (values["pulse_ms"] != 0):
            raise FieldError("set_output: pulse length does not match the state")
        if not values["pulse_ms"]:
            values.pop("pulse_ms")
    return Command(keyword, values), k


def decode_command(data: bytes) -> Command:
    """The one instruction ``data`` holds (FieldError if it is not exactly one)."""
    cmd, k = _decode_at(data, 0)
    if k != len(data):
        raise FieldError(f"{len(data) - k} bytes after the instruction")
    return cmd


def encode_program(cmds: Sequence[Command]) -> bytes:
    """The flash bytes of a program: a 16-bit line count, then the instructions."""
    return len(cmds).to_bytes(2, "little") + b"".join(encode_command(c) for c in cmds)


def decode_program(data: bytes) -> list[Command]:
    """The commands of flash bytes (FieldError if they are not a program)."""
    if len(data) < 2:
        raise FieldError("no program")
    n = int.from_bytes(data[:2], "little")
    k = 2
    cmds = []
    for _ in range(n):
        cmd, k = _decode_at(data, k)
        cmds.append(cmd)
    if k != len(data):
        raise FieldError(f"{len(data) - k} bytes after the last instruction")
    return cmds


def checksum(data: bytes) -> int:
    """16-bit sum of the bytes."""
    return sum(data) & 0xFFFF
