"""The firmware blocks the servo families share (``jvl_gym.physics.levels``,
``jvl_gym.physics.correction``): the analogue input's level with hysteresis (MAC050–141 manual
4.1.10), the zero-search sensor's edge (4.4.14, 4.4.15) and the speed loop's torque limit with
the function correction (4.2)."""

from __future__ import annotations

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from jvl_gym.physics.correction import corrected_profile, held_output, vf_output
from jvl_gym.physics.levels import hysteresis_level, sensor_edge

HIGH, LOW = 5.4, 4.4  # A2POS: high above 5.4 V, low below 4.4 V (manual 4.1.10)


@pytest.mark.parametrize(("level", "volts", "after"), [
    (0.0, 5.0, 0.0), (0.0, 5.5, 1.0), (1.0, 4.5, 1.0), (1.0, 4.3, 0.0), (1.0, 9.0, 1.0),
    (0.0, -9.0, 0.0)])
@pytest.mark.statements("mac050_141:4.1.10:1")
def test_hysteresis_level_switches_only_beyond_its_thresholds(level, volts, after):
    assert hysteresis_level(level, volts, HIGH, LOW) == after


@given(st.sampled_from([0.0, 1.0]), st.floats(-20.0, 20.0))
@pytest.mark.statements("mac050_141:4.1.10:1")
def test_hysteresis_level_keeps_its_level_inside_the_band(level, volts):
    after = hysteresis_level.py_func(level, volts, HIGH, LOW)
    if LOW <= volts <= HIGH:
        assert after == level
    else:
        assert after == (1.0 if volts > HIGH else 0.0)


def test_sensor_edge_rising_finds_the_sensor_becoming_active():
    assert sensor_edge(True, 0.0, True, False)
    assert not sensor_edge(True, 1.0, True, False)  # already active: no edge
    assert not sensor_edge(False, 1.0, True, False)
    assert not sensor_edge(True, -1.0, True, False)  # first sample of the search: no edge yet


def test_sensor_edge_falling_needs_the_search_armed():
    assert sensor_edge(False, 1.0, False, True)
    assert not sensor_edge(False, 1.0, False, False)
    assert not sensor_edge(True, 0.0, False, True)
    assert not sensor_edge(False, -1.0, False, True)


def test_vf_output_is_the_filter_output_and_its_scaling():
    assert vf_output(100.0, 40.0, 0.5, 3.0, 2.0) == (60.0, 33.0, 66.0)


@settings(deadline=None)  # the first example compiles ``rnd``
@given(st.floats(-5000.0, 5000.0), st.floats(0.05, 4.0), st.floats(0.1, 3.0),
       st.floats(-50.0, 50.0), st.floats(10.0, 1023.0))
@pytest.mark.statements("mac050_141:4.1.2:7")
def test_corrected_profile_brings_the_output_to_the_torque_limit(f, k_ff, x0, rest, t_limit):
    """With FF_OUT = k_ff·FNC_OUT (a one-tap FF) the corrected FNC_OUT gives VF_OUT at the
    limit within the rounding of FNC_OUT (half a unit times the gain)."""
    scale = 1.5
    _, _, vf = vf_output.py_func(k_ff * f, 0.0, x0, rest, scale)
    if abs(vf) <= t_limit:
        return
    gain = scale * x0 * k_ff
    f_new = corrected_profile.py_func(f, vf, t_limit, gain)
    assert f_new == math.floor(f_new)
    _, _, vf_new = vf_output.py_func(k_ff * f_new, 0.0, x0, rest, scale)
    assert abs(abs(vf_new) - t_limit) <= 0.5 * gain + 1e-9 * abs(vf)
    assert math.copysign(1.0, vf_new) == math.copysign(1.0, vf)


def test_held_output_limits_and_keeps_the_history_unscaled():
    assert held_output(1500.0, 1023.0, 2.0) == (1023.0, 511.5)
    assert held_output(-1500.0, 300.0, 0.5) == (-300.0, -600.0)
    assert held_output(1500.0, 1023.0, 0.0) == (1023.0, 0.0)


def test_compiled_blocks_equal_their_python():
    for args in [(0.0, 5.5, HIGH, LOW), (1.0, 4.0, HIGH, LOW), (1.0, 5.0, HIGH, LOW)]:
        assert hysteresis_level(*args) == hysteresis_level.py_func(*args)
    assert corrected_profile(10.0, 2000.0, 1023.0, 3.7) == \
        corrected_profile.py_func(10.0, 2000.0, 1023.0, 3.7)
