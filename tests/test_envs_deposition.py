"""Wire deposition model and the CoilWinding env's nominal registers."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

import jvl_gym  # noqa: F401
from jvl_gym.envs import deposition as dep
from jvl_gym.families.mac050_141 import constants as c

W, DELTA = 10.0, 0.05
CENTRES = dep.bin_centres(W, DELTA)


def _lay(h: np.ndarray, x: float, d: float, nest: bool = False) -> tuple[float, float, float]:
    base, void, xl = dep.lay_turns(h, CENTRES, np.array([0]), np.array([x]), np.array([d]), W,
                                   nest=nest)
    return float(base[0]), float(void[0]), float(xl[0])


def test_turns_at_exact_pitch_lay_a_flat_layer_without_voids() -> None:
    h = np.zeros((1, CENTRES.size))
    d = 0.5
    for k in range(20):
        base, void, _ = _lay(h, d / 2 + k * d, d)
        assert base == 0.0 and void == 0.0
    np.testing.assert_allclose(h, d)
    std, gaps, piles = dep.layer_flatness(h, np.array([0]), np.array([d]))
    assert std[0] == 0.0 and gaps[0] == 0.0 and piles[0] == 0.0


@settings(max_examples=40, deadline=None)
@given(st.lists(st.tuples(st.floats(0.0, W), st.floats(0.3, 0.7)), min_size=1, max_size=40),
       st.booleans())
def test_wound_area_is_wire_plus_voids(turns: list[tuple[float, float]], nest: bool) -> None:
    """Area conservation: the profile's area grows by d × footprint + void per turn."""
    h = np.zeros((1, CENTRES.size))
    expected = 0.0
    for x, d in turns:
        before = h.copy()
        _, void, _ = _lay(h, x, d, nest)
        changed = h != before
        footprint = np.count_nonzero(changed) * DELTA
        assert footprint > 0 and np.ptp(h[changed]) == 0.0  # the turn's top is flat
        expected += d * footprint + void
        assert void >= 0.0
    np.testing.assert_allclose(h.sum() * DELTA, expected, rtol=1e-9, atol=1e-9)


def test_overlapping_turn_climbs_without_nesting_and_slides_with_it() -> None:
    d = 0.5
    h = np.zeros((1, CENTRES.size))
    _lay(h, 2.0, d)
    base, void, _ = _lay(h, 2.0 + 0.8 * d, d)  # 20 % overlap
    assert base == d and void > 0
    h = np.zeros((1, CENTRES.size))
    _lay(h, 2.0, d, nest=True)
    base, void, x = _lay(h, 2.0 + 0.8 * d, d, nest=True)
    assert base == 0.0 and void == 0.0 and x >= 2.0 + d - 1e-9


def test_flanges_stop_the_wire() -> None:
    h = np.zeros((1, CENTRES.size))
    *_, x = _lay(h, -1.0, 0.5)
    assert x == 0.25
    *_, x = _lay(h, W + 3, 0.5)
    assert x == W - 0.25


def test_profile_summary_of_a_step_profile() -> None:
    h = np.zeros((1, 8))
    h[0, 4:] = 2.0
    s = dep.profile_summary(h, 2, np.array([1.0]))
    np.testing.assert_allclose(s, [[-1.0, 1.0]])


