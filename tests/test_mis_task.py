"""A compiled task on the MIS family: the engine's TaskDriver binds the family's step and a
task's hooks that use only the task interface (``families.mis.task``)."""

from __future__ import annotations

import numpy as np
from numba import njit

from jvl_gym import MotorArray
from jvl_gym.engine import TaskDriver
from jvl_gym.engine.view import EngineView
from jvl_gym.families import family
from jvl_gym.families.mis import constants as c
from jvl_gym.families.mis import layout as L
from jvl_gym.families.mis import task as T


@njit(cache=True, inline="always")
def _begin(i, view, episode, task, actions):  # pragma: no cover - compiled
    T.set_load_torque(view, i, actions[i, 0])
    T.set_reg(view, i, T.R.V_SOLL, 20000)


@njit(cache=True, inline="always")
def _end(i, view, episode, task, actions):  # pragma: no cover - compiled
    episode.t[i] += 1
    episode.reward[i] = -float(T.lost_steps(view, i)) - T.copper_energy(view, i)
    episode.terminated[i] = (T.reg(view, i, T.R.ERR_BITS) & T.ERROR_BITS) != 0
    episode.obs[i, 0] = T.rotor_speed(view, i)


def test_a_task_driver_runs_the_family_with_hooks() -> None:
    driver = TaskDriver(family(T.FAMILY_KEY), __file__, "mis_probe", begin=_begin, end=_end)
    n = 40  # threads (≥ PARALLEL_MIN)
    m = MotorArray(T.DEFAULT_MOTOR_TYPE, n=n, seed=0)
    m.write_many({"V_START": 1000, "A_SOLL": 2000, "FLWERRMAX": 30000, "MODE_REG": 1})
    episode = (np.zeros((n, 1)), np.zeros(n, dtype=np.int64), np.zeros(n, dtype=np.uint64),
               np.zeros((n, 1), dtype=np.float32), np.zeros(n), np.zeros(n, dtype=np.bool_),
               np.zeros(n, dtype=np.bool_))
    actions = np.zeros((n, 1))
    actions[n // 2:, 0] = 3.0  # beyond the holding torque: these motors stall
    for _ in range(30):
        assert driver.step(m.engine_view(), episode, (np.zeros(1),), actions, 50)
    lost = m.lost_steps
    assert np.all(lost[: n // 2] == 0) and np.all(lost[n // 2:] != 0)
    assert np.all(episode[5][n // 2:]) and not np.any(episode[5][: n // 2])
    assert np.all(episode[4][: n // 2] > episode[4][n // 2:])
    assert episode[3][0, 0] > 0.0
    one = MotorArray(T.DEFAULT_MOTOR_TYPE, n=1, seed=[int(m.keys[n - 1])])
    one.write_many({"V_START": 1000, "A_SOLL": 2000, "FLWERRMAX": 30000, "MODE_REG": 1})
    ep1 = tuple(a[n - 1:] for a in (np.zeros((n, 1)), np.zeros(n, dtype=np.int64),
                                    np.zeros(n, dtype=np.uint64),
                                    np.zeros((n, 1), dtype=np.float32), np.zeros(n),
                                    np.zeros(n, dtype=np.bool_), np.zeros(n, dtype=np.bool_)))
    for _ in range(30):
        driver.step(one.engine_view(), ep1, (np.zeros(1),), actions[n - 1:], 50)
    np.testing.assert_array_equal(one.state[0], m.state[n - 1])  # serial 1 = threaded copy


@njit(cache=True)
def _compiled_lost_steps(regs, state, params, inputs, keys, buf, rec, fmt, plan,
                         scratch):  # pragma: no cover - compiled
    view = EngineView(regs, state, params, inputs, keys, buf, rec, fmt, plan, scratch)
    out = np.empty(regs.shape[0], dtype=np.int64)
    for i in range(regs.shape[0]):
        out[i] = T.lost_steps(view, i)
    return out


def test_the_lost_steps_reported_are_the_ones_the_compiled_step_counts() -> None:
    """MisMotorArray.lost_steps (what an env reports) equals the compiled task's lost_steps
    (what ends its episode) at lags of exact half electrical turns, where rounding half to
    even and half up part."""
    m = MotorArray(T.DEFAULT_MOTOR_TYPE, n=9, seed=0)
    halves = np.arange(-4, 5) * 0.5
    m.state[:, L.S_THETA] = 0.0
    m.state[:, L.S_CMD] = halves * c.COUNTS_PER_ELECTRICAL_TURN
    compiled = _compiled_lost_steps(*m.engine_view())
    np.testing.assert_array_equal(m.lost_steps, compiled)
    np.testing.assert_array_equal(compiled, 4 * np.floor(halves + 0.5).astype(np.int64))
