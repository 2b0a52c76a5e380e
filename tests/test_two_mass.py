"""The elastic coupling to the load (docs/model.md §5.2): physics invariants of the two-mass
plant and the check of its parameters."""

from __future__ import annotations

import math

import numpy as np
import pytest

from jvl_gym import MotorArray
from jvl_gym.families.mac050_141 import constants as c
from jvl_gym.physics.mechanics import (
    MAX_COUPLING_OMEGA_H,
    coupling_problem,
    mech_constants,
    mech_step,
    mech_step_prepared,
    two_mass_step,
)

H = c.INNER_DT
J_M, J_L = 2.0e-5, 6.0e-5


def _stiffness(f_hz: float, j_m: float = J_M, j_l: float = J_L) -> float:
    """Coupling stiffness [N·m/rad] of a resonance at ``f_hz`` [Hz]."""
    return (2 * math.pi * f_hz) ** 2 / (1 / j_m + 1 / j_l)


def test_energy_balance_without_damping_or_friction() -> None:
    k = _stiffness(200.0)
    th, w, tl, wl = 0.0, 0.0, 0.0, 0.0
    work = 0.0
    for n in range(3000):
        drive = 0.2 * math.sin(n * 0.01)
        th1, w1, tl1, wl1, loss = two_mass_step(th, w, tl, wl, drive, 0.05, J_M, J_L, 0.0, 0.0,
                                                k, 0.0, H)
        assert abs(loss) < 1e-12 * (1 + abs(drive * (th1 - th)))
        work += drive * (th1 - th) - 0.05 * (tl1 - tl)
        th, w, tl, wl = th1, w1, tl1, wl1
    stored = 0.5 * J_M * w**2 + 0.5 * J_L * wl**2 + 0.5 * k * (th - tl) ** 2
    assert stored == pytest.approx(work, rel=1e-9)
    assert th != tl  # the coupling did twist


def test_losses_are_positive_with_damping_and_friction() -> None:
    k = _stiffness(100.0)
    th, w, tl, wl = 0.0, 50.0, 0.0, 0.0
    total = 0.0
    for _ in range(5000):
        th, w, tl, wl, loss = two_mass_step(th, w, tl, wl, 0.0, 0.0, J_M, J_L, 1e-5, 0.01, k,
                                            1e-3, H)
        assert loss > -1e-15
        total += loss
    e0 = 0.5 * J_M * 50.0**2
    e1 = 0.5 * J_M * w**2 + 0.5 * J_L * wl**2 + 0.5 * k * (th - tl) ** 2
    assert total == pytest.approx(e0 - e1, rel=1e-9)


def test_free_oscillation_at_the_coupling_frequency() -> None:
    f = 250.0
    k = _stiffness(f)
    th, w, tl, wl = 1e-3, 0.0, 0.0, 0.0
    twist = []
    for _ in range(4000):
        th, w, tl, wl, _ = two_mass_step(th, w, tl, wl, 0.0, 0.0, J_M, J_L, 0.0, 0.0, k, 0.0, H)
        twist.append(th - tl)
    x = np.array(twist)
    ups = np.flatnonzero((x[:-1] < 0) & (x[1:] >= 0))
    period = (ups[-1] - ups[0]) / (len(ups) - 1) * H
    wn = 2 * math.pi * f
    # the implicit midpoint rule's frequency (2/h)·atan(ω h/2), within 1 % of the true one here
    assert 1 / period == pytest.approx(2 / H * math.atan(wn * H / 2) / (2 * math.pi), rel=2e-3)
    assert 1 / period == pytest.approx(f, rel=0.01)
    # the momentum of the free pair is conserved
    assert J_M * w + J_L * wl == pytest.approx(0.0, abs=1e-12)


def test_rigid_shaft_step_is_the_one_mass_step() -> None:
    a = mech_step(0.3, 12.0, 0.05, J_M + J_L, 1e-5, 0.002, H)
    b = two_mass_step(0.3, 12.0, 0.3, 12.0, 0.05, 0.0, J_M, J_L, 1e-5, 0.002, 0.0, 0.0, H)
    assert (b[0], b[1], b[4]) == a
    assert (b[2], b[3]) == (b[0], b[1])


def test_rigid_form_gives_the_bits_of_the_coupled_form_for_a_rigid_shaft() -> None:
    """``mech_step_prepared(..., rigid=True)`` (the SIMD lanes of a block without an elastic
    coupling) leaves out the coupling's terms; for a rigid shaft they are exact zeros, so both
    forms give the same state and the same loss (the sign of a zero loss aside), at rest,
    stuck in Coulomb friction, through a reversal and with a signed zero drive."""
    for j, b, tc in ((J_M + J_L, 1e-5, 0.002), (J_M, 0.0, 0.0), (J_M, 2e-5, 0.05)):
        k = mech_constants(J_M, j - J_M, b, 0.0, 0.0, H)
        for th, w, drive in ((0.3, 12.0, 0.05), (0.0, 0.0, 0.0), (0.0, 0.0, -0.0),
                             (0.0, 0.0, 0.001), (-1.0, 0.0, -0.2), (2.0, -1e-3, 0.3),
                             (1.0, 5.0, -0.0), (1.0, -5.0, 0.0), (0.5, 1e-9, -1.0)):
            for _ in range(20):
                got = mech_step_prepared(th, w, th, w, drive, 0.0, j, tc, H, k, True)
                ref = mech_step_prepared(th, w, th, w, drive, 0.0, j, tc, H, k, False)
                assert np.array_equal(np.array(got[:4]).view(np.int64),
                                      np.array(ref[:4]).view(np.int64))
                assert got[4] == ref[4]
                th, w = got[0], got[1]


