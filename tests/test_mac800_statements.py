"""Statements of the MAC800 register overview (§1.1, §1.2) and serial quick guide (§1.3) that no
other test asserts, each test carrying the ids of the statements it checks
(``src/jvl_gym/families/mac800/statements.yaml``)."""

from __future__ import annotations

import numpy as np
import pytest

from jvl_gym import MotorArray
from jvl_gym.families import mac800
from jvl_gym.families.mac800 import constants as c
from jvl_gym.families.mac800 import units as u
from jvl_gym.protocol.mactalk import codec32 as m32
from jvl_gym.protocol.mactalk.dialect import MACTALK32
from jvl_gym.protocol.mactalk.twin16 import Twin
from jvl_gym.registers import RegisterError
from test_protocol_mactalk32 import READ_EXAMPLES, WRITE_EXAMPLES

RPM_1000 = 2771  # quick guide §1.3.4: "1000 RPM = 2771"
COUNTS_PER_REV = 8000


def twin(addresses: list[int], **kw) -> tuple[Twin, MotorArray]:
    m = MotorArray("MAC800", n=len(addresses), seed=0, **kw)
    return Twin(m, addresses, dialect=MACTALK32), m


def ask(t: Twin, raw: bytes) -> bytes:
    s = t.session()
    return s.feed(raw) + s.flush()


# ------------------------------------------------------------------ §1.1, §1.2 table shape
#: the overview's "Width" column, register by register (OCR letter slips repaired)
_FIXED16 = {"KVOUT", "LOAD0", "LOAD1", "LOAD2", "LOAD3", "KVFX6", "KVFX5", "KVFX4", "KVFX3",
            "KVFX2", "KVFX1", "KVFY5", "KVFY4", "KVFY3", "KVFY2", "KVFY1", "KVFY0", "KIFX2",
            "KIFX1", "KIFY1", "KIFY0", "FNC_OUT", "MAN_I_NOM"}
_FIXED24 = {"KFF5", "KFF4", "KFF3", "KFF2", "KFF1", "KFF0", "KVB4", "KVB3", "KVB2", "KVB1",
            "KVB0", "KIB1", "KIB0"}


@pytest.mark.statements("mac800:1.1:1", "mac800:1.2:2", "mac800:1.2:7", "mac800:1.2:8",
                        "mac800:1.2:9", "mac800:1.2:10", "mac800:1.2:11", "mac800:1.2:12",
                        "mac800:1.2:13", "mac800:1.2:14", "mac800:1.2:15")
def test_register_numbers_and_widths_are_the_overviews() -> None:
    """More than 200 register numbers (1 … 206); Fixed16 and Fixed24 where the overview's width
    column says so, Long Int (32-bit signed) everywhere else; a Fixed register keeps a
    fraction, a Long Int does not."""
    regs = [r for r in mac800.REGISTERS if not r.name.startswith("RESERVED_")]
    assert max(r.number for r in mac800.REGISTERS) == 206 > 200
    for r in regs:
        want = "Fixed16" if r.name in _FIXED16 else "Fixed24" if r.name in _FIXED24 else "Int32"
        assert r.format == want, r.name
    m = MotorArray("MAC800", n=1, seed=0)
    m.write("LOAD1", 1.5)
    m.write("KFF3", -0.25)
    assert (m.read("LOAD1")[0], m.read("KFF3")[0]) == (1.5, -0.25)
    m.write("P_SOLL", 1.25)
    assert m.read("P_SOLL")[0] == 1  # an integer register keeps no fraction


@pytest.mark.statements("mac800:1.2:4")
def test_grey_registers_are_marked_not_for_the_user() -> None:
    """The grey rows ("not for the normal user"): the filters 121–157 and the inner loop but
    U_BUS are marked; the set points and the monitor registers are not."""
    user = {r.name: r.user for r in mac800.REGISTERS if not r.name.startswith("RESERVED_")}
    for r in mac800.REGISTERS:
        if 121 <= r.number <= 157 and not r.name.startswith("RESERVED_"):
            assert user[r.name] is False, r.name
        if 172 <= r.number <= 201 and r.name != "U_BUS":
            assert user[r.name] is False, r.name
    for name in ("MODE_REG", "P_SOLL", "V_SOLL", "A_SOLL", "T_SOLL", "P_IST", "ERR_STAT",
                 "U_BUS", "MY_ADDR"):
        assert user[name] is True, name


