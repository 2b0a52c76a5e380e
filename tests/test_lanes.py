"""The SIMD lanes of mac050_141.lanes give the bits of the one-motor path (the inner sample
of mac050_141.inner with every per-motor feature)."""

from __future__ import annotations

import numpy as np
import pytest
from numba import njit

from jvl_gym import MotorArray
from jvl_gym.engine.jit import KERNEL
from jvl_gym.families.mac050_141 import constants as c
from jvl_gym.families.mac050_141 import layout as L
from jvl_gym.families.mac050_141.firmware import regs as R
from jvl_gym.families.mac050_141.inner import inner_samples_one
from jvl_gym.families.mac050_141.kernel import outer_firmware
from jvl_gym.families.mac050_141.lanes import LANES, in_lanes, lane_scratch
from jvl_gym.motor.array import driver
from jvl_gym.physics.trig import fma, sincos, sine


@njit(**KERNEL)
def _reference(regs, state, params, inputs, keys, buf, rec, fmt, n_outer, plan, scratch):
    """The kernel without lanes: every motor's inner samples by ``inner_samples_one``, in
    lane 0 of ``scratch`` (an int64, as the drivers pass it: a literal 0 would compile a
    second version)."""
    for t in range(n_outer):
        for i in range(regs.shape[0]):
            if plan.shape[0] > 0:
                for k in range(inputs.shape[1]):
                    inputs[i, k] = plan[t, i, k]
            outer_firmware(regs[i], state[i], params[i], inputs[i], keys[i],
                           buf[i] if rec else buf[0], rec, fmt)
        for i in range(regs.shape[0]):
            inner_samples_one(regs[i], state[i], params[i], inputs[i], keys[i],
                              buf[i] if rec else buf[0], rec, fmt, scratch, np.int64(0))


def _run_reference(m: MotorArray, n_outer: int) -> None:
    """``n_outer`` outer samples of ``m`` by :func:`_reference`, with the arrays the drivers
    get (the same types, so ``inner_samples_one`` keeps one compiled version)."""
    regs, state, params, inputs, keys, buf, rec, fmt, plan, scratch = m.engine_view()
    _reference(regs, state, params, inputs, keys, buf, rec, fmt, n_outer, plan, scratch[0])


def _mixed(n: int, coupled: bool = True) -> MotorArray:
    """Motors of every type in lane-eligible and ineligible conditions: speed and position
    modes, loads (some behind an elastic coupling unless not ``coupled``), Coulomb friction,
    end stops, with and without the PWM delay; some with noise, a hall start or no regulation
    (INIT), which run outside the lanes."""
    types = ["MAC050", "MAC095", "MAC140", "MAC141"]
    k = np.arange(n)
    m = MotorArray([types[i % 4] for i in range(n)], n=n, seed=3,
                   load_inertia=np.linspace(0.0, 1e-4, n),
                   coulomb_friction=np.where(k % 3 == 0, 0.02, 0.0),
                   viscous_friction=np.linspace(0.0, 1e-4, n),
                   pwm_delay_samples=(k % 2).astype(float),
                   end_stop_low=np.where(k % 5 == 0, -0.5, 1.0),
                   end_stop_high=np.where(k % 5 == 0, 0.5, -1.0),
                   end_stop_stiffness=np.where(k % 5 == 0, 50.0, 0.0),
                   current_noise=np.where(k % 11 == 1, 0.5, 0.0),
                   torque_noise=np.where(k % 13 == 2, 1e-4, 0.0),
                   hall_start=np.where(k % 7 == 3, 1.0, 0.0),
                   coupling_stiffness=np.where((k % 3 == 2) & (k > 0) & coupled, 2.0, 0.0),
                   coupling_damping=np.where(k % 2 == 0, 2e-4, 0.0))
    m.write("V_SOLL", np.linspace(-4000, 4000, n).round())
    m.write("P_SOLL", np.where(k % 4 == 1, 20000, -9000))
    modes = np.where(k % 4 == 1, c.P_MODE, c.V_MODE)
    modes[k % 9 == 4] = c.INIT_MODE
    m.write("MODE_REG", modes)
    m.set_input(load_torque=np.where(k % 6 == 5, 0.05, 0.0))
    return m


