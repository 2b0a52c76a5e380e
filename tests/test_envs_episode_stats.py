"""The episode statistics every env reports in ``info`` when an episode ends (``episode_stats``):
equal between single and vector envs, and what they say about the episode."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.envs.registration import load_env_creator

import jvl_gym  # noqa: F401
from jvl_gym.envs import ENV_IDS
from jvl_gym.envs.registration import vector_class

#: a short horizon per env (every copy ends in it)
HORIZON = {"jvl_gym/Positioning-v0": 40, "jvl_gym/GearSync-v0": 40,
           "jvl_gym/CoilWinding-v0": 30, "jvl_gym/StepperIndexing-v0": 60,
           "jvl_gym/FilterTuning-v0": 1}


def _single(env_id: str, **kwargs):
    """The single env of ``env_id`` built by its entry point (no TimeLimit wrapper: the env's
    own horizon ends the episode and reports why)."""
    return load_env_creator(gym.spec(env_id).entry_point)(**kwargs)


def _vector_episodes(env_id: str, n: int, seed: int, actions: np.ndarray, **kwargs):
    """Run the first episode of every copy of an n-copy vector env with ``actions`` (steps, n,
    A); returns each copy's last-step info values {name: (n,)}, reasons and rewards (steps, n)."""
    venv = gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point",
                        autoreset_mode=gym.vector.AutoresetMode.SAME_STEP, **kwargs)
    names = tuple(vector_class(env_id).episode_stats)
    venv.reset(seed=seed)
    stats = {name: np.full(n, np.nan) for name in names}
    reasons = [""] * n
    rewards = []
    alive = np.ones(n, dtype=bool)
    for a in actions:
        _, r, term, trunc, info = venv.step(a)
        rewards.append(np.where(alive, r, np.nan))
        ended = alive & (term | trunc)
        if ended.any():
            for name in names:
                assert info["_" + name].tolist() == (term | trunc).tolist()
                stats[name][ended] = info[name][ended]
            for i in np.flatnonzero(ended):
                reasons[i] = info["termination_reason"][i]
        alive &= ~ended
        if not alive.any():
            break
    assert not alive.any()
    venv.close()
    return stats, reasons, np.array(rewards)


@pytest.mark.parametrize("env_id", ENV_IDS)
def test_single_and_vector_envs_report_the_same_statistics(env_id: str) -> None:
    names = vector_class(env_id).episode_stats
    assert names, f"{env_id} reports no episode statistic"
    n, seed, horizon = 3, 21, HORIZON[env_id]
    probe = gym.make(env_id)
    dim = probe.action_space.shape[0]
    probe.close()
    acts = np.random.default_rng(5).uniform(-0.5, 0.5, (horizon, n, dim)).astype(np.float32)
    vstats, vreasons, _ = _vector_episodes(env_id, n, seed, acts, max_episode_steps=horizon)
    for i in range(n):
        env = _single(env_id, max_episode_steps=horizon)
        env.reset(seed=seed + i)
        for a in acts:
            _, _, terminated, truncated, info = env.step(a[i])
            if terminated or truncated:
                break
        else:
            pytest.fail("the single env did not end within the horizon")
        assert info["termination_reason"] == vreasons[i]
        assert set(info) == {"termination_reason", *names}
        for name in names:
            assert isinstance(info[name], float)
            np.testing.assert_equal(info[name], vstats[name][i])
        env.close()


@pytest.mark.parametrize("env_id", [env_id for env_id in ENV_IDS
                                    if "copper_loss" in vector_class(env_id).episode_stats])
def test_copper_loss_is_the_motors_copper_energy_account(env_id: str) -> None:
    venv = gym.make_vec(env_id, num_envs=3, vectorization_mode="vector_entry_point")
    venv.reset(seed=4)
    for a in np.random.default_rng(4).uniform(-1, 1, (10, *venv.action_space.shape)):
        venv.step(a)
    env = venv.unwrapped
    idx = np.array([2, 0])
    expected = env.motors.energy["copper"][idx]
    assert (expected > 0).all()
    assert env.copper_loss(idx).tolist() == expected.tolist()


