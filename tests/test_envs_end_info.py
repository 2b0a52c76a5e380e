"""The ``info`` of the step that ends episodes (``Stepping._end_info``): every key, dtype, mask,
reason text and statistic pinned against values set in the copies' state and written out here,
for terminated and truncated copies, ended copies among others and all copies at once; texts
kept per key follow the attributes they name."""

from __future__ import annotations

import itertools
from typing import Any

import numpy as np
import pytest

import jvl_gym  # noqa: F401
from jvl_gym.envs.coil_winding import CoilWindingVectorEnv
from jvl_gym.envs.filter_tuning import FilterTuningVectorEnv
from jvl_gym.envs.gear_sync import GearSyncVectorEnv
from jvl_gym.envs.stepper_indexing import StepperIndexingVectorEnv
from jvl_gym.families.mac050_141 import constants as c
from jvl_gym.families.mac050_141.firmware import regs as R
from jvl_gym.families.mac050_141.layout import S_E_COPPER

TIME_LIMIT = "time limit: max_episode_steps reached (truncated)"
BY_TASK = "terminated by the task"
BREAK = "web break: tension above 3 × the reference"
SLACK = "web slack for 5 outer samples"


def _mask(n: int, on: list[int]) -> np.ndarray:
    mask = np.zeros(n, dtype=np.bool_)
    mask[on] = True
    return mask


def _check_layout(info: dict, ended: np.ndarray, names: tuple[str, ...]) -> None:
    """Keys in order, dtypes and masks: one array of its own per mask, equal to ``ended``."""
    assert list(info) == ["termination_reason", "_termination_reason",
                          *(key for name in names for key in (name, "_" + name))]
    assert info["termination_reason"].dtype == object
    masks = [info["_termination_reason"], *(info["_" + name] for name in names)]
    for mask in masks:
        assert mask.dtype == np.bool_ and mask.tolist() == ended.tolist()
        assert mask is not ended and not np.shares_memory(mask, ended)
    arrays = [*masks, *(info[name] for name in names)]
    for a, b in itertools.combinations(arrays, 2):  # writing one changes no other
        assert not np.shares_memory(a, b)
    for name in names:
        assert info[name].dtype == np.float64 and info[name].shape == ended.shape
        assert (info[name][~ended] == 0.0).all()
    assert all(text == "" for text in info["termination_reason"][~ended])


def _stepped(cls: type, n: int) -> Any:
    """A vector env of class ``cls`` with ``n`` copies after one step of zero actions, with no
    motor error bit set (its :attr:`error_register` cleared)."""
    env = cls(num_envs=n)
    env.reset(seed=0)
    env.step(np.zeros(env.action_space.shape, dtype=np.float32))
    env.motors.regs[:, env.motors.table.lookup(env.error_register).number] = 0
    return env


def _gear_sync(n: int = 8) -> GearSyncVectorEnv:
    """A stepped GearSync env whose copies have no break, slack or error bit, episode step
    counts 10, error sums 0.5·(i+1), largest errors 0.01·i, copper accounts 1.25·i [J]."""
    env = _stepped(GearSyncVectorEnv, n)
    env.force[:] = env.tension_ref
    env.slack_count[:] = 0
    i = np.arange(n)
    env._t[:] = 10
    env.error_sum[:] = 0.5 * (i + 1)
    env.error_max[:] = 0.01 * i
    env.motors.state[:, S_E_COPPER] = 1.25 * i
    return env


def test_gear_sync_end_info_of_terminated_truncated_and_running_copies():
    env = _gear_sync()
    assert env.break_ratio == 3.0 and env.slack_samples == 5
    env.force[0] = 10 * env.tension_ref[0]
    env.slack_count[1] = 5
    env.motors.regs[2, R.ERR_STAT] = c.I2T_ERR
    env.force[3] = 4 * env.tension_ref[3]
    env.motors.regs[3, R.ERR_STAT] = c.FLW_ERR | c.I2T_ERR
    env.slack_count[4] = 7
    env.force[4] = 3.5 * env.tension_ref[4]
    env._t[6] = 0  # no step yet: the mean is over max(steps, 1)
    ended = _mask(8, [0, 1, 2, 3, 4, 5, 6])
    terminated = _mask(8, [0, 1, 2, 3, 4, 5])
    expected = [BREAK, SLACK, "motor error I2T_ERR (ERR_STAT)",
                f"{BREAK}; motor error I2T_ERR+FLW_ERR (ERR_STAT)", f"{BREAK}; {SLACK}", BY_TASK,
                TIME_LIMIT, ""]
    for _ in range(2):  # the texts made, then the texts kept
        info = env._end_info(ended, terminated)
        _check_layout(info, ended, ("tension_error", "tension_error_max", "copper_loss"))
        assert info["termination_reason"].tolist() == expected
        assert info["tension_error"].tolist() == [5.0, 10.0, 15.0, 20.0, 25.0, 30.0, 350.0, 0.0]
        np.testing.assert_allclose(info["tension_error_max"],
                                   [0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 0.0], rtol=1e-12)
        assert info["copper_loss"].tolist() == [0.0, 1.25, 2.5, 3.75, 5.0, 6.25, 7.5, 0.0]
    # the single env's path: the reasons of some copies
    idx = np.array([4, 6, 2])
    assert env._end_reasons(idx, terminated[idx]) == [f"{BREAK}; {SLACK}", TIME_LIMIT,
                                                      "motor error I2T_ERR (ERR_STAT)"]


