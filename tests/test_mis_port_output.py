"""The MIS multifunction port as an output (MIS manual §5.5, §8.2.68, §8.2.115, §8.2.116): the
internal encoder as quadrature at 4096 counts per revolution, the internal pulse generator
scaled by 16 as quadrature or pulse/direction by SETUP_BITS bits 2–3, nothing when nothing is
routed, and counts that carry their fractions exactly over long runs."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from jvl_gym import MotorArray
from jvl_gym.families.mis import layout as L

#: XFIELD set-ups of §5.5.2 and §5.5.3 (XFIELD_DATA, XFIELD_ADDR)
ENCODER_OUT = {"XFIELD_DATA": 5140, "XFIELD_ADDR": 4160}
GENERATOR_OUT = {"XFIELD_DATA": 4626, "XFIELD_ADDR": 4160}
QUADRATURE, PULSE_DIRECTION = 1 << 3, 1 << 2  # SETUP_BITS bits 2-3 as §5.5's table gives them


def _running(n: int = 1, rpm: float = 600.0, **regs: int | np.ndarray) -> MotorArray:
    """Motors with the set-up ``regs`` running at ``rpm`` (velocity mode, steady)."""
    m = MotorArray("MIS232", n=n, seed=0, **({"encoder_type": regs.pop("encoder_type")}
                                            if "encoder_type" in regs else {}))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        m.write_many(regs)
    m.write_many({"A_SOLL": 100000, "V_SOLL": round(rpm * 100), "MODE_REG": 1})
    m.run(0.3)
    return m


def _generator_floor(m: MotorArray) -> np.ndarray:
    return np.floor(np.round(m.state[:, L.S_CMD], 6) / 16).astype(np.int64)


def _encoder_floor(m: MotorArray) -> np.ndarray:
    return np.floor(m.state[:, L.S_THETA] * 4096 / (2 * math.pi)).astype(np.int64)


@pytest.mark.statements("mis:5.5.2:1", "mis:8.2.115:2", "mis:8.2.116:2")
def test_the_internal_encoder_goes_out_as_4096_quadrature_counts_per_revolution() -> None:
    """§5.5.2: with XFIELD_DATA 5140 and XFIELD_ADDR 4160 the internal encoder's A and B (1024
    pulses, 4096 counts per revolution) go out on the port; the H2/H4 options only, so a motor
    without an internal encoder emits nothing. At 600 RPM: 10 revolutions a second, 40.96
    counts per ms."""
    m = _running(n=2, encoder_type=np.array([3, 0]), **ENCODER_OUT)
    assert m.multifunction_routing == ["encoder quadrature", "none"]
    start_total, start_angle = m.multifunction_output_total, m.position_rad
    per_sample = []
    for _ in range(1000):
        m.step()
        per_sample.append(m.multifunction_output)
    counts = np.array(per_sample)
    revolutions = (m.position_rad - start_angle) / (2 * math.pi)
    assert abs(revolutions[0] - 10.0) < 0.01
    assert set(counts[:, 0].tolist()) <= {40, 41, 42} and counts[:, 1].tolist() == [0] * 1000
    emitted = m.multifunction_output_total - start_total
    assert emitted[0] == counts[:, 0].sum()
    assert abs(emitted[0] - 4096 * revolutions[0]) <= 1.0
    assert emitted[1] == 0


@pytest.mark.statements("mis:5.5.3:1", "mis:8.2.115:2", "mis:8.2.116:2")
def test_the_pulse_generator_goes_out_scaled_by_16_at_1_28_mhz_at_3000_rpm() -> None:
    """§5.5.3: with XFIELD_DATA 4626 and XFIELD_ADDR 4160 and quadrature format, the internal
    pulse generator (409 600 counts per revolution, 20 MHz at 3000 RPM) goes out scaled by 16:
    1.28 MHz at 3000 RPM, 1280 counts per 1 ms outer sample."""
    m = _running(rpm=3000.0, SETUP_BITS=QUADRATURE, **GENERATOR_OUT)
    assert m.multifunction_routing == ["generator quadrature"]
    start = m.multifunction_output_total
    counts = []
    for _ in range(1000):
        m.step()
        counts.append(int(m.multifunction_output[0]))
    assert set(counts) <= {1279, 1280, 1281} and abs(sum(counts) - 1_280_000) <= 1
    assert (m.multifunction_output_total - start)[0] == sum(counts)


@pytest.mark.statements("mis:5.5.4:1", "mis:8.2.68:4", "mis:5.5.3:1")
def test_setup_bits_2_and_3_choose_pulse_direction_or_quadrature_or_nothing() -> None:
    """§5.5.3–5.5.4: SETUP_BITS bit 2 = 1, bit 3 = 0 gives pulse/direction, bit 2 = 0, bit 3 = 1
    quadrature, both 0 none (both 1: no setting of the table, nothing). Either format counts
    409 600 / 16 per revolution; pulse/direction counts are pulses signed by the direction
    line, so the reverse run gives as many negative counts."""
    bits = np.array([PULSE_DIRECTION, QUADRATURE, 0, PULSE_DIRECTION | QUADRATURE])
    m = _running(n=4, rpm=300.0, SETUP_BITS=bits, **GENERATOR_OUT)
    assert m.multifunction_routing == ["generator pulse/direction", "generator quadrature",
                                       "none", "none"]
    m.step(100)  # 0.5 revolutions: 12 800 output counts
    assert m.multifunction_output.tolist() == [128, 128, 0, 0]
    forward = m.multifunction_output_total
    m.write("V_SOLL", -30000)
    m.run(0.5)
    m.step(100)
    assert m.multifunction_output.tolist() == [-128, -128, 0, 0]
    assert forward[2] == forward[3] == 0 and m.multifunction_output_total[2:].tolist() == [0, 0]


@pytest.mark.statements("mis:8.2.115:2", "mis:8.2.116:2")
def test_nothing_routed_or_an_unknown_xfield_set_up_emits_nothing_and_is_kept() -> None:
    """The defaults (XFIELD_ADDR = XFIELD_DATA = 0) route nothing to the output; a pair of
    values §5.5 does not give is stored and read back, and emits nothing."""
    m = _running(n=2, SETUP_BITS=QUADRATURE)
    m.write_many({"XFIELD_DATA": 1234, "XFIELD_ADDR": 4160}, index=1)
    assert m.multifunction_routing == ["none", "unknown"]
    m.run(1.0)
    assert m.read("XFIELD_DATA").tolist() == [0, 1234]
    assert m.read("XFIELD_ADDR").tolist() == [0, 4160]
    assert m.multifunction_output.tolist() == [0, 0]
    assert m.multifunction_output_total.tolist() == [0, 0]


@pytest.mark.statements("mis:5.5.3:1")
def test_the_output_starts_when_the_routing_is_set_and_a_reset_starts_the_sum_again() -> None:
    """Counts run from the routing's set-up on, not from power-on; a software reset (command
    267) restarts the sum at 0 without emitting the commanded position's jump."""
    m = _running(SETUP_BITS=QUADRATURE)
    assert m.multifunction_output_total.tolist() == [0]
    m.write_many(GENERATOR_OUT)
    before = _generator_floor(m)
    m.step(50)
    assert (m.multifunction_output_total == _generator_floor(m) - before).all()
    m.write("MODE_REG", 0)
    for _ in range(50):
        if m.read("MODE_REG")[0] == 0:
            break
        m.run(0.1)
    m.write("COMMAND", 267)
    assert m.multifunction_output_total.tolist() == [0]
    m.step()
    assert m.multifunction_output.tolist() == [0]


