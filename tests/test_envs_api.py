"""Gymnasium API of every jvl_gym env: checker, make/make_vec, seeding, autoreset, pickling."""

from __future__ import annotations

import pickle
import warnings

import gymnasium as gym
import numba
import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from gymnasium.vector import AutoresetMode

import jvl_gym  # noqa: F401
from jvl_gym.envs import ENV_IDS

SHORT = {"jvl_gym/FilterTuning-v0": 1}


def _actions(env_id: str, n_steps: int, n: int, dim: int, seed: int = 7) -> np.ndarray:
    a = np.random.default_rng(seed).uniform(-1, 1, (n_steps, n, dim)).astype(np.float32)
    if env_id == "jvl_gym/StepperIndexing-v0":  # moderate profiles: episodes run a while
        a[..., :2] = -0.65 + 0.35 * a[..., :2]
        a[..., 2] = 0.65 + 0.35 * a[..., 2]
    return a


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_check_env_passes_without_warnings(env_id: str) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        env = gym.make(env_id)
        check_env(env.unwrapped, skip_render_check=False)
        env.close()


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_make_vec_vector_entry_point_without_warnings(env_id: str) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        venv = gym.make_vec(env_id, num_envs=3, vectorization_mode="vector_entry_point")
        obs, _ = venv.reset(seed=0)
        assert obs.shape == (3, *venv.single_observation_space.shape)
        assert venv.metadata["autoreset_mode"] == AutoresetMode.NEXT_STEP
        assert venv.unwrapped.max_episode_steps == gym.spec(env_id).max_episode_steps
        obs, rew, term, trunc, _ = venv.step(venv.action_space.sample())
        assert obs in venv.observation_space and rew.shape == (3,) and term.dtype == bool
        venv.close()


def _assert_vector_copies_equal_single_envs(env_id: str, n: int, steps: int, seed: int,
                                            copies: list[int], action_seed: int = 7) -> None:
    """Copies ``copies`` of an n-copy vector env seeded ``seed`` equal single envs seeded
    ``seed + i`` for the same actions (observations with noise, rewards)."""
    venv = gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point",
                        obs_noise=0.05)
    dim = venv.single_action_space.shape[0]
    acts = _actions(env_id, steps, n, dim, seed=action_seed)
    vobs = [venv.reset(seed=seed)[0]]
    vrew = []
    for a in acts:
        o, r, *_ = venv.step(a)
        vobs.append(o)
        vrew.append(r)
    for i in copies:
        env = gym.make(env_id, obs_noise=0.05)
        np.testing.assert_array_equal(env.reset(seed=seed + i)[0], vobs[0][i])
        for k, a in enumerate(acts):
            o, r, terminated, truncated, _ = env.step(a[i])
            np.testing.assert_array_equal(o, vobs[k + 1][i])
            assert r == vrew[k][i]
            if terminated or truncated:  # the vector copy starts its next episode
                break


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_single_and_vector_trajectories_are_identical(env_id: str) -> None:
    _assert_vector_copies_equal_single_envs(env_id, 3, SHORT.get(env_id, 25), 11, [0, 1, 2])


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_pickled_env_continues_identically(env_id: str) -> None:
    env = gym.make(env_id)
    env.reset(seed=3)
    a = env.action_space.sample()
    if SHORT.get(env_id) != 1:
        env.step(a)
    clone = pickle.loads(pickle.dumps(env))
    # the same argument types for the compiled step (a writable copy of a read-only array
    # would compile the step again)
    views = [e.unwrapped.core.motors.engine_view() for e in (env, clone)]
    assert [numba.typeof(x) for x in views[0]] == [numba.typeof(x) for x in views[1]]
    o1, r1, *_ = env.step(a)
    o2, r2, *_ = clone.step(a)
    np.testing.assert_array_equal(o1, o2)
    assert r1 == r2