@pytest.mark.statements("mac800:1.2:6")
def test_reserved_numbers_refuse_a_write() -> None:
    """"Registers 89 to 120 are reserved for future purposes": a write is refused, nothing
    changes."""
    m = MotorArray("MAC800", n=1, seed=0)
    before = m.regs.copy()
    for number in (89, 100, 120):
        with pytest.raises(RegisterError, match="reserved"):
            m.write(number, 1)
    np.testing.assert_array_equal(m.regs, before)


# ------------------------------------------------------------------ Main Control
@pytest.mark.statements("mac800:reg1:2")
def test_prog_version_names_a_mac400_or_mac800() -> None:
    """PROG_VERSION bit 15 is set on a MAC400 or MAC800."""
    for motor in ("MAC400", "MAC800"):
        assert int(MotorArray(motor, n=1, seed=0).read("PROG_VERSION")[0]) & 0x8000


@pytest.mark.statements("mac800:reg2:8")
def test_analog_velocity_gear_mode_adds_the_input_to_the_gear() -> None:
    """Mode 6 (analogue velocity/gear): at 0 V the motor follows the pulse input geared by
    GEARF_1/GEARF_2; without pulses the analogue input alone turns it."""
    m = MotorArray("MAC800", n=2, seed=0)
    m.set_input(analog_volts=np.array([0.0, 5.0]), pulse_counts=np.array([8.0, 0.0]))
    m.write_many({"GEARF_1": 2, "GEARF_2": 1, "V_SOLL": RPM_1000, "MODE_REG": 6})
    m.run(0.5)
    geared_rpm = 2 * 8 * u.SAMPLE_HZ * 60 / COUNTS_PER_REV
    assert m.speed_rpm[0] == pytest.approx(geared_rpm, rel=0.02)
    assert m.speed_rpm[1] > 100.0


@pytest.mark.statements("mac800:reg2:9")
def test_analog_velocity_gear_mode_adds_300_rpm_at_10_volts_whatever_v_soll() -> None:
    """Mode 6 as the MAC050–141's AVG block (its manual 4.1.7, 4.4.7): ±10 V adds ±300 RPM to
    the geared velocity; V_SOLL (only the limit of a follow-error compensation the mode does
    not run) neither scales nor bounds it. Without pulses: 300 RPM at +10 V with V_SOLL at
    1000 RPM or 0, −300 RPM at −10 V; with pulses the 300 RPM add to the geared speed."""
    m = MotorArray("MAC800", n=4, seed=0)
    m.set_input(analog_volts=np.array([u.ANINP_VOLTS_PER_UNIT * 2047, 9.995, -9.995, 9.995]),
                pulse_counts=np.array([0.0, 0.0, 0.0, 8.0]))
    m.write_many({"GEARF_1": 2, "GEARF_2": 1, "V_SOLL": np.array([RPM_1000, 0, RPM_1000, 0]),
                  "MODE_REG": 6})
    m.run(0.6)
    geared_rpm = 2 * 8 * u.SAMPLE_HZ * 60 / COUNTS_PER_REV
    np.testing.assert_allclose(m.speed_rpm, [300.0, 300.0, -300.0, geared_rpm + 300.0],
                               rtol=0.02)


@pytest.mark.statements("mac800:reg2:17")
def test_analog_gear_factor_is_0_87_to_1_15_and_the_motor_stands_without_pulses() -> None:
    """Mode 18 as the MAC050–141's analogue gear block (its manual 4.1.9): ±10 V sets an
    analogue gear factor 0.87 … 1.15 on GEARF_1/GEARF_2, so the motor follows the pulses at
    any voltage (forwards at −10 V and at 0 V) and stands when they stop, whatever the input."""
    volts = np.array([-9.995, 0.0, 9.995])
    m = MotorArray("MAC800", n=3, seed=0)
    m.set_input(analog_volts=volts, pulse_counts=8)
    m.write_many({"GEARF_1": 2, "GEARF_2": 1, "V_SOLL": RPM_1000,
                  "MODE_REG": c.ANALOG_GEAR_MODE})
    m.run(0.6)
    geared_rpm = 2 * 8 * u.SAMPLE_HZ * 60 / COUNTS_PER_REV
    np.testing.assert_allclose(m.speed_rpm, geared_rpm * np.array([0.87, 1.01, 1.15]),
                               rtol=0.02)
    m.set_input(pulse_counts=0)
    m.run(0.6)
    assert np.all(np.abs(m.speed_rpm) < 1.0)


