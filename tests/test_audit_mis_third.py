"""A third independent sample of MIS manual statements, checked through the public interface.

Fifteen lines were drawn with ``random.Random(1207004).sample`` from the line ranges of the MIS
manual's chapters 5, 6, 8.2, 9, 11 (CANopen, with J1939 §11.8) and 13 (DMX512) in the text the
project audits; for each line the nearest sentence that states a checkable behaviour was taken
(six sentences that state nothing checkable were skipped: a wiring figure, a list heading, a
cross-reference, an object label, "Segment data." and a table heading). Each test checks one
statement as a user would: registers read and written by name on a ``MotorArray``, the world
inputs and parameters of docs/families/mis-sim.md, a stored program, or a CANopen master on a
python-can bus served by ``jvl-gym serve``'s CANopen server. The docstrings cite the section
and the drawn line and give the statement in our own words.
"""

from __future__ import annotations

import math
import uuid

import numpy as np
import pytest

from jvl_gym import MotorArray

COUNTS_PER_REV = 409_600
FULL_STEP = 2048  #: counts of one full step (200 per revolution)


def _counts(m: MotorArray) -> float:
    """The shaft's angle from power-on in motor counts."""
    return float(m.position_rad[0]) * COUNTS_PER_REV / (2.0 * math.pi)


def _reg(m: MotorArray, name: str, i: int = 0) -> int:
    return int(m.read(name)[i])


def _run_until(m: MotorArray, done, seconds: float) -> None:
    """Step 1 ms at a time until ``done(m)`` or ``seconds`` of simulated time."""
    for _ in range(int(seconds * 1000)):
        if done(m):
            return
        m.step(1)
    raise AssertionError(f"not done within {seconds} s of simulated time")


# --------------------------------------------------------------------------- §5.3.7, line 2586
@pytest.mark.statements("mis:5.3.7:4")
def test_current_decrement_at_3000_rpm_one_step_per_40621_clocks():
    """MIS manual §5.3.7 (line 2586): with the factory settings (CUR_SCALE_FACTOR 500,
    CUR_SCALE_DEC 4000) the decrement count at 3000 RPM is (3000·100/4096)·500 + 4000 = 40621
    clocks of 36 MHz, so the closed-loop current falls one of its 2048 steps every 1.13 ms."""
    m = MotorArray("MIS232")
    assert _reg(m, "CUR_SCALE_FACTOR") == 500 and _reg(m, "CUR_SCALE_DEC") == 4000
    m.write("SETUP_BITS", (1 << 24) | (1 << 25))  # closed loop with current control
    m.write_many({"A_SOLL": 20000, "V_SOLL": 300000, "MODE_REG": 1})  # 3000 RPM
    m.run(0.3)
    assert _reg(m, "V_IST") == 300000 and _reg(m, "ACTUAL_TORQUE") == 2047
    m.write("CUR_SCALE_MAX", 1700)  # the current must come down 347 steps
    tr = m.trace(["ACTUAL_TORQUE", "V_IST"], 600)
    torque = tr["ACTUAL_TORQUE"].ravel()
    assert np.all(tr["V_IST"].ravel() == 300000)
    reached_ms = int(np.argmax(torque <= 1700)) + 1
    expected_ms = (2047 - 1700) * 40621 / 36_000.0  # 391.5 ms
    assert abs(reached_ms - expected_ms) <= 2.0
    # and not at the 0 RPM rate (4000 clocks: 38.6 ms for the same 347 steps)
    assert reached_ms > 10 * (2047 - 1700) * 4000 / 36_000.0


