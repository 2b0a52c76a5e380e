"""Positioning-v0's reward against the task's engineering metrics (the env docstring,
"Rewards"): a controller better on settle time, final error, overshoot and copper loss earns
the better return; the in-window bonus and the copper term are what the docstring says; the
shipped policy beats the firmware on the four metrics."""

from __future__ import annotations

import math

import numpy as np
import pytest

from jvl_gym.envs.positioning import REWARD_WEIGHTS, PositioningEnv, step_reward
from jvl_gym.rl.evaluate import run_episodes

ENV = "jvl_gym/Positioning-v0"
METRICS = ("settle_time", "final_error", "overshoot", "copper_loss")
#: one load and one move: 1.5 turns, 5 × the rotor's inertia, Coulomb friction 5 % of rated
ONE_MOVE = {"target_turns": (1.5, 1.5), "inertia_ratio": (5.0, 5.0),
            "coulomb_ratio": (0.05, 0.05), "viscous_friction": (0.0, 0.0)}
NO_TERMS = {"overshoot_weight": 0.0, "fine_weight": 0.0, "window_bonus": 0.0,
            "copper_weight": 0.0}


def _law(kp: float, kd: float, kf: float):
    """The linear law a = kp·e − kd·v + kf·e_fine on the observation (e in turns, v in units
    of 3000 rpm, e_fine in units of 200 counts)."""
    def policy(obs: np.ndarray) -> np.ndarray:
        a = kp * 2.0 * obs[:, :1] - kd * obs[:, 2:3] + kf * obs[:, 1:2]
        return np.clip(a, -1.0, 1.0).astype(np.float32)
    return policy


def _episode(policy, **kwargs):
    ep = run_episodes(ENV, policy, 1, 1, {"randomization": ONE_MOVE, **kwargs})
    return float(ep.returns[0]), {k: float(ep.stats[k][0]) for k in METRICS}


def test_a_controller_better_on_every_metric_earns_the_better_return():
    # a gentle law that settles early, and a stiff one that rings, holds the shaft just
    # outside INPOSWIN and burns five times the copper: a reward of |e| alone ranked it first
    good_return, good = _episode(_law(0.5, 3.0, 0.1))
    bad_return, bad = _episode(_law(5.0, 5.0, 0.0))
    for name in METRICS:
        assert good[name] < bad[name], name
    assert bad["copper_loss"] > 3 * good["copper_loss"]
    assert good_return > bad_return + 50.0


def test_the_copper_term_is_the_copper_weight_times_the_episodes_copper_loss():
    policy = _law(2.0, 3.0, 0.0)
    plain, stats = _episode(policy, **NO_TERMS)
    weighted, _ = _episode(policy, **{**NO_TERMS, "copper_weight": 1.5})
    assert stats["copper_loss"] > 0.1
    assert plain - weighted == pytest.approx(1.5 * stats["copper_loss"], rel=1e-9)


def test_the_window_bonus_pays_every_step_inside_inposwin():
    policy = _law(0.5, 3.0, 0.1)
    plain, stats = _episode(policy, **NO_TERMS)
    bonus, _ = _episode(policy, **{**NO_TERMS, "window_bonus": 1.0})
    inside = bonus - plain
    assert inside == pytest.approx(round(inside), abs=1e-9)
    steps = PositioningEnv.vector_class.default_max_episode_steps
    step = PositioningEnv.vector_class.step_seconds()
    # settled: every step after the settle time ends inside the window
    settled_steps = steps - round(stats["settle_time"] / step)
    assert settled_steps > 100
    assert settled_steps <= round(inside) <= steps


def test_step_reward_terms_as_documented():
    w = {name: value for name, (value, _) in REWARD_WEIGHTS.items()}
    args = (w["overshoot_weight"], w["fine_weight"], w["window_bonus"], w["copper_weight"])
    cpr, window = 4096.0, 10.0
    # on target, at rest: the bonus alone
    assert step_reward(0.0, window, cpr, 0.0, 0.0, *args) == pytest.approx(w["window_bonus"])
    # on the window's edge: still inside; one count out: no bonus
    edge = step_reward(10.0, window, cpr, 0.0, 0.0, *args)
    out = step_reward(11.0, window, cpr, 0.0, 0.0, *args)
    assert edge == pytest.approx(w["window_bonus"] - 10 / cpr - w["fine_weight"] * math.log(2))
    assert out == pytest.approx(-11 / cpr - w["fine_weight"] * math.log(2.1))
    # the last counts pay: 50 counts off is worse than 20 by more than |e| says
    gain = (step_reward(20.0, window, cpr, 0.0, 0.0, *args)
            - step_reward(50.0, window, cpr, 0.0, 0.0, *args))
    assert gain > 2 * 30 / cpr
    # overshoot per turn and copper per joule
    assert (step_reward(0.0, window, cpr, 0.25, 0.0, *args)
            == pytest.approx(w["window_bonus"] - 0.25 * w["overshoot_weight"]))
    assert (step_reward(0.0, window, cpr, 0.0, 2.0, *args)
            == pytest.approx(w["window_bonus"] - 2.0 * w["copper_weight"]))


def test_bad_reward_weights_are_refused_in_one_line():
    with pytest.raises(TypeError, match="effort_weight"):
        PositioningEnv(effort_weight=0.01)


def test_the_shipped_policy_beats_the_firmware_on_every_metric():
    from jvl_gym.envs.baselines import BASELINES, make_baseline
    from jvl_gym.rl.evaluate import _model_policy
    from jvl_gym.rl.train import shipped_model

    n, seed = 8, 100000  # the first held-out seed
    policy = _model_policy(shipped_model(ENV, "mac050_141", "PPO"), "PPO")
    trained = run_episodes(ENV, policy, seed, n)
    bl = make_baseline(ENV, n, 1)
    firmware = run_episodes(ENV, bl, seed, n, BASELINES[ENV].env_kwargs, bl.reset)
    for name in METRICS:
        assert trained.stats[name].mean() < firmware.stats[name].mean(), name
    assert trained.returns.mean() > firmware.returns.mean()
