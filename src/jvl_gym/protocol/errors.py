"""Exceptions of the serial protocol layer (manual chapter 5).

Decoders never raise on bad input while streaming: they *return* :class:`FrameError` objects
so that a server can log the reason and carry on; the one-shot ``decode_*`` functions raise them.
"""

from __future__ import annotations

from ..registers.errors import echo_hex

__all__ = [
    "ProtocolError",
    "FrameError",
    "NoAnswerError",
    "UnexpectedReplyError",
    "RefusedError",
]


class ProtocolError(Exception):
    """Base class of all protocol errors."""


class FrameError(ProtocolError, ValueError):
    """A malformed frame, with a precise reason.

    Parameters
    ----------
    reason : str
        Human-readable reason, e.g. ``"bad complement in address: 13h followed by EDh
        (expected ECh)"``.
    code : str
        Short machine-readable class: ``unknown_sync``, ``bad_sync``, ``bad_complement``,
        ``wrong_length``, ``bad_end``, ``truncated``, ``bad_register``, ``bad_header``,
        ``bad_format``, ``bad_safe_pair``, ``bad_address``, ``trailing``.
    offset : int
        Stream offset of the first discarded byte (0 for one-shot decoding).
    data : bytes
        The bytes that were discarded because of this error.
    """

    def __init__(self, reason: str, code: str = "malformed", offset: int = 0,
                 data: bytes = b"") -> None:
        super().__init__(reason)
        self.reason = reason
        self.code = code
        self.offset = offset
        self.data = bytes(data)

    def __repr__(self) -> str:
        return f"FrameError({self.code}: {self.reason!r} at {self.offset}, {echo_hex(self.data)})"

    def __eq__(self, other: object) -> bool:
        return (isinstance(other, FrameError) and other.reason == self.reason
                and other.code == self.code and other.offset == self.offset
                and other.data == self.data)

    def __hash__(self) -> int:
        return hash((self.reason, self.code, self.offset, self.data))


class NoAnswerError(ProtocolError, TimeoutError):
    """The motor did not answer within the timeout, after all retries.

    Parameters
    ----------
    request : str
        The request that got no answer (``"WRITE 2 = 15"``).
    message : str
        What happened and what to check.
    """

    def __init__(self, request: str, message: str) -> None:
        super().__init__(message)
        self.request = request


class UnexpectedReplyError(ProtocolError):
    """The motor answered, but not with the reply the request calls for."""


class RefusedError(ProtocolError):
    """The client refused to send a request it knows the motor would reject."""