@pytest.mark.statements("mis:5.5.3:1")
def test_a_program_that_sets_the_routing_starts_the_output_at_its_sample() -> None:
    """§5.5.1: the set-up may be written by a program's lines; the output starts at the outer
    sample the lines run before (here after a 100 ms wait), whether the samples are stepped one
    at a time or 250 at once."""
    program = ("wait_ms time=100\nset_register register=SETUP_BITS value=8\n"
               "set_register register=XFIELD_DATA value=4626\n"
               "set_register register=XFIELD_ADDR value=4160\njump line=5\n")
    totals = []
    for chunk in (1, 250):
        m = MotorArray("MIS232", n=1, seed=0)
        m.write_many({"A_SOLL": 100000, "V_SOLL": 30000, "MODE_REG": 1})
        m.run(0.2)
        m.store_program(program)
        m.program_start()
        for _ in range(500 // chunk):
            m.step(chunk)
        assert m.multifunction_routing == ["generator quadrature"]
        totals.append(int(m.multifunction_output_total[0]))
    assert totals[0] == totals[1] > 0
    # the 400 samples after the wait only: 300 RPM is 128 output counts per ms
    assert abs(totals[0] - 128 * 400) <= 2 * 128


@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(rpm=st.floats(-1200.0, 1200.0).filter(lambda v: abs(v) > 1.0),
       chunks=st.lists(st.integers(1, 3000), min_size=1, max_size=8))
@pytest.mark.statements("mis:5.5.2:1", "mis:5.5.3:1")
def test_fractional_counts_carry_exactly_over_long_runs(rpm: float, chunks: list[int]) -> None:
    """A speed whose counts per outer sample are fractional (the generator's 409 600 / 16 and
    the encoder's 4096 per revolution): however the run is cut into steps, the sum of the
    emitted counts equals the whole counts the source has passed, never drifting from its travel
    by a count."""
    m = _running(n=2, rpm=rpm, SETUP_BITS=np.array([QUADRATURE, 0]), **{
        "XFIELD_DATA": np.array([4626, 5140]), "XFIELD_ADDR": 4160})
    g0, e0 = _generator_floor(m)[0], _encoder_floor(m)[1]
    cmd0, theta0 = m.state[0, L.S_CMD], m.state[1, L.S_THETA]
    t0 = m.multifunction_output_total
    for k in chunks:
        m.step(k)
    emitted = m.multifunction_output_total - t0
    assert emitted[0] == _generator_floor(m)[0] - g0
    assert emitted[1] == _encoder_floor(m)[1] - e0
    assert abs(emitted[0] - (m.state[0, L.S_CMD] - cmd0) / 16) < 1.0
    assert abs(emitted[1] - (m.state[1, L.S_THETA] - theta0) * 4096 / (2 * math.pi)) < 1.0


@pytest.mark.statements("mis:5.5.3:1")
def test_samples_a_compiled_task_runs_go_into_the_sum_at_the_next_step() -> None:
    """Samples advanced by the engine's driver outside :meth:`step` (as a compiled task does)
    are settled at the next step: into the sum, not into the last sample's counts."""
    from jvl_gym.motor.stepping import driver

    m = _running(rpm=300.0, SETUP_BITS=QUADRATURE, **GENERATOR_OUT)
    before, total = _generator_floor(m), m.multifunction_output_total
    driver("mis").run(m.engine_view(), 50)
    m.step()
    assert m.multifunction_output.tolist() == [128]  # 300 RPM: 128 counts per ms
    assert (m.multifunction_output_total - total == _generator_floor(m) - before).all()
    assert (m.multifunction_output_total - total)[0] == 128 * 51


@pytest.mark.statements("mis:5.5.2:1")
def test_the_encoder_output_counts_a_shaft_turned_in_passive_mode() -> None:
    """The encoder's signals come from the shaft: a passive motor turned by its load emits
    the encoder's counts, the generator's routing (no commanded motion) nothing."""
    m = MotorArray("MIS232", n=2, seed=0)
    m.write_many({"XFIELD_DATA": np.array([5140, 4626]), "XFIELD_ADDR": 4160,
                  "SETUP_BITS": QUADRATURE})
    start = _encoder_floor(m)
    m.set_input(load_torque=-0.5)  # turns the shaft forwards
    m.run(0.5)
    assert m.read("MODE_REG").tolist() == [0, 0]
    turned = _encoder_floor(m) - start
    assert turned[0] > 100
    assert m.multifunction_output_total.tolist() == [turned[0], 0]
