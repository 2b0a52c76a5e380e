"""The SB3 VecEnv adapter passes the checks of SB3's own vec-env tests."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode
from stable_baselines3 import PPO
from stable_baselines3.common.vec_env import VecMonitor

import jvl_gym  # noqa: F401
from jvl_gym.rl.sb3_adapter import SB3VecEnv, make_sb3_env

N = 3


def test_terminal_observation_and_truncation_flags() -> None:
    """As SB3's test_vecenv_terminal_obs: the terminal observation is the episode's last one,
    the returned observation is the next episode's first; TimeLimit.truncated on time limits."""
    venv = make_sb3_env("jvl_gym/Positioning-v0", N, max_episode_steps=4)
    ref = gym.make_vec("jvl_gym/Positioning-v0", num_envs=N,
                       vectorization_mode="vector_entry_point", max_episode_steps=4,
                       autoreset_mode=AutoresetMode.DISABLED)
    venv.seed(21)
    obs = venv.reset()
    np.testing.assert_array_equal(obs, ref.reset(seed=21)[0])
    a = np.full((N, 1), 0.2, dtype=np.float32)
    for step in range(4):
        obs, rew, dones, infos = venv.step(a)
        r_obs, r_rew, r_term, r_trunc, _ = ref.step(a)
        np.testing.assert_allclose(rew, r_rew.astype(np.float32))
        if step < 3:
            assert not dones.any() and all("terminal_observation" not in i for i in infos)
    assert dones.all()
    for i in range(N):
        np.testing.assert_array_equal(infos[i]["terminal_observation"], r_obs[i])
        assert infos[i]["TimeLimit.truncated"] is True
    fresh = ref.reset(options={"reset_mask": np.ones(N, dtype=bool)})[0]
    np.testing.assert_array_equal(obs, fresh)


def test_terminated_episodes_are_not_flagged_as_truncated() -> None:
    venv = make_sb3_env("jvl_gym/FilterTuning-v0", 2)
    venv.reset()
    _, _, dones, infos = venv.step(np.zeros((2, 3), dtype=np.float32))
    assert dones.all()
    assert all(i["TimeLimit.truncated"] is False for i in infos)
    assert all(i["terminal_observation"].shape == (7,) for i in infos)


def test_seeding_is_reproducible_and_distinct() -> None:
    def first(seed: int | None) -> np.ndarray:
        v = make_sb3_env("jvl_gym/GearSync-v0", N)
        if seed is not None:
            assert v.seed(seed) == [seed + i for i in range(N)]
        obs = v.reset()
        for _ in range(5):
            obs, *_ = v.step(np.zeros((N, 1), dtype=np.float32))
        return obs

    np.testing.assert_array_equal(first(3), first(3))
    assert not np.array_equal(first(3), first(4))


def test_get_set_attr_env_method_and_wrapping() -> None:
    venv = make_sb3_env("jvl_gym/Positioning-v0", N)
    venv.reset()
    assert venv.get_attr("max_episode_steps") == [300] * N
    assert venv.get_attr("max_episode_steps", indices=[0, 2]) == [300, 300]
    venv.set_attr("overshoot_weight", 3.5)
    assert venv.get_attr("overshoot_weight") == [3.5] * N
    with pytest.raises(ValueError):
        venv.set_attr("overshoot_weight", 1.0, indices=[1])
    venv.set_attr("target", 1234, indices=[1])  # per-copy array attribute
    assert [int(t) for t in venv.get_attr("target")][1] == 1234
    assert venv.env_method("error_bits", indices=[0])[0].shape == (N,)
    assert venv.env_is_wrapped(gym.Wrapper) == [False] * N
    assert venv.render_mode is None


def test_adapter_needs_same_step_autoreset() -> None:
    native = gym.make_vec("jvl_gym/Positioning-v0", num_envs=2,
                          vectorization_mode="vector_entry_point")
    with pytest.raises(ValueError):
        SB3VecEnv(native)


def test_ppo_learns_a_few_steps_through_the_adapter() -> None:
    venv = VecMonitor(make_sb3_env("jvl_gym/Positioning-v0", 4, max_episode_steps=20))
    model = PPO("MlpPolicy", venv, n_steps=32, batch_size=64, n_epochs=1, seed=0,
                device="cpu")
    model.learn(total_timesteps=256)
    assert len(model.ep_info_buffer) > 0  # VecMonitor saw finished episodes
    action, _ = model.predict(venv.reset(), deterministic=True)
    assert action.shape == (4, 1)