def test_positioning_firmware_loop_settles_and_no_torque_never_does() -> None:
    env_id = "jvl_gym/Positioning-v0"
    n = 4
    zeros = np.zeros((300, n, 1), dtype=np.float32)
    light = {"target_turns": (0.5, 1.0), "inertia_ratio": (0.0, 1.0), "coulomb_ratio": (0, 0),
             "viscous_friction": (0, 0)}
    fw, _, _ = _vector_episodes(env_id, n, 3, zeros, baseline=True, randomization=light)
    idle, _, _ = _vector_episodes(env_id, n, 3, zeros, randomization=light)
    episode = 300 * vector_class(env_id).step_seconds()
    # the firmware's position loop reaches the target of a light load within INPOSWIN (10 of
    # 4096 counts) after an overshoot and stays there; without torque the motor never leaves
    # the start
    assert (fw["settle_time"] > 0).all() and (fw["settle_time"] < 0.5 * episode).all()
    assert (fw["final_error"] <= 10 / 4096).all() and (fw["overshoot"] > 0).all()
    np.testing.assert_allclose(idle["settle_time"], episode)
    np.testing.assert_allclose(idle["final_error"], 0.75, atol=0.25)
    assert (idle["overshoot"] == 0).all()
    # moving the load costs copper, standing still with no current none
    assert (fw["copper_loss"] > 0).all() and (idle["copper_loss"] < 1e-3 * fw["copper_loss"]).all()
    # the default loads: an episode that ends outside the window has not settled
    heavy, _, _ = _vector_episodes(env_id, n, 3, zeros, baseline=True)
    outside = heavy["final_error"] > 10 / 4096
    np.testing.assert_allclose(heavy["settle_time"][outside], episode)


def test_gear_sync_tension_error_is_the_mean_of_the_steps() -> None:
    env_id = "jvl_gym/GearSync-v0"
    n, steps = 2, 50
    venv = gym.make_vec(env_id, num_envs=n, vectorization_mode="vector_entry_point",
                        max_episode_steps=steps)
    core = venv.unwrapped
    venv.reset(seed=4)
    errors = []
    acts = np.random.default_rng(2).uniform(-0.3, 0.3, (steps, n, 1)).astype(np.float32)
    for a in acts:
        _, _, term, trunc, info = venv.step(a)
        assert not term.any()
        errors.append(np.abs(core.force - core.tension_ref) / core.tension_ref)
    assert trunc.all()
    errors = np.array(errors)
    np.testing.assert_allclose(info["tension_error"], 100 * errors.mean(axis=0), rtol=1e-12)
    np.testing.assert_allclose(info["tension_error_max"], 100 * errors.max(axis=0), rtol=1e-12)
    assert (info["copper_loss"] > 0).all()


def test_stepper_lost_steps_and_moves_agree_with_the_reasons() -> None:
    env_id = "jvl_gym/StepperIndexing-v0"
    n = 8
    zeros = np.zeros((1000, n, 3), dtype=np.float32)
    # the default profile at half current against loads up to 60 % of the holding torque
    stats, reasons, _ = _vector_episodes(env_id, n, 100, zeros, baseline=True)
    for i, why in enumerate(reasons):
        if why.startswith("lost "):
            assert stats["lost_steps"][i] == int(why.split()[1]) > 0
            assert stats["moves_done"][i] < 3
        elif why == "all moves done":
            assert stats["lost_steps"][i] == 0 and stats["moves_done"][i] == 3
    assert {"all moves done"} < {r if r == "all moves done" else "lost" for r in reasons}
    assert (stats["copper_loss"] > 0).all()


def test_filter_tuning_reports_the_trial_figures() -> None:
    env_id = "jvl_gym/FilterTuning-v0"
    n = 6
    acts = np.random.default_rng(1).uniform(-1, 1, (1, n, 3)).astype(np.float32)
    stats, reasons, rewards = _vector_episodes(env_id, n, 8, acts)
    np.testing.assert_allclose(stats["design_cost"], -rewards[0])
    assert stats["unstable"].tolist() == [float("unstable" in r) for r in reasons]
    assert ((stats["unstable"] == 1) | (stats["design_cost"] < 10)).all()
    assert (stats["settling_time"] > 0).all() and (stats["overshoot"] >= 0).all()


def test_coil_winding_reports_layers_flatness_and_voids() -> None:
    env_id = "jvl_gym/CoilWinding-v0"
    n = 2
    zeros = np.zeros((1500, n, 3), dtype=np.float32)
    stats, reasons, rewards = _vector_episodes(env_id, n, 6, zeros)
    for i, why in enumerate(reasons):
        if why.startswith("coil complete"):
            assert stats["layers"][i] == 4
    assert (stats["voids"] > 0).all() and (stats["flatness"] > 0).all()
    assert (stats["copper_loss"] > 0).all()
