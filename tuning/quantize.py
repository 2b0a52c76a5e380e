"""Quantisation of filter coefficients to their register formats (manual 3.2.89–3.2.111, 3.2.13).

Fixed4 = int16/4096 (±7.999756, resolution 2.44e-4), Fixed8 = int16/256 (±127.996, resolution
3.91e-3). A value outside its format's range raises :class:`QuantizationError` naming the
register (nothing is silently saturated). Integrators stay exact: a filter whose denominator
coefficients sum to 1 (``KIFY1 + KIFY0 = 1``, ``KVFY3 + … + KVFY0 = 1``) is quantised so that the
stored values still sum to exactly 1 (the largest-remainder rounding of the sum), and the sum of a
PI numerator (the integral gain ``KVFX4 + KVFX3``, ``KIFX2 + KIFX1``) is rounded first and the
direct term derived from it, so the integral gain is as exact as the format allows.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

__all__ = [
    "FORMATS",
    "QuantizationError",
    "register_format",
    "quantize_value",
    "quantize_registers",
]

#: name → (format, scale, min, max) for every register the toolkit writes
FIXED4 = ("Fixed4", 4096, -32768, 32767)
FIXED8 = ("Fixed8", 256, -32768, 32767)
FORMATS: dict[str, tuple[str, int, int, int]] = {
    **{n: FIXED4 for n in ("KIFX2", "KIFX1", "KIFY1", "KIFY0")},
    **{n: FIXED4 for n in ("KVFX4", "KVFX3", "KVFX2", "KVFX1", "KVFY3", "KVFY2", "KVFY1",
                           "KVFY0")},
    **{n: FIXED8 for n in ("KIB1", "KIB0", "KFF3", "KFF2", "KFF1", "KFF0", "GEARB", "KVB3",
                           "KVB2", "KVB1", "KVB0", "KVOUT", "AMPLITUDE", "PHASE_COMP")},
}
_SECTIONS = {"KIF": "3.2.106", "KIB": "3.2.110", "KFF": "3.2.89", "KVF": "3.2.93",
             "KVB": "3.2.101", "GEA": "3.2.101", "KVO": "3.2.13", "AMP": "3.2.127",
             "PHA": "3.2.126"}


class QuantizationError(ValueError):
    """A coefficient does not fit its register format."""


def register_format(name: str) -> tuple[str, int, int, int]:
    """(format name, scale, raw min, raw max) of a filter register."""
    try:
        return FORMATS[name]
    except KeyError:
        raise KeyError(f"{name} is not a filter register known to the tuning toolkit") from None


def quantize_value(name: str, value: float) -> float:
    """Round ``value`` to register ``name``'s format; raise if it does not fit."""
    fmt, scale, lo, hi = register_format(name)
    raw = round(float(value) * scale)
    if not lo <= raw <= hi:
        sec = _SECTIONS.get(name[:3], "3.2")
        raise QuantizationError(
            f"{name} = {value:.6g} does not fit {fmt} (range {lo / scale:.6g} … {hi / scale:.6g}, "
            f"manual {sec}); reduce the target bandwidth or change the design")
    if name == "KVOUT" and not 0.0 < raw / scale <= 127.996:
        raise QuantizationError(f"KVOUT = {value:.6g} must be positive (manual 3.2.13)")
    return raw / scale


def _exact_sum(names: list[str], regs: dict[str, float], out: dict[str, float]) -> None:
    """Quantise ``names`` so their stored sum equals the rounded sum of the ideal values."""
    _, scale, _, _ = register_format(names[0])
    ideal = np.array([regs[n] for n in names]) * scale
    target = round(float(ideal.sum()))
    raw = np.floor(ideal)
    rem = ideal - raw
    need = int(target - raw.sum())
    order = np.argsort(-rem) if need >= 0 else np.argsort(rem)
    for k in order[: abs(need)]:
        raw[k] += 1 if need > 0 else -1
    for n, r in zip(names, raw):
        out[n] = quantize_value(n, r / scale)


def quantize_registers(regs: Mapping[str, float]) -> dict[str, float]:
    """Quantise a register set (name → value); non-filter registers are passed through.

    Parameters
    ----------
    regs : mapping
        Ideal (float) register values.

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
    groups = [["KIFY1", "KIFY0"], ["KVFY3", "KVFY2", "KVFY1", "KVFY0"],
              ["KIFX2", "KIFX1"], ["KVFX4", "KVFX3", "KVFX2", "KVFX1"]]
    for g in groups:
        if all(n in src for n in g):
            _exact_sum(g, src, out)
    for name, value in src.items():
        if name in out:
            continue
        out[name] = quantize_value(name, value) if name in FORMATS else value
    return {name: out[name] for name in src}
