"""An independent sample of MIS/SMC manual statements, each checked through the public interface.

The sample was drawn before reading the project's tests or statement files: the candidate lines
are those of the MIS/SMC integrated step motor manual's text edition in §5, §6, §8.2, §9, §11
(CANopen, with J1939 in §11.8) and §13 (DMX512); 15 line numbers were drawn with
``random.Random(1206004)`` (``choice`` over those lines) and for each the nearest sentence
stating a checkable behaviour was taken. Bus statements are checked on ``jvl-gym serve`` twins
with python-can's ``udp_multicast`` bus (a group of its own, so that no other test hears it) and
the ``canopen`` library as the master.

Candidate lines: 2231-3529, 3530-3935, 4264-6120, 6121-6589, 6598-9175, 9488-9660.
Drawn line -> statement line (section): 4371 -> 4372 (8.2.67), 4886 -> 4887 (8.2.24), 4535 ->
4535 (8.2.2), 2930 -> 2933 (5.7), 4919 -> 4922 (8.2.25), 8601 -> 8602-8606 (11.7.2), 6615 ->
6620 (11.1.1), 5688 -> 5691 (8.2.94), 6958 -> 6958 (11.4.1), 8424 -> 8420 (11.6), 7950 -> 7950
(11.5.8), 3194 -> 3194 (5.9.6), 2674 -> 2672 (5.5), 8830 -> 8830 (11.8.6), 5537 -> 5538
(8.2.83). Skipped as stating nothing checkable: 12 lines (reserved bits, headings, figure
captions, MacTalk/TwinCAT click steps).
"""

from __future__ import annotations

import os
import random
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np
import pytest

from jvl_gym import MotorArray

COUNTS_PER_REV = 409_600  # MIS manual §8.2.4
CAN_TYPES = ("MIS232", "MIS171", "MIS340", "MIS430", "SMC66", "SMC85")
CAN_NODES = (5, 6, 7, 8, 9, 10)


def _motor(**regs: float) -> MotorArray:
    m = MotorArray("MIS232", seed=0)
    for name, value in regs.items():
        m.write(name, value)
    return m


def _group() -> str:
    return f"239.74.163.{random.Random(os.getpid() ^ time.time_ns()).randrange(100, 250)}"


def _serve(args: list[str], ready: str) -> subprocess.Popen[str]:
    proc = subprocess.Popen([sys.executable, "-m", "jvl_gym.cli", "serve", *args],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=os.environ)
    assert proc.stdout is not None
    for text in proc.stdout:
        if ready in text:
            return proc
    proc.wait(20)
    pytest.fail(f"jvl-gym serve ended: {proc.stderr.read() if proc.stderr else ''}")


