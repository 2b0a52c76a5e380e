"""The integer current loop's position error (:mod:`tuning.loop_quantisation`) and the repeated
coil steps' intervals of the MAC800 identification (:mod:`tuning.identify_buffer`)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from tuning import identify_buffer as ib
from tuning.design_sixth_order import design_current_filter
from tuning.identify_buffer import CoilStepEstimate, combine_coil_steps
from tuning.identify_mechanics import electrical_position
from tuning.loop_quantisation import quantisation_error, quantised_position
from tuning.models import MotorData

from jvl_gym import MotorArray

LOAD = 6e-4
N = 100  #: servo samples of a step, as the identification records them


@pytest.fixture(scope="module")
def motor():
    md = MotorData.from_config("MAC800").with_(supply_voltage=325.0)
    return md, design_current_filter(md), md.J_m + LOAD


def _relative(err: np.ndarray, ref: np.ndarray) -> float:
    """The share of the step's acceleration term ``ref`` in ``err`` (offset and speed left
    out, as the fit leaves them free)."""
    q = np.linalg.qr(np.vander(np.arange(err.size, dtype=float), 2, increasing=True))[0]
    g = ref - q @ (q.T @ ref)
    return float(g @ (err - q @ (q.T @ err)) / (g @ g))


def test_without_rounding_the_per_phase_loop_is_the_electrical_model(motor):
    md, regs, J = motor
    start = np.array([0.0, 700.0, 2100.0])
    for vf in (42.0, 85.0):
        smooth = electrical_position(N, vf, J, 0.0, 0.0, md, regs, 0.0)
        per_phase = quantised_position(N, vf, J, md, regs, 0.0, start, rounding=False)
        assert np.max(np.abs(per_phase - smooth)) < 1e-6 * np.max(np.abs(smooth))


def test_the_rounding_error_is_the_simulators_mean_over_start_angles(motor):
    """Torque steps of the simulated MAC800 from 16 rotor angles over one electrical turn: the
    mean of their deviation from the smooth model is the rounding error the identification
    subtracts, within a quarter of it (the mean of 16 angles scatters that much)."""
    md, regs, J = motor
    k = 16
    angles = (np.arange(k) + 0.5) * 2.0 * math.pi / md.pole_pairs / k
    m = MotorArray("MAC800", n=k, load_inertia=LOAD, initial_angle=angles,
                   initial_speed=np.zeros(k))
    m.load_setup({"registers": regs})
    m.write("MODE_REG", ib._c.PASSIVE_MODE)
    m.step(3)
    m.write("MODE_REG", ib._c.ANALOG_TORQUE_MODE)
    m.step(2)
    vf = 85.0
    rec = ib.record_torque_steps(m, np.full(k, vf))
    smooth = electrical_position(N, vf, J, 0.0, 0.0, md, regs, 0.0)
    simulated = np.mean([_relative(r.position - r.position[0] - smooth, smooth) for r in rec])
    predicted = _relative(quantisation_error(N, vf, J, md, regs), smooth)
    assert simulated < -1e-3  # the rounding costs torque: 0.1 % of the motion or more
    assert predicted == pytest.approx(simulated, rel=0.25)


def test_coil_steps_combine_to_batch_means():
    ests = [CoilStepEstimate(2.9 + d, 8.7e-3 * (1 + d), dl, 1.0)
            for d, dl in ((-0.02, 1), (0.01, 1), (0.03, 0), (-0.01, 1))]
    c = combine_coil_steps(ests)
    r = np.array([e.R_phase for e in ests])
    h = 3.182446 * r.std(ddof=1) / 2.0  # t(0.975, 3)·sd/√4
    assert c.R_phase == pytest.approx(r.mean())
    assert c.ci["R_phase"] == pytest.approx((r.mean() - h, r.mean() + h), rel=1e-6)
    assert c.ci["L_phase"][0] < c.L_phase < c.ci["L_phase"][1]
    assert c.delay == 1 and len(c.repeats) == 4
    with pytest.raises(ValueError, match="at least two"):
        combine_coil_steps(ests[:1])
