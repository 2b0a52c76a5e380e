"""Conversions between user units, stored register integers and serial-line words (manual 3.1).

Manual 3.1 defines five data formats:

========  ===========================  ============================
format    storage                      range (user units)
========  ===========================  ============================
Word      16 bit unsigned              0 … 65535
Integer   16 bit signed                −32767 … +32767
LongInt   32 bit signed, two numbers   −2.147E9 … +2.147E9
Fixed4    16 bit signed, unit 1/4096   −7.999756 … +7.999756
Fixed8    16 bit signed, unit 1/256    −127.996 … +127.996
========  ===========================  ============================

Tables whose registers are 32 bits wide at one register number add four formats:

========  ====================================  =======================================
format    storage                               range (user units)
========  ====================================  =======================================
Int32     32 bit signed                         −2147483648 … 2147483647
Word32    32 bit unsigned                       0 … 4294967295
Fixed16   32 bit signed, unit 1/65536           −32768 … 32767.9999847412109375
Fixed24   32 bit signed, unit 1/16777216        −128 … 127.999999940395355224609375
========  ====================================  =======================================

On a 16-bit protocol such a value is two words, low word first, like a LongInt
(:func:`split_word32`, :func:`join_word32`).

Three representations are used here:

* *user units*: what the manual's register descriptions talk about (Fixed formats as reals);
* *raw*: the stored integer, ``raw = value · scale`` (scale 4096 / 256 / 1), a LongInt as its
  whole signed 32-bit value;
* *words*: the unsigned 16-bit words on the serial line.

Word order of a LongInt. Manual 3.2 says a LongInt "takes up two register numbers,
corresponding to two words", e.g. P_SOLL is registers 3 and 4 (3.2.3/3.2.4). The manual does not
say which word is which; its MacTalk example (chapter 5.1) reads register 7 "as if it is longint
format" and returns register 7's value 4711h first, then register 8. Together with the low-byte
first byte examples (docs/model.md §16) this reads as little-endian throughout: register N holds the
**low** word and N+1 the **high** word, and on the line the low word comes first. So
0x00054711 is (0x4711, 0x0005) and −1 is (0xFFFF, 0xFFFF). (The manual's text says
"big-endian"; the examples contradict it and are followed — a real motor is the final judge.)
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import njit

from ..engine.jit import KERNEL
from .errors import ReadOnlyRegisterError, RegisterRangeError, RegisterShapeError, echo
from .table import FORMAT_RAW_RANGE, FORMATS_32_ONE_NUMBER, Access, Format, Register

__all__ = [
    "to_raw",
    "whole_only",
    "real_values",
    "raws_of_floats",
    "raws_of_rows",
    "raw_bounds",
    "from_raw",
    "saturate_raw",
    "split_longint",
    "join_longint",
    "to_word16",
    "from_word16",
    "round_half_away",
    "split_word32",
    "join_word32",
]

_FIXED = (Format.FIXED4, Format.FIXED8, Format.FIXED16, Format.FIXED24)
#: :func:`to_raw` converts up to this many values one by one as Python floats
#: (:func:`raws_of_floats`), without numpy's fixed cost per call, which dominates for a few values
_SCALAR_MAX = 16
_SIGNED16 = (Format.INTEGER, Format.FIXED4, Format.FIXED8)


def round_half_away(x: Any) -> np.ndarray:
    """Round to the nearest integer, halves away from zero (float64 array).

    Parameters
    ----------
    x : array_like
        Values.

    Returns
    -------
    numpy.ndarray
        ``sign(x) · floor(|x| + 0.5)``.
    """
    a = np.asarray(x, dtype=np.float64)
    return np.copysign(np.floor(np.abs(a) + 0.5), a)


def _user_bounds(reg: Register) -> tuple[float, float]:
    """Accepted user-unit interval: the table range widened to the exactly representable ends.

    The manual prints Fixed ranges rounded (Fixed8 "127.996" for 32767/256 = 127.99609375), so
    a value that rounds to the raw limit is accepted.
    """
    s = reg.scale
    return min(reg.minimum, reg.raw_min / s), max(reg.maximum, reg.raw_max / s)


def whole_only(reg: Register) -> bool:
    """The register holds a code, a bit field, a register number or a count without a unit
    (MODE_REG, CNTRL_BITS, HOME_MODE, the pointers, SAMPLE1..4, MYADDR, GEARF1 …: a Word,
    Integer or LongInt register whose table unit is empty), so a value must be a whole number;
    quantities (a unit, or a Fixed format) are rounded half away from zero instead."""
    return reg.scale == 1 and not reg.unit


def _not_a_number(reg: Register, value: Any) -> RegisterRangeError:
    return RegisterRangeError(
        f"{reg.name} (register {reg.number}): value {echo(value)} is not a number; give an int, "
        f"a float or a real numeric array (manual {reg.section})")


def real_values(reg: Register, value: Any) -> np.ndarray:
    """``value`` as a float64 array if it is a real number or an array of them.

    Parameters
    ----------
    reg : Register
        Register the value is for (named in the error).
    value : array_like
        Python int or float, a numpy integer or float scalar, or a sequence or array of them.

    Returns
    -------
    numpy.ndarray
        float64 array of the shape of ``value``.

    Raises
    ------
    RegisterRangeError
        For a str, bytes, bool, complex, None or any other non-numeric value (also inside an
        array: an array's dtype must be an integer or float type), and for a Python int beyond
        64 bits (outside every register's range; the message quotes it exactly).
    """
    if isinstance(value, (str, bytes, bytearray, bool, np.bool_, complex, np.complexfloating)):
        raise _not_a_number(reg, value)
    if type(value) is int and abs(value) >= 2**63:  # beyond int64, so beyond every register
        raise RegisterRangeError(
            f"{reg.name} (register {reg.number}): value {value} is outside the range "
            f"{reg.range_text} ({reg.format.value}, manual {reg.section})")
    try:
        arr = np.asarray(value)
    except (TypeError, ValueError) as exc:  # a ragged sequence
        raise _not_a_number(reg, value) from exc
    if arr.dtype.kind not in "iuf":
        raise _not_a_number(reg, value)
    return arr.astype(np.float64, copy=False)


def _check_not_reserved(reg: Register) -> None:
    if reg.access == Access.RESERVED:
        raise ReadOnlyRegisterError(
            f"{reg.name} (register {reg.number}) is reserved (manual {reg.section}); it has no "
            "format and cannot hold a value")


def to_raw(reg: Register, value: Any) -> np.ndarray:
    """Convert user units to the stored integer, validating the range (manual 3.1, 3.2.N).

    ``raw = round_half_away(value · scale)`` with scale 4096 for Fixed4, 256 for Fixed8, 65536
    for Fixed16, 16777216 for Fixed24 and 1 otherwise: ``V_SOLL = 1600.7`` stores 1601. A
    register that holds a code rather than a quantity (:func:`whole_only`: MODE_REG, CNTRL_BITS,
    HOME_MODE, …) takes whole numbers only: ``MODE_REG = 0.5`` is refused, ``1.0`` is mode 1.

    Parameters
    ----------
    reg : Register
        Target register.
    value : array_like
        Scalar or array in user units.

    Returns
    -------
    numpy.ndarray
        int64 array of the shape of ``value`` (0-d for a scalar).

    Raises
    ------
    RegisterRangeError
        If any value is NaN, infinite or outside ``[minimum, maximum]``, not a whole number for
        a :func:`whole_only` register, or not a real number at all (str, bytes, bool, complex:
        :func:`real_values`); the message names the register, its number, its range with unit
        and the manual section.
    ReadOnlyRegisterError
        For a reserved register.
    """
    _check_not_reserved(reg)
    v = real_values(reg, value)
    if v.size <= _SCALAR_MAX:
        raw = raws_of_floats(reg, v.ravel().tolist())
        if raw is not None:
            return np.array(raw, dtype=np.int64).reshape(v.shape)
    lo, hi = _user_bounds(reg)
    bad = ~np.isfinite(v) | (v < lo) | (v > hi)
    if np.any(bad):
        flat = v[bad] if v.ndim else v.reshape(1)
        more = f" (and {int(np.count_nonzero(bad)) - 1} more)" if np.count_nonzero(bad) > 1 else ""
        raise RegisterRangeError(
            f"{reg.name} (register {reg.number}): value {flat.flat[0]:g}{more} is outside the "
            f"range {reg.range_text} ({reg.format.value}, manual {reg.section})")
    if whole_only(reg):
        frac = v != np.floor(v)
        if np.any(frac):
            raise RegisterRangeError(
                f"{reg.name} (register {reg.number}): value {v[frac].flat[0]:g} "
                f"is not a whole number; {reg.name} holds a code or a count, not a quantity that "
                f"could be rounded: give an integer (manual {reg.section})")
    raw = round_half_away(v * reg.scale)
    return np.clip(raw, reg.raw_min, reg.raw_max).astype(np.int64)


@njit(cache=True, inline="always")
def _raw(x: float, scale: float, raw_min: float, raw_max: float) -> int:  # pragma: no cover
    """Stored integer of ``x`` in user units: ``round_half_away(x · scale)`` within the raw
    range (compiled callers; the same IEEE operations as :func:`to_raw`'s numpy path)."""
    y = x * scale
    return int(min(max(math.copysign(math.floor(abs(y) + 0.5), y), raw_min), raw_max))


@njit(**KERNEL)
def _raws_within(v: np.ndarray, lo: float, hi: float, scale: float, raw_min: float,
                 raw_max: float, whole: float, out: np.ndarray) -> int:  # pragma: no cover
    """``out[j]`` = stored integer of ``v[j]`` (1-D arrays) while ``lo <= v[j] <= hi`` and,
    if ``whole`` is 1, ``v[j]`` is a whole number (:func:`whole_only`).

    Returns the position of the first value outside ``[lo, hi]`` (NaN included) or not whole,
    or −1.
    """
    for j in range(v.shape[0]):
        if not lo <= v[j] <= hi:
            return j
        if whole > 0.5 and v[j] != math.floor(v[j]):
            return j
        out[j] = _raw(v[j], scale, raw_min, raw_max)
    return -1


def raw_bounds(reg: Register) -> tuple[float, float, float, float, float, float]:
    """Conversion constants of a register: accepted user-unit interval (lo, hi), scale, raw
    range (raw_min, raw_max) and 1.0 if values must be whole numbers (:func:`whole_only`, else
    0.0), as floats (a row of the ``bounds`` of :func:`raws_of_rows`)."""
    lo, hi = _user_bounds(reg)
    return (float(lo), float(hi), float(reg.scale), float(reg.raw_min), float(reg.raw_max),
            float(whole_only(reg)))


@njit(**KERNEL)
def raws_of_rows(values: np.ndarray, bounds: np.ndarray,
                 out: np.ndarray) -> int:  # pragma: no cover - compiled
    """:func:`to_raw` of several registers at once, compiled (register writes in a batch).

    Parameters
    ----------
    values : numpy.ndarray
        (K, M) float64: row ``k`` in user units of register ``k``.
    bounds : numpy.ndarray
        (K, 6) float64: :func:`raw_bounds` of register ``k``.
    out : numpy.ndarray
        (K, M) int64, receives the stored integers.

    Returns
    -------
    int
        −1 when every value is in range; else the first row ``k`` with a value that is NaN,
        infinite, out of range or not whole where it must be (``out`` then partly written;
        :func:`to_raw` of that row raises the error).
    """
    for k in range(values.shape[0]):
        b = bounds[k]
        if _raws_within(values[k], b[0], b[1], b[2], b[3], b[4], b[5], out[k]) >= 0:
            return k
    return -1


def raws_of_floats(reg: Register, values: list[float]) -> list[int] | None:
    """:func:`to_raw` of a few Python floats without numpy's fixed cost per call (compiled,
    the same IEEE operations).

    Parameters
    ----------
    reg : Register
        Target register (not reserved).
    values : list of float
        Values in user units.

    Returns
    -------
    list of int or None
        The stored integers, or None if a value is NaN, infinite, out of range or not whole
        where it must be (then :func:`to_raw` raises the error).
    """
    v = np.array(values, dtype=np.float64)
    out = np.empty(v.size, dtype=np.int64)
    if _raws_within(v, *raw_bounds(reg), out) >= 0:
        return None
    return out.tolist()


def from_raw(reg: Register, raw: Any) -> np.ndarray:
    """Convert stored integers to user units (manual 3.1).

    Parameters
    ----------
    reg : Register
        Source register.
    raw : array_like
        Stored integer(s).

    Returns
    -------
    numpy.ndarray
        float64 ``raw / scale`` for the Fixed formats (Fixed4, Fixed8, Fixed16, Fixed24), int64
        otherwise (0-d for a scalar).
    """
    r = np.asarray(raw)
    if reg.format in _FIXED:
        return r.astype(np.float64) / reg.scale
    return r.astype(np.int64)


def saturate_raw(reg: Register, x: Any) -> np.ndarray:
    """Round and saturate a firmware result to the register, without raising (docs/model.md §4).

    This is what a store by the firmware does: ``clip(round_half_away(x · scale), raw_min,
    raw_max)``. ``x`` is in user units (for Word/Integer/LongInt that is the raw unit). NaN is
    stored as 0, ±inf as the limits.

    Parameters
    ----------
    reg : Register
        Target register.
    x : array_like
        Computed value(s) in user units.

    Returns
    -------
    numpy.ndarray
        int64 raw value(s).
    """
    v = np.nan_to_num(np.asarray(x, dtype=np.float64), nan=0.0, posinf=np.inf, neginf=-np.inf)
    scaled = np.clip(v * reg.scale, reg.raw_min, reg.raw_max)
    return np.clip(round_half_away(scaled), reg.raw_min, reg.raw_max).astype(np.int64)


def _as_int_array(x: Any, what: str) -> np.ndarray:
    a = np.asarray(x)
    if a.dtype.kind == "f":
        if not np.all(np.isfinite(a)) or np.any(a != np.round(a)):
            raise RegisterRangeError(f"{what} must be integers, got {echo(x)}")
        return a.astype(np.int64)
    if a.dtype.kind not in "iub":
        raise RegisterRangeError(f"{what} must be integers, got {echo(x)}")
    return a.astype(np.int64)


def _scalar_or_array(a: np.ndarray) -> Any:
    return int(a) if a.ndim == 0 else a


def split_longint(raw: Any) -> tuple[Any, Any]:
    """Split a signed 32-bit LongInt into its (low, high) unsigned 16-bit words (manual 3.1, 3.2).

    Register N holds the low word and N+1 the high word; on the line the low word is sent first
    (see the module docstring). Two's complement: −1 → (0xFFFF, 0xFFFF).

    Parameters
    ----------
    raw : int or array_like
        Value(s) in −2**31 … 2**31−1.

    Returns
    -------
    (low, high) : tuple
        Python ints for a scalar input, int64 arrays otherwise.

    Raises
    ------
    RegisterRangeError
        If a value does not fit in 32 signed bits.
    """
    return split_word32(raw, signed=True)


def join_longint(low: Any, high: Any) -> Any:
    """Join (low, high) 16-bit words into a signed 32-bit LongInt (manual 3.1, 3.2).

    Inverse of :func:`split_longint`: (0x4711, 0x0005) → 0x00054711, (0xFFFF, 0xFFFF) → −1.

    Parameters
    ----------
    low, high : int or array_like
        Unsigned words 0 … 65535 (register N and N+1).

    Returns
    -------
    int or numpy.ndarray
        Python int for scalar inputs, int64 array otherwise.

    Raises
    ------
    RegisterRangeError
        If a word is outside 0 … 65535.
    RegisterShapeError
        If ``low`` and ``high`` do not broadcast together.
    """
    return join_word32(low, high, signed=True)


def to_word16(reg: Register, raw: Any) -> np.ndarray:
    """Map stored integer(s) to the unsigned 16-bit word(s) on the serial line (manual 3.1, 5).

    Word and LongIntHigh pass through; Integer, Fixed4 and Fixed8 are 16-bit two's complement
    (−1 → 0xFFFF); a LongInt and the 32-bit formats at one number (Int32, Word32, Fixed16,
    Fixed24) give two words, low first.

    Parameters
    ----------
    reg : Register
        Register the value belongs to.
    raw : array_like
        Stored integer(s).

    Returns
    -------
    numpy.ndarray
        int64 words 0 … 65535: shape of ``raw`` for one-word formats, ``raw.shape + (2,)``
        (``[..., 0]`` low, ``[..., 1]`` high) for LongInt and the 32-bit formats.

    Raises
    ------
    RegisterRangeError
        If a raw value does not fit the register's format (manual 3.1).
    """
    _check_not_reserved(reg)
    a = _as_int_array(raw, f"{reg.name} (register {reg.number}) raw values")
    lo, hi = FORMAT_RAW_RANGE[reg.format]
    if np.any((a < lo) | (a > hi)):
        raise RegisterRangeError(
            f"{reg.name} (register {reg.number}): raw value {echo(raw)} does not fit the "
            f"{reg.format.value} format ({lo} … {hi}, manual 3.1)")
    if reg.format == Format.LONGINT:
        low, high = split_longint(a)
        return np.stack([np.asarray(low), np.asarray(high)], axis=-1).astype(np.int64)
    if reg.format in FORMATS_32_ONE_NUMBER:
        low, high = split_word32(a, signed=reg.format != Format.WORD32)
        return np.stack([np.asarray(low), np.asarray(high)], axis=-1).astype(np.int64)
    return (a & 0xFFFF).astype(np.int64)


def from_word16(reg: Register, word: Any) -> np.ndarray:
    """Map serial-line word(s) back to the stored integer(s) (manual 3.1, 5); inverse of
    :func:`to_word16`.

    Parameters
    ----------
    reg : Register
        Register the words belong to.
    word : array_like
        Words 0 … 65535; for a LongInt or a 32-bit format the last axis must have length 2
        (low, high).

    Returns
    -------
    numpy.ndarray
        int64 raw value(s). Integer/Fixed words ≥ 0x8000 are negative (0x8000 → −32768, which
        no register accepts; range checks are the writer's job).

    Raises
    ------
    RegisterRangeError
        If a word is outside 0 … 65535.
    RegisterShapeError
        If a LongInt's or 32-bit format's words do not have a trailing axis of length 2.
    """
    _check_not_reserved(reg)
    w = _as_int_array(word, f"{reg.name} (register {reg.number}) words")
    if np.any((w < 0) | (w > 0xFFFF)):
        raise RegisterRangeError(
            f"{reg.name} (register {reg.number}): words must be 0 … 65535, got {echo(word)}")
    if reg.format == Format.LONGINT:
        if w.ndim == 0 or w.shape[-1] != 2:
            raise RegisterShapeError(
                f"{reg.name} (register {reg.number}) is a LongInt: expected words with a "
                f"trailing axis of length 2 (low, high), got shape {w.shape}")
        return np.asarray(join_longint(w[..., 0], w[..., 1]), dtype=np.int64)
    if reg.format in FORMATS_32_ONE_NUMBER:
        if w.ndim == 0 or w.shape[-1] != 2:
            raise RegisterShapeError(
                f"{reg.name} (register {reg.number}) is {reg.format.value}: expected words with "
                f"a trailing axis of length 2 (low, high), got shape {w.shape}")
        return np.asarray(join_word32(w[..., 0], w[..., 1], signed=reg.format != Format.WORD32),
                          dtype=np.int64)
    if reg.format in _SIGNED16:
        return np.where(w >= 0x8000, w - 0x10000, w).astype(np.int64)
    return w.astype(np.int64)


def split_word32(raw: Any, signed: bool = True) -> tuple[Any, Any]:
    """Split 32-bit value(s) into (low, high) unsigned 16-bit words, low word first on the line.

    For the 32-bit formats at one register number: Int32, Fixed16 and Fixed24 (raw values
    signed, two's complement: −1 → (0xFFFF, 0xFFFF)) and Word32 (``signed=False``).

    Parameters
    ----------
    raw : int or array_like
        Raw value(s): −2**31 … 2**31−1 when ``signed``, else 0 … 2**32−1.
    signed : bool
        Whether the raw values are signed.

    Returns
    -------
    (low, high) : tuple
        Python ints for a scalar input, int64 arrays otherwise.

    Raises
    ------
    RegisterRangeError
        If a value is not an integer or does not fit in 32 bits of the given signedness.
    """
    a = _as_int_array(raw, "32-bit values")
    lo, hi = (-(2**31), 2**31 - 1) if signed else (0, 2**32 - 1)
    if np.any((a < lo) | (a > hi)):
        kind = "signed" if signed else "unsigned"
        raise RegisterRangeError(f"32-bit value {echo(raw)} does not fit in 32 {kind} bits "
                                 f"({lo} … {hi})")
    u = a & 0xFFFFFFFF
    return _scalar_or_array(u & 0xFFFF), _scalar_or_array(u >> 16)


def join_word32(low: Any, high: Any, signed: bool = True) -> Any:
    """Join (low, high) 16-bit words into 32-bit value(s); inverse of :func:`split_word32`.

    Parameters
    ----------
    low, high : int or array_like
        Unsigned words 0 … 65535.
    signed : bool
        Two's complement result (Int32, Fixed16, Fixed24) if True, unsigned (Word32) if False.

    Returns
    -------
    int or numpy.ndarray
        Python int for scalar inputs, int64 array otherwise.

    Raises
    ------
    RegisterRangeError
        If a word is not an integer in 0 … 65535.
    RegisterShapeError
        If ``low`` and ``high`` do not broadcast together.
    """
    lo = _as_int_array(low, "32-bit value words")
    hi = _as_int_array(high, "32-bit value words")
    for w in (lo, hi):
        if np.any((w < 0) | (w > 0xFFFF)):
            raise RegisterRangeError(f"words must be 0 … 65535, got {echo(low)}, {echo(high)}")
    try:
        lo, hi = np.broadcast_arrays(lo, hi)
    except ValueError as exc:
        raise RegisterShapeError(f"low and high word shapes differ: {lo.shape} vs {hi.shape}"
                                 ) from exc
    u = (hi << 16) | lo
    if signed:
        u = np.where(u >= 2**31, u - 2**32, u)
    return _scalar_or_array(np.asarray(u).astype(np.int64))