def _wait_for(predicate: Callable[[], bool], timeout: float = 60.0) -> bool:
    """Poll ``predicate`` until it holds (a generous margin, not a timing assertion)."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if predicate():
            return True
        time.sleep(0.05)
    return predicate()


@pytest.fixture(scope="module")
def canopen_net() -> Iterator[tuple[Any, str]]:
    canopen = pytest.importorskip("canopen")
    channel = _group()
    args = []
    for motor, node in zip(CAN_TYPES, CAN_NODES):
        args += ["--motor", motor, "--address", str(node), "--node-id", str(node)]
    proc = _serve([*args, "--canopen", "--can-interface", "udp_multicast",
                   "--can-channel", channel], f"node id {CAN_NODES[-1]}")
    net = canopen.Network()
    try:
        net.connect(interface="udp_multicast", channel=channel)
        yield net, channel
    finally:
        net.disconnect()
        proc.terminate()
        proc.wait(20)


def _node(net: Any, node_id: int) -> Any:
    import canopen

    return net.nodes.get(node_id) or net.add_node(node_id, canopen.ObjectDictionary())


def test_zero_search_bit_4_ignores_the_switch_and_finds_the_index() -> None:
    """MIS manual §8.2.67 (ZERO_SEARCH_BITS): bit 4 "ignore switch" is used to search only for
    the index: with bit 0 (search for index) the search ends at the encoder's index without any
    home sensor."""
    m = MotorArray("MIS232", seed=0)
    m.reset(initial_angle=1.0)
    for name, value in dict(V_HOME=100_000, P_HOME=0, ZERO_SEARCH_BITS=(1 << 4) | 1,
                            MODE_REG=13).items():
        m.write(name, value)
    tr = m.trace(["MODE_REG", "STATUSBITS", "position_rad"], 6000)
    done = int(np.argmax(tr["MODE_REG"][:, 0] != 13))
    assert done > 0
    assert int(tr["STATUSBITS"][done, 0]) & (1 << 7)  # zero search done
    turns = float(tr["position_rad"][done, 0]) / (2 * np.pi)
    assert turns == pytest.approx(round(turns), abs=0.01)  # at the index
    assert round(turns) != 0  # it went there: it started 0.16 turns away


@pytest.mark.statements("mis:8.2.24:2", "mis:5.2.2:3")
def test_statusbits_bit_1_autocorrection_active() -> None:
    """MIS manual §8.2.24 (STATUSBITS) with §5.2.2: bit 1 is "AutoCorrection active": a change
    of P_SOLL sets it and it stays set until the encoder position is within the target window
    (or the retries are used up), so it also covers the retries of a move whose steps were
    lost."""
    m = _motor(P_SOLL=COUNTS_PER_REV, MODE_REG=2)
    sb = m.trace(["STATUSBITS"], 1500)["STATUSBITS"][:, 0]
    assert sb[0] & 2
    assert not sb[-1] & 2  # the move ended in the window
    m = _motor(P_SOLL=COUNTS_PER_REV, MODE_REG=2)
    m.set_input(load_torque=3.0)  # beyond the pull-out torque: steps are lost
    m.run(1.5)  # the unloaded move would have ended by now
    m.set_input(load_torque=0.0)
    sb = m.trace(["STATUSBITS"], 200)["STATUSBITS"][:, 0]
    assert np.all(sb & 2)  # still correcting


def test_prog_version_bit_13_clear_on_a_released_firmware() -> None:
    """MIS manual §8.2.2 (PROG_VERSION): bit 13 is set only if the firmware is a beta version
    (the simulated firmware is a released one)."""
    assert not int(_motor().read("PROG_VERSION")[0]) & (1 << 13)


def test_ssi_clock_idles_high_and_goes_low_to_sample() -> None:
    """MIS manual §5.7: the SSI clock line idles high; for a reading it goes low for t1 µs so
    that the encoder samples its value, which then appears as the SSI encoder value (the clock
    line itself is electrical: what a user sees is the sampled value in EXTENCODER2 after a
    reading, command 321, on a port set up by command 320)."""
    m = _motor()
    m.write("SSI_SETUP1", 25 | (1 << 5) | (10 << 8))  # 25 data bits, 1 sample, 100 kHz
    m.write("COMMAND", 320)
    m.set_input(ssi_word=12345)
    m.write("COMMAND", 321)
    m.run(0.05)
    assert int(m.read("EXTENCODER2")[0]) == 12345


def test_temp_times_2_27_is_degrees_celsius() -> None:
    """MIS manual §8.2.25 (TEMP): the temperature in °C is about 2.27 x TEMP (at rest at room
    temperature the electronics read some 20-30 °C)."""
    assert 2.27 * float(_motor().read("TEMP")[0]) == pytest.approx(25.0, abs=8)


def test_lss_inquire_node_id(canopen_net: tuple[Any, str]) -> None:
    """MIS manual §11.7.2: the LSS "inquire node-ID" request (command 5Eh) is answered with 5Eh
    and the node-ID."""
    import can

    net, channel = canopen_net
    with can.Bus(interface="udp_multicast", channel=channel) as bus:
        bus.send(can.Message(arbitration_id=0x7E5, data=[0x04, 0x01] + [0] * 6,
                             is_extended_id=False))
        time.sleep(0.2)
        while bus.recv(0.05) is not None:
            pass
        bus.send(can.Message(arbitration_id=0x7E5, data=[0x5E] + [0] * 7, is_extended_id=False))
        answers = set()
        end = time.monotonic() + 10
        while time.monotonic() < end and len(answers) < len(CAN_NODES):
            msg = bus.recv(0.5)
            if msg is not None and msg.arbitration_id == 0x7E4 and msg.data[0] == 0x5E:
                answers.add(msg.data[1])
        bus.send(can.Message(arbitration_id=0x7E5, data=[0x04, 0x00] + [0] * 6,
                             is_extended_id=False))
    assert answers == set(CAN_NODES)


def test_canopen_on_mis17x_23x_34x_43x_and_smc(canopen_net: tuple[Any, str]) -> None:
    """MIS manual §11.1.1: the CANopen option is available for the MIS17x, MIS23x (SMC66),
    MIS34x and MIS43x (SMC85): each answers as a CANopen slave (device type 1000h)."""
    net, _ = canopen_net
    for node_id in CAN_NODES:
        raw = _node(net, node_id).sdo.upload(0x1000, 0)
        assert len(raw) == 4


@pytest.mark.statements("mis:8.2.94:1")
def test_available_io_is_read_only() -> None:
    """MIS manual §8.2.94 (AVAILABLE_IO): the value is read-only (set in manufacturing)."""
    m = _motor()
    before = int(m.read("AVAILABLE_IO")[0])
    with pytest.raises(ValueError):
        m.write("AVAILABLE_IO", before + 1)
    assert int(m.read("AVAILABLE_IO")[0]) == before


def test_identity_serial_number_is_uint32(canopen_net: tuple[Any, str]) -> None:
    """MIS manual §11.4.1 (identity object 1018h): sub-index 4 is the serial number, a UINT32;
    the object has 4 entries and the vendor ID 117h."""
    node = _node(canopen_net[0], CAN_NODES[0])
    assert node.sdo.upload(0x1018, 0) == bytes([4])
    assert int.from_bytes(node.sdo.upload(0x1018, 1), "little") == 0x117
    assert len(node.sdo.upload(0x1018, 4)) == 4


def test_rpdo1_mapping_count_is_rw_and_one(canopen_net: tuple[Any, str]) -> None:
    """MIS manual §11.6 (TwinCAT object list of the motor): 1600h:0, the receive PDO 1 mapping
    parameter, is read-write and holds 1 mapped object."""
    sdo = _node(canopen_net[0], CAN_NODES[1]).sdo
    assert sdo.upload(0x1600, 0) == bytes([1])
    sdo.download(0x1600, 0, bytes([0]))  # dynamic mapping: disable, then restore
    assert sdo.upload(0x1600, 0) == bytes([0])
    sdo.download(0x1600, 0, bytes([1]))
    assert sdo.upload(0x1600, 0) == bytes([1])


def test_interpolated_position_absolute_and_relative(canopen_net: tuple[Any, str]) -> None:
    """MIS manual §11.5.8 (60C1h:01): with interpolated data type 0 the data is an absolute
    position the motor goes to by the next SYNC; with type 1 a distance it moves."""
    net, _ = canopen_net
    sdo = _node(net, CAN_NODES[0]).sdo

    def u(index: int, sub: int, value: int, size: int, signed: bool = False) -> None:
        sdo.download(index, sub, value.to_bytes(size, "little", signed=signed))

    def position() -> int:
        return int.from_bytes(sdo.upload(0x6064, 0), "little", signed=True)

    u(0x6060, 0, 7, 1, signed=True)
    for cw in (0x06, 0x07, 0x0F, 0x1F):
        u(0x6040, 0, cw, 2)
    start = position()
    target = start + 40_960
    u(0x60C1, 1, target, 4, signed=True)
    net.sync.transmit()
    assert _wait_for(lambda: abs(position() - target) < 200)
    u(0x60C1, 2, 1, 1)
    u(0x60C1, 1, -20_480, 4, signed=True)
    net.sync.transmit()
    assert _wait_for(lambda: abs(position() - (target - 20_480)) < 200)
    u(0x6040, 0, 0x06, 2)


@pytest.mark.statements("mis:5.9.6:1")
def test_limit_without_memory_clears_has_been_warning_on_reversal() -> None:
    """MIS manual §5.9.6: with "position limits without memory" (SETUP_BITS bit 28) the limit's
    has-been warning clears by itself once the motor reverses and the switch is no longer
    active; without it the warning stays."""
    for without_memory, after in ((True, 0), (False, 1 << 2)):
        bits = (1 << 17) | ((1 << 28) if without_memory else 0)  # 17: stay in mode at a limit
        m = _motor(SETUP_BITS=bits, PL_MASK=1, V_SOLL=10_000, MODE_REG=1)
        m.run(0.3)
        m.set_input(digital_inputs=1)  # positive limit switch on IO1
        m.run(0.3)
        assert int(m.read("WARN_BITS")[0]) & 0b101 == 0b101
        m.set_input(digital_inputs=0)
        m.run(0.1)
        assert int(m.read("WARN_BITS")[0]) & (1 << 2)
        m.write("V_SOLL", -10_000)
        m.run(0.3)
        assert int(m.read("WARN_BITS")[0]) & (1 << 2) == after


def test_multifunction_port_takes_pulses_from_an_external_encoder() -> None:
    """MIS manual §5.5: the multifunction port can take pulses in from an external encoder:
    they are counted (EXT_ENCODER) and, in gear mode, move the motor by GEAR1/GEAR2."""
    m = _motor(GEAR1=409_600, GEAR2=2048, MODE_REG=3)
    m.set_input(pulse_counts=2)
    m.run(0.5)
    counted = int(m.read("EXT_ENCODER")[0])
    assert counted == 1000
    assert int(m.read("P_SOLL")[0]) == counted * 409_600 // 2048


def test_j1939_read_of_no_register_answers_operation_failed() -> None:
    """MIS manual §11.8.6-11.8.7: a memory access (DM14) the motor cannot carry out is answered
    with a DM15 whose status (byte 1 bits 1-3) is 5, "operation failed"; a valid read is
    answered with status 0, "proceed"."""
    import can

    channel = _group()
    proc = _serve(["--motor", "MIS232", "--j1939", f"udp_multicast:{channel}"], "j1939")
    tool = 0xF9
    try:
        with can.Bus(interface="udp_multicast", channel=channel) as bus:
            def request(pointer: int) -> int:
                data = [4, (1 << 1) | 1, pointer & 0xFF, pointer >> 8 & 0xFF, 0, 0x80, 0xFF,
                        0xFF]  # length 4, read, direct pointer, MAC registers
                bus.send(can.Message(arbitration_id=6 << 26 | 0xD9 << 16 | 5 << 8 | tool,
                                     data=data, is_extended_id=True))
                end = time.monotonic() + 20
                while time.monotonic() < end:
                    msg = bus.recv(0.5)
                    if (msg is not None and msg.arbitration_id >> 16 & 0xFF == 0xD8
                            and msg.arbitration_id >> 8 & 0xFF == tool):
                        return msg.data[1] >> 1 & 7
                pytest.fail("no DM15")

            time.sleep(0.5)  # the address claim
            assert request(600) == 5
            assert request(5) == 0
    finally:
        proc.terminate()
        proc.wait(20)


@pytest.mark.statements("mis:8.2.83:1")
def test_p_new_is_a_read_write_signed_32_bit_register_default_0() -> None:
    """MIS manual §8.2.83 (the P_NEW row): register 144, 32 bit, R/W, range -2^31..2^31-1,
    default 0, in counts."""
    m = _motor()
    assert int(m.read(144)[0]) == 0
    for value in (-(2**31), 2**31 - 1):
        m.write("P_NEW", value)
        assert int(m.read("P_NEW")[0]) == value
    with pytest.raises(ValueError):
        m.write("P_NEW", 2**31)


@pytest.mark.statements("mis:8.2.83:2")
def test_fastmac_23_and_24_set_and_offset_positions_by_p_new() -> None:
    """Beyond the sample (the description below the row), MIS manual §8.2.83 (P_NEW): FastMac
    command 23 (COMMAND 119) copies P_NEW to P_IST and P_SOLL; FastMac 24 (COMMAND 120) adds it
    with its sign to both."""
    m = _motor(P_NEW=5000, COMMAND=119)
    m.step(3)
    assert int(m.read("P_IST")[0]) == 5000
    assert int(m.read("P_SOLL")[0]) == 5000
    m.write("P_NEW", -200)
    m.write("COMMAND", 120)
    m.step(3)
    assert int(m.read("P_IST")[0]) == 4800
    assert int(m.read("P_SOLL")[0]) == 4800
