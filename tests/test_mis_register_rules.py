"""MIS behaviours the register chapter states (MIS manual §5.9, §5.11.2, §8.2.24, §8.2.68,
§8.2.77–78, §8.2.105, §8.2.122, §12.5): position limits in position and gear mode, the in-target
time, the dedicated outputs, the setup bits, the revolution counter, passive via the stop ramp
and the Modbus worked example."""

from __future__ import annotations

import numpy as np
import pytest

from jvl_gym import MotorArray
from jvl_gym.families.mis import constants as c
from jvl_gym.protocol.mactalk.twin16 import Twin
from jvl_gym.protocol.modbus import codec as mb
from jvl_gym.protocol.modbus.twin import modbus_bus

#: 0.01 RPM per ms per RPM/s: a ramp of A RPM/s changes V_IST by A/10 units per ms
_UNITS_PER_MS = 0.1


def _motor(**regs: int) -> MotorArray:
    m = MotorArray("MIS232", n=1, seed=0)
    m.write_many(regs)
    return m


def _largest_velocity_step(v: np.ndarray) -> float:
    return float(np.abs(np.diff(v.astype(float))).max())


# --- §5.9.3, §5.9.5: software limits in position and gear mode ----------------------------
@pytest.mark.statements(
    "mis:8.2.27:2", "mis:8.2.68:13", "mis:5.9.3:2", "mis:5.9.5:1", "mis:5.9.5:2")
def test_position_limit_in_position_mode_stops_at_the_limit_with_the_normal_deceleration(
        ) -> None:
    """§5.9.3: "in position mode … the motor will stop at Position Limit Max"; §5.9.5 (SETUP_BITS
    bit 17): "The normal acceleration is used on position limits in position and gear mode".
    At 300 RPM towards a 400 000-count limit P_IST never passes it, the motor stays in
    position mode, and the ramp down is D_SOLL's, not ACC_EMERG's."""
    m = _motor(MAX_P_IST=400000, MIN_P_IST=-100000, V_SOLL=30000, A_SOLL=10000, D_SOLL=1000,
               ACC_EMERG=50000, SETUP_BITS=c.SETUP_NO_LIMIT_ERROR, P_SOLL=1000000)
    m.write("MODE_REG", c.POSITION)
    tr = m.trace(["P_IST", "V_IST"], 2000)
    assert tr["P_IST"].max() == 400000 and m.read("P_IST")[0] == 400000
    assert m.read("MODE_REG")[0] == c.POSITION and m.read("ERR_BITS")[0] == 0
    assert m.read("WARN_BITS")[0] & c.WARN_POS_LIMIT
    v = tr["V_IST"][:, 0]
    assert v.max() == 30000  # it did run at 300 RPM
    down = np.diff(v[int(np.argmax(v)):].astype(float))
    # the last jump from the start/stop velocity aside, D_SOLL's slope (the braking curve
    # lands on the limit within a few %), far below ACC_EMERG's 5000 units per ms
    assert np.sort(-down)[-2] <= 1.1 * 1000 * _UNITS_PER_MS
    assert np.count_nonzero(down < 0) > 250  # 300 RPM at 1000 RPM/s: about 290 ms


@pytest.mark.statements("mis:8.2.27:2", "mis:8.2.31:6", "mis:5.9.4:2", "mis:7.2.6:1")
def test_position_limit_in_position_mode_without_bit_17_is_an_error_at_the_limit() -> None:
    """§5.9.4: "The motor will stop and activate an error, when reaching a limit" — and it
    stops at the limit, not beyond (§5.9.3)."""
    m = _motor(MAX_P_IST=100000, MIN_P_IST=-100000, V_SOLL=30000, A_SOLL=1000,
               P_SOLL=300000)
    m.write("MODE_REG", c.POSITION)
    tr = m.trace(["P_IST"], 1500)
    assert tr["P_IST"].max() == 100000
    assert m.read("ERR_BITS")[0] & c.ERR_POSITION_LIMIT
    assert m.read("MODE_REG")[0] == c.PASSIVE