def test_next_step_autoreset_returns_reset_observation_with_zero_reward() -> None:
    venv = gym.make_vec("jvl_gym/Positioning-v0", num_envs=2,
                        vectorization_mode="vector_entry_point", max_episode_steps=3)
    venv.reset(seed=0)
    a = np.full((2, 1), 0.3, dtype=np.float32)
    for _ in range(2):
        _, _, _, trunc, _ = venv.step(a)
        assert not trunc.any()
    _, _, _, trunc, _ = venv.step(a)
    assert trunc.all()
    obs, rew, term, trunc, _ = venv.step(a)
    assert not (term | trunc).any() and np.all(rew == 0.0)
    fresh = gym.make("jvl_gym/Positioning-v0")
    # the reset after an episode continues each copy's own generator: copy 0 of a vector env
    # seeded 0 equals a single env seeded 0 that was reset twice
    fresh.reset(seed=0)
    np.testing.assert_array_equal(obs[0], fresh.reset()[0])


def test_same_step_autoreset_reports_final_observation() -> None:
    venv = gym.make_vec("jvl_gym/Positioning-v0", num_envs=2,
                        vectorization_mode="vector_entry_point", max_episode_steps=3,
                        autoreset_mode=AutoresetMode.SAME_STEP)
    single = gym.make("jvl_gym/Positioning-v0", max_episode_steps=3)
    venv.reset(seed=5)
    single.reset(seed=5)
    a = np.full((2, 1), -0.4, dtype=np.float32)
    for _ in range(3):
        obs, rew, term, trunc, info = venv.step(a)
        s_obs, s_rew, _, s_trunc, _ = single.step(a[0])
        assert rew[0] == s_rew
    assert trunc.all() and s_trunc
    assert info["_final_obs"].all()
    np.testing.assert_array_equal(info["final_obs"][0], s_obs)
    np.testing.assert_array_equal(obs[0], single.reset()[0])


def test_reset_options_randomization_motor_type_and_mask() -> None:
    venv = gym.make_vec("jvl_gym/Positioning-v0", num_envs=3,
                        vectorization_mode="vector_entry_point")
    core = venv.unwrapped
    venv.reset(seed=0, options={"randomization": {"target_turns": (1.0, 1.0)},
                                "motor_type": "MAC095"})
    assert np.all(core.target == 4096)
    assert all(cfg.name == "MAC095" for cfg in core.motors.motor_configs)
    for _ in range(3):
        venv.step(np.zeros((3, 1), dtype=np.float32))
    t_before = core._t.copy()
    venv.reset(options={"reset_mask": np.array([False, True, False])})
    assert core._t[1] == 0 and core._t[0] == t_before[0] and core._t[2] == t_before[2]
    with pytest.raises(ValueError):
        venv.reset(options={"randomization": {"no_such_parameter": (0, 1)}})


def test_reset_draws_from_each_copy_generator_in_order() -> None:
    """Copy i seeded s + i draws: the randomised parameters, the motor type, two noise keys."""
    venv = gym.make_vec("jvl_gym/Positioning-v0", num_envs=3,
                        vectorization_mode="vector_entry_point",
                        motor_type=["MAC050", "MAC095", "MAC140", "MAC141"])
    core = venv.unwrapped
    venv.reset(seed=7)
    for i in range(3):
        rng = np.random.default_rng(7 + i)
        u = rng.random(len(core._range_names))
        u_type = rng.random()
        keys = rng.integers(0, 2**64 - 1, size=2, dtype=np.uint64, endpoint=True)
        lo, hi = core.ranges["target_turns"]
        turns = lo + u[core._range_names.index("target_turns")] * (hi - lo)
        assert core.target[i] == np.round(turns * 4096)
        assert core.motors.motor_configs[i].name == core.motor_types[int(u_type * 4)]
        assert core.motors.keys[i] == keys[0] and core._noise_key[i] == keys[1]


def test_constructor_ranges_and_decimation() -> None:
    env = gym.make("jvl_gym/Positioning-v0", decimation=3,
                   randomization={"target_turns": (-0.5, -0.5)}, motor_type=["MAC140"])
    env.reset(seed=1)
    core = env.unwrapped.core
    assert core.target[0] == -2048
    env.step(np.zeros(1, dtype=np.float32))
    assert core.motors.state[0, jvl_gym.families.mac050_141.layout.S_TICK] == 3 * 15
    with pytest.raises(ValueError):
        gym.make("jvl_gym/Positioning-v0", randomization={"target_turns": (1, -1)})
    with pytest.raises(ValueError):
        gym.make("jvl_gym/Positioning-v0", motor_type="MAC999")


