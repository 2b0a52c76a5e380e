"""The MAC050–141 tasks on the MAC800 family: an env's family follows from its motor
types, the hooks are specialised per family, observations and actions are in the family's own
units, CoilWinding refuses the MAC800 (docs/envs.md)."""

from __future__ import annotations

import warnings

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import jvl_gym  # noqa: F401
from jvl_gym.families.mac800 import constants as c800
from jvl_gym.families.mac800 import task as t800

ENVS = ("jvl_gym/Positioning-v0", "jvl_gym/GearSync-v0", "jvl_gym/FilterTuning-v0")
STEPS = {"jvl_gym/FilterTuning-v0": 2}


def _run(env_id: str, n: int, seed: int, steps: int, **kw):
    venv = gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point",
                        motor_type="MAC800", obs_noise=0.05, **kw)
    dim = venv.single_action_space.shape[0]
    acts = np.random.default_rng(5).uniform(-1, 1, (steps, n, dim)).astype(np.float32)
    out = [venv.reset(seed=seed)[0]]
    rewards = []
    for a in acts:
        o, r, *_ = venv.step(a)
        out.append(o)
        rewards.append(r)
    return venv, acts, np.array(out), np.array(rewards)


@pytest.mark.parametrize("env_id", ENVS)
def test_check_env_passes_without_warnings_on_mac800(env_id: str) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        env = gym.make(env_id, motor_type="MAC800")
        assert env.unwrapped.core.family_key == "mac800"
        check_env(env.unwrapped, skip_render_check=False)
        env.close()


@pytest.mark.parametrize("env_id", ENVS)
def test_single_equals_vector_and_runs_are_deterministic(env_id: str) -> None:
    steps = STEPS.get(env_id, 25)
    _, acts, vobs, vrew = _run(env_id, 3, 21, steps)
    _, _, again, again_rew = _run(env_id, 3, 21, steps)
    np.testing.assert_array_equal(vobs, again)
    np.testing.assert_array_equal(vrew, again_rew)
    for i in (0, 2):
        env = gym.make(env_id, motor_type="MAC800", obs_noise=0.05)
        np.testing.assert_array_equal(env.reset(seed=21 + i)[0], vobs[0][i])
        for k, a in enumerate(acts):
            o, r, terminated, truncated, _ = env.step(a[i])
            np.testing.assert_array_equal(o, vobs[k + 1][i])
            assert r == vrew[k][i]
            if terminated or truncated:
                break


def test_positioning_baseline_reaches_the_target_on_mac800() -> None:
    env = gym.make_vec("jvl_gym/Positioning-v0", num_envs=4,
                       vectorization_mode="vector_entry_point", motor_type=["MAC800", "MAC400"],
                       baseline=True, max_episode_steps=600)
    env.reset(seed=3)
    core = env.unwrapped
    for _ in range(599):
        obs, _, term, trunc, _ = env.step(np.zeros((4, 1), dtype=np.float32))
        assert not term.any()
    error = core.target - core.motors.read_raw("P_IST")
    assert np.all(np.abs(core.target) > 100)  # real moves
    assert np.all(np.abs(error) <= 0.005 * c800.COUNTS_PER_REV), error
    # the observation is in the MAC800's units: 2 turns of 8000 counts, 3000 rpm at 770 Hz
    np.testing.assert_allclose(obs[:, 0], error / (2.0 * 8000), atol=1e-6)
    v_norm = 3000.0 / 60.0 * 8000 / 770.0
    np.testing.assert_allclose(obs[:, 2], core.motors.read_raw("V_IST") / v_norm, atol=1e-6)


def test_positioning_torque_action_is_the_mac800_analogue_torque_mode() -> None:
    env = gym.make_vec("jvl_gym/Positioning-v0", num_envs=1,
                       vectorization_mode="vector_entry_point", motor_type="MAC800")
    env.reset(seed=0)
    m = env.unwrapped.motors
    assert int(m.read_raw("MODE_REG")[0]) == c800.ANALOG_TORQUE_MODE
    env.step(np.full((1, 1), 0.5, dtype=np.float32))
    env.step(np.full((1, 1), 0.5, dtype=np.float32))
    # ±full action ↔ ±2047 ANINP ↔ ±T_SOLL (firmware/analog.py: VF_OUT = ANINP·T_SOLL/2047)
    assert abs(int(m.read_raw("ANINP")[0]) - 1024) <= 1
    assert abs(int(m.read_raw("VF_OUT")[0]) - 512) <= 1