@pytest.mark.statements("mac800:reg2:14")
def test_dead_band_mode_is_analogue_velocity_beyond_the_band() -> None:
    """Mode 16: ±10 V is ±V_SOLL as in mode 5; about 0 V the motor stands (dead band)."""
    m = MotorArray("MAC800", n=2, seed=0)
    m.set_input(analog_volts=np.array([10.0, -0.5]))
    m.write_many({"V_SOLL": RPM_1000, "MODE_REG": 16})
    m.run(0.6)
    assert m.speed_rpm[0] == pytest.approx(1000.0, rel=0.02)
    assert abs(m.speed_rpm[1]) < 1.0


@pytest.mark.statements("mac800:reg7:1", "mac800:reg7:2")
def test_t_soll_limits_the_torque() -> None:
    """T_SOLL is the maximum allowed torque, 0 … 1023: VF_OUT never exceeds it; 1024 and −1
    are refused."""
    m = MotorArray("MAC800", n=1, seed=0)
    m.write_many({"T_SOLL": 200, "V_SOLL": RPM_1000, "MODE_REG": 1})
    m.set_input(load_torque=2.5)  # 2.5 N·m > 200/1023 of the peak torque
    vf = m.trace(["VF_OUT"], 100)["VF_OUT"][:, 0]
    assert np.abs(vf).max() == 200
    for bad in (1024, -1):
        with pytest.raises(RegisterError):
            m.write("T_SOLL", bad)
    assert m.read("T_SOLL")[0] == 200


@pytest.mark.statements("mac800:reg10:1")
def test_p_ist_counts_the_shaft_in_encoder_counts() -> None:
    """P_IST is the actual position in encoder counts (8000 a turn)."""
    m = MotorArray("MAC800", n=1, seed=0)
    m.write_many({"P_SOLL": 20000, "V_SOLL": RPM_1000, "MODE_REG": 2})
    m.run(1.0)
    assert m.read("P_IST")[0] == pytest.approx(m.position_rad[0] * COUNTS_PER_REV / (2 * np.pi),
                                               abs=1)
    assert abs(m.position_rad[0] - 2.5 * 2 * np.pi) < 0.01  # 20000 counts = 2.5 turns


@pytest.mark.statements("mac800:reg13:1")
def test_kvout_scales_the_servo_filter_output() -> None:
    """KVOUT, the servo filter's overall (inertia) factor: VF_OUT in proportion to it."""
    from jvl_gym.families.mac800.firmware.main_filter import clear_filter, main_filter

    out = []
    for kvout in (1.0, 2.0, 0.5):
        m = MotorArray("MAC800", n=1, seed=0)
        m.write_many({"KVOUT": kvout})
        r, s = m.regs[0], m.state[0]
        clear_filter(s)
        main_filter(r, s, 160.0, False, 1023.0)
        out.append(m.read("VF_OUT")[0])
    assert out[0] != 0 and out[1] == 2 * out[0] and out[2] == pytest.approx(out[0] / 2, abs=1)


# ------------------------------------------------------------------ Error Handling
@pytest.mark.statements("mac800:reg20:1")
def test_flwerr_is_the_function_position_less_the_actual() -> None:
    """FLWERR, the actual follow error in encoder counts: in position mode the function
    position less the actual one."""
    m = MotorArray("MAC800", n=1, seed=0)
    m.write_many({"V_SOLL": RPM_1000, "P_SOLL": 400000, "MODE_REG": 2})
    for _ in range(3):
        m.run(0.1)
        flw = m.read("FLWERR")[0]
        assert flw == m.read("P_FUNC")[0] - m.read("P_IST")[0]
        assert flw > 0  # the motor lags its profile


@pytest.mark.statements("mac800:reg21:1")
def test_u_24v_reads_the_logic_supply() -> None:
    """U_24V: VDC = U_24V × 0.013428."""
    m = MotorArray("MAC800", n=1, seed=0)
    for volts in (24.0, 20.0):
        m.set_input(control_volts=volts)
        m.step()
        assert m.read("U_24V")[0] * 0.013428 == pytest.approx(volts, abs=0.01)