def test_observation_noise_is_seeded_and_bounded() -> None:
    a = gym.make("jvl_gym/GearSync-v0", obs_noise=0.1)
    b = gym.make("jvl_gym/GearSync-v0", obs_noise=0.1)
    c = gym.make("jvl_gym/GearSync-v0")
    oa, ob, oc = a.reset(seed=4)[0], b.reset(seed=4)[0], c.reset(seed=4)[0]
    np.testing.assert_array_equal(oa, ob)
    assert not np.array_equal(oa, oc)
    assert np.all(np.abs(oa) <= 5.0)


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_render_draws_a_scope_image(env_id: str) -> None:
    env = gym.make(env_id, render_mode="rgb_array")
    env.reset(seed=0)
    env.step(env.action_space.sample())
    img = env.render()
    assert img.dtype == np.uint8 and img.ndim == 3 and img.shape[2] == 3
    assert img.std() > 0  # something was drawn
    plain = gym.make(env_id)
    plain.reset(seed=0)
    assert plain.render() is None


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_bad_actions_are_refused_and_change_nothing(env_id: str) -> None:
    venv = gym.make_vec(env_id, num_envs=2, vectorization_mode="vector_entry_point")
    obs, _ = venv.reset(seed=5)
    core = venv.unwrapped
    m = core.motors
    before = (m.regs.copy(), m.state.copy(), m.inputs.copy(), core._t.copy())
    bad = np.zeros((2, *venv.single_action_space.shape), dtype=np.float32)
    bad[1, 0] = np.nan
    with pytest.raises(ValueError, match="finite"):
        venv.step(bad)
    with pytest.raises(ValueError, match="shape"):
        venv.step(np.zeros((3, 7), dtype=np.float32))
    after = (m.regs, m.state, m.inputs, core._t)
    for x, y in zip(before, after):
        np.testing.assert_array_equal(x, y)
    np.testing.assert_array_equal(core._obs, obs)


@pytest.mark.parametrize("env_id", [e for e in ENV_IDS if e not in SHORT])
def test_threaded_vector_step_equals_single_envs(env_id: str) -> None:
    """From PARALLEL_MIN copies the compiled step runs copies in threads: same trajectories."""
    from jvl_gym.engine import PARALLEL_MIN

    n = PARALLEL_MIN + 1
    _assert_vector_copies_equal_single_envs(env_id, n, 12, 20, [0, n - 1], action_seed=3)


def _splitmix_normals(keys: np.ndarray, counters: np.ndarray, k: int) -> np.ndarray:
    """SplitMix64 uniforms and Box–Muller written out in numpy: the reference of the
    counter-based generator (jvl_gym.noise)."""
    golden, m1, m2 = (np.uint64(0x9E3779B97F4A7C15), np.uint64(0xBF58476D1CE4E5B9),
                      np.uint64(0x94D049BB133111EB))

    def mix(z: np.ndarray) -> np.ndarray:
        z = (z ^ (z >> np.uint64(30))) * m1
        z = (z ^ (z >> np.uint64(27))) * m2
        return z ^ (z >> np.uint64(31))

    ch = (np.arange(1, 2 * k + 1, dtype=np.uint64) * np.uint64(0xD1B54A32D192ED03))[None, :]
    z = keys[:, None] + golden * (counters.astype(np.uint64)[:, None] + np.uint64(1)) + ch
    u = ((mix(mix(z)) >> np.uint64(11)).astype(np.float64) + 1.0) * (1.0 / 9007199254740993.0)
    return np.sqrt(-2.0 * np.log(u[:, :k])) * np.cos(2.0 * np.pi * u[:, k:])


def test_observation_noise_is_the_splitmix64_stream() -> None:
    from jvl_gym.motor.noise import normals

    keys = np.array([1, 2**63 + 5, 12345678901234567], dtype=np.uint64)
    counters = np.array([0, 7, 123456], dtype=np.int64)
    np.testing.assert_array_equal(normals(keys, counters, 5),
                                  _splitmix_normals(keys, counters, 5))