def test_coil_winding_nominal_registers_and_traverse_follows_the_spindle() -> None:
    env = gym.make("jvl_gym/CoilWinding-v0", randomization={
        "speed_step": (0, 0), "walk": (0, 0), "spindle_rpm": (1200, 1200),
        "ramp_time": (0.2, 0.2), "wire_diameter": (0.5e-3, 0.5e-3)})
    env.reset(seed=0)
    core = env.unwrapped.core
    m = core.motors
    assert m.mode_name(0) == "COIL_MODE"
    gear = m.read("GEARF1")[0] / m.read("GEARF2")[0]
    np.testing.assert_allclose(gear, 0.5e-3 / 2e-3 * c.COUNTS_PER_REV / 1024, rtol=1e-4)
    p4 = m.read("P4")[0]
    assert m.read("P2")[0] == round(0.25e-3 / 2e-3 * 4096)
    assert m.read("P3")[0] == p4 - m.read("P2")[0]
    for _ in range(60):  # run-up and the first few turns
        env.step(np.zeros(3, dtype=np.float32))
    x0, rev0 = core.traverse_position()[0], core.spindle_rev[0]
    for _ in range(20):
        env.step(np.zeros(3, dtype=np.float32))
    x1, rev1 = core.traverse_position()[0], core.spindle_rev[0]
    np.testing.assert_allclose((x1 - x0) / (rev1 - rev0), 0.5e-3, rtol=0.05)
    assert core.h.max() > 0  # turns were laid


def test_coil_winding_pitch_trim_changes_the_gear_factor() -> None:
    env = gym.make("jvl_gym/CoilWinding-v0")
    env.reset(seed=0)
    m = env.unwrapped.core.motors
    g0 = m.read("GEARF1")[0]
    env.step(np.array([1.0, 0.0, 0.0], dtype=np.float32))
    assert m.read("GEARF1")[0] == round(g0 * 1.05)


def test_many_copies_wind_the_same_coil_as_one() -> None:
    n = 32
    venv = gym.make_vec("jvl_gym/CoilWinding-v0", num_envs=n,
                        vectorization_mode="vector_entry_point")
    acts = np.random.default_rng(3).uniform(-1, 1, (40, n, 3)).astype(np.float32)
    venv.reset(seed=70)
    for a in acts:
        obs, *_ = venv.step(a)
    single = gym.make("jvl_gym/CoilWinding-v0")
    single.reset(seed=70 + 9)
    for a in acts:
        o, *_ = single.step(a[9])
    np.testing.assert_array_equal(o, obs[9])
    np.testing.assert_array_equal(single.unwrapped.core.h[0], venv.unwrapped.h[9])


def test_coil_winding_laid_turns_reveal_the_wire_diameter() -> None:
    labels = gym.make("jvl_gym/CoilWinding-v0").unwrapped.core.obs_labels
    k = [labels.index(n) for n in ("laid_pitch", "laid_gap", "laid_slide")]
    for bias in (-0.04, 0.04):
        env = gym.make("jvl_gym/CoilWinding-v0", randomization={
            "diameter_bias": (bias, bias), "diameter_variation": (0, 0)})
        env.reset(seed=1)
        obs = np.array([env.step(np.zeros(3, dtype=np.float32))[0][k] for _ in range(300)])
        pitch, gap, slide = obs[-1]
        np.testing.assert_allclose(pitch - gap, 10 * bias, atol=1e-3)  # 10·(d/d0 − 1)
        if bias < 0:  # thin wire: open gaps between the turns at the nominal pitch
            assert gap > 0.2
        else:  # thick wire: the turns are pushed ahead by their neighbours
            assert obs[:, 2].max() > 0.2


def test_bin_spans_equal_a_binary_search() -> None:
    """``_count_below`` finds from the uniform spacing what ``np.searchsorted`` finds."""
    from numba import njit

    count = njit(lambda c_, v, eq: dep._count_below(c_, v, eq))
    rng = np.random.default_rng(1)
    for centres in (dep.bin_centres(20e-3, 0.05e-3), dep.bin_centres(20e-3, 0.07e-3),
                    dep.bin_centres(1.0, 0.3), np.array([0.5])):
        values = np.concatenate([rng.uniform(-0.5, 1.5, 3000) * centres[-1], centres,
                                 np.nextafter(centres, np.inf), np.nextafter(centres, -np.inf),
                                 [np.inf, -np.inf, np.nan]])
        for v in values:
            assert count(centres, v, True) == np.searchsorted(centres, v, side="right")
            assert count(centres, v, False) == np.searchsorted(centres, v, side="left")
