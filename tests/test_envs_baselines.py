"""Baselines, RL configs and the jvl-gym CLI."""

from __future__ import annotations

import numpy as np
import pytest
from typer.testing import CliRunner

import jvl_gym  # noqa: F401
from jvl_gym.cli.main import app
from jvl_gym.envs import ENV_IDS
from jvl_gym.envs.baselines import BASELINES, PITension, make_baseline
from jvl_gym.rl.config import load_rl_configs
from jvl_gym.rl.evaluate import episode_returns, format_table


def test_pi_integrates_and_stops_integrating_when_saturated() -> None:
    pi = PITension(2, kp=1.0, ki=10.0, dt=0.01)
    obs = np.array([[0.1], [5.0]])
    for _ in range(100):
        u = pi(obs)
    assert u[0, 0] < -0.1  # integral action beyond the proportional part
    assert u[1, 0] == -1.0
    assert pi.integral[1] == 0.0  # anti-windup: saturated by kp·e alone, nothing integrated
    assert pi.integral[0] > 0.0
    pi.reset(np.array([False, True]))
    assert pi.integral[0] > 0.0
    pi.reset()
    assert pi.integral[0] == 0.0


def test_pi_baseline_holds_tension_better_than_a_fixed_ratio() -> None:
    env_id = "jvl_gym/GearSync-v0"
    pi = make_baseline(env_id, 4, 1)
    held = episode_returns(env_id, pi, 123, 4, reset_policy=pi.reset)
    fixed = episode_returns(env_id, make_baseline("jvl_gym/CoilWinding-v0", 4, 1), 123, 4)
    assert held.mean() > fixed.mean()


def test_the_pi_baseline_steps_at_the_env_family_outer_sample_time() -> None:
    from jvl_gym.families.mac050_141 import constants as c141
    from jvl_gym.families.mac800 import constants as c800

    env_id = "jvl_gym/GearSync-v0"
    assert make_baseline(env_id, 1, 1, decimation=3, motor_type="MAC800").dt == (
        3 * c800.OUTER_DT)
    assert make_baseline(env_id, 1, 1, motor_type="MAC800").dt == 2 * c800.OUTER_DT
    assert 2 * c800.OUTER_DT == pytest.approx(2.597e-3, rel=1e-3)  # 770 Hz
    for pi in (make_baseline(env_id, 1, 1), make_baseline(env_id, 1, 1, motor_type="MAC140")):
        assert pi.dt == 2 * c141.OUTER_DT == pytest.approx(2 * 1.92e-3, rel=1e-15)
    with pytest.raises(ValueError, match="decimation"):
        make_baseline(env_id, 1, 1, decimation=0)


def test_the_mac050_141_pi_baseline_returns_are_those_of_the_1_92_ms_step() -> None:
    env_id = "jvl_gym/GearSync-v0"
    pi = make_baseline(env_id, 3, 1)
    old = PITension(3, kp=2.0, ki=15.0, dt=2 * 1.92e-3)
    np.testing.assert_array_equal(
        episode_returns(env_id, pi, 7, 3, {"max_episode_steps": 400}, pi.reset),
        episode_returns(env_id, old, 7, 3, {"max_episode_steps": 400}, old.reset))


def test_firmware_baselines_ignore_the_action() -> None:
    env_id = "jvl_gym/Positioning-v0"
    kwargs = BASELINES[env_id].env_kwargs
    a = episode_returns(env_id, lambda o: np.ones((2, 1), np.float32), 5, 2, kwargs)
    b = episode_returns(env_id, lambda o: -np.ones((2, 1), np.float32), 5, 2, kwargs)
    np.testing.assert_array_equal(a, b)


def test_every_env_has_an_rl_config_and_a_baseline() -> None:
    configs = load_rl_configs()
    for env_id in ENV_IDS:
        assert env_id in configs and env_id in BASELINES
        assert configs[env_id]["eval"]["n_seeds"] >= 5


def test_format_table_names_the_better_controller() -> None:
    table = format_table({"x": {"policy": (2.0, 0.1), "baseline": (1.0, 0.2),
                                "seeds_won": (4.0, 5.0)}})
    assert "| x | 2.00 ± 0.10 | 1.00 ± 0.20 | policy | 4/5 |" in table


def test_cli_lists_train_and_evaluate() -> None:
    result = CliRunner().invoke(app, ["--help"])
    assert result.exit_code == 0
    assert "train" in result.output and "evaluate" in result.output


def test_filter_tuning_trial_and_synthesis_baseline() -> None:
    import gymnasium as gym

    venv = gym.make_vec("jvl_gym/FilterTuning-v0", num_envs=4,
                        vectorization_mode="vector_entry_point", motor_type="MAC140",
                        randomization={"inertia_ratio": (8.0, 8.0)})
    venv.reset(seed=0)
    low = np.full((4, 3), -1.0, dtype=np.float32)  # default gains, KVOUT = 1 for a 9x load
    _, r_low, term, _, _ = venv.step(low)
    assert term.all()
    _, r_next, term, trunc, _ = venv.step(low)  # NEXT_STEP: only the reset
    assert np.all(r_next == 0.0) and not (term | trunc).any()
    matched = np.tile(np.array([0.0, 0.0, np.log2(9.0) / 2 - 1], dtype=np.float32), (4, 1))
    _, r_matched, *_ = venv.step(matched)  # KVOUT ≈ J_total/J_m
    assert r_matched.mean() > r_low.mean()
    from tuning.baseline import speed_loop_registers

    base = gym.make("jvl_gym/FilterTuning-v0", baseline=True, motor_type="MAC140",
                    designer=speed_loop_registers)  # the toolkit's synthesis, given to the env
    assert base.unwrapped.core.baseline_source == "designer"
    base.reset(seed=0)
    _, r_base, *_ = base.step(base.action_space.sample())
    assert r_base > -base.unwrapped.core.instability_penalty
