"""A load behind an elastic coupling in the envs' domain randomisation (docs/envs.md)."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest

from jvl_gym.physics.coupling import coupling_for


def _vec(env_id: str, **kw):
    return gym.make_vec(env_id, num_envs=3, vectorization_mode="vector_entry_point", **kw)


def test_coupling_for_gives_the_resonance_and_damping_ratio() -> None:
    j_m, j_l, f, z = 2e-5, 7e-5, 120.0, 0.03
    k, d = coupling_for(j_m, j_l, f, z)
    inv = 1 / j_m + 1 / j_l
    wn = math.sqrt(k * inv)
    assert wn / (2 * math.pi) == pytest.approx(f, rel=1e-12)
    assert d * inv / (2 * wn) == pytest.approx(z, rel=1e-12)
    assert coupling_for(j_m, 0.0, f, z) == (0.0, 0.0)
    assert coupling_for(j_m, j_l, 0.0, z) == (0.0, 0.0)


def test_positioning_draws_couplings_in_the_range_and_rigid_by_default() -> None:
    env = _vec("jvl_gym/Positioning-v0", randomization={"resonance_hz": (40.0, 200.0),
                                                         "inertia_ratio": (1.0, 5.0)})
    env.reset(seed=3)
    p = env.motors.parameters
    j_m = env.rotor_inertia(np.arange(3))
    wn = np.sqrt(p["coupling_stiffness"] * (1 / j_m + 1 / p["load_inertia"]))
    f = wn / (2 * math.pi)
    assert np.all((f >= 40.0 - 1e-9) & (f <= 200.0 + 1e-9))
    assert np.all(p["coupling_damping"] > 0.0)
    env.reset(seed=3, options={"randomization": {"resonance_hz": (0.0, 0.0)}})
    assert np.all(env.motors.parameters["coupling_stiffness"] == 0.0)
    rigid = _vec("jvl_gym/Positioning-v0")
    rigid.reset(seed=3)
    assert np.all(rigid.motors.parameters["coupling_stiffness"] == 0.0)


@pytest.mark.parametrize("ranges", [{"resonance_hz": (0.0, 900.0)}, {"resonance_hz": (-1.0, 9.0)},
                                    {"coupling_damping_ratio": (-0.1, 0.1)}])
def test_bad_coupling_ranges_are_refused(ranges) -> None:
    with pytest.raises(ValueError, match="resonance_hz|coupling_damping_ratio"):
        _vec("jvl_gym/Positioning-v0", randomization=ranges)


def test_a_refused_reset_option_changes_nothing() -> None:
    env = _vec("jvl_gym/Positioning-v0")
    env.reset(seed=1)
    before = {k: v.copy() for k, v in env.motors.parameters.items()}
    with pytest.raises(ValueError, match="622 Hz"):
        env.reset(options={"randomization": {"resonance_hz": (0.0, 5000.0)}})
    after = env.motors.parameters
    assert all(np.array_equal(before[k], after[k]) for k in before)


def test_families_without_a_coupling_refuse_it() -> None:
    with pytest.raises(ValueError, match="no elastic coupling"):
        _vec("jvl_gym/Positioning-v0", motor_type="MAC800",
             randomization={"resonance_hz": (50.0, 60.0)})
    with pytest.raises(ValueError, match="no elastic coupling"):
        _vec("jvl_gym/StepperIndexing-v0", randomization={"resonance_hz": (50.0, 60.0)})