def _gear_sync_errors(policy, steps: int) -> tuple[float, np.ndarray]:
    env = gym.make_vec("jvl_gym/GearSync-v0", num_envs=3,
                       vectorization_mode="vector_entry_point", motor_type="MAC800")
    obs, _ = env.reset(seed=4)
    core = env.unwrapped
    errors, ended = [], np.zeros(3, dtype=bool)
    for _ in range(steps):
        obs, _, term, trunc, _ = env.step(policy(obs))
        ended |= term | trunc
        errors.append(np.where(ended, np.nan, np.abs(core.force / core.tension_ref - 1.0)))
    return float(np.nanmean(errors)), ended


def test_gear_sync_runs_the_mac800_analogue_gear_mode_and_the_pi_baseline_holds() -> None:
    from jvl_gym.envs.baselines import ZeroAction, make_baseline

    env = gym.make_vec("jvl_gym/GearSync-v0", num_envs=2,
                       vectorization_mode="vector_entry_point", motor_type="MAC800")
    env.reset(seed=4)
    core = env.unwrapped
    m = core.motors
    assert np.all(m.read_raw("MODE_REG") == t800.ANALOG_GEAR_MODE)
    assert np.all(m.read_raw("GEARF_2") == 1000)
    assert core.gear_ratio == pytest.approx(7.5)  # 10 at 4000 rpm → 7.5 at 3000 rpm
    assert np.all(m.read("KVOUT") > 1.4)  # KVOUT = 1 + inertia ratio (0.5 … 3)
    env.step(np.zeros((2, 1), dtype=np.float32))
    # action 0 ↔ 0 V ↔ ANINP 0, the analogue gear factor's centre 1.01; action 1 ↔ ANINP 2047
    np.testing.assert_array_equal(m.read_raw("ANINP"), 0)
    env.step(np.ones((2, 1), dtype=np.float32))
    np.testing.assert_array_equal(m.read_raw("ANINP"), 2047)
    steps = 600
    pi_error, pi_ended = _gear_sync_errors(make_baseline("jvl_gym/GearSync-v0", 3, 1,
                                                          motor_type="MAC800"), steps)
    fixed_error, _ = _gear_sync_errors(ZeroAction(3, 1), steps)
    assert not pi_ended.any()
    assert pi_error < 0.1 and pi_error < fixed_error


def test_filter_tuning_on_mac800_writes_the_main_filter_pi_and_its_baseline_is_stable() -> None:
    env = gym.make_vec("jvl_gym/FilterTuning-v0", num_envs=3,
                       vectorization_mode="vector_entry_point", motor_type="MAC800",
                       randomization={"inertia_ratio": (1.0, 3.0)})
    core = env.unwrapped
    assert core.obs_labels[:2] == ("type_MAC400", "type_MAC800")
    assert env.single_observation_space.shape == (5,)
    # the viscous range is scaled to the MAC800's torque per speed (≈ 10 × the MAC140's)
    lo, hi = core.default_ranges["viscous_friction"]
    assert lo == 0.0 and 4e-4 < hi < 6e-4
    env.reset(seed=0)
    m = core.motors
    # the default setup's I-P split (configs/setups/MAC800.yaml): ki in VF, kp/ki in VB
    i = m.read("KVFX6")[0]
    p = -m.read("KVB3")[0] * i
    np.testing.assert_allclose((p, i), (0.2 / 2.004, 0.015 / 2.004), rtol=2e-3)
    env.step(np.array([[1.0, 0.0, -1.0]] * 3, dtype=np.float32))
    # proportional × 2, integral × 1 as a PI in VF, VB = 1, KVOUT = 1 (written before the trial)
    np.testing.assert_allclose(m.read("KVFX6"), 2 * p + i, atol=3e-4)
    np.testing.assert_allclose(m.read("KVFX5"), -2 * p, atol=3e-4)
    np.testing.assert_allclose(m.read("KVB4"), 1.0)
    np.testing.assert_allclose(m.read("KVB3"), 0.0)
    np.testing.assert_allclose(m.read("KVOUT"), 1.0)
    base = gym.make_vec("jvl_gym/FilterTuning-v0", num_envs=3,
                        vectorization_mode="vector_entry_point", motor_type="MAC800",
                        baseline=True, randomization={"inertia_ratio": (1.0, 3.0)})
    base.reset(seed=1)
    _, reward, term, _, _ = base.step(np.zeros((3, 3), dtype=np.float32))
    assert term.all() and not base.unwrapped.metrics["unstable"].any()
    assert np.all(reward > -base.unwrapped.instability_penalty)


