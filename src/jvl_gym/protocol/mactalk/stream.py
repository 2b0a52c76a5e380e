"""The streaming decoder shared by the MacTalk and FlexMAC codecs (manual 5.1, 5.2.2).

Bytes arrive in arbitrary chunks. A decoder keeps the bytes that may still become a frame,
returns every complete frame, and for malformed input returns one :class:`FrameError` per bad
frame (or run of garbage) with a precise reason, then resynchronises on the next position where a
frame could start. :meth:`StreamDecoder.flush` reports held-back bytes as truncated.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import Any

from ...registers.errors import echo_hex
from ..errors import FrameError


class NeedMore(Exception):
    """The buffer ends inside a frame."""


class Malformed(Exception):
    """The bytes at the start of the buffer cannot be a frame."""

    def __init__(self, reason: str, code: str) -> None:
        super().__init__(reason)
        self.reason = reason
        self.code = code


class StreamDecoder(ABC):
    """Base of the streaming decoders: subclasses give ``_parse`` and ``_is_start``."""

    def __init__(self) -> None:
        self._buf = bytearray()
        self._offset = 0  # stream offset of _buf[0]
        #: number of frames decoded and errors reported so far
        self.frames = 0
        self.errors = 0

    @property
    def pending(self) -> bytes:
        """Bytes held back because they may start a frame."""
        return bytes(self._buf)

    @abstractmethod
    def _parse(self, buf: bytearray) -> tuple[Any, int]:
        """Decode one frame at the start of ``buf``: (frame, length) or NeedMore/Malformed."""

    @abstractmethod
    def _is_start(self, k: int) -> bool:
        """Could a frame start at ``_buf[k]``?"""

    def _next_start(self) -> int:
        """Where the next frame could start after a malformed one at ``_buf[0]``: the first
        ``k >= 1`` with :meth:`_is_start`, or ``len(_buf)``. A subclass may skip positions
        that cannot start a well-formed frame in fewer steps (one error per run of garbage)."""
        k = 1
        while k < len(self._buf) and not self._is_start(k):
            k += 1
        return k

    def _truncated(self, data: bytes) -> str:
        return f"truncated frame: {len(data)} bytes ({echo_hex(data)}) and then no more"

    def _discard(self, n: int) -> bytes:
        out = bytes(self._buf[:n])
        del self._buf[:n]
        self._offset += n
        return out

    def feed(self, chunk: bytes) -> list[Any]:
        """Add bytes; return the frames and errors completed by them, in stream order."""
        self._buf += chunk
        out: list[Any] = []
        while self._buf:
            try:
                frame, n = self._parse(self._buf)
            except NeedMore:
                break
            except Malformed as bad:
                k = self._next_start()
                offset = self._offset
                out.append(FrameError(bad.reason, bad.code, offset, self._discard(k)))
                self.errors += 1
                continue
            self._discard(n)
            out.append(frame)
            self.frames += 1
        return out

    def flush(self) -> list[FrameError]:
        """Report held-back bytes as a truncated frame and clear them."""
        if not self._buf:
            return []
        offset = self._offset
        data = self._discard(len(self._buf))
        self.errors += 1
        return [FrameError(self._truncated(data), "truncated", offset, data)]


def decode_all_with(decoder: StreamDecoder, data: bytes) -> list[Any]:
    """All frames and errors of a complete byte string through a fresh ``decoder``, a trailing
    partial frame reported as truncated."""
    return decoder.feed(bytes(data)) + decoder.flush()


def decode_one_with(decoder: StreamDecoder, data: bytes, what: str = "frame") -> Any:
    """Exactly one ``what`` of ``data`` through a fresh ``decoder``; the first
    :class:`FrameError` of the bytes, or one saying how many there were, otherwise."""
    items = decode_all_with(decoder, data)
    for item in items:
        if isinstance(item, FrameError):
            raise item
    if len(items) != 1:
        raise FrameError(f"expected exactly one {what}, got {len(items)}", "trailing", 0,
                         bytes(data))
    return items[0]