# --------------------------------------------------------------------------- §5.8.1, line 2944
@pytest.mark.statements("mis:5.8.1:4")
def test_h3_encoder_keeps_the_position_while_unpowered():
    """MIS manual §5.8.1 (line 2949, the nearest checkable sentence to line 2944): with the
    absolute multi-turn encoder (H3) the motor keeps track of its position whether power is
    connected or not: a shaft turned while the motor is passive and then restarted (user
    command 267, with SETUP_BITS bit 11 taking the multi-turn position into P_IST) reads
    where the shaft is."""
    m = MotorArray("MIS232", encoder_type=2)  # H3
    m.write("SETUP_BITS", 1 << 11)
    m.write("COMMAND", 268)  # save in flash and reset
    m.write_many({"MODE_REG": 2, "V_SOLL": 30000, "P_SOLL": 1_024_000})
    _run_until(m, lambda m: _reg(m, "P_IST") == 1_024_000 and _reg(m, "V_IST") == 0, 5.0)
    m.write("MODE_REG", 0)
    m.run(0.05)
    m.set_input(supply_volts=0.0, control_volts=0.0)  # power off
    m.set_input(load_torque=0.2)  # the shaft is turned by hand while the motor is off
    m.run(0.3)
    m.set_input(load_torque=0.0)
    m.run(1.0)
    shaft = _counts(m)
    assert abs(shaft - 1_024_000) > COUNTS_PER_REV  # it was turned by more than a turn
    assert _reg(m, "P_IST") == 1_024_000  # the commanded position did not see it
    m.set_input(supply_volts=48.0, control_volts=24.0)  # power on again
    m.run(0.2)
    m.write("COMMAND", 267)  # restart
    m.step(1)
    assert abs(_reg(m, "P_IST") - shaft) <= 400  # H3: 1024 counts per turn inside
    assert abs(_reg(m, "ABSENCODER") - shaft) <= 400


# --------------------------------------------------------------------------- §5.8.1, line 2957
@pytest.mark.statements("mis:5.8.1:1")
def test_h3_resolution_409600_displayed_1024_inside():
    """MIS manual §5.8.1 (line 2959): the H3's position is displayed in 409 600 counts per
    revolution while the encoder resolves 1024 per revolution inside: one turn reads 409 600,
    and the reading moves in steps of 400 counts."""
    m = MotorArray("MIS232", encoder_type=2)
    m.write_many({"MODE_REG": 2, "V_SOLL": 1000, "P_SOLL": 8000})  # 10 RPM, slowly
    tr = m.trace(["ABSENCODER"], 1200)
    seen = np.unique(tr["ABSENCODER"].ravel())
    assert np.all(seen % 400 == 0)
    assert np.all(np.diff(seen) == 400) and seen.size >= 15
    m.write_many({"V_SOLL": 30000, "P_SOLL": 8000 + COUNTS_PER_REV})
    _run_until(m, lambda m: _reg(m, "P_IST") == 8000 + COUNTS_PER_REV
               and _reg(m, "V_IST") == 0, 5.0)
    m.run(0.1)
    assert abs(_reg(m, "ABSENCODER") - (8000 + COUNTS_PER_REV)) <= 400


# --------------------------------------------------------------------------- §5.9.3, line 3157
@pytest.mark.statements("mis:5.9.3:4")
def test_changing_a_passed_position_limit_lets_the_motor_move_on():
    """MIS manual §5.9.3 (line 3160): when a software position limit has stopped the motor
    (here kept in its mode by SETUP_BITS bit 17, §5.9.5), changing the limits may make it start
    to move again: it goes on to its target."""
    m = MotorArray("MIS232")
    m.write("SETUP_BITS", 1 << 17)
    m.write_many({"MIN_P_IST": -100_000, "MAX_P_IST": 100_000})
    m.write_many({"MODE_REG": 2, "V_SOLL": 30000, "P_SOLL": 200_000})
    m.run(2.0)
    assert _reg(m, "P_IST") <= 100_000 and _reg(m, "V_IST") == 0
    assert _reg(m, "MODE_REG") == 2
    m.write("MAX_P_IST", 300_000)
    m.run(2.0)
    assert _reg(m, "P_IST") == 200_000


