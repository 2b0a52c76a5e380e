"""MAC800 arrays: N motors in one array equal N one-motor arrays bit for bit (serial and
threaded drivers), and a run is determined by its seed."""

from __future__ import annotations

import numpy as np

from jvl_gym import MotorArray
from jvl_gym.engine import PARALLEL_MIN

N = 40  # >= PARALLEL_MIN: the threaded driver; one-motor arrays run the serial one


def _setup(m: MotorArray, idx=None, k=None) -> None:
    ks = np.arange(N) if k is None else np.array([k])
    m.write("V_SOLL", (np.linspace(-3000, 3000, N)[ks]).round(), idx)
    m.write("P_SOLL", (np.linspace(-50000, 50000, N)[ks]).round(), idx)
    m.write("MODE_REG", np.where(ks % 2 == 0, 1, 2), idx)


def test_n_motors_equal_one_motor_arrays() -> None:
    assert N >= PARALLEL_MIN
    inertia = np.linspace(0.0, 5e-4, N)
    types = ["MAC800" if k % 3 else "MAC400" for k in range(N)]
    noise = np.where(np.arange(N) % 4 == 1, 2.0, 0.0)
    big = MotorArray(types, n=N, seed=7, load_inertia=inertia, position_noise=noise)
    _setup(big)
    big.set_input(load_torque=np.linspace(-0.5, 0.5, N))
    big.step(200)
    keys = big.keys
    for k in (0, 1, 17, 39):
        one = MotorArray(types[k], n=1, seed=[int(keys[k])], load_inertia=inertia[k],
                         position_noise=noise[k])
        _setup(one, k=k)
        one.set_input(load_torque=np.linspace(-0.5, 0.5, N)[k])
        one.step(200)
        np.testing.assert_array_equal(one.regs[0], big.regs[k])
        np.testing.assert_array_equal(one.state[0], big.state[k])


def test_threads_equal_serial() -> None:
    from jvl_gym.motor.stepping import driver

    a = MotorArray("MAC800", n=N, seed=3)
    b = MotorArray("MAC800", n=N, seed=3)
    _setup(a)
    _setup(b)
    d = driver("mac800")
    d.parallel(*a.engine_view(), 150)
    d.serial(*b.engine_view(), 150)
    np.testing.assert_array_equal(a.regs, b.regs)
    np.testing.assert_array_equal(a.state, b.state)


def test_deterministic_under_a_seed() -> None:
    """With encoder noise: the same seed gives the same run, another seed another one."""
    runs = []
    for seed in (11, 11, 12):
        m = MotorArray("MAC800", n=3, seed=seed, load_inertia=[0.0, 1e-4, 2e-4],
                       position_noise=[0.0, 1.5, 3.0])
        m.write_many({"V_SOLL": 1000, "MODE_REG": 1})
        m.step(100)
        runs.append((m.regs.copy(), m.state.copy()))
    np.testing.assert_array_equal(runs[0][0], runs[1][0])
    np.testing.assert_array_equal(runs[0][1], runs[1][1])
    np.testing.assert_array_equal(runs[0][1][0], runs[2][1][0])  # no noise: seed-free
    assert not np.array_equal(runs[0][1][1:], runs[2][1][1:])