@pytest.mark.statements("mis:8.2.26:2", "mis:5.9.3:2", "mis:5.9.3:3", "mis:6.6:1")
def test_position_limit_in_gear_mode_is_never_passed() -> None:
    """§5.9.3: "in position mode or gear mode, the motor will stop at Position Limit Min"."""
    m = _motor(MAX_P_IST=100000, MIN_P_IST=-50000, V_SOLL=30000, A_SOLL=2000,
               GEAR1=409600, GEAR2=2048, SETUP_BITS=c.SETUP_NO_LIMIT_ERROR)
    m.write("MODE_REG", c.GEAR)
    m.set_input(pulse_counts=-3)
    tr = m.trace(["P_IST"], 800)
    assert tr["P_IST"].min() == -50000 and m.read("P_IST")[0] == -50000
    assert m.read("P_SOLL")[0] < -50000 and m.read("MODE_REG")[0] == c.GEAR


# --- §8.2.24 bit 22, §8.2.105 (register 177) ---------------------------------------------
@pytest.mark.statements("mis:8.2.24:22", "mis:8.2.105:2")
def test_in_target_position_waits_for_the_standstill_time() -> None:
    """§8.2.105: INTARGETPOSITIONTIME is the "time the motor must stand still before
    InTargetPosition (reg 25) flag is set"."""
    for wait in (10, 60):
        m = _motor(P_SOLL=409600, V_SOLL=30000, A_SOLL=3000, INTARGETPOSITIONTIME=wait)
        m.write("MODE_REG", c.POSITION)
        tr = m.trace(["STATUSBITS", "P_IST"], 1200)
        st, p = tr["STATUSBITS"][:, 0], tr["P_IST"][:, 0]
        last_move = int(np.flatnonzero(np.diff(p) != 0).max()) + 1
        first = int(np.flatnonzero(st & c.ST_IN_TARGET_POSITION).min())
        assert first - last_move == wait
        assert st[-1] & c.ST_IN_TARGET_POSITION


# --- §8.2.77–78: the dedicated outputs ----------------------------------------------------
@pytest.mark.statements(
    "mis:8.2.17:3", "mis:8.2.69:3", "mis:8.2.77:2", "mis:8.2.78:3", "mis:5.6.2:1")
def test_in_position_and_error_outputs_drive_outputs() -> None:
    """INPOS_MASK: "The In Position output will then be set after a movement has completed";
    ERROR_MASK: "set when any error is set"; both only on pins IOSETUP makes outputs
    (register 125, bits 8–15)."""
    m = _motor(IOSETUP=(0b11 << 8), INPOS_MASK=0b01, ERROR_MASK=0b10, P_SOLL=200000,
               V_SOLL=30000, A_SOLL=3000)
    m.write("MODE_REG", c.POSITION)
    m.step(20)
    assert m.read("OUTPUTS")[0] & 0b11 == 0  # moving, no error
    m.step(1500)
    assert m.read("OUTPUTS")[0] & 0b11 == 0b01
    m.write_many({"FLWERRMAX": 1, "ENCODER_POS": 100000})
    m.step(2)
    assert m.read("ERR_BITS")[0] & c.ERR_FOLLOW
    assert m.read("OUTPUTS")[0] & 0b10
    unset = _motor(INPOS_MASK=0b01, P_SOLL=2000)  # IO1 not an output: not driven
    unset.write("MODE_REG", c.POSITION)
    unset.step(200)
    assert unset.read("OUTPUTS")[0] == 0


# --- §8.2.68 SETUP_BITS --------------------------------------------------------------------
@pytest.mark.statements("mis:8.2.68:2")
def test_setup_bit_0_inverts_the_motor_direction() -> None:
    """Bit 0: "Invert motor direction": a positive move turns the shaft negative; the
    encoder counts with the motor, so the follow error stays small."""
    m = _motor(SETUP_BITS=c.SETUP_INVERT_DIRECTION, P_SOLL=409600, V_SOLL=30000, A_SOLL=3000)
    m.write("MODE_REG", c.POSITION)
    m.step(1500)
    assert m.read("P_IST")[0] == 409600
    assert abs(m.rotor_counts[0] + 409600) < 1000
    assert abs(m.read("ENCODER_POS")[0] - 409600) < 1000
    assert abs(m.read("FLWERR")[0]) < 1000