# --------------------------------------------------------------------------- §5.10.1, line 3233
@pytest.mark.statements("mis:5.10:1", "mis:5.10:2", "mis:5.10:3")
def test_three_under_voltage_options():
    """MIS manual §5.10.1 (line 3226, with §5.10 and §5.10.2): three options set what the motor
    does when P+ falls below "Min bus voltage": set the error bit (error stop, then passive,
    staying so with a "low bus voltage" error when P+ returns), stop controlled and go to
    passive (staying passive), or set the velocity to 0 (V_SOLL stays 0, mode kept)."""
    m = MotorArray("MIS232", n=3)
    for i, bit in enumerate((21, 22, 23)):
        m.write("SETUP_BITS", 1 << bit, index=i)
    m.write_many({"V_SOLL": 10000, "MODE_REG": 1})
    m.run(0.5)
    assert np.all(m.read("V_IST") == 10000)
    low = _reg(m, "MIN_BUSVOL") * 0.026525 - 3.0  # V below the trigger level
    m.set_input(supply_volts=low)
    m.run(1.0)
    m.set_input(supply_volts=48.0)
    m.run(0.5)
    mode, err = m.read("MODE_REG"), m.read("ERR_BITS")
    assert mode[0] == 0 and err[0] & (1 << 4)  # error bit, passive, error kept
    assert mode[1] == 0 and err[1] == 0  # controlled stop to passive, no error
    assert mode[2] == 1 and err[2] == 0 and _reg(m, "V_SOLL", 2) == 0  # velocity set to 0
    assert np.all(m.read("V_IST") == 0)


# --------------------------------------------------------------------------- §5.12.5, line 3501
@pytest.mark.statements("mis:5.12.5:1", "mis:5.12.5:2", "mis:5.12.5:3")
def test_turn_table_actual_position_stays_in_range():
    """MIS manual §5.12.5 (line 3500): in a turn table mode the actual position P_IST stays
    within the defined minimum and maximum, wrapping around when the motor passes them."""
    m = MotorArray("MIS232")
    m.write_many({"MIN_P_IST": 0, "MAX_P_IST": COUNTS_PER_REV - 1, "TURNTABLE_MODE": 4})
    m.write_many({"MODE_REG": 2, "V_SOLL": 60000, "A_SOLL": 5000})
    m.write("P_SOLL", 970_000)  # multiturn CW: 2 turns and 150 800 counts
    tr = m.trace(["P_IST", "V_IST"], 3000)
    p = tr["P_IST"].ravel()
    assert p.min() >= 0 and p.max() <= COUNTS_PER_REV - 1
    assert p.max() > 350_000 and tr["V_IST"].ravel()[-1] == 0
    assert _reg(m, "P_IST") == 150_800
    assert _reg(m, "TURNTAB_COUNT") == 2  # the wrap-arounds


@pytest.mark.statements("mis:5.12.5:1")
def test_turn_table_wraps_keep_the_encoder_in_the_frame_of_p_ist():
    """MIS manual §5.12.5 with §8.2.18 and §5.2.1 (found with the check of line 3500, fixed
    after the sample): with an encoder, a multiturn turn-table move of 970 000 counts wraps
    P_IST twice, TURNTAB_COUNT counts 2 and the shaft turns 970 000 counts. The follow error
    P_IST − ENCODER_POS stays that of the rotor (the encoder wraps with P_IST), so neither
    auto-correction (on by default: IN_POSITION_COUNT 2) retries a move that arrived nor a
    follow-error limit trips at a wrap."""
    m = MotorArray("MIS232")  # H2 encoder
    m.write_many({"MIN_P_IST": 0, "MAX_P_IST": COUNTS_PER_REV - 1, "TURNTABLE_MODE": 4})
    m.write_many({"MODE_REG": 2, "V_SOLL": 60000, "A_SOLL": 5000, "FLWERRMAX": 20000})
    m.write("P_SOLL", 970_000)
    tr = m.trace(["FLWERR", "TURNTAB_COUNT", "ERR_BITS"], 3000)
    assert np.abs(tr["FLWERR"].ravel()).max() < 20000
    assert np.all(tr["ERR_BITS"].ravel() == 0)
    assert _reg(m, "TURNTAB_COUNT") == 2 and _reg(m, "P_IST") == 150_800
    assert abs(_counts(m) - 970_000) < FULL_STEP
    assert abs(_reg(m, "ENCODER_POS") - 150_800) < FULL_STEP


