"""Exceptions of the register layer (manual 3.2), and the one way every error of the package
echoes its input (:func:`echo`, :func:`echo_hex`: a short prefix and the length).

Every error is a :class:`ValueError`, so callers that only care that "the value was bad" can
catch that; :class:`UnknownRegisterError` is also a :class:`KeyError` because it is a failed
lookup.
"""

from __future__ import annotations

import reprlib

__all__ = [
    "echo",
    "echo_hex",
    "ECHO_LIMIT",
    "RegisterError",
    "UnknownRegisterError",
    "RegisterRangeError",
    "ReadOnlyRegisterError",
    "RegisterShapeError",
]


class RegisterError(ValueError):
    """Base class of all register errors."""

    def __str__(self) -> str:  # KeyError would otherwise repr() the message
        return str(self.args[0]) if self.args else ""


class UnknownRegisterError(RegisterError, KeyError):
    """A register name or number that is not in the register table."""


class RegisterRangeError(RegisterError):
    """A value that is NaN, infinite or outside a register's range (manual 3.1, 3.2.N)."""


class ReadOnlyRegisterError(RegisterError):
    """A write to a register that the firmware computes (or a reserved one)."""


class RegisterShapeError(RegisterError):
    """A value or index array whose shape does not fit the request."""


#: characters of a bad input an error message repeats at most
ECHO_LIMIT = 40

_REPR = reprlib.Repr()
_REPR.maxstring = ECHO_LIMIT
_REPR.maxother = 3 * ECHO_LIMIT  # a decoded frame, a dataclass: their fields readable
_REPR.maxlist = _REPR.maxtuple = _REPR.maxdict = _REPR.maxset = 6


def echo(value: object, limit: int = ECHO_LIMIT) -> str:
    """``repr(value)`` for an error message, bounded: a string or bytes longer than ``limit``
    as its first ``limit`` characters (bytes) with its length, any other value as
    :mod:`reprlib` abbreviates it (with the length of a long sequence).

    >>> echo("V_SOLL")
    "'V_SOLL'"
    >>> echo("x" * 1000, limit=4)
    "'xxxx'… (1000 characters)"
    >>> echo(b"ab" * 9, limit=2)
    "b'ab'… (18 bytes)"
    """
    if isinstance(value, (bytes, bytearray, memoryview, str)):
        data = bytes(value) if not isinstance(value, str) else value
        if len(data) <= limit:
            return repr(data)
        head = data[:limit]
        while len(repr(head)) > limit + 3 and len(head) > 1:  # escapes: fewer of them
            head = head[:len(head) // 2]
        unit = "characters" if isinstance(data, str) else "bytes"
        return f"{head!r}… ({len(data)} {unit})"
    text = _REPR.repr(value)
    if isinstance(value, (list, tuple, set, frozenset, dict)) and len(value) > 6:
        text += f" ({len(value)} items)"
    return text


def echo_hex(data: bytes | bytearray | memoryview, limit: int = ECHO_LIMIT // 2) -> str:
    """Bytes as upper-case hex pairs for an error message, bounded: the first ``limit`` bytes
    and the length when there are more.

    >>> echo_hex(bytes(range(3)))
    '00 01 02'
    >>> echo_hex(bytes(100), limit=2)
    '00 00 … (100 bytes)'
    """
    data = bytes(data)
    if len(data) <= limit:
        return data.hex(" ").upper()
    return f"{data[:limit].hex(' ').upper()} … ({len(data)} bytes)"
