"""MIS behaviours the register chapter states (MIS manual §5.9, §5.11.2, §8.2.24, §8.2.68,
§8.2.77–78, §8.2.105, §8.2.122, §12.5): position limits in position and gear mode, the in-target
time, the dedicated outputs, the setup bits, the revolution counter, passive via the stop ramp
and the Modbus worked example."""

from __future__ import annotations

import numpy as np

from jvl_gym import MotorArray
from jvl_gym.families.mis import constants as c
from jvl_gym.protocol import modbus as mb
from jvl_gym.protocol.modbus_twin import modbus_bus
from jvl_gym.protocol.twin import Twin

#: 0.01 RPM per ms per RPM/s: a ramp of A RPM/s changes V_IST by A/10 units per ms
_UNITS_PER_MS = 0.1


def _motor(**regs: int) -> MotorArray:
    m = MotorArray("MIS232", n=1, seed=0)
    m.write_many(regs)
    return m


def _largest_velocity_step(v: np.ndarray) -> float:
    return float(np.abs(np.diff(v.astype(float))).max())


# --- §5.9.3, §5.9.5: software limits in position and gear mode ----------------------------
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
