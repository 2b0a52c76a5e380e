"""Second independent audit of the MIS/SMC family: 15 statements drawn afresh from the MIS
manual by someone who did not write the family's tests.

The sample: the candidate lines are those of the MIS manual's chapters 5 (functions), 6
(modes), 8.2 (registers), 9 (programming), 11 (CANopen and J1939) and 13 (DMX512), 6772 lines
in all; ``random.Random(2612064).sample(lines, 15)`` drew lines of §5, §8.2 and §11, and each
test below checks the sentence nearest to its drawn line that states a checkable behaviour (a
tie goes to the following line). Every check uses the public interface only: ``MotorArray``
registers by name and world inputs, and for the CANopen statements a CANopen master
(``canopen``) on a python-can bus served by ``CanopenServer``.
"""
from __future__ import annotations

import contextlib
import uuid
from collections.abc import Iterator
from typing import Any

import can
import canopen
import numpy as np
import pytest

from jvl_gym import MotorArray
from jvl_gym.protocol.canopen.eds import shipped_path
from jvl_gym.protocol.canopen.server import CanopenServer
from jvl_gym.protocol.mactalk.twin16 import Twin

NODE = 5  # the factory node id (register 166)
REV = 409_600  # counts per revolution


def _u32(node: Any, index: int, sub: int) -> int:
    return int.from_bytes(node.sdo.upload(index, sub), "little")


def _write(node: Any, index: int, sub: int, value: int, size: int) -> None:
    node.sdo.download(index, sub, int(value).to_bytes(size, "little", signed=value < 0))


@contextlib.contextmanager
def _canopen(setup: dict[str, int] | None = None) -> Iterator[tuple[Any, Any, Any, Any]]:
    """An MIS232 served as a CANopen slave on an in-process bus, and a master's node of it."""
    m = MotorArray("MIS232")
    for name, value in (setup or {}).items():
        m.write(name, value)
    channel = f"audit2-{uuid.uuid4().hex}"
    server = CanopenServer([Twin(m)], can.Bus(interface="virtual", channel=channel),
                           run_clock=False).start()
    net = canopen.Network()
    net.connect(interface="virtual", channel=channel)
    node = net.add_node(NODE, str(shipped_path()))
    try:
        yield m, server, net, node
    finally:
        net.disconnect()
        server.stop()


# -- §5 ---------------------------------------------------------------------------------------

@pytest.mark.statements("mis:5.5.4:1")
def test_setup_bits_2_3_select_pulse_direction_output() -> None:
    """MIS manual §5.5.4 (line 2765, drawn; its table at 2769-2772): with the multifunction
    port routed to the internal pulse generator, SETUP_BITS bit 2 = 1 and bit 3 = 0 give
    pulse/direction signals, the generator's 409600 counts per revolution divided by 16."""
    m = MotorArray("MIS232")
    m.write_many({"XFIELD_DATA": 4626, "XFIELD_ADDR": 4160, "SETUP_BITS": 1 << 2,
                  "V_SOLL": 6000, "MODE_REG": 2, "P_SOLL": REV})
    m.run(2.0)  # the move (1 s at 60 RPM and its ramps) is done
    assert int(m.read_raw("P_IST")[0]) == REV
    # a user would count the pulses on the port: one per 16 counts
    assert m.multifunction_routing == ["generator pulse/direction"]
    assert int(m.multifunction_output_total[0]) == REV // 16