# --------------------------------------------------------------------------- §5.12.6, line 3527
@pytest.mark.statements("mis:5.12.6:1", "mis:5.12.6:2")
def test_turn_table_jog_leaves_range_and_position_mode_moves():
    """MIS manual §5.12.6 (line 3524): after a jog in velocity mode P_IST may be left outside
    the turn table's range, and switching back to position mode may move the motor (to the old
    target) "unexpectedly"."""
    m = MotorArray("MIS232")
    m.write_many({"MIN_P_IST": 0, "MAX_P_IST": COUNTS_PER_REV - 1, "TURNTABLE_MODE": 1})
    m.write_many({"MODE_REG": 2, "V_SOLL": 30000, "P_SOLL": 100_000})
    m.run(1.0)
    assert _reg(m, "P_IST") == 100_000
    m.write("MODE_REG", 1)  # jog
    m.run(1.23)
    m.write("V_SOLL", 0)
    m.run(1.0)
    assert _reg(m, "V_IST") == 0
    assert not 0 <= _reg(m, "P_IST") <= COUNTS_PER_REV - 1  # outside the range
    before = _counts(m)
    m.write("MODE_REG", 2)
    m.write("V_SOLL", 30000)
    m.run(2.0)
    assert abs(_counts(m) - before) > 10 * FULL_STEP  # the motor moved
    assert _reg(m, "P_IST") == 100_000


# --------------------------------------------------------------------------- §6, line 3548
@pytest.mark.statements("mis:6.4.1:1", "mis:8.2.13:2")
def test_gear_ratio_from_gear1_and_gear2():
    """MIS manual §6 overview (line 3546): in gear mode the ratio, which may be large, is set
    by GEAR1 (register 14) and GEAR2 (register 15): the motor moves the input counts times
    GEAR1/GEAR2."""
    m = MotorArray("MIS232")
    m.write_many({"GEAR1": 40960, "GEAR2": 3, "V_SOLL": 60000, "A_SOLL": 10000})
    m.write("MODE_REG", 3)
    m.step(1)
    start = _reg(m, "P_SOLL")
    m.set_input(pulse_counts=1)
    m.run(0.09)  # 90 input counts
    m.set_input(pulse_counts=0)
    m.run(1.5)
    assert _reg(m, "P_SOLL") - start == 90 * 40960 // 3  # 1 228 800: three turns
    assert _reg(m, "P_IST") == _reg(m, "P_SOLL")
    assert abs(_counts(m) - 90 * 40960 / 3) < FULL_STEP


# --------------------------------------------------------------------------- §6, line 3551
@pytest.mark.statements("mis:6.5.1:1")
def test_zero_search_defines_zero_at_the_sensor():
    """MIS manual §6 overview (line 3550): the zero search mode searches for a sensor and makes
    the point where it is found the zero position."""
    m = MotorArray("MIS232")
    m.write_many({"HOME_MASK": 1, "V_HOME": -3000})  # sensor on IO1, search at -30 RPM
    sensor = -50_000.0  # the sensor is active at and below this shaft position [counts]
    m.write("MODE_REG", 13)

    def seen(m):
        m.set_input(digital_inputs=1 if _counts(m) <= sensor else 0)
        return _reg(m, "STATUSBITS") & (1 << 7)

    _run_until(m, seen, 10.0)
    m.run(0.5)
    assert abs(_reg(m, "P_IST") - (_counts(m) - sensor)) < 600