def test_gear_sync_texts_follow_the_attributes_they_name():
    env = _gear_sync(2)
    env.force[0] = 10 * env.tension_ref[0]
    env.slack_count[1] = 5
    ended = _mask(2, [0, 1])
    assert env._end_info(ended, ended)["termination_reason"].tolist() == [BREAK, SLACK]
    env.break_ratio = 2.5  # e.g. set by a user after construction
    env.slack_samples = 4
    assert env._end_info(ended, ended)["termination_reason"].tolist() == [
        "web break: tension above 2.5 × the reference", "web slack for 4 outer samples"]


def test_gear_sync_all_copies_truncated_or_terminated_at_once():
    n = 16
    env = _gear_sync(n)
    every = np.ones(n, dtype=np.bool_)
    info = env._end_info(every, np.zeros(n, dtype=np.bool_))
    _check_layout(info, every, ("tension_error", "tension_error_max", "copper_loss"))
    assert info["termination_reason"].tolist() == [TIME_LIMIT] * n
    assert info["tension_error"].tolist() == [5.0 * (i + 1) for i in range(n)]
    assert info["copper_loss"].tolist() == [1.25 * i for i in range(n)]
    env.force[::2] = 10 * env.tension_ref[::2]
    info = env._end_info(every, every)
    assert info["termination_reason"].tolist() == [BREAK, BY_TASK] * (n // 2)
    mixed = _mask(n, list(range(0, n, 4)))
    info = env._end_info(every, mixed)
    assert info["termination_reason"].tolist() == [BREAK, TIME_LIMIT, TIME_LIMIT,
                                                   TIME_LIMIT] * (n // 4)


def test_coil_winding_end_info():
    n = 5
    env = _stepped(CoilWindingVectorEnv, n)
    assert env.n_layers == 4
    env.layer[:] = [4.0, 4.0, 2.0, 1.0, 3.0]
    env.voids[:] = [0.5, 0.0, 1.5, 2.0, 0.25]
    env.motors.regs[1, R.ERR_STAT] = c.FNC_ERR
    env.motors.regs[2, R.ERR_STAT] = c.UIT_ERR
    env.motors.state[:, S_E_COPPER] = [2.0, 0.5, 1.0, 4.0, 8.0]
    d0 = env.d0.copy()
    env.h[:] = d0[:, None]  # a flat surface: flatness 0
    env.h[0, ::2] = 0.0  # wire on every second bin: std d0/2, flatness 0.5
    env.h[0, 1::2] = d0[0]
    ended = _mask(n, [0, 1, 2, 3])
    terminated = _mask(n, [0, 1, 2])
    names = ("layers", "flatness", "voids", "copper_loss")
    info = env._end_info(ended, terminated)
    _check_layout(info, ended, names)
    assert info["termination_reason"].tolist() == [
        "coil complete: 4 layers wound",
        "coil complete: 4 layers wound; motor error FNC_ERR (ERR_STAT)",
        "motor error UIT_ERR (ERR_STAT)", TIME_LIMIT, ""]
    assert info["layers"].tolist() == [4.0, 4.0, 2.0, 1.0, 0.0]
    np.testing.assert_allclose(info["flatness"], [0.5, 0.0, 0.0, 0.0, 0.0], atol=1e-9)
    assert info["voids"].tolist() == [0.5, 0.0, 1.5, 2.0, 0.0]
    assert info["copper_loss"].tolist() == [2.0, 0.5, 1.0, 4.0, 0.0]
    env.layer[3] = 4.0
    info = env._end_info(_mask(n, [3, 4]), _mask(n, [3, 4]))
    assert info["termination_reason"].tolist() == [
        "", "", "", "coil complete: 4 layers wound", BY_TASK]


def test_filter_tuning_reasons():
    n = 4
    env = _stepped(FilterTuningVectorEnv, n)
    env.metrics["unstable"][:] = [False, True, False, True]
    env.motors.regs[2, R.ERR_STAT] = c.FLW_ERR
    env.motors.regs[3, R.ERR_STAT] = c.FLW_ERR | c.PLIM_ERR
    every = np.ones(n, dtype=np.bool_)
    info = env._end_info(every, every)
    assert info["termination_reason"].tolist() == [
        "trial done", "trial done: unstable design", "trial done (motor error FLW_ERR (ERR_STAT))",
        "trial done: unstable design (motor error FLW_ERR+PLIM_ERR (ERR_STAT))"]
    assert info["unstable"].tolist() == [0.0, 1.0, 0.0, 1.0]


@pytest.mark.parametrize("lag_turns", [1, -2])
def test_stepper_indexing_reasons(lag_turns: int):
    from jvl_gym.families.mis import constants as mc
    from jvl_gym.families.mis import layout as L
    from jvl_gym.families.mis.units import COUNTS_PER_RAD

    n = 4
    env = _stepped(StepperIndexingVectorEnv, n)
    reg = env.motors.table.lookup("ERR_BITS").number
    env.motors.state[:, L.S_CMD] = env.motors.state[:, L.S_THETA] * COUNTS_PER_RAD
    env.moves_left[:] = [0, 0, 2, 0]
    env.motors.state[1, L.S_CMD] += lag_turns * mc.COUNTS_PER_ELECTRICAL_TURN
    env.motors.regs[3, reg] = dict(env.terminal_errors)["FOLLOW"]
    every = np.ones(n, dtype=np.bool_)
    info = env._end_info(every, every)
    assert info["termination_reason"].tolist() == [
        "all moves done", f"lost {4 * abs(lag_turns)} full steps", "",
        "motor error FOLLOW (ERR_BITS)"]
    assert info["lost_steps"].tolist() == [0.0, 4.0 * abs(lag_turns), 0.0, 0.0]
    assert info["moves_done"].tolist() == [3.0, 3.0, 1.0, 3.0]
