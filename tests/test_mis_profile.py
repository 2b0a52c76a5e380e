"""The MIS profile generator: the manual's worked examples of V_START, V_SOLL, A_SOLL, P_IST
and position moves (MIS manual §8.2.3–§8.2.12)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from jvl_gym import MotorArray
from jvl_gym.families.mis import constants as c


def _motor(**regs: int) -> MotorArray:
    m = MotorArray("MIS232", n=1, seed=0)
    m.write_many(regs)
    return m


@pytest.mark.statements("mis:8.2.5:3", "mis:6.2.1:1")
def test_the_family_is_found_by_motor_type_and_v_soll_is_in_hundredths_of_rpm() -> None:
    m = _motor(V_SOLL=25000)
    assert type(m).__name__ == "MisMotorArray"
    assert m.family.key == "mis"
    m.write_many({"A_SOLL": 100000, "MODE_REG": 1})
    m.run(0.1)
    assert m.read("V_IST")[0] == 25000  # "V_SOLL = 25000 will limit the velocity to 250 RPM"
    assert m.speed_rpm[0] == pytest.approx(250.0, abs=15.0)
    m.run(1.0)  # 250 RPM for a second: 250/60 revolutions of 409600 counts
    assert m.rotor_counts[0] == pytest.approx(m.read("P_IST")[0], abs=2048)


@pytest.mark.statements("mis:8.2.11:2", "mis:8.2.12:2", "mis:8.2.12:5", "mis:8.2.12:6")
def test_v_start_example_of_the_manual() -> None:
    """§8.2.12: V_START 100 RPM, V_SOLL 200 RPM: ramp from 100 RPM; V_SOLL 50 RPM: decelerate
    to 100 RPM and stay; V_SOLL −50 RPM: stop, then run at −50 RPM."""
    m = _motor(V_START=10000, V_SOLL=20000, A_SOLL=1000)
    m.write("MODE_REG", 1)
    tr = m.trace(["V_IST"], 150)["V_IST"][:, 0]
    assert tr[0] == 10000  # the jump to the start velocity
    assert np.all(np.diff(tr[:101]) == 100)  # 1000 RPM/s = 1 RPM per ms: 100 ms to 200 RPM
    assert np.all(tr[100:] == 20000)
    m.write("V_SOLL", 5000)
    tr = m.trace(["V_IST"], 300)["V_IST"][:, 0]
    assert np.all(np.diff(tr) <= 0) and tr.min() == 10000  # down to V_START, not to 50 RPM
    assert np.all(tr[150:] == 10000)
    m.write("V_SOLL", -5000)
    tr = m.trace(["V_IST"], 5)["V_IST"][:, 0]
    assert tr.tolist() == [0, -5000, -5000, -5000, -5000]  # stop, then −50 RPM without a ramp
    assert m.lost_steps[0] == 0


@pytest.mark.statements("mis:8.2.3:4", "mis:8.2.6:2", "mis:8.2.12:4")
def test_a_soll_and_v_start_changes_wait_for_standstill() -> None:
    m = _motor(V_START=1000, V_SOLL=30000, A_SOLL=1000)
    m.write("MODE_REG", 1)
    m.step(50)
    m.write_many({"A_SOLL": 5000, "V_START": 20000})
    tr = m.trace(["V_IST"], 20)["V_IST"][:, 0]
    assert np.all(np.diff(tr) == 100)  # still 1000 RPM/s
    m.write("V_SOLL", -30000)  # reverse: decelerate with the old values, stop, new values
    tr = m.trace(["V_IST"], 200)["V_IST"][:, 0]
    stop = int(np.flatnonzero(tr == 0)[0])
    assert np.all(np.diff(tr[:stop - 1]) == -100)
    assert tr[stop + 1] == -20000  # the new V_START
    assert tr[stop + 2] - tr[stop + 1] == -500  # the new A_SOLL: 5 RPM per ms


@pytest.mark.statements("mis:8.2.1:3")
def test_d_soll_decelerates_and_zero_means_a_soll() -> None:
    m = _motor(V_START=1000, V_SOLL=20000, A_SOLL=1000, D_SOLL=4000)
    m.write("MODE_REG", 1)
    m.step(300)
    m.write("V_SOLL", 10000)
    tr = m.trace(["V_IST"], 10)["V_IST"][:, 0]
    assert np.diff(tr)[0] == -400
    m.write_many({"V_SOLL": 0})
    m.step(200)
    m.write_many({"D_SOLL": 0, "V_SOLL": 20000})
    m.step(300)
    m.write("V_SOLL", 10000)
    tr = m.trace(["V_IST"], 10)["V_IST"][:, 0]
    assert np.diff(tr)[0] == -100


@pytest.mark.statements("mis:8.2.12:3")
def test_below_v_start_runs_without_a_ramp() -> None:
    m = _motor(V_START=10000, V_SOLL=3000)
    m.write("MODE_REG", 1)
    tr = m.trace(["V_IST"], 3)["V_IST"][:, 0]
    assert tr.tolist() == [3000, 3000, 3000]


@pytest.mark.statements("mis:8.2.3:5", "mis:8.2.24:5")
def test_position_move_lands_on_p_soll_with_the_profile() -> None:
    m = _motor(V_START=1000, V_SOLL=30000, A_SOLL=2000, P_SOLL=409600 * 3)
    m.write("MODE_REG", 2)
    tr = m.trace(["P_IST", "V_IST", "STATUSBITS"], 2500)
    p, v = tr["P_IST"][:, 0], tr["V_IST"][:, 0]
    assert p[-1] == 409600 * 3 and np.all(np.diff(p) >= 0)
    assert v.max() == 30000 and v[-1] == 0
    assert tr["STATUSBITS"][-1, 0] & c.ST_IN_POSITION
    assert not tr["STATUSBITS"][len(p) // 4, 0] & c.ST_IN_POSITION
    assert m.lost_steps[0] == 0
    assert abs(m.read("FLWERR")[0]) < 2048


@pytest.mark.statements("mis:8.2.10:2")
def test_writing_p_ist_in_position_mode_makes_a_move() -> None:
    """§8.2.10: P_IST = P_SOLL = 1000, P_IST := 500: the motor moves 500 steps forward and
    P_IST is again 1000."""
    m = _motor(P_SOLL=1000)
    m.write("MODE_REG", 2)
    m.step(100)
    assert m.read("P_IST")[0] == 1000
    before = m.rotor_counts[0]
    m.write("P_IST", 500)
    m.step(200)
    assert m.read("P_IST")[0] == 1000
    # the rotor follows to within the detent torque's microstep error (about 80 counts here)
    assert m.rotor_counts[0] - before == pytest.approx(500, abs=160)


@pytest.mark.statements("mis:8.2.4:2", "mis:8.2.10:3")
def test_relative_moves_wrap_at_2_to_the_31() -> None:
    """§8.2.4: P_SOLL wraps at 2³¹ − 1 and the motor moves correctly; P_IST wraps too."""
    m = _motor(V_SOLL=300000, A_SOLL=500000, IN_POSITION_COUNT=0)  # no auto-correction:
    m.write("P_IST", 2**31 - 1000)  # the encoder is not synchronised with this P_IST
    m.write_many({"P_SOLL": 2**31 - 1000, "MODE_REG": 2})
    m.step(5)
    m.write("P_SOLL", -(2**31) + 3000)  # 4000 counts ahead across the wrap
    m.step(100)
    assert m.read("P_IST")[0] == -(2**31) + 3000
    assert m.rotor_counts[0] == pytest.approx(4000, abs=100)


@pytest.mark.statements("mis:8.2.3:9")
def test_stop_mode_decelerates_then_goes_passive() -> None:
    m = _motor(V_START=1000, V_SOLL=20000, A_SOLL=1000)
    m.write("MODE_REG", 1)
    m.step(300)
    m.write("MODE_REG", 11)
    tr = m.trace(["V_IST", "MODE_REG"], 300)
    v, mode = tr["V_IST"][:, 0], tr["MODE_REG"][:, 0]
    stop = int(np.flatnonzero(v == 0)[0])
    assert 180 < stop < 200 and np.all(np.diff(v[:stop - 1]) == -100)
    assert mode[stop] == 0 and mode[stop - 2] == 11


@given(st.integers(-500_000, 500_000), st.integers(5000, 300000), st.integers(1, 300000),
       st.integers(100, 50000), st.integers(0, 50000))
@settings(max_examples=30, deadline=None)
@pytest.mark.statements("mis:8.2.3:5", "mis:8.2.12:2")
def test_position_moves_land_exactly_without_overshoot(target: int, v_soll: int, v_start: int,
                                                       a_soll: int, d_soll: int) -> None:
    """Any move ends exactly on P_SOLL, P_IST never passes it, the speed never exceeds
    max(|V_SOLL|, V_START), starts with a jump to at most the start velocity and changes by
    about A_SOLL/D_SOLL per ms while moving (§8.2.3–§8.2.12)."""
    m = _motor(V_SOLL=v_soll, V_START=v_start, A_SOLL=a_soll, D_SOLL=d_soll, P_SOLL=target,
               IN_POSITION_COUNT=0)
    m.write("MODE_REG", 2)
    p, v = [], []
    for _ in range(100):
        tr = m.trace(["P_IST", "V_IST"], 100)
        p.extend(tr["P_IST"][:, 0])
        v.extend(tr["V_IST"][:, 0])
        if p[-1] == target and v[-1] == 0:
            break
    p, v = np.array(p), np.concatenate([[0], v])
    assert p[-1] == target
    assert np.all(np.sign(target) * np.diff(np.concatenate([[0], p])) >= 0)
    vs = min(v_start, v_soll)
    assert np.abs(v).max() <= max(v_soll, vs)
    moving = np.flatnonzero(v != 0)
    if moving.size:
        assert abs(v[moving[0]]) <= vs + 1  # the start: a jump to the start velocity
        ramp = max(a_soll, d_soll or a_soll) * 0.1  # RPM/s → 0.01 RPM per ms
        both = (v[1:] != 0) & (v[:-1] != 0)
        assert np.all(np.abs(np.diff(v))[both] <= 1.5 * ramp + 2)
