"""The design searches' shortcuts give what the plain computation gives: the integral-gain levels
tried from the largest down (``tuning.synthesis._feasible``), ``models.polymul`` and the
speed plants kept by ``models.speed_plant``."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from tuning.models import MotorData, _lifted_speed_plant, polymul, speed_plant
from tuning.synthesis import _feasible

SETTINGS = settings(max_examples=60, deadline=None, derandomize=True)
REGS = {"KIFX2": 1.6, "KIFX1": -1.35, "KIFY1": 1.0, "KIFY0": 0.0, "KIB1": 1.0, "KIB0": 0.0}


def _largest_integral(feasible: list) -> tuple:
    """The current loop's choice: the largest integral gain (the first in grid order)."""
    return max(feasible, key=lambda f: f[1])


def _most_damped_near_largest_integral(feasible: list) -> tuple:
    """The speed loop's choice: the largest proportional gain within 2 % of the largest
    integral gain (the first in grid order)."""
    top = max(f[1] for f in feasible)
    return max((f for f in feasible if f[1] >= 0.98 * top), key=lambda f: f[0])


@st.composite
def grids(draw: st.DrawFn) -> tuple[int, int, set[tuple[int, int]], float]:
    """Grid sizes, the feasible points (indices) and the ratio of neighbouring integral
    gains."""
    n_p, n_i = draw(st.integers(1, 7)), draw(st.integers(1, 7))
    ok = draw(st.sets(st.tuples(st.integers(0, n_p - 1), st.integers(0, n_i - 1))))
    return n_p, n_i, ok, draw(st.sampled_from([1.01, 1.015, 1.03, 1.5]))


@SETTINGS
@given(grid=grids())
def test_the_largest_integral_levels_choose_what_the_whole_grid_chooses(grid):
    n_p, n_i, ok, ratio = grid
    grid_p = np.geomspace(0.03, 1.2, n_p)
    grid_i = 0.002 * ratio ** np.arange(n_i)  # levels 1 % to 50 % apart: some within 2 %
    calls = []

    def candidate(kpn: float, kin: float) -> tuple | None:
        i, j = int(np.flatnonzero(grid_p == kpn)[0]), int(np.flatnonzero(grid_i == kin)[0])
        calls.append((i, j))
        return (kpn, kin, i, j) if (i, j) in ok else None

    full = _feasible(grid_p, grid_i, candidate, None)
    assert len(calls) == n_p * n_i and [f[2:] for f in full] == sorted(ok)
    for within, choose in ((1.0, _largest_integral), (0.98, _most_damped_near_largest_integral)):
        calls.clear()
        some = _feasible(grid_p, grid_i, candidate, within)
        assert len(calls) <= n_p * n_i
        if not ok:
            assert some == [] and len(calls) == n_p * n_i
        else:
            assert choose(some) == choose(full)


coefficients = st.lists(st.sampled_from([0.0, -0.0, 1.0, -2.5, 1e-300, 3.25e7]), min_size=1,
                        max_size=5)


@SETTINGS
@given(a=coefficients, b=coefficients)
def test_polymul_is_numpys_polymul(a, b):
    got, want = polymul(a, b), np.polymul(a, b)
    assert type(got) is np.ndarray and got.dtype == want.dtype
    assert got.tobytes() == np.asarray(want).tobytes()


def test_speed_plant_is_kept_per_exact_arguments():
    md = MotorData.from_config("MAC140")
    first = speed_plant(md, REGS, J=3e-5)
    assert speed_plant(md, dict(REGS), J=3e-5) is first
    fresh = _lifted_speed_plant(md, REGS, 3e-5, 0.0, None, False)
    for got, want in ((first.num, fresh.num), (first.den, fresh.den)):
        assert np.asarray(got[0][0]).tobytes() == np.asarray(want[0][0]).tobytes()
    assert speed_plant(md, {**REGS, "KIFY0": -0.0}, J=3e-5) is not first
    assert speed_plant(md, REGS, J=3e-5 * (1 + 1e-15)) is not first
    assert speed_plant(md, {**REGS, "KIFX2": 1.7}, J=3e-5) is not first
    assert speed_plant(md.with_(R_phase=md.R_phase * 1.3), REGS, J=3e-5) is not first
    other = speed_plant(md, REGS, J=3e-5, b=1e-5)
    assert other is not first and speed_plant(md, REGS, J=3e-5, b=1e-5) is other
    assert speed_plant(md, REGS, J=3e-5) is first


def test_speed_plant_needs_the_current_loop_registers():
    md = MotorData.from_config("MAC140")
    with pytest.raises(KeyError):
        speed_plant(md, {k: v for k, v in REGS.items() if k != "KIB0"})
