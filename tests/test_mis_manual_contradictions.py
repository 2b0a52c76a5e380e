"""Where the MIS manual contradicts itself, the reading the simulator takes (docs/families/
mis-sim.md, one heading per decision): each test asserts the chosen reading and carries the
statement id of the reading that was not taken (``families/mis/statements.yaml``)."""

from __future__ import annotations

import pytest

from jvl_gym import MotorArray
from jvl_gym.families.mis import constants as c
from jvl_gym.registers import RegisterError

SIZE = 409600  #: a turn table of one revolution: 0 … 409599


@pytest.mark.statements("mis:5.3.4:1")
def test_closed_loop_and_current_control_are_off_by_default() -> None:
    """§5.3.4 "by default enabled" against its "Default: inactive": a new motor with an encoder
    runs open loop at full current (SETUP_BITS 0, bits 24 and 25 clear)."""
    m = MotorArray("MIS232", n=1, seed=0)
    assert m.read("SETUP_BITS")[0] == 0
    m.write("MODE_REG", c.POSITION)
    m.step(20)
    assert not m.read("STATUSBITS")[0] & c.ST_CLOSED_LOOP
    assert m.read("ACTUAL_TORQUE")[0] == 2047  # no current control: 100 % (§8.2.112)
    m.write("SETUP_BITS", c.SETUP_CLOSED_LOOP)
    m.step(1)
    assert m.read("STATUSBITS")[0] & c.ST_CLOSED_LOOP


@pytest.mark.statements("mis:5.10:4")
def test_under_voltage_is_a_warning_only_by_default() -> None:
    """§5.10 "Under voltage -> Set error bit. Default = ON" against SETUP_BITS' default 0: with
    the defaults an under voltage sets the warning, not the error, and the motor keeps its
    mode; SETUP_BITS bit 21 makes it the error."""
    m = MotorArray("MIS232", n=2, seed=0)
    m.write("SETUP_BITS", 1 << 21, index=1)
    m.write_many({"V_SOLL": 1000, "MODE_REG": c.VELOCITY})
    m.step(20)
    m.set_input(supply_volts=10.0)  # below MIN_BUSVOL (15 V)
    m.step(50)
    assert (m.read("WARN_BITS") & c.WARN_LOW_BUS).all()
    assert m.read("ERR_BITS")[0] == 0 and m.read("MODE_REG")[0] == c.VELOCITY
    assert m.read("ERR_BITS")[1] & c.ERR_LOW_BUS and m.read("MODE_REG")[1] == c.PASSIVE


@pytest.mark.statements("mis:6.6:3")
def test_error_deceleration_keeps_the_register_tables_default() -> None:
    """§6.6 "Default is 0, meaning that the feature is disabled" against the register tables'
    ACC_EMERG 1 … 500000, default 10000: 10000 at power-on, 0 refused with nothing changed."""
    m = MotorArray("MIS232", n=1, seed=0)
    assert m.read("ACC_EMERG")[0] == 10000
    with pytest.raises(RegisterError):
        m.write("ACC_EMERG", 0)
    assert m.read("ACC_EMERG")[0] == 10000


@pytest.mark.statements("mis:8.2.71:1")
def test_turntable_size_is_not_read() -> None:
    """§8.2.71 (TURNTABLE_SIZE) against §5.12.1 (MIN_P_IST … MAX_P_IST): the range is the
    chapter's; TURNTABLE_SIZE changes neither the range of P_SOLL nor where P_IST wraps."""
    out = []
    for size in (0, 1000):
        m = MotorArray("MIS232", n=1, seed=0)
        m.write_many({"TURNTABLE_MODE": c.TT_MULTI_CW, "MIN_P_IST": 0, "MAX_P_IST": SIZE - 1,
                      "TURNTABLE_SIZE": size, "A_SOLL": 10000, "V_SOLL": 60000,
                      "IN_POSITION_COUNT": 0, "MODE_REG": c.POSITION})
        m.write("P_SOLL", SIZE + 5000)
        m.step(800)
        out.append((int(m.read("P_SOLL")[0]), int(m.read("P_IST")[0]),
                    int(m.read("TURNTAB_COUNT")[0])))
    assert out[0] == out[1] == (5000, 5000, 1)


@pytest.mark.statements("mis:2.3.5:7")
@pytest.mark.parametrize(("outside", "bit"), [(50, 0), (51, 1)])
def test_filter_status_needs_more_than_half_the_samples(outside: int, bit: int) -> None:
    """§2.3.5 "at least half" against §8.2.56 "more than half" of the second's samples: 50 of
    the 100 samples outside the confidence limits leave FILTERSTATUS bit 0 clear, 51 set it."""
    m = MotorArray("MIS232", n=1, seed=0)
    m.write("AFZUP_CONFMAX", 2000)  # 2.44 V
    m.write("AFZUP_WRITEBITS", 255)  # to every input (§8.2.50)
    m.set_input(analog1=4.0)
    m.step(10 * outside)  # one analogue sample each 10 ms
    m.set_input(analog1=0.0)
    m.step(1000 - 10 * outside)
    assert m.read("FILTERSTATUS")[0] == bit
