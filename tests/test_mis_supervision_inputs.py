"""The MIS world inputs of the hardware supervision refuse what is not a value of theirs and
then change nothing (``MisMotorArray.set_input``): not finite, outside the physical range, not
whole where it must be; the defaults are the nominal values, so a motor that is not told
otherwise runs as before (control and STO channels at 24 V, 25 °C, no fault)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from jvl_gym import MotorArray
from jvl_gym.families.mis import constants as c

#: input → (low, high) of its physical range
RANGES = {"supply_volts": (0.0, 150.0), "control_volts": (0.0, 48.0),
          "ambient_celsius": (-40.0, 150.0), "sto_a": (0.0, 48.0), "sto_b": (0.0, 48.0),
          "faults": (0.0, float(c.FAULT_BITS))}

_M = MotorArray(["MIS232", "SMC85"], n=2, seed=0)


def test_inputs_at_rest_are_the_nominal_values() -> None:
    m = MotorArray("MIS232", n=1, seed=0)
    got = {name: m.inputs[0, m.INPUTS[name]] for name in RANGES if name != "supply_volts"}
    assert got == {"control_volts": 24.0, "ambient_celsius": 25.0, "sto_a": 24.0,
                   "sto_b": 24.0, "faults": 0.0}
    assert {name: m.INPUT_RULES[name].low for name in RANGES} == {
        k: v[0] for k, v in RANGES.items()}
    assert {name: m.INPUT_RULES[name].high for name in RANGES} == {
        k: v[1] for k, v in RANGES.items()}


@settings(max_examples=60, deadline=None)
@given(name=st.sampled_from(sorted(RANGES)),
       value=st.one_of(st.just(math.nan), st.just(math.inf), st.just(-math.inf),
                       st.floats(allow_nan=False, allow_infinity=False)),
       other=st.booleans())
def test_a_bad_value_is_refused_and_changes_nothing(name: str, value: float,
                                                    other: bool) -> None:
    """A value that is not finite or outside the range (or not whole for ``faults``, or a
    fault bit the motors cannot have) raises ValueError and sets no input, not even another
    one given with it."""
    low, high = RANGES[name]
    ok = math.isfinite(value) and low <= value <= high
    if name == "faults" and ok:
        # both motors have the H2 (code 3): no fault of the H3/H4's, and the MIS232 no
        # driver overload
        h3_h4 = (c.ERR_ENCODER_LOST_POSITION | c.ERR_ENCODER_REED | c.ERR_ENCODER_COM
                 | c.ERR_H4_ENCODER)
        refused = h3_h4 | c.ERR_DRIVER_OVERLOAD | ~c.FAULT_BITS
        ok = value == int(value) and int(value) & refused == 0
    before = _M.inputs.copy()
    extra = {"load_torque": 0.25} if other else {}
    if ok:
        return
    with pytest.raises(ValueError):
        _M.set_input(**extra, **{name: value})
    np.testing.assert_array_equal(_M.inputs, before)
