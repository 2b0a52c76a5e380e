"""The compiled entry taken once for arguments of fixed types (``jvl_gym.engine.entry``) and the
callers that keep it: ``MotorArray.step`` with its inputs held and an env's compiled step. The
kept entry must step the arrays the motors have now, survive pickling and take any action
layout the dispatcher takes."""

from __future__ import annotations

import pickle

import gymnasium as gym
import numpy as np
from numba import njit

from jvl_gym import MotorArray
from jvl_gym.engine.entry import entry_point
from jvl_gym.families.mac050_141 import constants as c


@njit(cache=False)
def _scaled_sum(x: np.ndarray, k: float) -> float:  # pragma: no cover - compiled
    total = 0.0
    for v in x:
        total += k * v
    return total


def test_entry_point_runs_the_compiled_code_for_those_types_and_else_is_the_dispatcher() -> None:
    x = np.arange(5.0)
    assert entry_point(_scaled_sum, (x, 2.0)) is _scaled_sum  # not compiled for them yet
    assert _scaled_sum(x, 2.0) == 20.0
    entry = entry_point(_scaled_sum, (x, 2.0))
    assert entry is not _scaled_sum
    assert entry(x + 1.0, 3.0) == _scaled_sum(x + 1.0, 3.0) == 45.0
    assert entry_point(_scaled_sum, (np.arange(5), 2.0)) is _scaled_sum  # other types

    def plain(a: float) -> float:
        return a

    assert entry_point(plain, (1.0,)) is plain  # not a compiled dispatcher


def _motors() -> MotorArray:
    m = MotorArray("MAC140", n=1, seed=3)
    m.write("V_SOLL", 1500)
    m.write("MODE_REG", 1)
    return m


def test_step_calls_advance_as_one_long_step() -> None:
    a, b = _motors(), _motors()
    for _ in range(40):
        a.step(1)
    b.step(40)
    np.testing.assert_array_equal(a.regs, b.regs)
    np.testing.assert_array_equal(a.state, b.state)


def test_step_advances_an_array_bound_anew_and_the_sample_buffer_of_a_recording() -> None:
    m, ref = _motors(), _motors()
    m.step(3)
    ref.step(3)
    old = m.state
    m.state = m.state.copy()  # the motors' state bound anew after steps with the old one
    m.step(5)
    ref.step(5)
    np.testing.assert_array_equal(m.state, ref.state)
    assert not np.array_equal(old, m.state)  # the old array was left behind
    for motors in (m, ref):  # a recording allocates the sample buffer (a new array)
        motors.write("CNTRL_BITS", c.RECORDBIT | c.AUTO_RESYNC)
    m.step(6)
    ref.step(6)
    assert int(m.read("REC_CNT")[0]) > 0
    np.testing.assert_array_equal(m.sample_buffer_raw(0), ref.sample_buffer_raw(0))
    np.testing.assert_array_equal(m.regs, ref.regs)


def test_a_pickled_motor_array_steps_on_like_the_original() -> None:
    m = _motors()
    m.step(4)
    clone = pickle.loads(pickle.dumps(m))
    m.step(6)
    clone.step(6)
    np.testing.assert_array_equal(m.regs, clone.regs)
    np.testing.assert_array_equal(m.state, clone.state)


def test_an_env_step_takes_actions_of_any_memory_layout() -> None:
    envs = [gym.make_vec("jvl_gym/Positioning-v0", num_envs=3,
                         vectorization_mode="vector_entry_point") for _ in range(2)]
    for env in envs:
        env.reset(seed=7)
    rng = np.random.default_rng(0)
    for _ in range(5):
        actions = rng.uniform(-1, 1, (3, envs[0].single_action_space.shape[0]))
        wide = np.zeros((3, 2 * actions.shape[1]))
        wide[:, ::2] = actions  # the same numbers, strided (not C-contiguous)
        out_a = envs[0].step(actions)
        out_b = envs[1].step(wide[:, ::2])
        for x, y in zip(out_a[:4], out_b[:4]):
            np.testing.assert_array_equal(x, y)
