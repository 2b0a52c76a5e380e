"""An N-motor array equals N one-motor arrays bit for bit; seeds reproduce runs."""

from __future__ import annotations

import numpy as np

from jvl_gym import MotorArray
from jvl_gym.motor.noise import motor_keys

TYPES = ["MAC050", "MAC095", "MAC140", "MAC141"]
LOADS = [0.0, 20e-6, 60e-6, 5e-6]
V_SOLL = [800, -1600, 2400, 3000]
MODES = [1, 2, 1, 2]
NOISE = dict(current_noise=1.5, position_noise=0.3, torque_noise=1e-3)


def _drive(m: MotorArray, index, k: int) -> None:
    m.write("V_SOLL", V_SOLL[k], index=index)
    m.write("P_SOLL", 20000 * (k + 1), index=index)
    m.write("MODE_REG", MODES[k], index=index)
    m.set_input(index=index, load_torque=0.01 * k)


def _run_split(m: MotorArray) -> None:
    m.step(7)
    m.step(1)
    m.step(60)


def test_mixed_array_equals_separate_arrays_bit_for_bit():
    keys = motor_keys(42, 4)
    big = MotorArray(TYPES, n=4, seed=42, load_inertia=LOADS, **NOISE)
    for k in range(4):
        _drive(big, [k], k)
    _run_split(big)
    for k in range(4):
        one = MotorArray(TYPES[k], n=1, seed=[keys[k]], load_inertia=LOADS[k], **NOISE)
        _drive(one, None, k)
        _run_split(one)
        np.testing.assert_array_equal(one.regs[0], big.regs[k])
        np.testing.assert_array_equal(one.state[0], big.state[k])


def test_parallel_kernel_equals_serial_kernel():
    n = 40  # above the parallel threshold
    a = MotorArray("MAC140", n=n, seed=1, load_inertia=np.linspace(0, 1e-4, n), **NOISE)
    b = MotorArray("MAC140", n=n, seed=1, load_inertia=np.linspace(0, 1e-4, n), **NOISE)
    for m in (a, b):
        m.write("V_SOLL", np.linspace(-3000, 3000, n).round())
        m.write("MODE_REG", 1)
    a.step(50)
    from jvl_gym.motor.array import driver

    driver(b.family.key).serial(*b.engine_view(), 50)
    np.testing.assert_array_equal(a.regs, b.regs)
    np.testing.assert_array_equal(a.state, b.state)


def test_same_seed_same_run_and_different_seed_differs():
    runs = []
    for seed in (5, 5, 6):
        m = MotorArray("MAC140", n=3, seed=seed, **NOISE)
        m.write("V_SOLL", 1600)
        m.write("MODE_REG", 1)
        m.step(100)
        runs.append(m.state.copy())
    np.testing.assert_array_equal(runs[0], runs[1])
    assert not np.array_equal(runs[0], runs[2])


def test_noise_is_off_by_default_and_runs_are_deterministic():
    a = MotorArray("MAC140", n=2, seed=1)
    b = MotorArray("MAC140", n=2, seed=99)
    for m in (a, b):
        m.write("V_SOLL", 1600)
        m.write("MODE_REG", 1)
        m.step(50)
    np.testing.assert_array_equal(a.state, b.state)


def test_partial_reset_does_not_disturb_other_motors():
    a = MotorArray("MAC140", n=3, seed=0)
    b = MotorArray("MAC140", n=3, seed=0)
    for m in (a, b):
        m.write("V_SOLL", 1600)
        m.write("MODE_REG", 1)
        m.step(30)
    a.reset(index=[1], load_inertia=50e-6, coulomb_friction=0.01)
    a.step(30)
    b.step(30)
    np.testing.assert_array_equal(a.state[[0, 2]], b.state[[0, 2]])
    assert a.parameters["load_inertia"][1] == 50e-6
    assert a.mode_name(1) == "INIT_MODE" and a.read("P_IST")[1] == 0
