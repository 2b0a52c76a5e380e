"""World signal sources: profiles, pulse counting, analogue noise, supply events."""

from __future__ import annotations

import numpy as np
import pytest

from jvl_gym import MotorArray
from jvl_gym.families.mac050_141 import constants as c
from jvl_gym.world import AnalogInput, PulseInput, SpeedProfile, SupplyEvents, World


def test_profiles_ramp_steps_stops_recorded():
    ramp = SpeedProfile.ramp([2.0, 4.0], t_ramp=1.0, n=2)
    np.testing.assert_allclose(ramp(0.5), [1.0, 2.0])
    np.testing.assert_allclose(ramp(3.0), [2.0, 4.0])
    steps = SpeedProfile.steps([0.1, 0.5, 0.9], [3.0, 0.0, -1.0], n=1)  # 0 is a stop
    assert steps(0.05)[0] == 0.0 and steps(0.3)[0] == 3.0 and steps(0.6)[0] == 0.0
    assert steps(1.0)[0] == -1.0
    rec = SpeedProfile.recorded([0.0, 1.0], [0.0, 10.0], n=3)
    np.testing.assert_allclose(rec(0.25), [2.5] * 3)
    with pytest.raises(ValueError):
        SpeedProfile.steps([0.5, 0.1], [1.0, 2.0], n=1)


def test_ripple_mean_and_amplitude():
    base = SpeedProfile.constant(5.0, n=1)
    rip = SpeedProfile.ripple(0.1, base)
    v = np.array([rip(k * c.OUTER_DT)[0] for k in range(2000)])
    assert v.max() == pytest.approx(5.5, rel=0.01) and v.min() == pytest.approx(4.5, rel=0.01)
    assert v.mean() == pytest.approx(5.0, rel=0.01)


def test_random_walk_statistics_and_seed():
    a = SpeedProfile.random_walk(10.0, sigma=0.5, tau=0.05, n=200, seed=1, horizon=2.0)
    b = SpeedProfile.random_walk(10.0, sigma=0.5, tau=0.05, n=200, seed=1, horizon=2.0)
    samples = np.array([a(t) for t in np.arange(0.5, 2.0, 0.1)])
    assert samples.mean() == pytest.approx(10.0, abs=0.05)
    assert samples.std() == pytest.approx(0.5, rel=0.1)
    np.testing.assert_array_equal(a(1.0), b(1.0))


def test_pulse_counts_are_never_lost():
    prof = SpeedProfile.constant(0.37, n=1)
    src = PulseInput(prof, lines=1000, signal="quadrature")
    quadrature = np.array([False]), np.array([False])
    total = sum(src.advance(c.OUTER_DT, *quadrature)[0] for _ in range(1000))
    assert total == np.floor(0.37 * 4000 * 1000 * c.OUTER_DT)


def test_analog_noise_is_per_motor_and_the_adc_clips():
    src = AnalogInput(9.9, n=3, noise_std=0.5, seed=4)
    v = np.array([src.advance(c.OUTER_DT) for _ in range(500)])
    assert v.max() > 10.0  # the terminal voltage: the motor's ADC clips (3.2.122)
    assert not np.array_equal(v[:, 0], v[:, 1])
    with pytest.raises(ValueError):
        AnalogInput(0.0, n=1, noise_std=-1.0)
    m = MotorArray("MAC140", n=2, seed=0)
    m.world = World(analog=AnalogInput(np.array([12.0, -12.0]), n=2))
    m.step(1)
    np.testing.assert_array_equal(m.read("ANINP"), [1023, -1023])  # ±10 V full scale


def test_supply_events_and_bad_events():
    ev = SupplyEvents([(0.01, 0.02, 0.0)], nominal=48.0, n=2)
    v = np.array([ev.advance(c.OUTER_DT)[0] for _ in range(20)])
    assert v[0] == 48.0 and 0.0 in v
    with pytest.raises(ValueError):
        SupplyEvents([(0.2, 0.1, 24.0)], nominal=48.0, n=1)


def test_world_and_held_inputs_combine():
    m = MotorArray("MAC140", n=1, seed=0)
    m.set_input(load_torque=0.01)
    m.world = World(analog=AnalogInput(lambda t: np.array([5.0]), n=1))
    m.step(3)
    assert m.read("ANINP")[0] == 512  # 5 V → 511.5 → 512 (half away from zero)
    assert m.inputs[0, 0] == 0.01  # the held load torque is kept


def test_world_takes_the_sample_time_and_pulse_decoding_from_the_motors():
    """The sources advance by the array's own sample time; the pulse decoding is the motors'
    latched configuration (PULSEDIR, INPSIGN on the MAC050–141, manual 3.2.36)."""
    m = MotorArray("MAC140", n=2, seed=0)
    m.write("CNTRL_BITS", [0, c.PULSEDIR | c.INPSIGN])
    m.enter_safe_mode()
    m.write_flash()  # saved, then a reset: latched at power-on
    np.testing.assert_array_equal(m.pulse_decoding()[0], [False, True])
    np.testing.assert_array_equal(m.pulse_decoding()[1], [False, True])
    world = World(pulse=PulseInput(SpeedProfile.constant(1.0, n=2), lines=1000))
    out = world.schedule(m, 100)
    counts = out[:, :, m.INPUTS["pulse_counts"]].sum(axis=0)
    np.testing.assert_allclose(counts, [4000 * 100 / m.OUTER_HZ, -1000 * 100 / m.OUTER_HZ],
                               atol=1)  # whole counts: a fraction is carried to the next
    assert world.t == pytest.approx(100 / m.OUTER_HZ)



def test_a_world_input_the_motors_lack_is_named_in_plain_words():
    m = MotorArray("MIS232")  # the MIS/SMC integrated step motors have no analog_volts input
    world = World(analog=AnalogInput(1.0, n=1))
    with pytest.raises(ValueError, match="analog_volts") as info:
        world.schedule(m, 1)
    assert "which MIS/SMC integrated step motors do not have" in str(info.value)
    assert "motors motors" not in str(info.value)


def test_the_shaft_error_names_the_motors_once():
    from types import SimpleNamespace

    stand_in = SimpleNamespace(family=SimpleNamespace(title="MAC800 integrated servo motors"))
    with pytest.raises(AttributeError) as info:
        MotorArray._shaft(stand_in, -1)  # a family that declares no shaft state column
    assert str(info.value).startswith("MAC800 integrated servo motors declare no shaft state")