@pytest.mark.statements("mac800:reg29:1")
def test_degc_reads_degrees_celsius() -> None:
    """DEGC: °C = DEGC × 0.12207."""
    for celsius in (25.0, 60.0):
        m = MotorArray("MAC800", n=1, seed=0, initial_temperature=celsius)
        m.step()
        assert m.read("DEGC")[0] * 0.12207 == pytest.approx(celsius, abs=0.2)


@pytest.mark.statements("mac800:reg32:1", "mac800:reg32:2")
def test_acc_emerg_360_brakes_at_100000_rpm_per_s() -> None:
    """ACC_EMERG: the deceleration after a fatal error, in A_SOLL's unit; 360 is 100 000 RPM/s
    (the velocity profile falls by 360/16 count/sample each sample)."""
    m = MotorArray("MAC800", n=1, seed=0)
    m.write_many({"ACC_EMERG": 360, "V_SOLL": RPM_1000, "MODE_REG": 1})
    m.run(0.3)
    m.write("I2TLIM", 0)  # I2T ≥ I2TLIM: overload, a stopping error
    f = m.trace(["FNC_OUT"], 5)["FNC_OUT"][:, 0]
    assert m.read("ERR_STAT")[0] & c.I2T_ERR
    slope = np.diff(f)
    assert np.all(slope == -360 / 16)
    rpm_per_s = -slope * u.SAMPLE_HZ**2 * 60.0 / COUNTS_PER_REV
    assert np.all(rpm_per_s == pytest.approx(100000.0, rel=0.01))


@pytest.mark.statements("mac800:reg33:2")
def test_in_position_at_the_velocity() -> None:
    """INPOSWIN in a velocity mode: the in-position bit is set when the speed is within the
    window of V_SOLL, clear while the motor ramps up."""
    m = MotorArray("MAC800", n=1, seed=0)
    m.write_many({"V_SOLL": RPM_1000, "A_SOLL": 20, "INPOSWIN": 5, "MODE_REG": 1})
    tr = m.trace(["ERR_STAT", "V_IST"], 400)
    st, v = tr["ERR_STAT"][:, 0], tr["V_IST"][:, 0]
    assert not st[10] & c.IN_POS  # ramping up at 20/16 count/sample²
    assert st[-1] & c.IN_POS and abs(RPM_1000 / 16 - v[-1]) < 5


@pytest.mark.statements("mac800:reg35:15")
def test_speed_err_is_above_3600_rpm() -> None:
    """ERR_STAT bit 13 SPEED_ERR: over 3600 RPM, not below."""
    for rpm, expected in ((3500.0, False), (3700.0, True)):
        m = MotorArray("MAC800", n=1, seed=0, initial_speed=rpm * 2 * np.pi / 60)
        m.step(2)
        assert bool(m.read("ERR_STAT")[0] & c.SPEED_ERR) is expected


# ------------------------------------------------------------------ Power + zero search
@pytest.mark.statements("mac800:reg36:7")
def test_syncposauto_keeps_the_set_point_at_the_actual_position() -> None:
    """CNTRL_BITS bit 5 SYNCPOSAUTO: while passive, P_SOLL follows P_IST, so entering position
    mode does not pull the motor back; without the bit P_SOLL stays."""
    for auto in (True, False):
        m = MotorArray("MAC800", n=1, seed=0, initial_speed=20.0)
        m.write("CNTRL_BITS", c.SYNCPOSAUTO if auto else 0)
        m.run(0.3)
        p = m.read("P_IST")[0]
        assert p > 5000
        assert m.read("P_SOLL")[0] == (p if auto else 0)


#: the default setup's filter (a ``setup`` replaces the setup file)
_DEFAULT_FILTER = {"KFF5": 1.0, "KVB4": 1.0, "KVFX6": 0.1073, "KVFX5": -0.0998, "KVFY5": 1.0,
                   "KIFX2": 3.621, "KIFX1": -3.057, "KIFY1": 1.0, "KIB1": 1.0, "AMPLITUDE": 776}


@pytest.mark.statements("mac800:reg37:1")
def test_start_mode_is_the_mode_after_power_up() -> None:
    """START_MODE: the mode the motor is in after power-up."""
    m = MotorArray("MAC800", n=1, seed=0,
                   setup={**_DEFAULT_FILTER, "START_MODE": 1, "V_SOLL": 277})
    assert m.read("MODE_REG")[0] == 1
    m.run(0.5)
    assert m.speed_rpm[0] == pytest.approx(100.0, rel=0.05)
    assert MotorArray("MAC800", n=1, seed=0).read("MODE_REG")[0] == 0  # START_MODE 0


