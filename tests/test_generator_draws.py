"""The compiled draws of many generators (``envs.generator_draws``) are numpy's own draws."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from jvl_gym.envs.generator_draws import draw_rows, uniform_rows

seeds = st.lists(st.integers(0, 2**63), min_size=0, max_size=6)


@settings(max_examples=40, deadline=None)
@given(seeds=seeds, width=st.integers(0, 9), raws=st.integers(0, 4), skip=st.integers(0, 3))
def test_draws_are_the_numpy_calls_and_leave_the_same_states(seeds, width, raws, skip):
    ours = [np.random.default_rng(s) for s in seeds]
    theirs = [np.random.default_rng(s) for s in seeds]
    for a, b in zip(ours, theirs):  # generators part-way through their streams
        a.random(skip)
        b.random(skip)
    if skip % 2:  # both kinds in one call, or one call each
        u, k = draw_rows(ours, width, raws)
    else:
        u = uniform_rows(ours, width)
        k = draw_rows(ours, 0, raws)[1]
    assert u.shape == (len(seeds), width) and u.dtype == np.float64
    assert k.shape == (len(seeds), raws) and k.dtype == np.uint64
    for j, rng in enumerate(theirs):
        np.testing.assert_array_equal(u[j], rng.random(width))
        np.testing.assert_array_equal(k[j], rng.bit_generator.random_raw(raws))
    for a, b in zip(ours, theirs):  # the streams go on alike, for any kind of draw
        assert a.bit_generator.state == b.bit_generator.state
        assert a.normal() == b.normal() and a.integers(0, 7, dtype=np.int32) == b.integers(
            0, 7, dtype=np.int32)


def test_generators_of_another_kind_are_drawn_by_numpy():
    ours = [np.random.default_rng(1), np.random.Generator(np.random.Philox(2))]
    theirs = [np.random.default_rng(1), np.random.Generator(np.random.Philox(2))]
    u, k = draw_rows(ours, 3, 2)
    for j, rng in enumerate(theirs):
        np.testing.assert_array_equal(u[j], rng.random(3))
        np.testing.assert_array_equal(k[j], rng.bit_generator.random_raw(2))
