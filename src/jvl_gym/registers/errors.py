"""Exceptions of the register layer (manual 3.2).

Every error is a :class:`ValueError`, so callers that only care that "the value was bad" can
catch that; :class:`UnknownRegisterError` is also a :class:`KeyError` because it is a failed
lookup.
"""

from __future__ import annotations

__all__ = [
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