@pytest.mark.statements("mis:8.2.68:6", "mis:5.2.3:2")
def test_setup_bit_6_recalculates_in_physical_position_while_moving() -> None:
    """Bit 6: "InPhysPosMode (If set, recalc InPhysPos continuously. If 0, only after
    stop)"."""
    seen = {}
    for bits in (0, c.SETUP_IN_PHYS_POS_CONTINUOUS):
        m = _motor(SETUP_BITS=bits, P_SOLL=409600, V_SOLL=30000, A_SOLL=3000)
        m.write("MODE_REG", c.POSITION)
        tr = m.trace(["STATUSBITS", "V_IST"], 1200)
        st, v = tr["STATUSBITS"][:, 0], tr["V_IST"][:, 0]
        seen[bits] = bool(np.any(((st & c.ST_IN_PHYSICAL_POSITION) != 0) & (v != 0)))
        assert st[-1] & c.ST_IN_PHYSICAL_POSITION
    assert seen == {0: False, c.SETUP_IN_PHYS_POS_CONTINUOUS: True}


@pytest.mark.statements("mis:8.2.32:4", "mis:8.2.68:21", "mis:8.2.73:2", "mis:5.9.6:1")
def test_setup_bit_28_limits_without_memory() -> None:
    """Bit 28 (§5.9.6): "the sensor has-been warning is automatically cleared when the
    direction of the motor is reversed and the limit switch is no longer active"."""
    for bits, kept in ((c.SETUP_NO_LIMIT_ERROR, True),
                       (c.SETUP_NO_LIMIT_ERROR | c.SETUP_LIMITS_WITHOUT_MEMORY, False)):
        m = _motor(PL_MASK=0b100, V_SOLL=5000, V_START=10000, SETUP_BITS=bits)
        m.write("MODE_REG", c.VELOCITY)
        m.step(20)
        m.set_input(digital_inputs=0b100)
        m.step(5)
        m.set_input(digital_inputs=0)
        m.write("V_SOLL", -5000)
        m.step(10)
        assert bool(m.read("WARN_BITS")[0] & c.WARN_POS_LIMIT_SEEN) is kept


# --- §8.2.122 MOTOR_REV ---------------------------------------------------------------------
@pytest.mark.statements("mis:8.2.122:1", "mis:8.2.122:2")
def test_motor_rev_counts_revolutions_and_is_writable() -> None:
    """"Counts multiples of 409600 counts since power on", R/W."""
    m = _motor(V_SOLL=30000, A_SOLL=3000)
    m.write("P_SOLL", 3 * 409600 + 1000)
    m.write("MODE_REG", c.POSITION)
    m.step(2500)
    assert m.read("MOTOR_REV")[0] == 3
    m.write("P_SOLL", 409600 + 1000)  # two revolutions back: they count as run too
    m.step(2500)
    assert m.read("MOTOR_REV")[0] == 5
    m.write("MOTOR_REV", 100)
    assert m.read("MOTOR_REV")[0] == 100


# --- §5.11.2: passive via the stop ramp ----------------------------------------------------
@pytest.mark.statements("mis:8.2.3:9", "mis:5.11.2:2")
def test_mode_0_on_a_running_motor_decelerates_with_the_stop_ramp_first() -> None:
    """§5.11.2: "When changing to Passive mode the motor goes into Stop mode to decelerate
    according to the 'Deceleration'-ramp. When 'Actual velocity' is 0 … the motor goes
    passive"."""
    m = _motor(V_SOLL=30000, A_SOLL=5000, D_SOLL=1000)
    m.write("MODE_REG", c.VELOCITY)
    m.step(200)
    m.write("MODE_REG", c.PASSIVE)
    assert m.read("MODE_REG")[0] == c.STOP
    tr = m.trace(["V_IST", "MODE_REG"], 400)
    v, mode = tr["V_IST"][:, 0], tr["MODE_REG"][:, 0]
    assert v[0] > 29000 and v[-1] == 0 and mode[-1] == c.PASSIVE
    assert int(np.flatnonzero(v == 0).min()) > 250  # 300 RPM at 1000 RPM/s: about 290 ms
    assert np.sort(np.abs(np.diff(v.astype(float))))[-2] <= 1000 * _UNITS_PER_MS + 1
    idle = _motor()
    idle.write("MODE_REG", c.VELOCITY)
    idle.write("MODE_REG", c.PASSIVE)  # at standstill: passive at once
    assert idle.read("MODE_REG")[0] == c.PASSIVE


