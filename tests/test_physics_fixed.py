"""The compiled rounding of ``jvl_gym.physics.fixed``: ``rint`` is numpy's ``np.round`` of a
float, bit for bit (the env resets use it in place of ``np.round`` in compiled code)."""

from __future__ import annotations

import numpy as np
from hypothesis import given
from hypothesis import strategies as st
from numba import njit

from jvl_gym.engine.jit import KERNEL
from jvl_gym.physics.fixed import rint, rnd


@njit(**KERNEL)
def _rint_all(x: np.ndarray, out: np.ndarray) -> None:  # pragma: no cover - compiled
    for i in range(x.size):
        out[i] = rint(x[i])


@njit(**KERNEL)
def _rnd_all(x: np.ndarray, out: np.ndarray) -> None:  # pragma: no cover - compiled
    for i in range(x.size):
        out[i] = rnd(x[i])


def _apply(fn, x: np.ndarray) -> np.ndarray:
    out = np.empty_like(x)
    fn(x, out)
    return out


HALVES = np.array([-2.5, -1.5, -0.5, 0.5, 1.5, 2.5, 1e15 + 0.5, -(1e15 + 0.5)])


def test_rint_rounds_halves_to_even_and_rnd_away_from_zero() -> None:
    np.testing.assert_array_equal(_apply(_rint_all, HALVES),
                                  [-2.0, -2.0, -0.0, 0.0, 2.0, 2.0, 1e15, -1e15])
    np.testing.assert_array_equal(_apply(_rnd_all, HALVES),
                                  [-3.0, -2.0, -1.0, 1.0, 2.0, 3.0, 1e15 + 1, -(1e15 + 1)])


@given(st.lists(st.floats(allow_nan=True, allow_infinity=True), min_size=1, max_size=50))
def test_rint_is_np_round_bit_for_bit(values: list[float]) -> None:
    x = np.array(values, dtype=np.float64)
    got = _apply(_rint_all, x)
    want = np.round(x)
    np.testing.assert_array_equal(got.view(np.uint64)[~np.isnan(x)],
                                  want.view(np.uint64)[~np.isnan(x)])
    assert np.isnan(got[np.isnan(x)]).all()