# --------------------------------------------------------------------------- §6.5.1, line 3779
@pytest.mark.statements("mis:6.5.1:1", "mis:6.5.1:2", "mis:6.5.1:3")
@pytest.mark.parametrize("kind", ["sensor type 1", "sensor type 2", "torque"])
def test_three_zero_search_modes(kind):
    """MIS manual §6.5.1 (line 3780; the modes in its table): the motor offers three zero
    search modes, started by a command over a serial interface (MODE_REG): sensor type 1 (the
    zero where the sensor becomes active), sensor type 2 (reversing after the sensor and taking
    the zero where it is released) and torque (with the closed loop and current control, the
    zero at a mechanical collision)."""
    sensor_rad = -0.6
    sensor = sensor_rad * COUNTS_PER_REV / (2 * math.pi)
    if kind == "torque":
        m = MotorArray("MIS232", end_stop_low=sensor_rad)
        m.write("SETUP_BITS", (1 << 24) | (1 << 25))
        m.write_many({"HOME_MASK": 0, "T_HOME": 1500, "V_HOME": -3000})
    else:
        m = MotorArray("MIS232", home_position=sensor_rad)
        m.write_many({"HOME_MASK": 1, "V_HOME": -3000})
    m.write("MODE_REG", 14 if kind == "sensor type 2" else 13)
    tr = m.trace(["STATUSBITS", "V_IST", "P_IST"], 8000)
    done = (tr["STATUSBITS"].ravel() & (1 << 7)) != 0
    assert done.any()
    v = tr["V_IST"].ravel()
    if kind == "sensor type 2":
        assert v.min() < 0 < v.max()  # reversed after the sensor
    else:
        assert v.max() <= 0
    m.run(0.2)
    assert abs(_reg(m, "P_IST") - (_counts(m) - sensor)) < FULL_STEP


# --------------------------------------------------------------------------- §8.2.3, line 4620
@pytest.mark.statements("mis:8.2.3:5")
def test_position_mode_moves_to_p_soll_with_v_soll_and_a_soll():
    """MIS manual §8.2.3 (line 4620): MODE_REG = 2 sets position mode; a new P_SOLL makes the
    motor move there at no more than V_SOLL, accelerating with A_SOLL."""
    m = MotorArray("MIS232")
    m.write_many({"V_SOLL": 20000, "A_SOLL": 2000, "MODE_REG": 2})
    assert _reg(m, "MODE_REG") == 2
    m.write("P_SOLL", COUNTS_PER_REV)
    tr = m.trace(["V_IST", "P_IST"], 1500)
    v = tr["V_IST"].ravel() * 0.01  # RPM
    assert v.max() == pytest.approx(200.0)
    rise = v[:int(np.argmax(v >= 200.0))]  # the acceleration, 1 ms per sample
    t50, t150 = np.argmax(rise >= 50.0), np.argmax(rise >= 150.0)
    slope = 100.0 / ((t150 - t50) / 1000.0)  # RPM/s from 50 to 150 RPM
    assert slope == pytest.approx(2000.0, rel=0.05)
    assert tr["P_IST"].ravel()[-1] == COUNTS_PER_REV


# --------------------------------------------------------------------------- §8.2.112, line 5908
@pytest.mark.statements("mis:8.2.112:1")
def test_actual_torque_zero_in_passive_mode():
    """MIS manual §8.2.112 (line 5909): ACTUAL_TORQUE reads 0 % in passive mode (after running
    with the closed loop and current control too)."""
    m = MotorArray("MIS232")
    assert _reg(m, "MODE_REG") == 0 and _reg(m, "ACTUAL_TORQUE") == 0
    m.write("SETUP_BITS", (1 << 24) | (1 << 25))
    m.write_many({"V_SOLL": 20000, "MODE_REG": 1})
    m.run(0.5)
    assert _reg(m, "ACTUAL_TORQUE") > 0
    m.write("MODE_REG", 0)
    _run_until(m, lambda m: _reg(m, "MODE_REG") == 0, 2.0)
    m.step(1)
    assert _reg(m, "ACTUAL_TORQUE") == 0


# --------------------------------------------------------------------------- §9.7.19, line 6458
@pytest.mark.statements("mis:9.7.19:1")
def test_program_save_position_keeps_p_ist_for_a_move():
    """MIS manual §9.7.19 (line 6460): the program command "Save position" copies the actual
    position (P_IST, register 10) to one of three locations of the user memory, and a move
    command can then use the saved position."""
    m = MotorArray("MIS232")
    m.store_program(
        "mode mode=position\n"
        "move_absolute position=50000 velocity=300\n"
        "save_position register=register2\n"
        "move_absolute position=-20000 velocity=300\n"
        "move_absolute position=register2 velocity=300\n"
        "wait_ms time=10\n"
        "jump line=6\n")
    m.program_start()
    m.run(3.0)
    assert _reg(m, "P2") == 50000
    assert _reg(m, "P_IST") == 50000 and _reg(m, "V_IST") == 0