# --- §12.5: the worked example of Write Multiple Registers ------------------------------
@pytest.mark.statements("mis:8.2.42:1", "mis:12.1:6", "mis:12.5:1")
def test_modbus_write_multiple_example_is_accepted_as_the_manual_replies() -> None:
    """§12.5: V1 (65) = 409 600 and V2 (66) = 13 on slave 60; the manual shows the motor's
    reply {0x3C, 0x10, 0x00, 0x82, 0x00, 0x04, CRC}."""
    m = MotorArray("MIS232", n=1, seed=0)
    m.write("MY_ADDR", 60)
    bus = modbus_bus(Twin(m))
    request = bytes((0x3C, 0x10, 0x00, 0x82, 0x00, 0x04, 0x08, 0x40, 0x00, 0x00, 0x06, 0x00,
                     0x0D, 0x00, 0x00))
    reply, _ = bus.handle(mb.append_crc(request), now=0.0)
    assert reply == mb.append_crc(bytes((0x3C, 0x10, 0x00, 0x82, 0x00, 0x04)))
    assert m.read("V1")[0] == 409600 and m.read("V2")[0] == 13
    m.write("COMMAND", c.CMD_REGISTER_SET[0])  # V_SOLL = V1, within V_SOLL's range
    assert m.read("V_SOLL")[0] == 300000


# --- §8.2.21, §8.2.41–44: the register sets ------------------------------------------------
@pytest.mark.parametrize("command, names", [
    (108, ("P1", "V1", "A1", "T1")), (109, ("P2", "V2", "A2", "T2")),
    (110, ("P3", "V3", "A3", "T3")), (111, ("P4", "V4", "A4", "T4"))])
@pytest.mark.statements(
    "mis:8.2.20:1", "mis:8.2.20:2", "mis:8.2.21:6", "mis:8.2.21:7", "mis:8.2.21:8",
    "mis:8.2.21:9", "mis:8.2.41:9", "mis:8.2.42:2", "mis:8.2.43:2", "mis:8.2.44:2")
def test_fastmac_register_sets_load_the_profile(command: int, names: tuple[str, ...]) -> None:
    """FastMac 12–15 (commands 108–111): P_SOLL, V_SOLL, A_SOLL and the running current from
    position, velocity, acceleration and current register n."""
    m = _motor(**dict(zip(names, (123456, 4321, 2222, 300))))
    m.write("COMMAND", command)
    got = [m.read(k)[0] for k in ("P_SOLL", "V_SOLL", "A_SOLL", "RUN_CURRENT")]
    assert got == [123456, 4321, 2222, 300] and m.read("COMMAND")[0] == 0


@pytest.mark.parametrize("command, name", [(113, "P7"), (114, "P8")])
@pytest.mark.statements("mis:8.2.21:10", "mis:8.2.21:11", "mis:8.2.41:10")
def test_fastmac_relative_moves_add_p7_and_p8(command: int, name: str) -> None:
    """FastMac 17/18 (commands 113/114): P_SOLL = P_IST + position register 7 / 8."""
    m = _motor(P_IST=1000, **{name: -400})
    m.write("COMMAND", command)
    assert m.read("P_SOLL")[0] == 600


# --- §8.2.45–46, §2.3.5: the eight analogue inputs -------------------------------------
@pytest.mark.parametrize("k", range(1, 9))
@pytest.mark.statements(
    "mis:8.2.45:1", "mis:8.2.45:2", "mis:8.2.46:1", "mis:8.2.52:2", "mis:2.3.5:2", "mis:2.3.5:3")
