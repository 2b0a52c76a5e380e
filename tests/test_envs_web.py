"""Web line process model: strain, radius, tension, load cell; GearSync wiring."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import jvl_gym  # noqa: F401
from jvl_gym.envs import web
from jvl_gym.envs.profiles import SpeedProfile, row_speed
from jvl_gym.families.mac050_141 import layout as L


def test_strain_settles_to_speed_difference_over_winder_speed() -> None:
    v1, v2 = np.array([1.0, 2.0]), np.array([1.004, 1.98])
    eps = np.array([0.0, 0.01])
    for _ in range(2000):
        eps = web.span_step(eps, v1, v2, np.array([1.0, 0.5]), 0.01)
    np.testing.assert_allclose(eps, (v2 - v1) / v2, rtol=1e-8)
    np.testing.assert_allclose(web.steady_strain(v1, v2), (v2 - v1) / v2)


@settings(max_examples=50, deadline=None)
@given(st.floats(0.0, 0.01), st.floats(0.1, 3.0), st.floats(0.1, 3.0), st.floats(0.2, 3.0))
def test_span_step_is_exact_independent_of_step(eps0: float, v1: float, v2: float,
                                                length: float) -> None:
    e = np.array([eps0])
    a = web.span_step(e, np.array([v1]), np.array([v2]), np.array([length]), 0.02)
    b = e
    for _ in range(4):
        b = web.span_step(b, np.array([v1]), np.array([v2]), np.array([length]), 0.005)
    np.testing.assert_allclose(a, b, rtol=1e-10, atol=1e-14)


def test_span_step_at_standstill_holds_strain() -> None:
    e = web.span_step(np.array([0.003]), np.array([0.0]), np.array([0.0]), np.array([1.0]), 0.1)
    np.testing.assert_allclose(e, [0.003])


@settings(max_examples=50, deadline=None)
@given(st.floats(0.01, 0.1), st.floats(1e-5, 1e-3), st.floats(0.0, 500.0))
def test_winder_radius_conserves_wound_area(r0: float, h: float, wound: float) -> None:
    r = web.winder_radius(np.array([r0]), np.array([h]), np.array([wound]))
    np.testing.assert_allclose(np.pi * (r**2 - r0**2), h * wound, rtol=1e-9, atol=1e-15)


def test_tension_is_zero_when_slack_and_linear_when_taut() -> None:
    f = web.tension(np.array([-0.01, 0.0, 0.002]), np.array([5000.0, 5000.0, 5000.0]))
    np.testing.assert_allclose(f, [0.0, 0.0, 10.0])


def test_load_cell_converges_to_force() -> None:
    m = np.zeros(1)
    for _ in range(200):
        m = web.load_cell_step(m, np.array([12.0]), 0.001, 0.005)
    np.testing.assert_allclose(m, [12.0], rtol=1e-12)


def test_gear_sync_starts_at_reference_and_loads_the_motor_with_the_web() -> None:
    env = gym.make("jvl_gym/GearSync-v0")
    env.reset(seed=2)
    core = env.unwrapped.core
    assert core.motors.mode_name(0) == "AG_MODE"
    np.testing.assert_allclose(core.force, core.tension_ref, rtol=1e-12)
    for _ in range(50):
        env.step(np.zeros(1, dtype=np.float32))
    load = core.motors.inputs[0, L.I_LOAD_TORQUE]
    np.testing.assert_allclose(load, core.radius * core.force / core.gear_ratio)
    assert core.wound[0] > 0 and core.radius[0] > core.r0[0]


def test_gear_sync_analogue_input_trims_the_tension() -> None:
    """More analogue input -> faster winder -> more tension (AG factor 0.87..1.15)."""
    finals = []
    for a in (-0.3, 0.3):
        env = gym.make("jvl_gym/GearSync-v0", randomization={"speed_step": (0, 0),
                                                                "walk": (0, 0)})
        env.reset(seed=9)
        for _ in range(150):
            _, _, term, _, _ = env.step(np.array([a], dtype=np.float32))
            if term:
                break
        finals.append((env.unwrapped.core.force[0], term))
    (f_lo, _), (f_hi, _) = finals
    assert f_hi > f_lo


def test_slack_web_terminates_the_episode() -> None:
    env = gym.make("jvl_gym/GearSync-v0")
    env.reset(seed=0)
    for _ in range(1500):
        _, _, term, trunc, _ = env.step(np.array([-1.0], dtype=np.float32))
        if term or trunc:
            break
    core = env.unwrapped.core
    assert term and core.strain[0] <= 0.0


def test_scalar_twins_equal_the_numpy_model() -> None:
    rng = np.random.default_rng(0)
    for _ in range(200):
        e, v1, v2, length = rng.uniform(-0.01, 0.01), *rng.uniform(0.0, 3.0, 2), rng.uniform(
            0.2, 3.0)
        ref = web.span_step(np.array([e]), np.array([v1]), np.array([v2]), np.array([length]),
                            0.00192)[0]
        assert web.span_step_s(e, v1, v2, length, 0.00192) == pytest.approx(ref, rel=1e-12,
                                                                            abs=1e-15)
        r0, h, wound = rng.uniform(0.01, 0.1), rng.uniform(1e-5, 1e-3), rng.uniform(0, 100)
        assert web.winder_radius_s(r0, h, wound) == pytest.approx(
            web.winder_radius(np.array([r0]), np.array([h]), np.array([wound]))[0], rel=1e-14)
        assert web.tension_s(e, 5000.0) == web.tension(np.array([e]), np.array([5000.0]))[0]


def test_profile_row_speed_equals_the_vectorised_profile() -> None:
    n = 16
    prof = SpeedProfile(n)
    rngs = [np.random.default_rng(k) for k in range(n)]
    u = np.random.default_rng(1).uniform(size=(6, n))
    prof.reset(np.arange(n), rngs, 0.5 + u[0], 0.2 + u[1], u[2] - 0.5, 1 + u[3], 0.05 * u[4],
               0.01 * u[5])
    t = np.linspace(0.0, 5.0, n)
    theta = np.linspace(0.0, 30.0, n)
    ref = prof.speed(t, theta)
    got = [row_speed(prof.params[i], t[i], theta[i], prof.t_change) for i in range(n)]
    np.testing.assert_allclose(got, ref, rtol=1e-12, atol=1e-15)


def test_many_copies_run_the_same_line_as_one() -> None:
    """From 32 copies the motor kernel runs multi-threaded between compiled line updates."""
    n = 32
    venv = gym.make_vec("jvl_gym/GearSync-v0", num_envs=n, vectorization_mode="vector_entry_point")
    acts = np.random.default_rng(3).uniform(-0.2, 0.2, (20, n, 1)).astype(np.float32)
    venv.reset(seed=40)
    for a in acts:
        obs, *_ = venv.step(a)
    single = gym.make("jvl_gym/GearSync-v0")
    single.reset(seed=40 + 5)
    for a in acts:
        o, *_ = single.step(a[5])
    np.testing.assert_array_equal(o, obs[5])