@pytest.mark.parametrize("coupled", [True, False])
def test_lanes_give_the_bits_of_the_one_motor_kernel(coupled: bool) -> None:
    """With elastically coupled motors in every block (their lanes run the coupled form of
    the plant) and without (the rigid form: ``lanes.lane_samples_rigid``)."""
    n = 2 * LANES + 5  # two full blocks and a partial one
    a, b = _mixed(n, coupled), _mixed(n, coupled)
    eligible = [in_lanes(a.regs[i], a.params[i]) for i in range(n)]
    assert 10 < sum(eligible) < n  # both paths are exercised
    a.step(150)  # lanes (parallel driver: n >= 32)
    _run_reference(b, 150)
    np.testing.assert_array_equal(a.regs, b.regs)
    np.testing.assert_array_equal(a.state, b.state)
    assert np.any(a.state[:, L.S_OMEGA] != 0.0)
    twist = a.state[:, L.S_THETA] - a.state[:, L.S_LOAD_THETA]
    # two-mass motors ran in the lanes
    assert np.any(twist[np.array(eligible)] != 0.0) == coupled
    c_ = _mixed(n, coupled)
    driver(c_.family.key).serial(*c_.engine_view(), 150)
    np.testing.assert_array_equal(a.state, c_.state)


@pytest.mark.statements("mac050_141:3.2.35:4")
def test_lanes_flag_a_saturated_current_reading() -> None:
    n = LANES
    a, b = MotorArray("MAC140", n=n, seed=0), MotorArray("MAC140", n=n, seed=0)
    for m in (a, b):
        m.write("KIA", np.where(np.arange(n) < 4, 4 * m.read_raw("KIA"), m.read_raw("KIA")))
        m.write("V_SOLL", 3000)
        m.write("MODE_REG", c.V_MODE)
    assert all(in_lanes(a.regs[i], a.params[i]) for i in range(n))
    driver(a.family.key).parallel(*a.engine_view(), 40)
    _run_reference(b, 40)
    np.testing.assert_array_equal(a.regs, b.regs)
    np.testing.assert_array_equal(a.state, b.state)
    assert np.any(a.regs[:4, R.ERR_STAT] & c.IX_ERR)


def test_lane_scratch_has_a_row_per_block() -> None:
    assert lane_scratch(1).shape[0] == 1
    assert lane_scratch(LANES).shape[0] == 1
    assert lane_scratch(LANES + 1).shape[0] == 2


