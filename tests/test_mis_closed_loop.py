"""MIS closed loop (MIS manual §5.3): current-scaling timing of §5.3.7, no lost position after
an overload, less copper loss at light load; auto-correction (§5.2)."""

from __future__ import annotations

import numpy as np
import pytest

from jvl_gym import MotorArray
from jvl_gym.families.mis import constants as c
from jvl_gym.families.mis import layout as L
from jvl_gym.families.mis.firmware.closed_loop import scale_current

CL = c.SETUP_CLOSED_LOOP | c.SETUP_CURRENT_CONTROL


def _ms_to(goal: float, start: float, follow_error: float, rpm: float) -> int:
    m = MotorArray("MIS232", n=1)
    m.write("CUR_SCALE_MIN", 0)
    regs, s = m.regs[0], m.state[0]
    s[L.S_CUR_SCALE] = start
    for ms in range(1, 5000):
        scale_current(regs, s, follow_error, rpm)
        if s[L.S_CUR_SCALE] == goal:
            return ms
    raise AssertionError("never reached")


@pytest.mark.statements(
    "mis:8.2.110:2", "mis:8.2.113:2", "mis:8.2.114:2", "mis:5.3.7:2", "mis:5.3.7:3", "mis:5.3.7:4")
def test_current_scaling_times_of_the_manual() -> None:
    """§5.3.7: one step up per 55.56 µs (0 → 100 % in about 113 ms); one step down per 111 µs
    at 0 RPM (100 % → 0 in 227 ms) and per 1.13 ms at 3000 RPM (2.3 s)."""
    assert _ms_to(2047, 0, 5000, 0.0) == 114  # 2047 × 55.56 µs = 113.7 ms
    assert _ms_to(0, 2047, 0, 0.0) == 228  # 2047 × 111.1 µs = 227.4 ms
    assert _ms_to(0, 2047, 0, 3000.0) == pytest.approx(2310, abs=1)  # 2047 × 1.128 ms
    # proportional below one full step of follow error
    assert _ms_to(1023, 0, 1024, 0.0) == 57  # 1023 steps of 55.56 µs


@pytest.mark.statements(
    "mis:8.2.24:16", "mis:8.2.68:19", "mis:8.2.68:20", "mis:8.2.112:4", "mis:8.2.112:5",
    "mis:5.3.1:3", "mis:5.3.5:1")
def test_closed_loop_current_follows_the_load_in_a_running_motor() -> None:
    m = MotorArray("MIS232", n=2, seed=0)
    m.write_many({"SETUP_BITS": np.array([CL, 0]), "V_SOLL": 30000, "A_SOLL": 2000,
                  "RUN_CURRENT": 1022, "MODE_REG": 1})
    m.set_input(load_torque=0.2)
    m.run(2.0)
    torque = m.read("ACTUAL_TORQUE")
    assert 0 < torque[0] < 2047 and torque[1] == 2047
    assert m.read("STATUSBITS")[0] & c.ST_CLOSED_LOOP
    e0 = m.energy["copper"].copy()
    m.run(1.0)
    copper = m.energy["copper"] - e0
    assert copper[0] < 0.5 * copper[1]
    assert m.lost_steps.tolist() == [0, 0]


@pytest.mark.statements("mis:8.2.128:2", "mis:5.3.1:1", "mis:5.3.4:3")
def test_closed_loop_keeps_its_position_through_an_overload() -> None:
    """§5.3.1: in closed loop an overload does not stall the motor; §8.2.128: without
    CL_CATCH_UP's overspeed the rotor keeps its lag at V_SOLL, with it the rotor catches up;
    a position move ends on its target either way. Open loop loses the steps for good."""
    catch = (1000 << 8) | 50  # 50 % overspeed beyond 1000 counts of follow error
    m = MotorArray("MIS232", n=3, seed=0)
    m.write_many({"SETUP_BITS": np.array([c.SETUP_CLOSED_LOOP, c.SETUP_CLOSED_LOOP, 0]),
                  "CL_CATCH_UP": np.array([catch, 5000 << 8, catch]), "V_SOLL": 20000,
                  "A_SOLL": 2000, "MODE_REG": 1})
    m.run(1.0)
    m.set_input(load_torque=1.3 * m.pull_out_torque(200.0)[0])
    m.run(0.04)
    m.set_input(load_torque=0.0)
    m.run(0.5)
    lagging = m.read("FLWERR")[1]
    m.run(1.0)
    flw = m.read("FLWERR")
    assert abs(flw[0]) < c.COUNTS_PER_FULL_STEP  # caught up to within the 1000 counts
    assert flw[1] > 5000 and flw[1] == pytest.approx(lagging, abs=c.COUNTS_PER_FULL_STEP)
    assert m.lost_steps[2] > 0 and flw[2] == pytest.approx(
        m.lost_steps[2] * c.COUNTS_PER_FULL_STEP, abs=c.COUNTS_PER_FULL_STEP)
    target = int(m.read("P_IST")[1]) + 409600
    m.write_many({"P_SOLL": target, "MODE_REG": 2}, index=1)
    m.run(3.0)
    assert abs(m.read("ENCODER_POS")[1] - target) < c.COUNTS_PER_FULL_STEP


@pytest.mark.statements(
    "mis:8.2.15:3", "mis:8.2.24:2", "mis:8.2.24:3", "mis:8.2.29:2", "mis:8.2.30:2",
    "mis:8.2.120:2", "mis:5.2.1:1", "mis:5.2.2:1", "mis:5.2.2:2", "mis:5.2.2:3", "mis:5.2.3:1")
def test_auto_correction_retries_a_blocked_move() -> None:
    """§5.2.2: after a move whose encoder position is outside IN_POSITION_WINDOW, P_IST is
    reloaded from the encoder and the move repeated, up to IN_POSITION_COUNT times."""
    m = MotorArray("MIS232", n=2, seed=0)
    m.write_many({"IN_POSITION_COUNT": np.array([2, 0]), "IN_POSITION_WINDOW": 1000,
                  "SETTLINGTIME": 20, "V_SOLL": 20000, "A_SOLL": 3000, "V_SOLL_AUTO": 5000,
                  "V_START": 10000, "MODE_REG": 2})
    m.set_input(load_torque=1.3 * m.pull_out_torque(200.0)[0])
    m.write("P_SOLL", 409600)
    m.run(0.06)
    m.set_input(load_torque=0.0)
    v = m.trace(["V_IST"], 4000)["V_IST"][:, 0]
    first_stop = int(np.flatnonzero(v == 0)[0])
    retry = np.abs(v[first_stop:])
    assert retry.max() == 5000  # the retry runs at V_SOLL_AUTO (§8.2.120)
    status = m.read("STATUSBITS")
    assert abs(m.read("ENCODER_POS")[0] - 409600) <= 1000
    assert status[0] & c.ST_IN_PHYSICAL_POSITION and not status[0] & c.ST_AUTOCORRECTION
    assert abs(m.read("ENCODER_POS")[1] - 409600) > 1000  # no retries
    assert not status[1] & c.ST_IN_PHYSICAL_POSITION