def test_coil_winding_refuses_the_mac800_and_families_do_not_mix() -> None:
    with pytest.raises(ValueError, match=r"CoilWinding.*MAC800.*COIL mode"):
        gym.make("jvl_gym/CoilWinding-v0", motor_type="MAC800")
    with pytest.raises(ValueError, match="one family"):
        gym.make("jvl_gym/Positioning-v0", motor_type=["MAC140", "MAC800"])
    with pytest.raises(ValueError, match="MIS232.*refused.*step motor"):
        gym.make("jvl_gym/GearSync-v0", motor_type="MIS232")
    env = gym.make_vec("jvl_gym/Positioning-v0", num_envs=2,
                       vectorization_mode="vector_entry_point", motor_type="MAC800")
    env.reset(seed=0)
    with pytest.raises(ValueError, match="MAC400"):
        env.reset(options={"motor_type": "MAC140"})  # the motors are MAC800-family ones
    env.reset(options={"motor_type": "MAC400"})


def test_each_family_has_its_own_specialisation() -> None:
    from jvl_gym.envs import positioning

    for motor_type in ("MAC140", "MAC800"):
        env = gym.make("jvl_gym/Positioning-v0", motor_type=motor_type)
        env.reset(seed=0)
        env.step(np.zeros(1, dtype=np.float32))
    drivers = positioning.TASK._drivers
    assert set(drivers) >= {"mac050_141", "mac800"}
    assert drivers["mac050_141"].serial is not drivers["mac800"].serial


@pytest.fixture(scope="module")
def mac800_envs():
    out = {}
    for env_id in ENVS:
        venv = gym.make_vec(env_id, num_envs=2, vectorization_mode="vector_entry_point",
                            motor_type="MAC800")
        venv.reset(seed=0)
        out[env_id] = venv
    return out


@settings(max_examples=25, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(env_index=st.integers(0, len(ENVS) - 1),
       shape=st.sampled_from([(2,), (1, 1), (3, 1), (2, 4), (1, 2), (2, 1, 1)]),
       bad=st.sampled_from(["nan", "inf", "shape"]))
def test_bad_actions_are_refused_and_change_nothing(mac800_envs, env_index, shape, bad) -> None:
    env_id = ENVS[env_index]
    venv = mac800_envs[env_id]
    core = venv.unwrapped
    dim = venv.single_action_space.shape[0]
    m = core.motors
    before = (m.regs.copy(), m.state.copy(), m.inputs.copy(), core._t.copy(), core._obs.copy())
    if bad == "shape":
        if shape == (2, dim):
            shape = (2, dim + 1)
        a = np.zeros(shape, dtype=np.float32)
        match = "shape"
    else:
        a = np.zeros((2, dim), dtype=np.float32)
        a[1, dim - 1] = np.nan if bad == "nan" else np.inf
        match = "finite"
    with pytest.raises(ValueError, match=match):
        venv.step(a)
    after = (m.regs, m.state, m.inputs, core._t, core._obs)
    for x, y in zip(before, after):
        np.testing.assert_array_equal(x, y)


@pytest.mark.parametrize("env_id", ENVS)
def test_pickled_mac800_env_continues_identically(env_id: str) -> None:
    import pickle

    env = gym.make(env_id, motor_type="MAC400")
    env.reset(seed=3)
    a = env.action_space.sample()
    if env_id != "jvl_gym/FilterTuning-v0":
        env.step(a)
    clone = pickle.loads(pickle.dumps(env))
    assert clone.unwrapped.core.family_key == "mac800"
    o1, r1, *_ = env.step(a)
    o2, r2, *_ = clone.step(a)
    np.testing.assert_array_equal(o1, o2)
    assert r1 == r2
