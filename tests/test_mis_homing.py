"""The DSP-402 homing methods of the MIS CANopen slave (MIS manual §11.5.6: "the standard Homing
Search modes from 1-34 are supported"), driven over the bus by a ``canopen`` master.

The world: a home switch on IO4 active while the rotor is between 5 and 8 rad, a negative limit
switch on IO1 at −4 rad and below, a positive one on IO2 at 14 rad and above, set every
millisecond from the rotor angle. The motor's internal encoder (H2) gives the index once per
revolution, at whole revolutions of the rotor (0, 2π, 4π rad). Each test asserts the first
direction of motion, the last switch edge crossed (where, which way, entering or leaving) and
where the zero is (the rotor angle where the position would read 607Ch), and that the homing is
attained (statusword bit 12).
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass

import canopen
import numpy as np
import pytest

from canopen_rig import Rig

REV = 409_600
NL, PL, HOME = 1 << 0, 1 << 1, 1 << 3
LOW, HIGH = 5.0, 8.0  # the home switch's edges [rad]
NEG_LIMIT, POS_LIMIT = -4.0, 14.0
TWO_PI = 2 * math.pi
TOL = 0.03  # rad: one millisecond at the crawl velocity (30 RPM) and the encoder's step


def _inputs(theta: float) -> int:
    bits = HOME if LOW <= theta <= HIGH else 0
    bits |= NL if theta <= NEG_LIMIT else 0
    bits |= PL if theta >= POS_LIMIT else 0
    return bits


@dataclass
class Run:
    """What a homing did: the first direction of motion (0: none beyond half a radian), the
    lowest rotor angle, the home switch's changes (angle, direction, now active), the zero's
    rotor angle, the statusword."""

    first: int
    lowest: float
    edges: list[tuple[float, int, bool]]
    zero: float
    statusword: int


@pytest.fixture
def rig() -> Iterator[Rig]:
    r = Rig()
    yield r
    r.close()


def _start_at(rig: Rig, theta: float) -> None:
    """The rotor moved to ``theta`` rad, then the motor passive (as the drive starts)."""
    m = rig.m
    m.write_many({"V_SOLL": 30000, "A_SOLL": 20000, "MODE_REG": 2})
    m.step()
    m.write("P_SOLL", round(theta * REV / TWO_PI))
    m.run(2.0)
    m.write("MODE_REG", 0)
    m.run(0.3)  # settled
    m.write_many({"NL_MASK": NL, "PL_MASK": PL, "HOME_MASK": HOME})
    m.set_input(digital_inputs=_inputs(float(m.position_rad[0])))
    m.step()


def _home(rig: Rig, method: int, start: float | None, seconds: float = 8.0) -> Run:
    """Home with ``method`` from ``start`` rad (None: where the motor stands)."""
    if start is not None:
        _start_at(rig, start)
    node = rig.node()
    rig.m.write("ZERO_SEARCH_BITS", 1 << 5)  # the user's (no time-out): kept, and restored
    node.sdo[0x6098].raw = method
    node.sdo[0x6099][1].raw = 30000  # 300 RPM towards the switch
    node.sdo[0x6099][2].raw = 3000  # 30 RPM for the zero
    node.sdo[0x609A].raw = 20000
    node.sdo[0x607C].raw = 0
    node.sdo[0x6060].raw = 6
    for cw in (0x06, 0x07, 0x0F, 0x1F):
        node.sdo[0x6040].raw = cw
    m = rig.m
    start_theta = theta = float(m.position_rad[0])
    first = 0
    lowest = math.inf
    edges: list[tuple[float, int, bool]] = []
    was = bool(_inputs(theta) & HOME)
    for _ in range(int(seconds * 1000)):
        m.set_input(digital_inputs=_inputs(theta))
        rig.server.advance(0.001)
        before, theta = theta, float(m.position_rad[0])
        lowest = min(lowest, theta)
        if not first and abs(theta - start_theta) > 0.5:
            first = int(np.sign(theta - start_theta))
        now = bool(_inputs(theta) & HOME)
        if now != was:
            edges.append((theta, int(np.sign(theta - before)), now))
            was = now
        if (first and int(m.read("MODE_REG")[0]) == 2
                and abs(float(m.speed_rad_s[0])) < 1e-3):
            break
    rig.advance(0.05)
    assert int(m.read("ZERO_SEARCH_BITS")[0]) == 1 << 5
    sw = node.sdo[0x6041].raw
    zero = float(m.position_rad[0]) - int(node.sdo[0x6064].raw) * TWO_PI / REV
    return Run(first, lowest, edges, zero, sw)


def _attained(run: Run) -> None:
    assert run.statusword & 0x3400 == 0x1400, hex(run.statusword)  # attained, target reached


@pytest.mark.statements("mis:11.5.6:2")
def test_every_standard_method_of_1_to_34_is_taken_reserved_ones_refused(rig: Rig) -> None:
    """6098h takes 1–14, 17–30, 33, 34 (and the table's −3, −4); 15, 16, 31, 32 (reserved by
    the standard), −2, −1, 35 (the table's "No") are refused with 0609 0030h."""
    node = rig.node()
    for method in [*range(1, 15), *range(17, 31), 33, 34, -3, -4]:
        node.sdo[0x6098].raw = method
        assert node.sdo[0x6098].raw == method
    for method in (15, 16, 31, 32, -2, -1, 35, 36):
        with pytest.raises(canopen.SdoAbortedError) as info:
            node.sdo[0x6098].raw = method
        assert info.value.code == 0x06090030
    assert node.sdo[0x6098].raw == -4  # the last taken


# method: (first direction from below the switch, the edge, the approach direction, entering)
SWITCH_METHODS = {
    23: (1, LOW, -1, False), 24: (1, LOW, 1, True), 25: (1, HIGH, -1, True),
    26: (1, HIGH, 1, False), 27: (-1, HIGH, 1, False), 28: (-1, HIGH, -1, True),
    29: (-1, LOW, 1, True), 30: (-1, LOW, -1, False),
}


def _switch_search(rig: Rig, method: int, expected: tuple | None = None):
    """Home with ``method`` from 1 rad (below the switch) and check the search's first
    direction and the last switch edge crossed (where, which way, entering or leaving) against
    ``expected`` (default ``SWITCH_METHODS[method]``); the run."""
    first, edge, approach, entering = expected or SWITCH_METHODS[method]
    run = _home(rig, method, 1.0)
    _attained(run)
    assert run.first == first
    theta, direction, active = run.edges[-1]
    assert theta == pytest.approx(edge, abs=TOL)
    assert (direction, active) == (approach, entering)
    return run


@pytest.mark.statements("mis:11.5.6:2")
@pytest.mark.parametrize("method", sorted(SWITCH_METHODS))
def test_home_switch_methods_without_index(rig: Rig, method: int) -> None:
    """23–30 (7–14 without index): from below the switch the search starts in the method's
    direction (turning at the negative limit switch for 27–30); the zero is the method's edge,
    crossed last in the method's direction, entering or leaving the switch."""
    run = _switch_search(rig, method)
    first, edge, _, _ = SWITCH_METHODS[method]
    assert run.zero == pytest.approx(edge, abs=TOL)
    if first == -1:  # it went to the negative limit and turned there
        assert run.lowest <= NEG_LIMIT
    assert int(rig.m.read("ERR_BITS")[0]) == 0


# method: (the index the zero is on, the approach direction)
INDEX_METHODS = {7: (0.0, -1), 8: (TWO_PI, 1), 9: (TWO_PI, -1), 10: (2 * TWO_PI, 1),
                 11: (2 * TWO_PI, 1), 12: (TWO_PI, -1), 13: (TWO_PI, 1), 14: (0.0, -1)}


@pytest.mark.statements("mis:11.5.6:2")
@pytest.mark.parametrize("method", sorted(INDEX_METHODS))
def test_home_switch_methods_with_index(rig: Rig, method: int) -> None:
    """7–14: as 23–30, then on in the approach direction to the encoder's next index, which
    is the zero; the last switch edge crossed is the method's."""
    run = _switch_search(rig, method, SWITCH_METHODS[method + 16])
    index, _ = INDEX_METHODS[method]
    assert run.zero == pytest.approx(index, abs=TOL)


@pytest.mark.statements("mis:11.5.6:2")
@pytest.mark.parametrize(("method", "start", "first"), [(7, 11.0, 1), (10, 6.5, 1),
                                                         (12, -2.0, -1), (29, 6.5, -1)])
def test_home_switch_methods_from_other_starts(rig: Rig, method: int, start: float,
                                              first: int) -> None:
    """From above the switch the initial motion reaches the limit switch and turns; from on
    the switch there is no first search: the zero is the same edge or index either way."""
    run = _home(rig, method, start)
    _attained(run)
    assert run.first == first
    _, edge, approach, entering = SWITCH_METHODS[method if method > 14 else method + 16]
    theta, direction, active = run.edges[-1]
    assert theta == pytest.approx(edge, abs=TOL)
    assert (direction, active) == (approach, entering)
    if method <= 14:
        assert run.zero == pytest.approx(INDEX_METHODS[method][0], abs=TOL)
    else:
        assert run.zero == pytest.approx(edge, abs=TOL)
    assert int(rig.m.read("ERR_BITS")[0]) == 0


@pytest.mark.statements("mis:11.5.6:2")
@pytest.mark.parametrize(("method", "start", "index", "direction"),
                         [(33, 1.0, 0.0, -1), (34, 9.0, 2 * TWO_PI, 1)])
def test_index_pulse_methods(rig: Rig, method: int, start: float, index: float,
                             direction: int) -> None:
    """33, 34: no switch; the next index in the negative / positive direction is the zero."""
    run = _home(rig, method, start)
    _attained(run)
    assert run.first == direction
    assert run.zero == pytest.approx(index, abs=TOL)
    assert run.edges == []


@pytest.mark.statements("mis:11.5.6:4")
@pytest.mark.parametrize(("method", "start", "first", "edge", "approach", "index"), [
    (3, 11.0, -1, HIGH, -1, TWO_PI), (19, 11.0, -1, HIGH, -1, None),
    (4, 1.0, 1, LOW, 1, TWO_PI), (20, 1.0, 1, LOW, 1, None),
    (5, 11.0, -1, HIGH, 1, 2 * TWO_PI), (21, 11.0, -1, HIGH, 1, None),
    (6, 1.0, 1, LOW, -1, 0.0), (22, 1.0, 1, LOW, -1, None)])
def test_table_methods_with_and_without_index(rig: Rig, method: int, start: float, first: int,
                                              edge: float, approach: int,
                                              index: float | None) -> None:
    """§11.5.6's table: 3, 4 "rising edge homing switch", negative / positive direction, the
    zero where the switch becomes active; 5, 6 "falling edge", the zero where it is released
    after reversing onto it; 3-6 then on to the next index; 19-22 "same as 3-6 without
    index"."""
    run = _home(rig, method, start)
    _attained(run)
    assert run.first == first
    theta, direction, active = run.edges[-1]
    assert theta == pytest.approx(edge, abs=TOL)
    assert (direction, active) == (approach, method in (3, 4, 19, 20))
    assert run.zero == pytest.approx(edge if index is None else index, abs=TOL)


@pytest.mark.statements("mis:11.5.6:4", "mis:11.5.6:5")
@pytest.mark.parametrize(("method", "limit", "index"), [
    (1, NEG_LIMIT, 0.0), (17, NEG_LIMIT, None), (2, POS_LIMIT, 4 * math.pi), (18, POS_LIMIT, None)])
def test_limit_switch_methods(rig: Rig, method: int, limit: float, index: float | None) -> None:
    """1, 2 (and 17, 18 without index) with the limit switch as the home input (§11.5.6,
    "Homing on limit switch"): onto the limit switch, off it at the crawl velocity, the zero
    where it is released (or the next index after it); the limit raises no error."""
    _start_at(rig, 1.0)
    rig.m.write("HOME_MASK", NL if limit < 0 else PL)
    run = _home(rig, method, None)
    _attained(run)
    assert run.first == (-1 if limit < 0 else 1)
    assert int(rig.m.read("ERR_BITS")[0]) == 0
    zero = limit if index is None else index
    assert run.zero == pytest.approx(zero, abs=TOL)