def test_each_analogue_input_has_its_registers(k: int) -> None:
    """ANALOGUE_INPUTn (register 88 + n) is the raw 0 … 5 V value of IOn; ANALOGUE_FILTEREDn
    (80 + n) its filtered value; AFZUP_CONFMIN discards raw samples below it."""
    names = {"ANALOGUE_INPUT1": 89, "ANALOGUE_INPUT2": 90, "ANALOGUE_INPUT3": 91,
             "ANALOGUE_INPUT4": 92, "ANALOGUE_INPUT5": 93, "ANALOGUE_INPUT6": 94,
             "ANALOGUE_INPUT7": 95, "ANALOGUE_INPUT8": 96, "ANALOGUE_FILTERED1": 81,
             "ANALOGUE_FILTERED2": 82, "ANALOGUE_FILTERED3": 83, "ANALOGUE_FILTERED4": 84,
             "ANALOGUE_FILTERED5": 85, "ANALOGUE_FILTERED6": 86, "ANALOGUE_FILTERED7": 87,
             "ANALOGUE_FILTERED8": 88}
    raw, filt = f"ANALOGUE_INPUT{k}", f"ANALOGUE_FILTERED{k}"
    assert (names[raw], names[filt]) == (88 + k, 80 + k)
    m = _motor()
    m.set_input(**{f"analog{k}": 2000 * 5.0 / 4095})
    m.step(200)
    assert m.read(raw)[0] == 2000 and m.read(filt)[0] == 2000
    low = _motor(AFZUP_CONFMIN=2500, AFZUP_WRITEBITS=255)  # to every input (§8.2.50)
    low.set_input(**{f"analog{k}": 2000 * 5.0 / 4095})
    low.step(200)
    assert low.read(raw)[0] == 2000 and low.read(filt)[0] == 0


# --- §8.2.60–64: the fourth channel and the buffer size ----------------------------------
@pytest.mark.statements("mis:8.2.60:2", "mis:8.2.63:2", "mis:8.2.64:1")
def test_sample4_records_and_the_buffer_holds_buf_size_samples() -> None:
    m = _motor(SAMPLE1=0, SAMPLE2=0, SAMPLE3=0, SAMPLE4=10, REC_CNT=1024, S_TIME=1,
               V_SOLL=5000, V_START=10000)
    m.write("MODE_REG", c.VELOCITY)
    m.write("S_CONTROL", 2)
    m.step(m.read("BUF_SIZE")[0] + 20)
    buf = m.sample_buffer()
    assert buf["P_IST"].shape == (1, m.read("BUF_SIZE")[0]) == (1, 1024)
    assert np.all(np.diff(buf["P_IST"][0]) > 0) and m.read("S_CONTROL")[0] == 0


# --- §5.9.2, §8.2.72: the negative limit input --------------------------------------------
@pytest.mark.statements("mis:8.2.32:3", "mis:8.2.72:2", "mis:5.9.2:1", "mis:5.9.2:3")
def test_negative_limit_input_of_nl_mask() -> None:
    m = _motor(NL_MASK=0b1000, V_SOLL=-5000, V_START=10000, SETUP_BITS=c.SETUP_NO_LIMIT_ERROR)
    m.write("MODE_REG", c.VELOCITY)
    m.step(20)
    m.set_input(digital_inputs=0b1000)
    m.step(5)
    assert m.read("WARN_BITS")[0] & c.WARN_NEG_LIMIT and m.read("V_IST")[0] == 0
    m.write("V_SOLL", 5000)  # away from it
    m.step(5)
    assert m.read("V_IST")[0] == 5000


# --- §8.2.121, §8.2.131: the velocities ---------------------------------------------------
@pytest.mark.statements("mis:8.2.121:2", "mis:8.2.131:2")
def test_v_ist_calc_and_v_encoder_follow_the_motion() -> None:
    m = _motor(V_SOLL=12000, A_SOLL=5000)
    m.write("MODE_REG", c.VELOCITY)
    m.step(800)
    assert m.read("V_IST_CALC")[0] == m.read("V_IST")[0] == 12000
    venc = m.trace(["V_ENCODER"], 200)["V_ENCODER"][:, 0]
    assert abs(venc.mean() - 12000) < 300


