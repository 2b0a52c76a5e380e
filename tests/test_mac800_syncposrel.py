"""CNTRL_BITS bit 8 SYNCPOSREL of the MAC800 (register overview, register 36: "Offset P_IST
with P_NEW"): with bit 6 (SYNCPOSMAN) it offsets the positions by P_NEW instead of setting
them to P_NEW."""

from __future__ import annotations

import warnings

import pytest

from jvl_gym import MotorArray
from jvl_gym.families.mac800 import constants as c


@pytest.mark.statements("mac800:1.2:36")
def test_syncposrel_offsets_p_ist_and_p_soll_by_p_new() -> None:
    m = MotorArray("MAC800", n=1, seed=0)
    m.write_many({"P_NEW": 5000, "CNTRL_BITS": c.SYNCPOSMAN})
    m.step()
    assert m.read("P_IST")[0] == 5000 and m.read("P_SOLL")[0] == 5000
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a modelled bit: no "has no effect" warning
        m.write_many({"P_NEW": 300, "CNTRL_BITS": c.SYNCPOSMAN | c.SYNCPOSREL})
    m.step()
    assert m.read("P_IST")[0] == 5300 and m.read("P_SOLL")[0] == 5300
    assert m.read("CNTRL_BITS")[0] & c.SYNCPOSMAN == 0  # done, as bit 6 alone
    m.write("MODE_REG", 2)
    m.run(0.2)
    assert abs(m.read("P_IST")[0] - 5300) < 3  # the motor holds the offset position
