"""The checks of world inputs (``motor.inputs.staged_inputs``): a few values, checked as Python
floats, get the verdict many values get from numpy."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from jvl_gym.motor.inputs import InputRule, staged_inputs

_RULES = {"free": InputRule(), "volts": InputRule(0.0, 60.0, unit="V"),
          "counts": InputRule(whole=True, unit="counts"),
          "level": InputRule(0.0, 1.0, whole=True, allow_bool=True)}
_COLUMNS = {name: k for k, name in enumerate(_RULES)}
_VALUES = st.one_of(st.floats(allow_nan=True, allow_infinity=True, width=64),
                    st.integers(-100, 100).map(float), st.sampled_from([0.0, 0.5, 60.0, 60.5]))


def _outcome(name: str, values: np.ndarray) -> tuple[str, object]:
    try:
        [(_, out)] = staged_inputs({name: values}, _COLUMNS, _RULES, values.size)
    except ValueError as exc:  # the message up to the values it quotes
        return "refused", str(exc).split(",")[0]
    return "set", out.tolist()


@given(name=st.sampled_from(sorted(_RULES)), values=st.lists(_VALUES, min_size=1, max_size=8))
@settings(max_examples=200, deadline=None)
def test_a_few_inputs_are_checked_as_many_are(name: str, values: list[float]) -> None:
    """The rules give the same verdict, with the same message, on a few values (checked as
    Python floats) as on the same values within many (checked with numpy)."""
    few = np.array(values)
    many = np.concatenate([few, np.full(64 - few.size, 1.0)])
    verdict, detail = _outcome(name, few)
    assert (verdict, detail) == _outcome(name, many) if verdict == "refused" else (
        _outcome(name, many)[0] == "set" and detail == values)


@pytest.mark.parametrize(("name", "value", "message"), [
    ("free", [1.0, math.nan], "values must be finite"),
    ("counts", [1.0, 2.5], "must be whole counts"),
    ("volts", [1.0, 61.0], "must be within 0..60 V"),
    ("level", [0.0, 2.0], "must be within 0..1"),
])
def test_a_broken_input_rule_is_named(name: str, value: list[float], message: str) -> None:
    with pytest.raises(ValueError, match=message):
        staged_inputs({name: np.array(value)}, _COLUMNS, _RULES, 2)
