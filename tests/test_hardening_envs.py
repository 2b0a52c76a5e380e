"""Environments: exact action shapes and types, a single env that ended must be reset,
unknown keywords named, and every env's info says why an episode ended."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.vector import AutoresetMode

import jvl_gym  # noqa: F401
from jvl_gym.envs import ENV_IDS
from jvl_gym.families.mac050_141 import constants as c
from jvl_gym.families.mac050_141.firmware import regs as R


def _state(core):
    m = core.motors
    return (m.regs.copy(), m.state.copy(), m.inputs.copy(), core._t.copy(), core._obs.copy())


def _unchanged(core, before):
    for x, y in zip(before, _state(core)):
        np.testing.assert_array_equal(x, y)


def test_transposed_and_complex_actions_are_refused():
    venv = gym.make_vec("jvl_gym/CoilWinding-v0", num_envs=2,
                        vectorization_mode="vector_entry_point")
    venv.reset(seed=1)
    core = venv.unwrapped
    before = _state(core)
    with pytest.raises(ValueError, match=r"shape \(2, 3\).*got \(3, 2\)"):
        venv.step(np.zeros((3, 2), dtype=np.float32))
    with pytest.raises(ValueError, match="shape"):
        venv.step(np.zeros(6, dtype=np.float32))
    for bad in (np.zeros((2, 3), dtype=np.complex64), np.zeros((2, 3), dtype=bool),
                np.full((2, 3), "0.1"), [[0.1j, 0, 0], [0, 0, 0]]):
        with pytest.raises(ValueError, match="real"):
            venv.step(bad)
    _unchanged(core, before)


def test_single_env_reports_its_own_action_shape_and_refuses_complex():
    env = gym.make("jvl_gym/Positioning-v0")
    env.reset(seed=0)
    core = env.unwrapped.core
    before = _state(core)
    with pytest.raises(ValueError, match=r"shape \(1,\).*got \(2,\)"):
        env.unwrapped.step(np.zeros(2, dtype=np.float32))
    with pytest.raises(ValueError, match=r"shape \(1,\).*got \(1, 1\)"):
        env.unwrapped.step(np.zeros((1, 1), dtype=np.float32))
    with pytest.raises(ValueError, match="real"):
        env.unwrapped.step(np.zeros(1, dtype=np.complex128))
    _unchanged(core, before)


def test_single_env_stepped_after_the_end_raises():
    from jvl_gym.envs.positioning import PositioningEnv

    env = PositioningEnv(max_episode_steps=2)
    env.reset(seed=0)
    action = np.zeros(1, dtype=np.float32)
    *_, truncated, info = env.step(action)
    assert not truncated and "termination_reason" not in info
    _, _, terminated, truncated, info = env.step(action)
    assert truncated and not terminated
    assert "max_episode_steps" in info["termination_reason"]
    with pytest.raises(RuntimeError, match="reset"):
        env.step(action)
    env.reset()
    env.step(action)


def test_error_bit_termination_is_explained_in_info():
    env = gym.make("jvl_gym/Positioning-v0").unwrapped
    env.reset(seed=0)
    env.motors.regs[0, R.ERR_STAT] |= c.FLW_ERR
    _, _, terminated, _, info = env.step(np.zeros(1, dtype=np.float32))
    assert terminated
    assert "FLW_ERR" in info["termination_reason"]
    venv = gym.make_vec("jvl_gym/Positioning-v0", num_envs=3,
                        vectorization_mode="vector_entry_point",
                        autoreset_mode=AutoresetMode.SAME_STEP)
    venv.reset(seed=0)
    venv.unwrapped.motors.regs[1, R.ERR_STAT] |= c.FNC_ERR
    _, _, terminated, _, info = venv.step(np.zeros((3, 1), dtype=np.float32))
    assert terminated.tolist() == [False, True, False]
    assert info["_termination_reason"].tolist() == [False, True, False]
    assert "FNC_ERR" in info["termination_reason"][1]


def test_gear_sync_reasons_name_break_slack_and_errors():
    from jvl_gym.envs import gear_sync as G

    venv = G.GearSyncVectorEnv(num_envs=3)
    venv.reset(seed=0)
    venv.line[0, G._W_FORCE] = 10 * venv.line[0, G._W_REF]
    venv.line[1, G._W_SLACK] = venv.slack_samples
    venv.motors.regs[2, R.ERR_STAT] |= c.I2T_ERR
    reasons = venv._termination_reasons(np.arange(3))
    assert "break" in reasons[0] and "slack" in reasons[1] and "I2T_ERR" in reasons[2]


def test_coil_winding_reason_names_the_finished_coil():
    from jvl_gym.envs import coil_winding as W

    venv = W.CoilWindingVectorEnv(num_envs=1)
    venv.reset(seed=0)
    venv.coil[0, W._C_LAYER] = venv._k[W._N_LAYERS]
    assert "layers" in venv._termination_reasons(np.arange(1))[0]


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_unknown_keywords_name_the_env_and_the_known_ones(env_id):
    name = env_id.split("/")[1].split("-")[0]
    with pytest.raises(TypeError, match=f"{name}.*'motor'.*motor_type"):
        gym.make(env_id, motor="MAC140")
    with pytest.raises(TypeError, match=f"{name}.*'colour'.*known:.*decimation"):
        gym.make_vec(env_id, num_envs=2, vectorization_mode="vector_entry_point",
                     colour="red")


@pytest.mark.parametrize("kwargs", [{"decimation": 1.5}, {"decimation": True},
                                    {"max_episode_steps": 2.5}, {"obs_noise": True},
                                    {"obs_noise": "0.1"}, {"num_envs": 1.5},
                                    {"randomization": {"target_turns": ("1", 2)}},
                                    {"randomization": {"target_turns": (1, 2, 3)}},
                                    {"randomization": {"target_turns": 5}},
                                    {"motor_type": ["MAC140", 5]}])
def test_env_constructor_arguments_are_checked(kwargs):
    from jvl_gym.envs.positioning import PositioningVectorEnv

    with pytest.raises((ValueError, TypeError)):
        PositioningVectorEnv(**{"num_envs": 2, **kwargs})


def test_short_motor_names_work_in_envs():
    from jvl_gym.envs.positioning import PositioningVectorEnv

    env = PositioningVectorEnv(num_envs=1, motor_type="MAC50")
    assert env.motor_types == ("MAC050",)
