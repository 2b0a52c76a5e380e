"""Quantisation of filter coefficients to their register formats (manual 3.1, 3.2.89–3.2.111,
3.2.13, 3.2.126, 3.2.127).

Formats, scales, ranges and manual sections come from the register table of the family the
registers are for (the ``table`` argument: the MAC050–141's, docs/registers.md, or e.g. the
MAC800's Fixed16 = raw/65536 and Fixed24 = raw/16777216 of its register overview §1.2), the
one source of these facts: on the MAC050–141 Fixed4 = raw/4096 and Fixed8 = raw/256 with the
raw range of the table (±32767, so Fixed4 ±7.999756, Fixed8 ±127.996; AMPLITUDE 0 … 0.83).
A value outside its register's range raises :class:`QuantizationError` naming the register and
its section (nothing is silently saturated).
Integrators stay exact: a filter whose denominator coefficients sum to 1 (``KIFY1 + KIFY0 = 1``,
``KVFY3 + … + KVFY0 = 1``) is quantised so that the stored values still sum to exactly 1 (the
largest-remainder rounding of the sum), and the sum of a PI numerator (the integral gain
``KVFX4 + KVFX3``, ``KIFX2 + KIFX1``) is rounded first and the direct term derived from it, so the
integral gain is as exact as the format allows.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from jvl_gym.registers import Format, RegisterTable, round_half_away

__all__ = [
    "FILTER_REGISTERS",
    "QuantizationError",
    "register_format",
    "quantize_value",
    "quantize_registers",
    "MAC050_141_GROUPS",
]

#: the registers the toolkit designs and quantises (manual 3.2.13, 3.2.89–3.2.111, 3.2.126–127)
FILTER_REGISTERS: tuple[str, ...] = (
    "KIFX2", "KIFX1", "KIFY1", "KIFY0", "KIB1", "KIB0",
    "KFF3", "KFF2", "KFF1", "KFF0", "GEARB", "KVB3", "KVB2", "KVB1", "KVB0",
    "KVFX4", "KVFX3", "KVFX2", "KVFX1", "KVFY3", "KVFY2", "KVFY1", "KVFY0",
    "KVOUT", "AMPLITUDE", "PHASE_COMP")


#: the formats the toolkit quantises: the Fixed formats of manual 3.1 and of the 32-bit tables,
#: and the 32-bit integers (MAC800 AMPLITUDE, MODEL_POT, S_ORDER)
_QUANTISED = (Format.FIXED4, Format.FIXED8, Format.FIXED16, Format.FIXED24, Format.INT32)
#: the groups of the MAC050–141 filters whose stored sums are kept exact (module docstring)
MAC050_141_GROUPS: tuple[tuple[str, ...], ...] = (
    ("KIFY1", "KIFY0"), ("KVFY3", "KVFY2", "KVFY1", "KVFY0"), ("KIFX2", "KIFX1"),
    ("KVFX4", "KVFX3", "KVFX2", "KVFX1"))


class QuantizationError(ValueError):
    """A coefficient does not fit its register format."""


def register_format(name: str, table: RegisterTable) -> tuple[str, int, int, int]:
    """(format name, scale, raw min, raw max) of a filter register of the family's register
    ``table``; KeyError for a register it does not have, ValueError for one that is not of a
    quantised format."""
    try:
        reg = table.lookup(name)
    except KeyError:
        raise KeyError(f"{name} is not a register of the family's table") from None
    if reg.format not in _QUANTISED:
        raise ValueError(f"{name} is {reg.format.value}, not a Fixed filter register")
    return reg.format.value, reg.scale, reg.raw_min, reg.raw_max


def quantize_value(name: str, value: float, table: RegisterTable) -> float:
    """Round ``value`` to register ``name``'s format; raise if it does not fit.

    Parameters
    ----------
    name : str
        A register of a quantised format (the MAC050–141's :data:`FILTER_REGISTERS`).
    value : float
        Ideal value in user units.
    table : RegisterTable
        The family's register table.

    Returns
    -------
    float
        ``round(value·scale)/scale``, halves away from zero as the motor stores it (scale
        4096 or 256, manual 3.1; :func:`jvl_gym.registers.round_half_away`).

    Raises
    ------
    QuantizationError
        The stored integer is outside the register's raw range (message: the range and the
        manual section from the register table), or KVOUT is not positive (3.2.13).
    """
    fmt, scale, lo, hi = register_format(name, table)
    raw = int(round_half_away(float(value) * scale))
    if not lo <= raw <= hi:
        sec = table.lookup(name).section
        raise QuantizationError(
            f"{name} = {value:.6g} does not fit {fmt} (range {lo / scale:.6g} … {hi / scale:.6g}, "
            f"manual {sec}); reduce the target bandwidth or change the design")
    if name == "KVOUT" and not raw > 0:
        raise QuantizationError(f"KVOUT = {value:.6g} must be positive (manual 3.2.13)")
    return raw / scale


def _exact_sum(names: list[str], regs: dict[str, float], out: dict[str, float],
               table: RegisterTable) -> None:
    """Quantise ``names`` so their stored sum equals the rounded sum of the ideal values."""
    _, scale, _, _ = register_format(names[0], table)
    ideal = np.array([regs[n] for n in names]) * scale
    target = int(round_half_away(float(ideal.sum())))
    raw = np.floor(ideal)
    rem = ideal - raw
    need = int(target - raw.sum())
    order = np.argsort(-rem) if need >= 0 else np.argsort(rem)
    for k in order[: abs(need)]:
        raw[k] += 1 if need > 0 else -1
    for n, r in zip(names, raw):
        out[n] = quantize_value(n, r / scale, table)


def quantize_registers(regs: Mapping[str, float], table: RegisterTable,
                       groups: Sequence[Sequence[str]] = MAC050_141_GROUPS
                       ) -> dict[str, float]:
    """Quantise a register set (name → value); non-filter registers are passed through.

    Parameters
    ----------
    regs : mapping
        Ideal (float) register values.
    table : RegisterTable
        The family's register table: every register of a quantised format is quantised (on
        the MAC050–141 the filter registers :data:`FILTER_REGISTERS` and L1–L4).
    groups : sequence of sequence of str
        Registers whose stored sum is kept exact (integrators, integral gains), in order;
        default :data:`MAC050_141_GROUPS`.

    Returns
    -------
    dict
        Values exactly representable in each register's format, with the integrators and
        integral gains kept exact (module docstring).

    Raises
    ------
    QuantizationError
        A value out of its format's range.
    """
    src = dict(regs)
    out: dict[str, float] = {}
    known = {r.name for r in table if r.format in _QUANTISED}
    for g in groups:
        if all(n in src for n in g):
            _exact_sum(list(g), src, out, table)
    for name, value in src.items():
        if name in out:
            continue
        out[name] = quantize_value(name, value, table) if name in known else value
    return {name: out[name] for name in src}