# --------------------------------------------------------------------------- CANopen rig
@pytest.fixture
def master():
    """A CANopen master (``canopen``) and the served MIS232 (node 5) on a virtual bus, with
    simulated time advanced by the test (``server.advance``)."""
    canopen = pytest.importorskip("canopen")
    from jvl_gym.cli.serve import canopen_server
    from jvl_gym.protocol.canopen.eds import shipped_path
    from jvl_gym.protocol.mactalk.twin16 import Twin

    channel = f"audit3-{uuid.uuid4().hex}"
    m = MotorArray("MIS232")
    server = canopen_server(Twin(m), "virtual", channel, [5], 1.0, run_clock=False).start()
    net = canopen.Network()
    net.connect(interface="virtual", channel=channel)
    node = net.add_node(5, str(shipped_path()))
    # simulated time is the server's; the wall-clock time-out only ends a wait for a server
    # that never answers (the canopen package's 0.3 s can pass on a loaded machine)
    node.sdo.RESPONSE_TIMEOUT = 5.0
    try:
        yield m, server, node
    finally:
        net.disconnect()
        server.stop()


def _sdo_write(node, index: int, sub: int, value: int, size: int) -> None:
    node.sdo.download(index, sub, int(value).to_bytes(size, "little", signed=value < 0))


def _sdo_read(node, index: int, sub: int) -> int:
    return int.from_bytes(node.sdo.upload(index, sub), "little", signed=False)


# --------------------------------------------------------------------------- §11.5.8, line 7947
@pytest.mark.statements("mis:11.5.8:2")
def test_ip_mode_ready_bit_10(master):
    """MIS manual §11.5.8 (line 7944): in interpolated position mode, once ENABLE_IP_MODE
    (controlword bit 4) is set, the motor sets statusword bit 10 (IP_MODE_READY) when it is
    ready for position data."""
    m, server, node = master
    node.nmt.state = "OPERATIONAL"
    _sdo_write(node, 0x60C2, 1, 10, 1)
    _sdo_write(node, 0x6060, 0, 7, 1)
    for cw in (0x06, 0x07, 0x0F):
        _sdo_write(node, 0x6040, 0, cw, 2)
        server.advance(0.005)
    assert _sdo_read(node, 0x6041, 0) & 0x6F == 0x27  # operation enabled
    _sdo_write(node, 0x60C1, 1, _sdo_read(node, 0x6064, 0), 4)
    assert not _sdo_read(node, 0x6041, 0) & (1 << 10)  # not before bit 4
    _sdo_write(node, 0x6040, 0, 0x1F, 2)  # ENABLE_IP_MODE
    server.advance(0.005)
    assert _sdo_read(node, 0x6041, 0) & (1 << 10)


# --------------------------------------------------------------------------- §11.9.4, line 9046
@pytest.mark.statements("mis:11.9.4:1")
def test_sdo_abort_when_mapping_exceeds_pdo_length(master):
    """MIS manual §11.9.4 (line 9047): mapping objects whose number and length exceed a PDO's
    length is refused with SDO abort code 0604 0042h."""
    import canopen

    m, server, node = master
    node.nmt.state = "PRE-OPERATIONAL"
    server.advance(0.002)
    cob = _sdo_read(node, 0x1800, 1)
    _sdo_write(node, 0x1800, 1, cob | 0x8000_0000, 4)  # disable TPDO 1
    _sdo_write(node, 0x1A00, 0, 0, 1)
    for sub, reg in ((1, 5), (2, 10), (3, 3)):  # three 32-bit registers: 96 bits
        _sdo_write(node, 0x1A00, sub, 0x2012_0020 | (reg << 8), 4)
    with pytest.raises(canopen.SdoAbortedError) as err:
        _sdo_write(node, 0x1A00, 0, 3, 1)
    assert err.value.code == 0x0604_0042