@pytest.mark.statements("mac800:reg40:1")
def test_v_home_is_the_search_speed() -> None:
    """V_HOME: the zero search's speed, in V_SOLL's unit (1 RPM = 2.77056)."""
    m = MotorArray("MAC800", n=1, seed=0, home_position=20.0)
    m.write_many({"V_HOME": 600, "T_HOME": 100, "MODE_REG": 13})
    rpm = m.trace(["speed_rpm"], 200)["speed_rpm"][:, 0]
    assert rpm[-50:].mean() == pytest.approx(600 / 2.77056, rel=0.01)


@pytest.mark.statements("mac800:reg41:2")
def test_t_home_sign_sets_the_sensor_polarity() -> None:
    """T_HOME's sign is the sensor's polarity: with T_HOME < 0 the sensor is active at a low
    input, so a search that runs into the low region from the high one finds the zero there."""
    m = MotorArray("MAC800", n=1, seed=0, home_position=2.0, initial_angle=3.0,
                   coulomb_friction=0.2)
    m.write_many({"V_HOME": -600, "T_HOME": -100, "P_HOME": 0, "MODE_REG": 13})
    m.run(3.0)
    assert m.read("HOME_MODE")[0] & c.HOME_DONE
    zero_rad = m.position_rad[0] - m.read("P_IST")[0] * c.RAD_PER_COUNT
    travel = 600 / 16 * c.RAD_PER_COUNT  # a sample's travel at V_HOME
    assert zero_rad == pytest.approx(2.0, abs=2 * travel)
    m = MotorArray("MAC800", n=1, seed=0, home_position=2.0, initial_angle=3.0)
    m.write_many({"V_HOME": -600, "T_HOME": 100, "MODE_REG": 13})  # active high: on it
    m.run(1.0)
    assert not m.read("HOME_MODE")[0] & c.HOME_DONE and m.position_rad[0] > 3.0


# ------------------------------------------------------------------ Diverse
@pytest.mark.statements("mac800:reg202:1")
def test_my_addr_is_the_address_on_the_serial_link() -> None:
    """MY_ADDR, the motor address: the motor answers at it and at no other."""
    t, m = twin([8])
    assert m.read("MY_ADDR")[0] == 8
    m.write("MY_ADDR", 12)
    assert ask(t, m32.encode_read(8, 5)) == b""
    assert m32.decode(ask(t, m32.encode_read(12, 202))).data == bytes([12, 0, 0, 0])


# ------------------------------------------------------------------ §1.3 serial link
@pytest.mark.statements("mac800:1.2:1", "mac800:1.2:3", "mac800:1.3.1:3", "mac800:1.3.1:4")
def test_every_register_reads_over_the_serial_link_and_nothing_changes() -> None:
    """Every register 1 … 255 is read over the serial link with 4 data bytes, the reply
    naming it; reading changes nothing."""
    t, m = twin([8])
    m.write_many({"V_SOLL": 277, "MODE_REG": 1})
    m.run(0.2)
    regs, state = m.regs.copy(), m.state.copy()
    for number in range(1, 256):
        reply = m32.decode(ask(t, m32.encode_read(8, number)))
        assert reply.register == number and len(reply.data) == 4
        if number <= 206:
            assert m32.data_value(reply.data) == m.read_raw(number)[0]
    np.testing.assert_array_equal(m.regs, regs)
    np.testing.assert_array_equal(m.state, state)


@pytest.mark.statements("mac800:1.3.1:1", "mac800:1.3.4:1", "mac800:1.3.4:4")
def test_the_motor_is_run_by_register_writes_over_the_serial_link() -> None:
    """"The MAC motor is completely controlled by reading and writing to registers": the
    quick guide's frames set velocity mode and 1000 RPM, and the motor runs."""
    t, m = twin([8])
    for frame, address, register, value in WRITE_EXAMPLES:
        if address == 8 and register in (2, 5) and value in (1, RPM_1000):
            assert ask(t, frame) == m32.ACCEPT
    m.run(0.6)
    assert m.read("MODE_REG")[0] == 1 and m.speed_rpm[0] == pytest.approx(1000.0, rel=0.02)


