"""FastMac and user commands of the MIS COMMAND register that the conformance file names
(MIS manual §8.2.21, §8.2.22), each issued and checked for the manual's effect: 98 (P_SOLL = 0),
103 (clear the in-position, accelerating and decelerating flags), 121 (P_IST and the encoder
+= P_NEW, P_SOLL kept) and 257 (re-sync P_IST to the encoder position)."""

from __future__ import annotations

import pytest

from jvl_gym import MotorArray
from jvl_gym.families.mis import constants as c


def _motor(**regs: int) -> MotorArray:
    m = MotorArray("MIS232", n=1, seed=0)
    m.write_many({"IN_POSITION_COUNT": 0, **regs})
    return m


@pytest.mark.statements("mis:8.2.21:2")
def test_command_98_sets_the_target_position_to_zero() -> None:
    """98 (FastMac 2): "Target position = 0 (P_SOLL = 0)"; in position mode the motor then
    moves there."""
    m = _motor(V_SOLL=50000, A_SOLL=10000, P_SOLL=200000)
    m.write("MODE_REG", c.POSITION)
    m.step(800)
    assert m.read("P_IST")[0] == 200000
    m.write("COMMAND", 98)
    assert m.read("P_SOLL")[0] == 0 and m.read("COMMAND")[0] == 0
    assert m.read("P_IST")[0] == 200000
    m.step(800)
    assert m.read("P_IST")[0] == 0


@pytest.mark.statements("mis:8.2.21:5")
def test_command_103_clears_in_position_accelerating_and_decelerating() -> None:
    """103 (FastMac 7): "Clear flags: In Position, Acceleration and Deceleration" (STATUSBITS
    bits 4, 5, 6); the other bits stay."""
    m = _motor(V_SOLL=50000, A_SOLL=10000)
    m.write("MODE_REG", c.POSITION)
    m.step(20)
    st = m.read("STATUSBITS")[0]
    assert st & c.ST_IN_POSITION
    m.write("COMMAND", 103)
    after = m.read("STATUSBITS")[0]
    assert not after & c.ST_IN_POSITION
    assert after == st & ~(c.ST_IN_POSITION | c.ST_ACCELERATING | c.ST_DECELERATING)
    m.write("P_SOLL", 400000)
    m.step(10)
    assert m.read("STATUSBITS")[0] & c.ST_ACCELERATING
    m.write("COMMAND", 103)
    assert not m.read("STATUSBITS")[0] & c.ST_ACCELERATING
    m.step(150)
    assert m.read("STATUSBITS")[0] & c.ST_DECELERATING
    m.write("COMMAND", 103)
    assert not m.read("STATUSBITS")[0] & c.ST_DECELERATING


@pytest.mark.statements("mis:8.2.21:17")
def test_command_121_adds_p_new_to_p_ist_and_the_encoder_only() -> None:
    """121 (FastMac 25): "P_IST += P_NEW, P_Encoder += P_NEW" — P_SOLL is not changed (unlike
    120)."""
    m = _motor(P_SOLL=1000, P_NEW=250)
    m.step(5)
    p, e = m.read("P_IST")[0], m.read("ENCODER_POS")[0]
    m.write("COMMAND", 121)
    assert m.read("P_IST")[0] == p + 250
    assert m.read("ENCODER_POS")[0] == e + 250
    assert m.read("P_SOLL")[0] == 1000
    m.step(5)
    assert m.read("ENCODER_POS")[0] == e + 250  # the encoder keeps its new value


@pytest.mark.statements("mis:8.2.22:1")
def test_command_257_resyncs_p_ist_to_the_encoder_position() -> None:
    """257: "Re-sync P_IST and P_ENCODER position" — P_IST := the encoder position, so the
    follow error is 0, after steps were lost under an overload."""
    m = _motor(V_SOLL=20000, A_SOLL=1000)
    m.write("MODE_REG", c.VELOCITY)
    m.step(200)
    m.set_input(load_torque=5.0)  # stalls the rotor: P_IST runs on, the encoder does not
    m.step(200)
    m.write("MODE_REG", c.PASSIVE)
    m.set_input(load_torque=0.0)
    m.step(300)
    assert abs(m.read("FLWERR")[0]) > 10000
    m.write("COMMAND", 257)
    assert m.read("P_IST")[0] == m.read("ENCODER_POS")[0]
    m.step(1)
    assert m.read("FLWERR")[0] == 0


@pytest.mark.statements("mis:8.2.22:2", "mis:8.2.22:4")
def test_command_269_saves_and_continues_and_267_resets_from_flash() -> None:
    """269: "Save to flash memory, then continue normal execution" — no reset (TICKS counts
    on); 267: "Reset the CPU" — the registers come back from flash (the saved V_SOLL, not the
    one written after the save) and TICKS starts at zero."""
    m = _motor(V_SOLL=1234)
    m.step(10)
    m.write("COMMAND", 269)
    assert m.read("TICKS")[0] == 10 and m.read("V_SOLL")[0] == 1234
    m.write("V_SOLL", 999)
    m.step(5)
    assert m.read("TICKS")[0] == 15
    m.write("COMMAND", 267)
    assert m.read("V_SOLL")[0] == 1234 and m.read("TICKS")[0] == 0
