"""World inputs of a motor array: what each input accepts, checked before any is set.

A family declares its inputs (``MotorArray.INPUTS``: name → column of ``inputs``) and, where an
input accepts less than any finite real number, an :class:`InputRule` for it
(``MotorArray.INPUT_RULES``). :meth:`MotorArray.set_inputs` checks every value given against
its rule and sets none if one fails.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from .arguments import InputValue, real_array

__all__ = ["InputRule", "staged_inputs"]


@dataclass(frozen=True)
class InputRule:
    """What one world input accepts.

    Attributes
    ----------
    low, high : float
        Closed range of the values.
    whole : bool
        Only whole numbers (counts, bit patterns).
    allow_bool : bool
        ``True``/``False`` are accepted as 1/0 (levels).
    unit : str
        Unit or meaning, for messages (``"V"``, ``"counts per outer sample"``).
    """

    low: float = -math.inf
    high: float = math.inf
    whole: bool = False
    allow_bool: bool = False
    unit: str = ""


#: the rule of an input the family gives none: any finite real number
_ANY_REAL = InputRule()
#: up to this many values are checked as Python floats (an env's reset sets a few), without
#: the fixed cost of numpy's reductions
_FEW = 32


def _broken_rule(arr: np.ndarray, rule: InputRule) -> str | None:
    """The first rule the float64 values ``arr`` break, in the order checked: ``"finite"``,
    ``"whole"`` (where ``rule.whole``), ``"range"`` (outside ``rule.low..rule.high``), or None."""
    bounded = rule.low > -math.inf or rule.high < math.inf
    if arr.size <= _FEW:
        values = arr.ravel().tolist()
        if not all(map(math.isfinite, values)):
            return "finite"
        if rule.whole and not all(v.is_integer() for v in values):
            return "whole"
        if bounded and values and (min(values) < rule.low or max(values) > rule.high):
            return "range"
        return None
    if not np.isfinite(arr).all():
        return "finite"
    if rule.whole and (arr != np.round(arr)).any():
        return "whole"
    if bounded and ((arr < rule.low) | (arr > rule.high)).any():
        return "range"
    return None


def staged_inputs(values: Mapping[str, InputValue], columns: Mapping[str, int],
                  rules: Mapping[str, InputRule], count: int) -> list[tuple[int, np.ndarray]]:
    """The checked ``(column, (count,) values)`` of every input given (None: not given).

    Raises
    ------
    TypeError
        An input the family does not have.
    ValueError
        A value that is not a real number, a wrong shape, a value that is not finite, not
        whole where it must be, or outside the input's range.
    """
    staged = []
    for name, value in values.items():
        if name not in columns:
            raise TypeError(f"unknown input {name!r}; known: {', '.join(columns)}")
        if value is None:
            continue
        rule = rules.get(name) or _ANY_REAL
        arr = real_array(name, value, allow_bool=rule.allow_bool)
        if arr.ndim > 1 or (arr.ndim == 1 and arr.shape[0] != count):
            raise ValueError(f"{name}: expected a scalar or shape ({count},), got {arr.shape}")
        broken = _broken_rule(arr, rule)
        unit = f" {rule.unit}" if rule.unit else ""
        if broken == "finite":
            raise ValueError(f"{name}: values must be finite, got {value!r}")
        if broken == "whole":
            raise ValueError(f"{name} must be whole{unit}")
        if broken == "range":
            raise ValueError(f"{name} must be within {rule.low:g}..{rule.high:g}{unit}")
        staged.append((columns[name], arr if arr.ndim == 1 else np.full(count, arr)))
    return staged
