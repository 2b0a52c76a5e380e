"""``tuning.identify_mechanics.electrical_position`` runs on Python numbers and gives, bit for bit,
the numbers of the plain complex loop on the argument types it is called with (NumPy scalars
from the optimiser among them: NumPy divides a complex number by a real one differently)."""

from __future__ import annotations

import cmath

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from tuning.identify_mechanics import current_loop_model, electrical_position
from tuning.models import MotorData

SETTINGS = settings(max_examples=80, deadline=None, derandomize=True)


def _plain_loop(n, t_soll, J, b, tc, motor, current_regs, phase_comp=0.0):
    """The model of :func:`electrical_position` as the plain loop on whatever numbers it gets."""
    fam = motor.family
    (h, per_outer, R, a, k_u, amps, pp, lam, kt,
     x2, x1, y1, y0, b1, b0) = current_loop_model(motor, current_regs)
    d = int(motor.pwm_delay)
    amp = motor.amplitude * t_soll / fam.amplitude_vf
    adv = pp * h * phase_comp
    s = m_prev = e1 = u1 = u2 = 0j
    pend = [0j] * d
    theta = omega = 0.0
    out = np.empty(n)
    for k in range(n):
        out[k] = theta * fam.counts_per_rad
        for _ in range(per_outer):
            th_e = pp * theta
            meas = s / amps
            ref = amp * cmath.exp(1j * (th_e + adv * omega))
            e = ref - (b1 * meas + b0 * m_prev)
            u = x2 * e + x1 * e1 + y1 * u1 + y0 * u2
            e1, u2, u1, m_prev = e, u1, u, meas
            pend.append(u)
            ua = pend.pop(0)
            th_mid = th_e + 0.5 * pp * omega * h
            emf = pp * omega * lam * cmath.exp(1j * th_mid)
            s_new = a * s + (1.0 - a) / R * (k_u * ua - emf)
            torque = kt * ((0.5 * (s + s_new)) * cmath.exp(-1j * th_mid)).real
            s = s_new
            acc = (torque - b * omega - (tc if omega > 0 or torque > tc else torque)) / J
            omega_new = max(omega + acc * h, 0.0)
            theta += 0.5 * (omega + omega_new) * h
            omega = omega_new
    return out - out[0]


def _typed(draw, value: float) -> float:
    """``value`` as a Python float or a NumPy scalar."""
    return np.float64(value) if draw(st.booleans()) else float(value)


@st.composite
def steps(draw):
    motor = MotorData.from_config(draw(st.sampled_from(["MAC140", "MAC050", "MAC800"])))
    motor = motor.with_(pwm_delay=draw(st.sampled_from([0, 1])),
                        R_phase=_typed(draw, motor.R_phase * draw(st.floats(0.8, 1.2))),
                        flux_linkage=_typed(draw, motor.flux_linkage),
                        amplitude=_typed(draw, motor.amplitude))
    kp = draw(st.floats(0.2, 1.0))
    regs = {"KIFX2": kp + draw(st.floats(0.01, 0.2)), "KIFX1": -kp, "KIFY1": 1.0, "KIFY0": 0.0,
            "KIB1": 1.0, "KIB0": 0.0}
    return (draw(st.integers(2, 40)), _typed(draw, draw(st.floats(-300.0, 600.0))),
            _typed(draw, motor.J_m * draw(st.floats(1.0, 20.0))),
            _typed(draw, draw(st.sampled_from([0.0, 1e-5, 3e-4]))),
            _typed(draw, draw(st.sampled_from([0.0, 0.01, 0.2, 5.0]))), motor, regs,
            _typed(draw, draw(st.sampled_from([0.0, 0.3]))))


@SETTINGS
@given(args=steps())
def test_electrical_position_is_the_plain_loop_bit_for_bit(args):
    with np.errstate(all="ignore"):
        want = _plain_loop(*args)
        got = electrical_position(*args)
    assert got.tobytes() == want.tobytes()


def test_the_argument_types_matter_to_the_last_bit():
    """The reason the flags exist: the plain loop on NumPy scalars differs from it on floats."""
    md = MotorData.from_config("MAC140")
    regs = {"KIFX2": 1.6, "KIFX1": -1.35, "KIFY1": 1.0, "KIFY0": 0.0, "KIB1": 1.0, "KIB0": 0.0}
    floats = electrical_position(40, 300.0, 6e-5, 1e-6, 0.01, md, regs)
    scalars = electrical_position(40, 300.0, np.float64(6e-5), np.float64(1e-6),
                                  np.float64(0.01), md, regs)
    assert floats.tobytes() != scalars.tobytes()
    np.testing.assert_allclose(floats, scalars, rtol=1e-12, atol=1e-9)