# --- §8.2.108–114: the closed-loop current scale ------------------------------------------
@pytest.mark.statements(
    "mis:8.2.108:2", "mis:8.2.109:2", "mis:8.2.110:2", "mis:8.2.112:3", "mis:8.2.113:2",
    "mis:5.3.7:1")
def test_closed_loop_current_scale_stays_within_its_limits() -> None:
    """ACTUAL_TORQUE stays within CUR_SCALE_MIN … CUR_SCALE_MAX; a larger CUR_SCALE_INC
    (time per step up) and CUR_SCALE_DEC / CUR_SCALE_FACTOR (time per step down) slow the
    scale's changes."""
    cl = c.SETUP_CLOSED_LOOP | c.SETUP_CURRENT_CONTROL
    m = MotorArray("MIS232", n=2, seed=0)
    m.write_many({"SETUP_BITS": cl, "CUR_SCALE_MAX": 1500, "CUR_SCALE_MIN": 400,
                  "CUR_SCALE_INC": np.array([2000, 20000]),
                  "CUR_SCALE_DEC": np.array([4000, 40000]),
                  "CUR_SCALE_FACTOR": 500, "V_SOLL": 30000, "A_SOLL": 2000, "MODE_REG": 1})
    tr = m.trace(["ACTUAL_TORQUE"], 1500)["ACTUAL_TORQUE"]
    assert tr[300:, 0].min() >= 400 and tr[300:, 0].max() <= 1500 and tr.min() >= 400
    assert np.abs(np.diff(tr[:, 1])).max() < np.abs(np.diff(tr[:, 0])).max()


# --- §5.6 type 2 zero search: the crawl velocity ------------------------------------------
@pytest.mark.statements("mis:8.2.125:2", "mis:6.5.1:2")
def test_zero_search_type_2_leaves_the_sensor_at_v_home_crawl() -> None:
    """V_HOME_CRAWL (§8.2.125): type 2 leaves the sensor at this velocity (0: V_HOME/64)."""
    m = MotorArray("MIS232", n=1, seed=0, home_position=-0.5)
    m.write_many({"HOME_MASK": 1, "V_HOME": -20000, "V_HOME_CRAWL": 700,
                  "IN_POSITION_COUNT": 0})
    m.write("MODE_REG", c.ZERO_SEARCH_2)
    v = m.trace(["V_IST"], 3000)["V_IST"][:, 0]
    assert v.min() < -5000 and 700 in v.tolist() and v.max() == 700


# --- §8.2.96: not saved -------------------------------------------------------------------
@pytest.mark.statements("mis:8.2.96:2")
def test_notsaved_is_zero_after_a_reset() -> None:
    """NOTSAVED: "not used by the firmware", 0 after power-on, even when saved in flash."""
    m = _motor(NOTSAVED=77)
    assert m.read("NOTSAVED")[0] == 77
    m.enter_safe_mode()
    m.write_flash()
    assert m.read("NOTSAVED")[0] == 0


# --- §8.2.67 bit 5, §5.10.2 bit 23 -------------------------------------------------------
@pytest.mark.statements("mis:8.2.67:6")
def test_zero_search_bit_5_disables_the_time_out() -> None:
    """ZERO_SEARCH_BITS bit 5: "Disable zero search time out"."""
    m = _motor(HOME_MASK=1, V_HOME=-3000, V_HOME_TIMEOUT=200, ZERO_SEARCH_BITS=1 << 5)
    m.write("MODE_REG", c.ZERO_SEARCH_1)
    m.step(400)
    assert m.read("ERR_BITS")[0] == 0 and m.read("MODE_REG")[0] == c.ZERO_SEARCH_1


@pytest.mark.statements("mis:8.2.68:18", "mis:5.10:3")
def test_low_bus_voltage_bit_23_sets_v_soll_to_0() -> None:
    """SETUP_BITS bit 23: "Low bus voltage" sets V_SOLL to 0 RPM; the motor decelerates and
    stays in its mode (§5.10)."""
    m = _motor(V_SOLL=10000, SETUP_BITS=1 << 23)
    m.write("MODE_REG", c.VELOCITY)
    m.step(50)
    m.set_input(supply_volts=10.0)
    m.step(300)
    assert m.read("V_SOLL")[0] == 0 and m.read("V_IST")[0] == 0
    assert m.read("MODE_REG")[0] == c.VELOCITY and m.read("ERR_BITS")[0] == 0


