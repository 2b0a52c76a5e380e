"""User command 342 (MIS manual §8.2.22: "Clear all flash sectors in the RXP area") over every
protocol that writes COMMAND (register 24): MacTalk, Modbus RTU and a CANopen SDO erase the
stored program; a write refused as a whole keeps it."""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from canopen_rig import Rig
from jvl_gym import MotorArray
from jvl_gym.protocol.mactalk import codec32 as m32
from jvl_gym.protocol.mactalk.twin16 import Twin
from jvl_gym.protocol.modbus import codec as mb
from jvl_gym.protocol.modbus.twin import modbus_bus

ADDRESS = 7
COMMAND = 24  #: the COMMAND register (§8.2.20)
PROGRAM = "set_register register=P2 value=1\njump line=1\n"


def _twin() -> Twin:
    m = MotorArray("MIS232", n=1, seed=0)
    m.store_program(PROGRAM)
    m.program_start()
    return Twin(m, [ADDRESS])


def _modbus_write(twin: Twin, first: int, values: list[int]) -> mb.Response:
    words = [w for v in values for w in mb.words_of(v)]
    reply, _ = modbus_bus(twin).handle(mb.encode_write_request(ADDRESS, 2 * first, words), 0.0)
    return mb.decode_response(reply)


@pytest.mark.statements("mis:8.2.22:11")
def test_mactalk_write_of_command_342_erases_the_program() -> None:
    twin = _twin()
    reply = twin.session().feed(m32.encode_write_value(ADDRESS, COMMAND, 342))
    assert reply == m32.ACCEPT
    assert twin.m.program_text() is None and twin.m.program_status().name == "passive"


@pytest.mark.statements("mis:8.2.22:11")
def test_modbus_write_of_command_342_erases_the_program() -> None:
    twin = _twin()
    assert isinstance(_modbus_write(twin, COMMAND, [342]), mb.WriteResponse)
    assert twin.m.program_text() is None


def test_modbus_write_refused_as_a_whole_keeps_the_program() -> None:
    """COMMAND 342, then STATUSBITS (read-only, §8.2.24): the request is refused and the
    program stays stored and running where it was."""
    twin = _twin()
    twin.m.step(1)
    status = twin.m.program_status()
    assert isinstance(_modbus_write(twin, COMMAND, [342, 0]), mb.ExceptionResponse)
    assert twin.m.program_text() == PROGRAM and twin.m.program_status() == status


@pytest.fixture
def rig() -> Iterator[Rig]:
    m = MotorArray("MIS232", n=1, seed=0)
    m.store_program(PROGRAM)
    r = Rig(motors=m)
    yield r
    r.close()


@pytest.mark.statements("mis:8.2.22:11")
def test_canopen_sdo_write_of_command_342_erases_the_program(rig: Rig) -> None:
    """Register 24 is object 2012h sub-index 24 (§11.4.6)."""
    rig.node().sdo[0x2012][COMMAND].raw = 342
    assert rig.m.program_text() is None
