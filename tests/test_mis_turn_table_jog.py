"""The turn table outside position mode (MIS manual §5.12.6): a jog in velocity mode may leave
P_IST outside MIN_P_IST … MAX_P_IST; position mode keeps it inside (§5.12.5)."""

from __future__ import annotations

import pytest

from jvl_gym import MotorArray
from jvl_gym.families.mis import constants as c

SIZE = 409600  #: the range 0 … 409599: one revolution


def _table(**regs: int) -> MotorArray:
    m = MotorArray("MIS232", n=1, seed=0)
    m.write_many({"TURNTABLE_MODE": c.TT_SHORTEST, "MIN_P_IST": 0, "MAX_P_IST": SIZE - 1,
                  "A_SOLL": 10000, "IN_POSITION_COUNT": 0, **regs})
    return m


@pytest.mark.statements("mis:5.12.6:1", "mis:5.12.6:2")
def test_a_jog_in_velocity_mode_leaves_p_ist_outside_the_range() -> None:
    """§5.12.6: "After a JOG function the P_IST may be left outside the Turn Table position
    range" — in velocity mode P_IST runs on past MAX_P_IST, unwrapped, and TURNTAB_COUNT does
    not count; back in position mode P_IST is inside the range again (§5.12.5), the whole
    turns counted in TURNTAB_COUNT, and a move lands on P_SOLL inside it."""
    m = _table(V_SOLL=60000)  # 600 RPM: 10 revolutions per second
    m.write("MODE_REG", c.VELOCITY)
    m.step(500)
    p = m.read("P_IST")[0]
    assert p > 2 * SIZE
    assert m.read("TURNTAB_COUNT")[0] == 0
    assert m.rotor_counts[0] == pytest.approx(p, abs=3000)
    m.write("V_SOLL", 0)  # the manual's advice: V_SOLL = 0 when leaving the jog
    m.step(300)
    p = m.read("P_IST")[0]
    m.write_many({"P_SOLL": 100000, "MODE_REG": c.POSITION})
    m.step(1)
    assert 0 <= m.read("P_IST")[0] < SIZE
    assert m.read("TURNTAB_COUNT")[0] == p // SIZE
    m.write("V_SOLL", 60000)
    m.step(1000)
    assert m.read("P_IST")[0] == 100000


@pytest.mark.statements("mis:5.12.5:1")
def test_position_mode_keeps_p_ist_inside_the_range() -> None:
    """§5.12.5: "P_IST ... stays within the min. and max. limits defined" (position mode)."""
    m = _table(V_SOLL=60000, TURNTABLE_MODE=c.TT_MULTI_CW)
    m.write("MODE_REG", c.POSITION)
    m.write("P_SOLL", 3 * SIZE + 5000)
    tr = m.trace(["P_IST"], 1500)["P_IST"][:, 0]
    assert tr.min() >= 0 and tr.max() < SIZE
    assert m.read("P_IST")[0] == 5000 and m.read("TURNTAB_COUNT")[0] == 3