def test_static_twist_is_load_torque_over_stiffness() -> None:
    k = _stiffness(80.0)
    # a rotor held by static friction: the load settles where the coupling carries its torque
    th, w, tl, wl = 0.0, 0.0, 0.0, 0.0
    for _ in range(20000):
        th, w, tl, wl, _ = two_mass_step(th, w, tl, wl, 0.0, 0.2, J_M, J_L, 0.0, 10.0, k, 2e-3,
                                         H)
    assert (th, w) == (0.0, 0.0)
    assert th - tl == pytest.approx(0.2 / k, rel=1e-9)
    # a motor holding its position (P_MODE) under a load behind the coupling
    m = MotorArray("MAC140", n=1, seed=0, load_inertia=J_L, coupling_stiffness=k,
                   coupling_damping=5e-3)
    m.write("P_SOLL", 0)
    m.write("MODE_REG", c.P_MODE)
    m.set_input(load_torque=0.2)
    m.step(1000)
    assert {"load_angle", "load_speed"} <= m.PHYSICAL
    tr = m.trace(["load_angle", "position_rad", "load_speed"], 500)
    twist = tr["position_rad"][:, 0] - tr["load_angle"][:, 0]
    assert twist.mean() == pytest.approx(0.2 / k, rel=2e-3)  # the position loop hunts ±1 count
    assert np.abs(tr["load_speed"]).max() < 0.5


def test_rigid_limit_of_a_stiff_coupling() -> None:
    j_m = MotorArray("MAC140").parameters["rotor_inertia"][0]
    # the stiffest coupling the inner step carries, well damped
    k = (MAX_COUPLING_OMEGA_H / H) ** 2 / (1 / j_m + 1 / 4e-5) * 0.99
    kw = dict(n=1, seed=0, load_inertia=4e-5, viscous_friction=1e-5)
    rigid = MotorArray("MAC140", **kw)
    elastic = MotorArray("MAC140", coupling_stiffness=k, coupling_damping=0.02, **kw)
    out = []
    for m in (rigid, elastic):
        m.write("V_SOLL", 3000)
        m.write("A_SOLL", 40)
        m.write("MODE_REG", c.V_MODE)
        out.append(m.trace(["speed_rad_s", "load_speed", "V_IST"], 200))
    a, b = out
    peak = np.max(np.abs(a["speed_rad_s"]))
    assert np.max(np.abs(a["speed_rad_s"] - b["speed_rad_s"])) < 0.02 * peak
    assert np.max(np.abs(b["load_speed"] - b["speed_rad_s"])) < 0.02 * peak
    np.testing.assert_array_equal(a["load_speed"], a["speed_rad_s"])  # rigid: one body
    # the energy accounts close as the rigid shaft's do (their remainder is the coil's
    # electromechanical conversion, the same in both)
    closure = []
    for m in (rigid, elastic):
        e = m.energy
        closure.append((e["electrical"] - e["copper"] - e["friction"] - e["load"]
                        - e["kinetic"] - e["coupling"])[0])
    assert abs(closure[1] - closure[0]) < 2e-5 * elastic.energy["electrical"][0]
    assert rigid.energy["coupling"][0] == 0.0 < elastic.energy["coupling"][0]


@pytest.mark.parametrize(("kw", "field"), [
    ({"coupling_stiffness": -1.0, "load_inertia": 1e-5}, "coupling_stiffness"),
    ({"coupling_damping": float("nan")}, "coupling_damping"),
    ({"coupling_stiffness": 1.0}, "load_inertia"),
    ({"coupling_stiffness": 1e4, "load_inertia": 1e-5}, "coupling_stiffness"),
    ({"coupling_stiffness": 1.0, "load_inertia": 1e-5, "coupling_damping": 10.0},
     "coupling_damping"),
])
def test_bad_couplings_are_refused_naming_the_field(kw: dict, field: str) -> None:
    m = MotorArray(["MAC140", "MAC050"], n=2, seed=0, load_inertia=3e-5)
    m.step(3)
    before = (m.params.copy(), m.state.copy(), m._type_of.copy())
    with pytest.raises(ValueError, match=field):
        m.reset(index=[1], motor_type="MAC095", **kw)
    np.testing.assert_array_equal(m.params, before[0])
    np.testing.assert_array_equal(m.state, before[1])
    np.testing.assert_array_equal(m._type_of, before[2])


def test_coupling_problem_accepts_the_limit() -> None:
    k = (MAX_COUPLING_OMEGA_H / H) ** 2 / (1 / J_M + 1 / J_L)
    assert coupling_problem(J_M, J_L, 0.999 * k, 0.0, H) is None
    assert "Hz" in coupling_problem(J_M, J_L, 1.01 * k, 0.0, H)
    assert coupling_problem(J_M, 0.0, 0.0, 0.0, H) is None  # rigid: no load needed
