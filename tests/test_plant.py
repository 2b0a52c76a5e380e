"""Physics of the plant kernels on their own: exactness, invariants, closed forms."""

from __future__ import annotations

import math

import numpy as np
import pytest

from jvl_gym.physics.bus import bus_step
from jvl_gym.physics.coil import coil_step, phase_to_vector, vector_to_phases
from jvl_gym.physics.mechanics import mech_step

R, LL, LAM, PP = 0.83, 0.83e-3, 0.0265, 2.0
H = 128e-6


def _run(s0, su, th, w, h, n):
    s = s0
    torque_int = 0.0
    for k in range(n):
        s, t, _, _ = coil_step(s, su, th + w * k * h, w, R, LL, LAM, PP, h)
        torque_int += t * h
    return s, torque_int


@pytest.mark.parametrize("omega_e", [0.0, 300.0, 2000.0])
def test_coil_step_is_exact_independent_of_step(omega_e):
    """One step of 128 µs equals 2, 8, 64 sub-steps to rounding (docs/model.md §5.1)."""
    s0 = complex(3.0, -1.0)
    su = phase_to_vector(10.0, -4.0, -6.0)
    ref, _ = _run(s0, su, 0.3, omega_e, H, 1)
    for sub in (2, 8, 64):
        s, _ = _run(s0, su, 0.3, omega_e, H / sub, sub)
        assert abs(s - ref) < 1e-12 * max(1.0, abs(ref))


def test_coil_dc_steady_state_is_u_over_r():
    su = phase_to_vector(2.0, 0.0, -2.0)
    s = 0j
    for _ in range(2000):
        s, *_ = coil_step(s, su, 0.0, 0.0, R, LL, LAM, PP, H)
    ia, ib, ic = vector_to_phases(s)
    # star, floating neutral at 0 V: ia = 2/R, ib = 0, ic = -2/R
    assert ia == pytest.approx(2.0 / R, rel=1e-9)
    assert ib == pytest.approx(0.0, abs=1e-9)
    assert ic == pytest.approx(-2.0 / R, rel=1e-9)


def test_coil_rl_step_closed_form():
    """Phase current of a voltage step follows U/R (1 − e^{−t/τ})."""
    su = phase_to_vector(1.0, -0.5, -0.5)  # pure phase-a excitation, neutral at 0
    s = 0j
    for k in range(1, 20):
        s, *_ = coil_step(s, su, 0.0, 0.0, R, LL, LAM, PP, H)
        expected = 1.0 / R * (1.0 - math.exp(-k * H * R / LL))
        assert s.real == pytest.approx(expected, rel=1e-12)


def test_coil_energy_balance_with_back_emf():
    """Electrical input = copper loss + magnetic energy change + mechanical work (T·ω)."""
    su = phase_to_vector(5.0, -1.0, -4.0)
    w = 800.0
    s = complex(1.0, 2.0)
    e_in = e_cu = e_mech = 0.0
    th = 0.0
    for _ in range(400):
        s1, t, p_el, p_cu = coil_step(s, su, th, w, R, LL, LAM, PP, H)
        e_in += p_el * H
        e_cu += p_cu * H
        e_mech += t * (w / PP) * H
        th += w * H
        s = s1
    e_mag = 1.5 * LL * (abs(s) ** 2 - abs(complex(1.0, 2.0)) ** 2) / 2.0
    assert e_in == pytest.approx(e_cu + e_mag + e_mech, rel=1e-6)


def test_phase_vector_round_trip_removes_zero_sequence():
    s = phase_to_vector(3.0, 2.0, 7.0)
    a, b, c = vector_to_phases(s)
    mean = (3.0 + 2.0 + 7.0) / 3.0
    assert (a, b, c) == pytest.approx((3.0 - mean, 2.0 - mean, 7.0 - mean))


def test_mechanics_constant_torque_ramp_and_energy():
    j, h = 2e-5, H
    th, w = 0.0, 0.0
    for _ in range(1000):
        th, w, ef = mech_step(th, w, 0.1, j, 0.0, 0.0, h)
        assert ef == pytest.approx(0.0, abs=1e-15)
    t = 1000 * h
    assert w == pytest.approx(0.1 / j * t, rel=1e-12)
    assert th == pytest.approx(0.5 * 0.1 / j * t * t, rel=1e-12)


def test_mechanics_static_friction_holds_and_coulomb_stops():
    th, w, ef = mech_step(0.0, 0.0, 0.05, 1e-5, 0.0, 0.06, H)
    assert (th, w, ef) == (0.0, 0.0, 0.0)
    th, w = 0.0, 10.0
    for _ in range(100000):
        th, w, ef = mech_step(th, w, 0.0, 1e-5, 0.0, 0.01, H)
        if w == 0.0:
            break
    assert w == 0.0
    # stopping distance of a Coulomb decelerated rotor: w0²/(2 Tc/J)
    assert th == pytest.approx(10.0**2 / (2 * 0.01 / 1e-5), rel=2e-3)


def test_bus_regeneration_charges_and_dump_clamps():
    u, dump = 48.0, 0.0
    top = 0.0
    for _ in range(200000):
        u, dump, _, _ = bus_step(u, -300.0, 48.0, 2e-3, 0.05, 52.0, 3.0, dump, H)
        top = max(top, u)
    assert 52.0 < top < 56.0
    u2, *_ = bus_step(48.0, 200.0, 48.0, 2e-3, 0.05, 52.0, 3.0, 0.0, H)
    assert u2 < 48.0
    assert np.isfinite(u)
