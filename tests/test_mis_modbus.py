"""A simulated MIS motor behind the Modbus RTU slave (MIS manual §12): registers written and
read over the line as 32-bit values, refusals as exception replies that change nothing."""

from __future__ import annotations

from jvl_gym import MotorArray
from jvl_gym.protocol.mactalk.twin16 import Twin
from jvl_gym.protocol.modbus import codec as mb
from jvl_gym.protocol.modbus.server import ModbusBus
from jvl_gym.protocol.modbus.twin import modbus_bus


def _exchange(bus: ModbusBus, frame: bytes) -> mb.Response:
    reply, _ = bus.handle(frame, now=0.0)
    return mb.decode_response(reply)


def test_modbus_writes_and_reads_a_simulated_motor() -> None:
    m = MotorArray("MIS232", n=2, seed=0)
    m.write("MY_ADDR", 7, index=1)
    bus = modbus_bus(Twin(m))
    v_soll = mb.words_of(25000)
    _exchange(bus, mb.encode_write_request(7, 2 * 5, list(v_soll)))  # V_SOLL, register 5
    _exchange(bus, mb.encode_write_request(7, 2 * 13, list(mb.words_of(30000))))  # V_START
    _exchange(bus, mb.encode_write_request(7, 2 * 2, list(mb.words_of(1))))  # MODE_REG
    assert m.read("V_SOLL").tolist() == [10000, 25000]
    m.step(10)
    reply = _exchange(bus, mb.encode_read_request(7, 2 * 12, 2))  # V_IST
    assert mb.value_of(*reply.words) == 25000
    m.write("P_SOLL", -5, index=1)
    reply = _exchange(bus, mb.encode_read_request(7, 2 * 3, 2))
    assert mb.value_of(*reply.words) == -5
    refused = _exchange(bus, mb.encode_write_request(7, 2 * 5, list(mb.words_of(400000))))
    assert isinstance(refused, mb.ExceptionResponse)
    assert m.read("V_SOLL")[1] == 25000