def _autocorrection_motors(window: list[int], v_auto: int = 0) -> Any:
    """Two MIS232 with an end stop at 0.5 rad before a target of half a revolution."""
    m = MotorArray("MIS232", n=len(window), end_stop_high=0.5)
    for k, w in enumerate(window):
        m.write("IN_POSITION_WINDOW", w, index=k)
    m.write_many({"IN_POSITION_COUNT": 2, "SETTLINGTIME": 50, "V_SOLL": 6000,
                  "V_SOLL_AUTO": v_auto, "MODE_REG": 2})
    m.step(2)
    m.write("P_SOLL", REV // 2)
    return m


@pytest.mark.statements("mis:8.2.29:2")
def test_autocorrection_when_encoder_differs_more_than_window() -> None:
    """MIS manual §5.8.3 (line 3021): an auto-correction after the end of a movement is
    performed when the actual position and the encoder position differ by more than the
    "Autocorrection In position window" (IN_POSITION_WINDOW)."""
    m = _autocorrection_motors([20_000, 2_000_000_000])
    tr = m.trace(["P_IST", "ENCODER_POS"], 4000)
    p_ist = tr["P_IST"]
    target = REV // 2
    arrived = [int(np.argmax(p_ist[:, k] == target)) for k in range(2)]
    assert all(p_ist[a, k] == target for k, a in enumerate(arrived))
    # the rotor stands at the end stop, far more than 20000 counts short of the target
    assert target - tr["ENCODER_POS"][arrived[0], 0] > 20_000
    # window 20000: the motor corrects (P_IST taken from the encoder, then the move again)
    assert p_ist[arrived[0]:, 0].min() < target - 20_000
    # a window wider than the difference: no correction, P_IST stays at the target
    assert (p_ist[arrived[1]:, 1] == target).all()


@pytest.mark.statements("mis:8.2.120:2", "mis:5.2.3:1")
def test_autocorrection_velocity_used_during_a_retry() -> None:
    """MIS manual §5.8.3 (line 3023): the "Autocorrection velocity" (V_SOLL_AUTO) is the
    velocity used during a retry."""
    m = _autocorrection_motors([20_000], v_auto=2_000)
    tr = m.trace(["P_IST", "V_IST"], 4000)
    p_ist, v_ist = tr["P_IST"][:, 0], tr["V_IST"][:, 0]
    assert abs(v_ist).max() == pytest.approx(6000, abs=1)  # the first move at V_SOLL
    first = int(np.argmax(p_ist == REV // 2))
    retry = first + int(np.argmax(p_ist[first:] < REV // 2 - 20_000))
    assert retry > first
    # during the retries the motor runs at 20 RPM, not at V_SOLL's 60 RPM
    assert abs(v_ist[retry:]).max() == pytest.approx(2000, abs=1)


# -- §8.2 -------------------------------------------------------------------------------------

@pytest.mark.statements("mis:8.2.53:1", "mis:8.2.53:2")
def test_afzup_confmax_is_the_maximum_confidence_limit() -> None:
    """MIS manual §8.2.1 (line 4338): register 103 AFZUP_ConfMax, R/W, 1-4095, default 4095
    (1.221 mV): the maximum confidence limit for the analogue inputs; samples above it are not
    taken by the filter."""
    m = MotorArray("MIS232", n=2)
    assert list(m.read("AFZUP_CONFMAX")) == [4095, 4095]
    m.write_many({"AFZUP_CONFMIN": 0, "AFZUP_CONFMAX": 2000, "AFZUP_MAXSLOPE": 4095,
                  "AFZUP_FILTER": 64}, index=0)
    m.write("AFZUP_WRITEBITS", 1, index=0)  # input 1 of motor 0 takes them
    m.run(0.05)
    assert int(m.read("AFZUP_WRITEBITS")[0]) & (1 << 15)
    m.set_input(analog1=4.0)  # 3276 counts, above motor 0's limit
    m.run(0.5)
    filtered = m.read("ANALOGUE_FILTERED1")
    assert int(m.read("ANALOGUE_INPUT1")[0]) == pytest.approx(3276, abs=2)
    assert filtered[1] == pytest.approx(3276, abs=3)  # default limit: the value is taken
    assert filtered[0] <= 2000  # the samples above ConfMax are discarded


@pytest.mark.statements("mis:8.2.21:12", "mis:8.2.21:14")
def test_command_118_sets_flag_relative_move() -> None:
    """MIS manual §8.2.21 (line 4825): command 118 (FastMac 22) sets the flag RelativeMove
    (116, FastMac 20, clears it)."""
    m = MotorArray("MIS232")
    m.write("COMMAND", 116)
    m.step()
    assert not bool(m.relative_move[0])
    m.write("COMMAND", 118)
    m.step()
    assert bool(m.relative_move[0])
    assert int(m.read("COMMAND")[0]) == 0


@pytest.mark.statements("mis:8.2.49:2")
def test_encoder_type_2_is_the_absolute_multiturn_h3() -> None:
    """MIS manual §8.2.49 (line 5176): ENCODER_TYPE = 2 is the absolute multi-turn encoder
    (H3): a motor with the H3 reads 2 and its encoder counts over several revolutions."""
    m = MotorArray("MIS232", encoder_type=2)
    assert int(m.read("ENCODER_TYPE")[0]) == 2
    m.write_many({"V_SOLL": 10000, "MODE_REG": 2})
    m.step()
    m.write("P_SOLL", 5 * REV // 2)
    m.run(3.0)
    assert int(m.read("ENCODER_POS")[0]) == pytest.approx(5 * REV // 2, abs=REV // 200)


@pytest.mark.statements("mis:8.2.59:1")
def test_ssi_setup2_prepare_time_in_microseconds() -> None:
    """MIS manual §8.2.59 (line 5272): SSI_SETUP2 bits 0-7 are the prepare time, "in
    milliseconds" by that line; the same register row's default ("prepare time=100µs"),
    §5.7.2's field (1-255 µs), §5.7.3's worked example and §5.7.4's t1 all give microseconds,
    which the simulator takes (docs/families/mis-sim.md "Prepare time unit"): with 100 a
    reading is there within 5 ms, where milliseconds would need at least 100 ms."""
    m = MotorArray("MIS232")
    m.set_input(ssi_word=12345)
    m.write("SSI_SETUP2", 100)
    m.write("COMMAND", 320)
    m.step()
    m.write("COMMAND", 321)
    m.run(0.005)
    assert int(m.read("EXTENCODER2")[0]) == 12345


@pytest.mark.statements("mis:8.2.81:1", "mis:8.2.81:2")
def test_save_voltage_default_15_volt_in_8_764_mv() -> None:
    """MIS manual §8.2.81 (line 5524, nearest to the drawn 5521): register 141 Save voltage,
    R/W, default 1710 (15 V), unit 8.764 mV: the CVI level where the program shuts down."""
    m = MotorArray("MIS232", n=2)
    assert list(m.read("SAVE_VOLTAGE")) == [1710, 1710]
    assert 1710 * 8.764e-3 == pytest.approx(15.0, abs=0.02)
    m.write_many({"V_SOLL": 5000, "MODE_REG": 1})
    m.set_input(index=0, control_volts=15.3)
    m.set_input(index=1, control_volts=14.7)
    m.run(0.05)
    err = m.read("ERR_BITS")
    assert not int(err[0]) & (1 << 17)  # above 15 V: runs on
    assert int(m.read("V_IST")[0]) == 5000
    assert int(err[1]) & (1 << 17)  # below: the program shut down
    assert int(m.read("V_IST")[1]) == 0


@pytest.mark.statements("mis:8.2.89:2")
def test_motortype_104_is_the_mis515() -> None:
    """MIS manual §8.2.89 (line 5619): the MIS515 stepper motor reads motor type 104 (its motor
    data are chosen, docs/families/mis-sim.md "Motor data"); it runs as a stepper motor."""
    m = MotorArray("MIS515")
    assert int(m.read("MOTORTYPE")[0]) == 104
    m.write_many({"V_SOLL": 30000, "MODE_REG": 2})
    m.step()
    m.write("P_SOLL", REV)
    m.run(1.0)
    assert int(m.read("P_IST")[0]) == REV
    assert int(m.lost_steps[0]) == 0
    assert m.rotor_counts[0] == pytest.approx(REV, abs=REV // 200)


@pytest.mark.statements("mis:8.2.93:1", "mis:8.2.93:2", "mis:8.2.93:3")
def test_max_voltage_bits_0_15_are_the_bus_maximum() -> None:
    """MIS manual §8.2.93 (line 5680, nearest to the drawn 5679): MAX_VOLTAGE bits 0-15 are the
    maximum voltage on the bus (above it the motor enters an error state); read-only."""
    m = MotorArray("MIS232", n=2)
    vmax = int(m.read("MAX_VOLTAGE")[0]) & 0xFFFF
    assert 0 < vmax <= 100
    with pytest.raises(Exception, match="MAX_VOLTAGE"):
        m.write("MAX_VOLTAGE", 1)
    m.set_input(index=0, supply_volts=vmax - 2)
    m.set_input(index=1, supply_volts=vmax + 2)
    m.write_many({"V_SOLL": 5000, "MODE_REG": 1})
    m.run(0.1)
    err = m.read("ERR_BITS")
    assert not int(err[0]) & (1 << 5)
    assert int(err[1]) & (1 << 5)


# -- §11 --------------------------------------------------------------------------------------

def test_operational_state_enables_pdos() -> None:
    """MIS manual §11.3.3 (line 6896, nearest checkable to the drawn 6906): the bus state is
    changed with NMT, "e.g. to Operational to enable PDOs": a transmit PDO is sent in
    operational and not in pre-operational."""
    with _canopen() as (_m, server, net, node):
        frames: list[bytes] = []
        net.subscribe(0x180 + NODE, lambda _id, data, _ts: frames.append(bytes(data)))
        cob = _u32(node, 0x1800, 1)
        assert cob & 0x8000_0000  # disabled at boot
        _write(node, 0x1800, 1, cob & 0x7FF, 4)
        for _ in range(3):
            net.sync.transmit()
            server.advance(0.01)
        _u32(node, 0x1000, 0)  # its answer comes after any frame the slave sent before
        assert frames == []  # pre-operational: no PDO
        node.nmt.state = "OPERATIONAL"
        server.advance(0.01)
        for _ in range(3):
            net.sync.transmit()
            server.advance(0.01)
        _u32(node, 0x1000, 0)
        assert len(frames) == 3  # one per SYNC (transmission type 1)


def test_beckhoff_receive_pdo4_default_is_the_outputs() -> None:
    """MIS manual §11.4.13 (line 7386, nearest to the drawn 7385): the tables shown are the
    default mapping: in Beckhoff mode receive PDO 4 updates the outputs, object 2014h sub 13h
    (register 19, 16 bits)."""
    with _canopen({"SETUP_BITS": 1 << 14, "IOSETUP": 0x0300}) as (m, server, net, node):
        assert _u32(node, 0x1603, 0) == 1
        assert _u32(node, 0x1603, 1) == 0x2014_1310
        node.nmt.state = "OPERATIONAL"
        server.advance(0.01)
        cob = _u32(node, 0x1403, 1) & 0x7FF
        net.send_message(cob, (3).to_bytes(2, "little"))
        server.advance(0.01)
        assert int(m.read("OUTPUTS")[0]) & 0x3 == 0x3


@pytest.mark.statements("mis:11.5.6:2")
def test_homing_methods_1_to_34_are_supported() -> None:
    """MIS manual §11.5.6 (line 7749, nearest checkable to the drawn 7751): the standard
    homing search modes 1-34 are supported: 6098h takes each of them (the standard defines
    1-14, 17-30, 33, 34; 15, 16, 31, 32 are reserved there, and refused)."""
    with _canopen() as (_m, _server, _net, node):
        for method in [*range(1, 15), *range(17, 31), 33, 34]:
            _write(node, 0x6098, 0, method, 1)
            assert int.from_bytes(node.sdo.upload(0x6098, 0), "little", signed=True) == method
        for method in (15, 16, 31, 32):
            with pytest.raises(canopen.SdoAbortedError):
                _write(node, 0x6098, 0, method, 1)


def test_controlword_drives_cyclic_synchronous_velocity_mode() -> None:
    """MIS manual §11.5.10 (line 8010): in cyclic synchronous velocity mode (6060h = 9) the
    control word 6040h sub 0 is one of the objects affected: the motor runs at the target
    velocity 60FFh (rpm/100) once the control word enables the operation, and not before."""
    with _canopen() as (m, server, _net, node):
        _write(node, 0x6060, 0, 9, 1)
        _write(node, 0x60FF, 0, 10000, 4)
        server.advance(0.2)
        assert int(m.read("V_IST")[0]) == 0
        for cw in (0x06, 0x07, 0x0F):
            _write(node, 0x6040, 0, cw, 2)
            server.advance(0.01)
        server.advance(0.5)
        assert int(m.read("V_IST")[0]) == pytest.approx(10000, abs=50)
        assert _u32(node, 0x6061, 0) == 9


def test_nc_axis_pdos_carry_controlword_position_and_status() -> None:
    """MIS manual §11.6.6 (line 8253, nearest checkable to the drawn 8229): an NC axis sends
    the control word and the requested position to the motor in receive PDOs and receives the
    status word and the actual position in transmit PDO 1 (the default mappings)."""
    with _canopen() as (_m, _server, _net, node):
        rx1 = [_u32(node, 0x1600, s) for s in range(1, _u32(node, 0x1600, 0) + 1)]
        rx3 = [_u32(node, 0x1602, s) for s in range(1, _u32(node, 0x1602, 0) + 1)]
        tx1 = [_u32(node, 0x1A00, s) for s in range(1, _u32(node, 0x1A00, 0) + 1)]
        assert 0x6040_0010 in rx1  # controlword
        assert 0x607A_0020 in rx3  # target (requested) position
        assert {0x6041_0010, 0x6064_0020} <= set(tx1)  # statusword, position actual
