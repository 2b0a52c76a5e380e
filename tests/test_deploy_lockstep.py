"""A deployment beside its link model, period by period, in motor time (jvl_gym.rl.lockstep):
the same policy sees the same observations, writes the same registers and earns the same reward
deployed (the bridge, the supervisor and the machine ``jvl-gym serve --line`` serves) as behind
the link model it was trained in. No wall clock: the machine is stepped by the link's period and
latency, so the comparison holds on a loaded machine."""

from __future__ import annotations

import numpy as np
import pytest

from jvl_gym.envs import positioning as pos
from jvl_gym.envs.link import TorqueLimitCommand, make_link_vec
from jvl_gym.families import family_of_motor
from jvl_gym.rl.deploy import PositioningBridge, load_policy, loop_period
from jvl_gym.rl.lockstep import deployed_trace, link_trace
from jvl_gym.rl.train import shipped_model

MOTOR = "MAC140"
LINK = "mactalk-tcp:10ms,max_step=0.5"


def _policy(env_id: str):
    return load_policy(str(shipped_model(env_id, "mac050_141", "PPO", "nolink")), env_id, 1, 0.0)


def test_positioning_deployed_agrees_with_its_link_model_period_by_period():
    env_id = "jvl_gym/Positioning-v0"
    policy = _policy(env_id)
    d = deployed_trace(env_id, policy, LINK, MOTOR, seed=100000, periods=25)
    m = link_trace(env_id, policy, LINK, MOTOR, seed=100000, periods=25)
    assert len(d["reward"]) == len(m["reward"]) == 25
    # the same observation each period: the motor moved alike (position error, speed)
    np.testing.assert_allclose(d["obs"], m["obs"], atol=0.01)
    # the same command, rate-limited and quantised alike, through the same registers
    np.testing.assert_allclose(d["action"], m["action"], atol=2 / 1023)
    np.testing.assert_allclose(d["registers"], m["registers"], atol=2)
    # the deployment's reward (its two reads a period) sums the env's steps closely; in a
    # period whose error passes through zero or across the in-position window between its
    # reads, two reads cannot tell on which step |e| turned or the window's bonus began:
    # there within that bonus of the period's steps
    fine = pos._FINE_TURNS * family_of_motor(MOTOR).constants.COUNTS_PER_REV
    error = d["obs"][:, 1] * fine  # [counts] (unclipped near the target)
    inside = np.abs(error) <= 10  # INPOSWIN of the default setup [counts]
    turned = (inside[1:] != inside[:-1]) | (np.sign(error[1:]) != np.sign(error[:-1]))
    crossing = np.append(turned, True)  # the last period's end is not read
    steps = round(loop_period("jvl_gym/Positioning-v0", LINK, MOTOR) / pos.PositioningVectorEnv
                  .step_seconds(MOTOR, 1))
    bonus = pos.REWARD_WEIGHTS["window_bonus"][0] * steps
    assert crossing.sum() <= 6
    np.testing.assert_allclose(d["reward"][~crossing], m["reward"][~crossing], rtol=0.05,
                               atol=1.5)
    assert np.all(np.abs(d["reward"] - m["reward"])[crossing] <= 1.5 + bonus)
    # over the episode: the deployment estimates the copper loss from VF_OUT at its reads,
    # not from the motor's copper account, and |e| between reads by the trapezoid
    assert d["reward"].sum() == pytest.approx(m["reward"].sum(), rel=0.05)


def test_gear_sync_deployed_agrees_with_its_link_model_over_the_start():
    env_id = "jvl_gym/GearSync-v0"
    policy = _policy(env_id)
    d = deployed_trace(env_id, policy, LINK, MOTOR, seed=100000, periods=20)
    m = link_trace(env_id, policy, LINK, MOTOR, seed=100000, periods=20, loadcell_noise=0.0)
    assert len(d["reward"]) == len(m["reward"]) == 20
    # the tension error (the load cell's ANINP: 0.1 N a count), the master's and the motor's
    # speed, the following error: the winder starts holding the web as the env's does
    np.testing.assert_allclose(d["obs"][:, 0], m["obs"][:, 0], atol=0.05)
    np.testing.assert_allclose(d["obs"][:, 3:6], m["obs"][:, 3:6], atol=0.25)
    assert d["reward"].sum() == pytest.approx(m["reward"].sum(), abs=0.1 * 3 * 20)


def test_positioning_behind_mactalk_commands_the_bridges_registers():
    fam = family_of_motor(MOTOR)
    env = make_link_vec("jvl_gym/Positioning-v0", 2, LINK)
    assert isinstance(env.command, TorqueLimitCommand)
    env.reset(seed=3)
    for a in (0.5, 0.9):
        env.step(np.array([[a], [-a]]))
    m = env.env.motors
    bridge = PositioningBridge(fam)
    assert (m.read_raw("MODE_REG") == fam.task.VELOCITY_MODE).all()
    # the rate limit held the second action to 0.5 + 0.5
    for i, a in enumerate((0.9, -0.9)):
        want = bridge.to_registers(env.link.quantise(np.array([a])))
        assert {name: int(m.read_raw(name)[i]) for name in want} == want
    # a DAC drives the env's own analogue torque
    assert make_link_vec("jvl_gym/Positioning-v0", 1, "dac:12").command is None


def test_gear_sync_behind_mactalk_reads_the_tension_through_the_load_cell():
    env = make_link_vec("jvl_gym/GearSync-v0", 2, LINK)
    obs, _ = env.reset(seed=5)
    for _ in range(4):
        obs, *_ = env.step(np.zeros((2, 1)))
    ref = env.env.tension_ref
    # the tension the controller sees is a whole ANINP count (0.1 N), as the bridge reads it
    counts = ref * (1.0 + obs[:, 0].astype(np.float64)) / 100.0 * 1023
    np.testing.assert_allclose(counts, np.round(counts), atol=1e-3)
    # its rate is the change of those readings over the period
    assert make_link_vec("jvl_gym/GearSync-v0", 1, "dac:12").observer is None