@njit(cache=True)
def _sincos_all(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    s = np.empty_like(x)
    co = np.empty_like(x)
    for i in range(x.size):
        s[i], co[i] = sincos(x[i])
    return s, co


@njit(cache=True)
def _sine_all(x: np.ndarray) -> np.ndarray:
    out = np.empty_like(x)
    for i in range(x.size):
        out[i] = sine(x[i])
    return out


def test_sine_is_the_sine_of_sincos_bit_for_bit() -> None:
    x = np.random.default_rng(1).uniform(-1e4, 1e4, 10_000)
    x[:3] = [0.0, -0.0, np.pi]
    np.testing.assert_array_equal(_sine_all(x), _sincos_all(x)[0])


def test_sincos_is_within_two_units_in_the_last_place() -> None:
    rng = np.random.default_rng(0)
    for hi in (1.0, 10.0, 1e3, 1e5, 1.6e6):
        x = rng.uniform(-hi, hi, 200_000)
        x[:4] = [0.0, -0.0, np.pi / 4, -np.pi / 2]
        s, co = _sincos_all(x)
        for got, ref in ((s, np.sin(x)), (co, np.cos(x))):
            # two units in the last place; near a zero of the result (cos(-π/2) = 6e-17)
            # the error of the reduced argument, 1e-21 after the three-part reduction
            assert np.all(np.abs(got - ref) <= 2.0 * np.spacing(np.abs(ref)) + 1e-21), hi
    x = rng.uniform(1.6e6, 1e9, 100_000)  # beyond: of the order of the spacing of x itself
    s, co = _sincos_all(x)
    assert np.all(np.abs(s - np.sin(x)) <= np.spacing(x))
    assert np.all(np.abs(co - np.cos(x)) <= np.spacing(x))


def test_lanes_follow_a_parameter_change_between_steps() -> None:
    """The lanes keep each motor's plant factors while its parameters stay the same: a change
    of inertia, friction or coil parameters between steps must reach the next sample."""
    n = LANES + 3
    a, b = _mixed(n), _mixed(n)
    for cols, scale in (((),  1.0), ((L.P_J_LOAD, L.P_VISCOUS), 3.0), ((L.P_R, L.P_L), 1.5),
                        ((L.P_LAMBDA, L.P_C_BUS, L.P_R_DUMP), 0.8)):
        for m in (a, b):
            m.params[:, list(cols)] *= scale
        driver(a.family.key).serial(*a.engine_view(), 40)
        _run_reference(b, 40)
        np.testing.assert_array_equal(a.state, b.state)


@njit(cache=True)
def _fma_all(a: np.ndarray, b: np.ndarray, c_: np.ndarray) -> np.ndarray:
    out = np.empty_like(a)
    for i in range(a.size):
        out[i] = fma(a[i], b[i], c_[i])
    return out


def test_fma_rounds_once() -> None:
    from fractions import Fraction

    rng = np.random.default_rng(1)
    a, b, c_ = rng.normal(size=(3, 500)) * rng.uniform(0.5, 2.0, (3, 500))
    got = _fma_all(a, b, c_)
    for x, y, z, g in zip(a, b, c_, got):
        assert g == float(Fraction(x) * Fraction(y) + Fraction(z))  # the exact value, rounded
    assert np.any(got != a * b + c_)  # and not the twice-rounded one


def test_commutation_sines_are_the_exact_sines_of_the_angle_units() -> None:
    """The current references compute sin/cos of the 2048 angle units (3.2.143) instead of
    looking them up: within one unit in the last place of the exact values (1e-21 near their
    zeros, the error of the reduced argument), and so the references IA/IB/IC_SOLL =
    amp·sin(PHI + k·120°) are those of the table."""
    from jvl_gym.families.mac050_141.firmware.current_loop import RAD_PER_UNIT, phase_references

    k = np.arange(c.ELDEG_PER_TURN, dtype=np.float64)
    s, co = _sincos_all(k * RAD_PER_UNIT)
    exact = 2.0 * np.pi * k / c.ELDEG_PER_TURN
    for got, ref in ((s, np.sin(exact)), (co, np.cos(exact))):
        assert np.all(np.abs(got - ref) <= np.spacing(np.abs(ref)) + 1e-21)
    for phi in range(0, c.ELDEG_PER_TURN, 7):
        got = phase_references(800.0, float(phi))
        ref = [np.clip(np.sign(x) * np.floor(abs(x) + 0.5), -850, 850)
               for x in 800.0 * np.sin(exact[phi] + np.array([0.0, 2.0, 4.0]) * np.pi / 3.0)]
        assert np.allclose(got, ref, atol=1.0)  # table sines combined by the 120° identities
        assert got[0] == ref[0]


def test_the_inner_samples_are_compiled_once_for_the_drivers_and_the_env_steps() -> None:
    """The family's ``prepare`` compiles ``inner_samples`` for the types the drivers and the
    compiled env steps pass: stepping them adds no second compiled version (with an empty
    numba cache, a mismatch would compile the function again inside its caller)."""
    import gymnasium as gym

    import jvl_gym  # noqa: F401
    from jvl_gym.families.mac050_141.lanes import inner_samples

    MotorArray("MAC140", n=3, seed=0).step(2)
    MotorArray("MAC140", n=70, seed=0).step(1)  # threaded driver
    env = gym.make("jvl_gym/Positioning-v0")
    env.reset(seed=0)
    env.step(env.action_space.sample())
    venv = gym.make_vec("jvl_gym/Positioning-v0", num_envs=40,
                        vectorization_mode="vector_entry_point")
    venv.reset(seed=0)
    venv.step(venv.action_space.sample())
    assert len(inner_samples.signatures) == 1
    assert len(inner_samples_one.signatures) == 1


def test_block_index_is_int64_for_a_prange_index() -> None:
    """The threaded drivers call the block function with ``block_index(blk)``: int64 whether
    numba types the loop index as int64 or as uint64, so the block function has one version."""
    from numba import types

    from jvl_gym.engine.driver import block_index

    @njit
    def index_of(blk):
        return block_index(blk)

    assert index_of(np.uint64(5)) == 5
    assert index_of(np.int64(5)) == 5
    assert {sig.return_type for sig in index_of.nopython_signatures} == {types.int64}


def _features(types: list[str], params: dict[str, np.ndarray], k: np.ndarray | None = None,
              seed: int = 4) -> MotorArray:
    """Motors in every mode of the one-motor path: TESTU and TESTKI (their records end in
    INIT), MANI, INIT, hall start with and without HALL_INT, current and torque noise, an
    inner-rate recording, beside motors in the lanes; ``k`` selects motors of the set."""
    idx = np.arange(len(types)) if k is None else k
    m = MotorArray([types[i] for i in idx], n=idx.size, seed=seed,
                   **{name: v[idx] for name, v in params.items()})
    modes = np.array([c.TESTU_MODE, c.TESTKI_MODE, c.MANI_MODE, c.V_MODE, c.V_MODE, c.P_MODE,
                      c.INIT_MODE, c.V_MODE, c.V_MODE])
    m.write_many({"V_SOLL": 2500, "P_SOLL": 40000, "UMEAS": 60, "MAN_I_NOM": 150,
                  "MAN_ALPHA": 1900, "MODE_REG": modes[idx % modes.size]})
    for j, i in enumerate(idx):
        bits = int(m.read_raw("CNTRL_BITS")[j])
        if i % modes.size == 4:
            m.write_raw("CNTRL_BITS", bits | c.HALL_INT, index=j)
        elif i % modes.size == 7:
            m.write("SAMPLE1", R.IA_IST, index=j)
            m.write_raw("CNTRL_BITS", bits | c.RECORDBIT | c.RECINNERBIT, index=j)
    return m


def test_the_one_motor_path_gives_each_motor_the_bits_of_a_one_motor_array() -> None:
    """A block mixing lanes and the one-motor path (which runs in the block's top lanes) gives
    every motor the bits of the same motor alone, in every per-motor feature."""
    n = LANES
    k = np.arange(n)
    types = ["MAC140" if i % 2 == 0 else "MAC050" for i in range(n)]
    params = {"hall_start": np.where(k % 9 == 3, 1.0, 0.0) + np.where(k % 9 == 4, 1.0, 0.0),
              "current_noise": np.where(k % 5 == 1, 0.7, 0.0),
              "torque_noise": np.where(k % 7 == 5, 2e-4, 0.0),
              "pwm_delay_samples": (k % 2).astype(float)}
    a = _features(types, params)
    eligible = [in_lanes(a.regs[i], a.params[i]) for i in range(n)]
    assert 0 < sum(eligible) < n
    a.step(300)
    assert set(a.read_raw("MODE_REG")[:2]) == {c.INIT_MODE}  # the test records ended
    for i in range(n):
        one = _features(types, params, np.array([i]))
        one.reseed(a.keys[i:i + 1])
        one.step(300)
        np.testing.assert_array_equal(one.regs[0], a.regs[i])
        np.testing.assert_array_equal(one.state[0], a.state[i])