# --- §8.2.68 SETUP_BITS 5, 12, 16 ----------------------------------------------------------
@pytest.mark.statements("mis:8.2.68:5")
def test_setup_bit_5_syncs_the_encoder_to_p_ist_on_entering_an_active_mode() -> None:
    """Bit 5: "Synchronize encoder position to P_IST after change to active mode. Follow
    error = 0"."""
    for bits, synced in ((0, False), (c.SETUP_SYNC_ENCODER, True)):
        m = _motor(SETUP_BITS=bits, P_IST=50000, P_SOLL=50000)
        m.write("MODE_REG", c.POSITION)
        assert bool(m.read("ENCODER_POS")[0] == 50000) is synced
        if synced:
            m.step(5)
            assert abs(m.read("FLWERR")[0]) < 1000


@pytest.mark.statements("mis:8.2.68:9")
def test_setup_bit_12_keeps_the_external_encoder_over_a_reset() -> None:
    """Bit 12 KeepExtEncoder: "Do not zero the external encoder count on startup"."""
    for bits, kept in ((0, 0), (c.SETUP_KEEP_EXT_ENCODER, 1234)):
        m = _motor(SETUP_BITS=bits, EXT_ENCODER=1234)
        m.enter_safe_mode()
        m.write_flash()
        assert m.read("EXT_ENCODER")[0] == kept


@pytest.mark.statements("mis:8.2.68:12")
def test_setup_bit_16_inverts_the_external_encoder_count() -> None:
    """Bit 16: "External Encoder counting direction (1 = inverse)"."""
    for bits, sign in ((0, 1), (c.SETUP_EXT_ENCODER_INVERSE, -1)):
        m = _motor(SETUP_BITS=bits, GEAR1=1, GEAR2=1, V_SOLL=100000, A_SOLL=100000)
        m.write("MODE_REG", c.GEAR)
        m.set_input(pulse_counts=5)
        m.step(10)
        assert m.read("EXT_ENCODER")[0] == sign * 50 and m.read("P_SOLL")[0] == sign * 50


# --- §8.2.67 bits 1, 2 and 4: turn at a limit, the back side of the sensor, no sensor ---
_SENSOR = (30_000, 90_000)  #: rotor counts where the zero-search sensor (input 3) is active


def _search_over_a_sensor(mode: int, bits: int, start_input: bool = False,
                          sensor: tuple[int, int] = _SENSOR,
                          limit: int | None = None) -> tuple[float, int, int]:
    """A zero search of ``mode`` with ZERO_SEARCH_BITS ``bits`` from the rotor at 0 upwards
    over a sensor on input 3 active between the rotor counts ``sensor`` (and below them with
    ``start_input``), with a positive limit switch on input 1 from the count ``limit`` up:
    where on the shaft P_IST = 0 ended up [rotor counts], the MODE_REG after it (STARTMODE 1
    when done) and ERR_BITS."""
    m = _motor(HOME_MASK=0b100, PL_MASK=0b1, V_HOME=3000, V_HOME_CRAWL=300, P_HOME=0,
               STARTMODE=1, V_SOLL=0, IN_POSITION_COUNT=0, ZERO_SEARCH_BITS=bits)
    m.write("MODE_REG", mode)
    for _ in range(20_000):
        rotor = m.rotor_counts[0]
        on_sensor = sensor[0] <= rotor <= sensor[1] or (start_input and rotor < sensor[0])
        on_limit = limit is not None and rotor >= limit
        m.set_input(digital_inputs=(0b100 if on_sensor else 0) | (0b1 if on_limit else 0))
        m.step()
        if m.read("MODE_REG")[0] != mode:
            break
    return (float(m.rotor_counts[0] - m.read("P_IST")[0]), int(m.read("MODE_REG")[0]),
            int(m.read("ERR_BITS")[0]))


