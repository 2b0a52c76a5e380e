"""The draws of an env's reset and the checks of world inputs: the fast paths give what the
plain numpy calls give (``envs.randomisation.raw_rows``/``uniforms_of``,
``motor.inputs.staged_inputs`` on a few values and on many)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from jvl_gym.envs.randomisation import raw_rows, uniform_rows, uniforms_of
from jvl_gym.motor.inputs import InputRule, staged_inputs


@given(seeds=st.lists(st.integers(0, 2**63), min_size=1, max_size=6),
       width=st.integers(1, 20), keys=st.integers(0, 3))
@settings(max_examples=60, deadline=None)
def test_one_raw_call_draws_what_the_uniforms_and_keys_draw_one_by_one(
        seeds: list[int], width: int, keys: int) -> None:
    one_by_one = [np.random.default_rng(s) for s in seeds]
    at_once = [np.random.default_rng(s) for s in seeds]
    u = uniform_rows(one_by_one, width)
    k = np.array([rng.integers(0, 2**64 - 1, size=keys, dtype=np.uint64, endpoint=True)
                  for rng in one_by_one]).reshape(len(seeds), keys)
    raw = raw_rows(at_once, width + keys)
    assert raw.dtype == np.uint64 and raw.shape == (len(seeds), width + keys)
    np.testing.assert_array_equal(uniforms_of(raw[:, :width]), u)
    np.testing.assert_array_equal(raw[:, width:], k)
    # and both generators go on with the same stream
    assert [rng.random() for rng in one_by_one] == [rng.random() for rng in at_once]


def test_uniforms_of_spans_zero_to_just_below_one() -> None:
    raw = np.array([0, 2**64 - 1], dtype=np.uint64)
    np.testing.assert_array_equal(uniforms_of(raw), [0.0, 1.0 - 2.0**-53])


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
