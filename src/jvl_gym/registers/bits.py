"""Named bits of a bit-field register (status, error and control words).

A family's ``constants`` module states a bit-field register's bits once, as their names in bit
order; :func:`bit_masks` gives each name its mask, and the module makes every name a constant
(the compiled firmware reads them as compile-time constants).
"""

from __future__ import annotations

from collections.abc import Mapping

from .errors import echo

__all__ = ["bit_masks", "mask_of"]


def bit_masks(names: str) -> dict[str, int]:
    """The mask of each named bit of a bit-field register, bit 0 first.

    Parameters
    ----------
    names : str
        The bits' names separated by white space, in bit order from bit 0; ``-`` for a bit
        without a name.

    Returns
    -------
    dict of str to int
        Name → ``1 << bit``, in bit order.

    Raises
    ------
    ValueError
        A name that is not an identifier or that stands twice.
    """
    out: dict[str, int] = {}
    for bit, name in enumerate(names.split()):
        if name == "-":
            continue
        if not name.isidentifier() or name in out:
            raise ValueError(f"bit {bit}: {echo(name)} is not a new identifier")
        out[name] = 1 << bit
    return out


def mask_of(bits: Mapping[str, int], names: str) -> int:
    """The OR of the masks of ``names`` (separated by white space) in ``bits``."""
    out = 0
    for name in names.split():
        out |= bits[name]
    return out