@pytest.mark.parametrize(("mode", "near"), [(c.ZERO_SEARCH_1, 200.0), (c.ZERO_SEARCH_2, 50.0)])
@pytest.mark.statements("mis:8.2.67:4", "mis:6.5.1:1", "mis:6.5.1:2", "mis:6.5.4:2")
def test_zero_search_bit_2_finds_the_back_side_of_the_sensor(mode: int, near: float) -> None:
    """ZERO_SEARCH_BITS bit 2, "Search for opposite side of sensor": the zero is on the
    sensor's back side instead of its front side, in both types; type 2 takes the edge at its
    crawl velocity, so closer."""
    front, done, _ = _search_over_a_sensor(mode, 0)
    assert done == 1 and front == pytest.approx(_SENSOR[0], abs=near)
    back, done, _ = _search_over_a_sensor(mode, c.ZS_OPPOSITE_SIDE)
    assert done == 1 and back == pytest.approx(_SENSOR[1], abs=near)


@pytest.mark.parametrize("mode", [c.ZERO_SEARCH_1, c.ZERO_SEARCH_2])
@pytest.mark.statements("mis:8.2.67:5", "mis:6.5.4:3")
def test_zero_search_bit_4_takes_the_position_where_the_motor_is(mode: int) -> None:
    """ZERO_SEARCH_BITS bit 4, "Ignore switch": the sensor input is not looked at, the actual
    position becomes the zero at once (here with the input active from the start, which would
    otherwise make type 2 leave the sensor first)."""
    zero, done, _ = _search_over_a_sensor(mode, c.ZS_IGNORE_SWITCH, start_input=True)
    assert done == 1 and zero == 0.0


@pytest.mark.parametrize("mode", [c.ZERO_SEARCH_1, c.ZERO_SEARCH_2])
@pytest.mark.statements("mis:8.2.67:3", "mis:6.5.4:1")
def test_zero_search_bit_1_turns_at_a_limit_switch(mode: int) -> None:
    """ZERO_SEARCH_BITS bit 1, "Change direction on limit": a search that meets the limit
    switch ahead before its sensor turns and finds the sensor behind it, from the other side
    (its front side is then the upper edge); without the bit the limit stops the motor with
    the position-limit error (ERR_BITS bit 3) and it goes passive."""
    behind = (-90_000, -30_000)
    zero, done, err = _search_over_a_sensor(mode, c.ZS_TURN_AT_LIMIT, sensor=behind,
                                            limit=50_000)
    assert done == 1 and err == 0 and zero == pytest.approx(behind[1], abs=200)
    _, done, err = _search_over_a_sensor(mode, 0, sensor=behind, limit=50_000)
    assert done == c.PASSIVE and err & c.ERR_POSITION_LIMIT


# --- §8.2.65, §8.2.67 bit 0: zero search with the encoder index -------------------------------
@pytest.mark.statements("mis:8.2.67:2", "mis:8.2.65:2")
def test_zero_search_bit_0_goes_on_to_the_encoder_index() -> None:
    """ZERO_SEARCH_BITS bit 0, "Search for index": after the sensor the search goes on to the
    encoder's index (single-turn position 0), which is the zero; INDEX_OFFSET holds the encoder's
    single-turn position where the sensor was found (§8.2.65). Without the bit the sensor's
    point is the zero."""
    rev = 409600
    sensor = -0.5 * rev / (2 * np.pi)  # home_position = -0.5 rad
    zero = {}
    for bits in (0, 1):
        m = MotorArray("MIS232", n=1, seed=0, home_position=-0.5)
        m.write_many({"HOME_MASK": 1, "V_HOME": -20000, "V_HOME_CRAWL": 5000,
                      "ZERO_SEARCH_BITS": bits, "IN_POSITION_COUNT": 0})
        m.write("MODE_REG", c.ZERO_SEARCH_1)
        m.step(3000)
        assert m.read("STATUSBITS")[0] & c.ST_ZERO_SEARCH_DONE, bits
        zero[bits] = m.rotor_counts[0] - m.read("P_IST")[0]  # the rotor where P_IST is 0
        if bits:
            assert abs(m.read("INDEX_OFFSET")[0] - (rev + sensor)) < 2000
    assert abs(zero[0] - sensor) < 3000
    assert abs(zero[1] - (-rev)) < 1000  # the next index on, one revolution below 0