@pytest.mark.statements("mac800:1.3.1:2")
def test_the_serial_port_is_19200_baud_8_data_bits_no_parity() -> None:
    """RS232 at 19200 baud, 8 data bits, no parity."""
    from jvl_gym.protocol.mactalk.master import DEFAULT_BAUDRATE, open_port

    port = open_port("loop://", timeout=0.1)
    try:
        assert DEFAULT_BAUDRATE == 19200 and port.baudrate == 19200
        assert port.bytesize == 8 and port.parity == "N"
    finally:
        port.close()


@pytest.mark.statements("mac800:1.3.1:5")
def test_a_wrong_complement_is_refused() -> None:
    """Every protected byte is followed by its complement 255 − x: a frame with a wrong one
    gets no answer and changes nothing."""
    t, m = twin([8])
    good = m32.encode_write_value(8, 5, 600)
    assert ask(t, good) == m32.ACCEPT
    before = m.regs.copy()
    for k in range(4, len(good) - 2, 2):  # each complement byte of the protected fields
        bad = bytearray(m32.encode_write_value(8, 5, 700))
        bad[k] ^= 0x01
        assert ask(t, bytes(bad)) == b""
    np.testing.assert_array_equal(m.regs, before)


@pytest.mark.parametrize("frame, address, register, value", WRITE_EXAMPLES)
@pytest.mark.statements("mac800:1.3.2:1", "mac800:1.3.2:2", "mac800:1.3.2:3", "mac800:1.3.2:4",
                        "mac800:1.3.4:1", "mac800:1.3.4:2", "mac800:1.3.4:4")
def test_quick_guide_writes_are_taken_by_a_mac800(frame: bytes, address: int, register: int,
                                                  value: int) -> None:
    """The quick guide's write frames (§1.3.2 examples 1 and 2, §1.3.4), byte for byte, sent to
    two MAC800 at addresses 7 and 8: accepted with 11h,11h,11h; the addressed motor's register
    holds the value (low byte first), the other motor's is unchanged."""
    t, m = twin([7, 8])
    assert frame[:3] == b"\x52\x52\x52" and frame[-2:] == b"\xaa\xaa"
    before = m.read_raw(register).copy()
    assert ask(t, frame) == b"\x11\x11\x11"
    i = [7, 8].index(address)
    assert m.read_raw(register)[i] == value
    assert m.read_raw(register)[1 - i] == before[1 - i]


@pytest.mark.parametrize("request_, reply, address, register, value",
                         [e for e in READ_EXAMPLES if e[2] == 8])
@pytest.mark.statements("mac800:1.3.3:1", "mac800:1.3.3:2", "mac800:1.3.3:3", "mac800:1.3.4:3",
                        "mac800:1.3.4:5")
def test_quick_guide_reads_are_answered_by_a_mac800(request_: bytes, reply: bytes,
                                                    address: int, register: int,
                                                    value: int) -> None:
    """The quick guide's read frames (§1.3.3, §1.3.4) to a MAC800 at address 8 holding the
    value: the reply is a write frame to address 0 naming the register, Len 4, byte for byte
    (the misprinted complement and register byte of §1.3.3 as decided)."""
    t, m = twin([8])
    if register == 10:  # P_IST: set by a manual position sync to P_NEW
        m.write_many({"P_NEW": value, "CNTRL_BITS": c.SYNCPOSMAN})
        m.step()
    elif register == 35:  # ERR_STAT: in position after a move
        m.write_many({"P_SOLL": 4000, "V_SOLL": RPM_1000, "MODE_REG": 2})
        m.run(1.0)
    else:
        m.write(register, value)
    assert m.read_raw(register)[0] == value
    assert ask(t, request_) == reply
    assert reply[3:5] == b"\x00\xff" and reply[7:9] == b"\x04\xfb"



@pytest.mark.statements("mac800:reg16:3")
def test_i2t_tends_to_100_percent_at_the_rated_torque() -> None:
    """I2T's 100 % is the continuous rating: held at the nominal (rated) torque, I2T rises as
    65536·(1 − e^(−t/τ)) towards 65536 (τ the motor's thermal time constant); at 1.2 times the
    rated torque it heads for 144 %."""
    m = MotorArray("MAC800", n=2, seed=0)
    cfg = m.motor_configs[0]
    m.write_many({"V_SOLL": 0, "MODE_REG": 1})
    m.set_input(load_torque=np.array([1.0, 1.2]) * cfg.rated_torque)
    m.run(0.2)
    i0 = m.read("I2T").astype(float)
    m.run(2.0)
    decay = np.exp(-2.0 / cfg.thermal_time_constant)
    final = (m.read("I2T") - i0 * decay) / (1.0 - decay)  # the level I2T is heading for
    assert final[0] == pytest.approx(65536, rel=0.03)
    assert final[1] == pytest.approx(1.44 * 65536, rel=0.03)


@pytest.mark.statements("mac800:reg2:4", "mac800:reg5:3")
def test_v_soll_is_the_top_speed_of_a_move_which_lands_without_overshoot() -> None:
    """Position mode (MAC050–141 position function block): the profile is limited to ±V_SOLL
    (MacTalk's "Max velocity") and A_SOLL, and reaches P_SOLL without passing it."""
    m = MotorArray("MAC800", n=1, seed=0)
    m.write_many({"V_SOLL": 1385, "A_SOLL": 360, "P_SOLL": 60000, "MODE_REG": 2})
    tr = m.trace(["FNC_OUT", "P_FUNC", "P_IST"], 1500)
    f = tr["FNC_OUT"][:, 0]
    assert np.abs(f).max() == 1385 / 16  # 500 RPM, the top speed, reached and held
    assert np.all(np.abs(np.diff(f)) <= 360 / 16 + 1e-9)
    assert tr["P_FUNC"][:, 0].max() == 60000
    assert tr["P_IST"][:, 0].max() <= 60000 + 5 and abs(tr["P_IST"][-1, 0] - 60000) <= 2


@pytest.mark.statements("mac800:reg28:1")
def test_min_p_ist_is_the_negative_limit() -> None:
    """MIN_P_IST (register 28) limits the travel in the negative direction: below it PLIM_ERR
    is set and the motor stops."""
    m = MotorArray("MAC800", n=1, seed=0)
    m.write_many({"MIN_P_IST": -3000, "MAX_P_IST": 1000000, "V_SOLL": -831, "MODE_REG": 1})
    for _ in range(int(1.0 * c.OUTER_HZ)):
        m.step()
        if m.read("ERR_STAT")[0] & c.PLIM_ERR:
            break
    assert m.read("ERR_STAT")[0] & c.PLIM_ERR and m.read("P_IST")[0] < -3000
    m.run(0.3)
    assert m.read("MODE_REG")[0] == 0


@pytest.mark.statements("mac800:reg2:21")
def test_analogue_to_position_relative_to_p_soll() -> None:
    """Mode 21 with CNTRL_BITS RELPOSPSOLL (MAC050–141 analogue 2 position block): a rising
    level adds P2 (POS1) to P_SOLL, a falling one P1 (POS0)."""
    m = MotorArray("MAC800", n=1, seed=0)
    m.write_many({"POS0": -1000, "POS1": 5000, "P_SOLL": 0, "V_SOLL": RPM_1000,
                  "CNTRL_BITS": c.RELPOSPSOLL, "MODE_REG": 21})
    m.run(0.2)
    assert m.read("P_SOLL")[0] == 0  # entry: the level without an edge
    for volts, target in ((8.0, 5000), (2.0, 4000), (8.0, 9000)):
        m.set_input(analog_volts=volts)
        m.run(0.6)
        assert m.read("P_SOLL")[0] == target
    assert abs(m.read("P_IST")[0] - 9000) < 10


@pytest.mark.statements("mac800:reg2:20")
def test_analogue_to_position_level_has_hysteresis() -> None:
    """Mode 21 reads the input as a level with hysteresis: high above 5.4 V, low below 4.4 V;
    between them the level stays (MAC050–141 analogue 2 position block)."""
    m = MotorArray("MAC800", n=1, seed=0)
    m.write_many({"POS0": 0, "POS1": 8000, "V_SOLL": RPM_1000, "MODE_REG": 21})
    for volts, target in ((5.3, 0), (5.5, 8000), (4.5, 8000), (4.3, 0), (5.3, 0)):
        m.set_input(analog_volts=volts)
        m.run(0.05)
        assert m.read("P_SOLL")[0] == target, volts
