"""Statements of the MIS/SMC manual that no other test asserts: the register tables' defaults,
ranges and access (MIS manual §8.2), and short checks of the numbers and conditions of the
register descriptions (§8.2) and of the function chapters (§5, §6). Each test carries the ids of
the statements it asserts (``families/mis/statements.yaml``)."""

from __future__ import annotations

import numpy as np
import pytest

from jvl_gym import MotorArray
from jvl_gym.families.mis import constants as c
from jvl_gym.motor.array import ModeError
from jvl_gym.registers import RegisterError

#: 0.01 RPM per ms per RPM/s: a ramp of A RPM/s changes V_IST by A/10 units per ms
_UNITS_PER_MS = 0.1
#: counts per ms at 0.01 RPM
_COUNTS_PER_MS_PER_UNIT = 409600 / 60000 / 100
#: peak amperes of one RUN_CURRENT unit (5.87 mA RMS)
_PEAK_AMPS_PER_UNIT = np.sqrt(2.0) * 5.87e-3


def _motor(motor: str = "MIS232", **regs: int) -> MotorArray:
    m = MotorArray(motor, n=1, seed=0)
    m.write_many(regs)
    return m


# --- §8.2: the register tables --------------------------------------------------------------
#: defaults the register descriptions print (where the overview and the detail agree)
_DEFAULTS = {
    "MODE_REG": 0, "P_SOLL": 0, "V_SOLL": 10000, "A_SOLL": 1000, "RUN_CURRENT": 511,
    "STANDBY_TIME": 500, "STANDBY_CURRENT": 128, "GEAR1": 409600, "GEAR2": 2048, "OUTPUTS": 0,
    "FLWERRMAX": 0, "MIN_P_IST": 0, "MAX_P_IST": 0, "ACC_EMERG": 10000,
    "IN_POSITION_WINDOW": 20000, "IN_POSITION_COUNT": 2, "ERR_BITS": 0, "WARN_BITS": 0,
    "STARTMODE": 0, "P_HOME": 0, "T_HOME": 1024, "HOMEMODE": 0, "ABSENCODER": 0,
    "EXTENCODER2": 0, "FLEXREGISTER": 0,
    **{f"P{n}": 0 for n in range(1, 9)}, **{f"V{n}": 25000 for n in range(1, 9)},
    **{f"A{n}": 1000 for n in range(1, 5)}, **{f"T{n}": 511 for n in range(1, 5)},
    **{f"ANALOGUE_FILTERED{n}": 0 for n in range(1, 9)},
    "AFZUP_WRITEBITS": 0, "AFZUP_READINDEX": 0, "AFZUP_CONFMIN": 0, "AFZUP_CONFMAX": 4095,
    "AFZUP_MAXSLOPE": 4095, "AFZUP_FILTER": 64, "FILTERSTATUS": 0, "SETTLINGTIME": 0,
    **{f"SAMPLE{n}": 0 for n in range(1, 5)}, "REC_CNT": 0, "S_TIME": 1, "S_CONTROL": 0,
    "ZERO_SEARCH_BITS": 0, "SETUP_BITS": 0, "IOSETUP": 0, "TURNTABLE_MODE": 0,
    "TURNTABLE_SIZE": 0, "NL_MASK": 0, "PL_MASK": 0, "HOME_MASK": 0, "INPUT_FILTER_MASK": 0,
    "INPUT_FILTER_CNT": 5, "INPOS_MASK": 0, "ERROR_MASK": 0, "ACCEPT_VOLTAGE": 2052,
    "ACCEPT_COUNT": 100, "SAVE_VOLTAGE": 1710, "P_NEW": 0, "BAUD_RATE": 1, "TX_DELAY": 15,
    "MY_ADDR": 254, "NOTSAVED": 0, "FBUS_NODE_ID": 5, "FBUS_BAUD": 2,
    "INTARGETPOSITIONTIME": 10, "BRAKE": 0, "CUR_SCALE_MAX": 2047, "CUR_SCALE_MIN": 1,
    "CUR_SCALE_FACTOR": 500, "CUR_SCALE_INC": 2000, "CUR_SCALE_DEC": 4000, "XFIELD_ADDR": 0,
    "XFIELD_DATA": 0, **{f"FLEXREGSETUP{n}": 0 for n in range(1, 9)},
    "FLEXLEDSETUP1": 102303769, "FLEXLEDSETUP2": 504954880, "V_SOLL_AUTO": 0, "V_IST_CALC": 0,
    "MOTOR_REV": 0, "EX_CYCLIC_SETUP": 0, "EX_CRC_ERR": 0, "V_HOME_CRAWL": 0,
    "V_HOME_TIMEOUT": 0, "LOWBUSCVI_CNT": 10, "D_SOLL": 1000, "TICKS": 0,
    "TURNTAB_COUNT": 0, **{n: 0 for n in (
        "CONTROL_WORD", "STATUS_WORD", "MODE_OF_OPERATION", "MODE_OF_OPERATION_DISPLAY",
        "TARGET_POSITION", "ACTUAL_POSITION", "TARGET_VELOCITY", "ACTUAL_VELOCITY",
        "DIGITAL_OUTPUTS", "DIGITAL_INPUT")},
}

#: where the overview and the detail table disagree, the chosen default (MIS register page)
_CHOSEN_DEFAULTS = {"V_START": 1000, "V_HOME": -5000, "MIN_BUSVOL": 565,
                    "TEMP_LIMITS": 80 + (90 << 16), "CL_CATCH_UP": 5000 << 8}


@pytest.mark.parametrize("motor", ["MIS171", "MIS232", "MIS340"])
@pytest.mark.statements(
    "mis:8.2.3:1", "mis:8.2.4:1", "mis:8.2.5:1", "mis:8.2.6:1", "mis:8.2.7:1", "mis:8.2.8:1",
    "mis:8.2.9:1", "mis:8.2.12:1", "mis:8.2.13:1", "mis:8.2.14:1", "mis:8.2.17:1", "mis:8.2.19:1",
    "mis:8.2.20:1", "mis:8.2.26:1", "mis:8.2.27:1", "mis:8.2.28:1", "mis:8.2.29:1",
    "mis:8.2.30:1", "mis:8.2.31:2", "mis:8.2.32:1", "mis:8.2.33:1", "mis:8.2.34:1",
    "mis:8.2.35:1", "mis:8.2.36:1", "mis:8.2.37:1", "mis:8.2.38:1", "mis:8.2.39:1",
    "mis:8.2.40:1", "mis:8.2.41:1", "mis:8.2.41:2", "mis:8.2.41:3", "mis:8.2.41:4",
    "mis:8.2.41:5", "mis:8.2.41:6", "mis:8.2.41:7", "mis:8.2.41:8", "mis:8.2.42:1",
    "mis:8.2.43:1", "mis:8.2.44:1", "mis:8.2.45:1", "mis:8.2.48:1", "mis:8.2.50:2",
    "mis:8.2.51:2", "mis:8.2.52:1", "mis:8.2.53:1", "mis:8.2.54:1", "mis:8.2.55:1",
    "mis:8.2.56:1", "mis:8.2.58:1", "mis:8.2.60:1", "mis:8.2.61:1", "mis:8.2.62:1",
    "mis:8.2.63:1", "mis:8.2.67:1", "mis:8.2.68:1", "mis:8.2.69:1", "mis:8.2.71:2",
    "mis:8.2.72:1", "mis:8.2.73:1", "mis:8.2.74:1", "mis:8.2.75:1", "mis:8.2.76:1",
    "mis:8.2.77:1", "mis:8.2.78:2", "mis:8.2.79:1", "mis:8.2.80:1", "mis:8.2.81:1",
    "mis:8.2.83:1", "mis:8.2.84:1", "mis:8.2.85:1", "mis:8.2.88:1", "mis:8.2.96:1",
    "mis:8.2.98:1", "mis:8.2.99:1", "mis:8.2.105:1", "mis:8.2.106:1", "mis:8.2.108:1",
    "mis:8.2.109:1", "mis:8.2.110:1", "mis:8.2.113:1", "mis:8.2.114:1", "mis:8.2.115:1",
    "mis:8.2.116:1", "mis:8.2.117:1", "mis:8.2.120:1", "mis:8.2.121:1", "mis:8.2.123:1",
    "mis:8.2.124:1", "mis:8.2.125:1", "mis:8.2.126:1", "mis:8.2.127:1", "mis:8.2.128:1",
    "mis:8.2.130:1", "mis:8.2.1:2", "mis:12.1:10", "mis:5.3.4:2", "mis:5.3.4:3", "mis:5.9.2:1",
    "mis:6.1.1:1", "mis:2.2.2:1")
def test_defaults_of_the_register_tables(motor: str) -> None:
    m = MotorArray(motor, n=1)
    for name, value in {**_DEFAULTS, **_CHOSEN_DEFAULTS}.items():
        assert m.read(name)[0] == value, name


#: ranges of read-write registers the register descriptions print (lowest, highest)
_I32 = (-(2**31), 2**31 - 1)
_RANGES = {
    "P_SOLL": _I32, "V_SOLL": (-300000, 300000), "A_SOLL": (1, 500000),
    "RUN_CURRENT": (0, 1533), "STANDBY_TIME": (1, 65535), "STANDBY_CURRENT": (0, 1533),
    "P_IST": _I32, "GEAR1": _I32, "GEAR2": _I32, "ENCODER_POS": _I32, "FLWERRMAX": _I32,
    "MIN_P_IST": _I32, "MAX_P_IST": _I32, "ACC_EMERG": (1, 500000),
    "IN_POSITION_WINDOW": (0, 2**31 - 1), "IN_POSITION_COUNT": (0, 100), "P_HOME": _I32,
    "V_HOME": (-300000, 300000), "T_HOME": (0, 2047),
    **{f"P{n}": _I32 for n in range(1, 9)}, **{f"A{n}": (1, 500000) for n in range(1, 5)},
    **{f"T{n}": (0, 1533) for n in range(1, 5)},
    "MIN_BUSVOL": (0, 4095), "AFZUP_CONFMIN": (0, 4094), "AFZUP_CONFMAX": (1, 4095),
    "AFZUP_MAXSLOPE": (2, 4095), "AFZUP_FILTER": (1, 64), "SETTLINGTIME": (0, 32676),
    "TURNTABLE_MODE": (0, 5), "P_NEW": _I32, "BAUD_RATE": (0, 7), "TX_DELAY": (1, 255),
    "GROUP_ID": (0, 255), "MY_ADDR": (0, 254), "NOTSAVED": (0, 65535),
    "FBUS_NODE_ID": (1, 127), "FBUS_BAUD": (0, 8), "INTARGETPOSITIONTIME": (0, 2**32 - 1),
    "BRAKE": (0, 2**32 - 1), "CUR_SCALE_MAX": (0, 2047), "CUR_SCALE_MIN": (0, 2047),
    "CUR_SCALE_FACTOR": (1, 10000), "KPHASE": (0, 200), "CUR_SCALE_INC": (1, 100000),
    "CUR_SCALE_DEC": (1, 100000), "V_SOLL_AUTO": (-300000, 300000),
    "MOTOR_REV": (0, 2**32 - 1), "V_HOME_CRAWL": (0, 300000),
    "V_HOME_TIMEOUT": (0, 2**32 - 1), "AFZUP_READINDEX": (0, 32775),
}


@pytest.mark.filterwarnings("ignore:.*is not modelled")
@pytest.mark.statements(
    "mis:8.2.4:1", "mis:8.2.5:1", "mis:8.2.6:1", "mis:8.2.7:1", "mis:8.2.8:1", "mis:8.2.9:1",
    "mis:8.2.10:1", "mis:8.2.13:1", "mis:8.2.14:1", "mis:8.2.19:1", "mis:8.2.26:1",
    "mis:8.2.27:1", "mis:8.2.28:1", "mis:8.2.29:1", "mis:8.2.30:1", "mis:8.2.34:1",
    "mis:8.2.35:1", "mis:8.2.36:1", "mis:8.2.41:1", "mis:8.2.41:2", "mis:8.2.41:3",
    "mis:8.2.41:4", "mis:8.2.41:5", "mis:8.2.41:6", "mis:8.2.41:7", "mis:8.2.41:8",
    "mis:8.2.43:1", "mis:8.2.44:1", "mis:8.2.48:1", "mis:8.2.51:2", "mis:8.2.52:1",
    "mis:8.2.53:1", "mis:8.2.54:1", "mis:8.2.55:1", "mis:8.2.58:1", "mis:8.2.70:1",
    "mis:8.2.83:1", "mis:8.2.84:1", "mis:8.2.85:1", "mis:8.2.86:1", "mis:8.2.88:1",
    "mis:8.2.96:1", "mis:8.2.98:1", "mis:8.2.99:1", "mis:8.2.105:1", "mis:8.2.106:1",
    "mis:8.2.108:1", "mis:8.2.109:1", "mis:8.2.110:1", "mis:8.2.111:1", "mis:8.2.113:1",
    "mis:8.2.114:1", "mis:8.2.120:1", "mis:8.2.122:1", "mis:8.2.125:1", "mis:8.2.126:1")
def test_ranges_of_the_register_tables() -> None:
    """The lowest and the highest value of each range are taken and read back; one beyond
    either end is refused and changes nothing."""
    m = _motor()
    for name, (lo, hi) in _RANGES.items():
        before = int(m.read(name)[0])
        for value in (lo, hi):
            m.write(name, value)
            assert m.read(name)[0] == value, name
        m.write(name, before)
        for value in (lo - 1, hi + 1):
            with pytest.raises(RegisterError):
                m.write(name, value)
            assert m.read(name)[0] == before, name


#: registers the register descriptions mark read-only (R)
_READ_ONLY = ["PROG_VERSION", "V_IST", "INPUTS", "FLWERR", "STATUSBITS", "TEMP", "ABSENCODER",
              "EXTENCODER2", "FLEXREGISTER", *[f"ANALOGUE_FILTERED{n}" for n in range(1, 9)],
              *[f"ANALOGUE_INPUT{n}" for n in range(1, 9)], "BUSVOL", "ENCODER_TYPE",
              "FILTERSTATUS", "BUF_SIZE", "INDEX_OFFSET", "CVI_VOLT", "GROUP_SEQ",
              "MOTORTYPE", "SERIAL_NUMBER", "CHECKSUM_1", "CHECKSUM_2", "HARDWARE_REV",
              "MAX_VOLTAGE", "AVAILABLE_IO", "BOOTLOADER_VER", "OPTION_BITS", "MODULE_TYPE",
              "EXT_ENCODER_VEL", "FW_BUILD", "ACTUAL_TORQUE", "TEMP_LIMITS", "TEMP_HIGHRES",
              "V_ENCODER", "EX_CYCLIC_SETUP", "V_IST_CALC", "EX_CRC_ERR",
              "STATUS_WORD", "MODE_OF_OPERATION_DISPLAY", "ACTUAL_POSITION", "ACTUAL_VELOCITY",
              "DIGITAL_INPUT"]


@pytest.mark.statements(
    "mis:8.2.2:1", "mis:8.2.11:1", "mis:8.2.16:1", "mis:8.2.18:1", "mis:8.2.24:1", "mis:8.2.25:1",
    "mis:8.2.38:1", "mis:8.2.39:1", "mis:8.2.40:1", "mis:8.2.45:1", "mis:8.2.46:1",
    "mis:8.2.47:1", "mis:8.2.49:1", "mis:8.2.56:1", "mis:8.2.64:1", "mis:8.2.65:1",
    "mis:8.2.82:1", "mis:8.2.87:1", "mis:8.2.89:1", "mis:8.2.90:1", "mis:8.2.91:1",
    "mis:8.2.92:1", "mis:8.2.93:1", "mis:8.2.94:1", "mis:8.2.95:1", "mis:8.2.97:1",
    "mis:8.2.100:1", "mis:8.2.102:1", "mis:8.2.104:1", "mis:8.2.112:3", "mis:8.2.121:1",
    "mis:8.2.123:1", "mis:8.2.124:1", "mis:8.2.127:1", "mis:8.2.129:1", "mis:8.2.131:1",
    "mis:8.2.1:5")
def test_read_only_registers_refuse_a_write() -> None:
    m = _motor()
    for name in _READ_ONLY:
        before = int(m.read(name)[0])
        with pytest.raises(RegisterError, match="ro"):
            m.write(name, before + 1)
        assert m.read(name)[0] == before, name


# --- §8.2.3 MODE_REG ---------------------------------------------------------------------------
@pytest.mark.statements("mis:8.2.3:2")
def test_passive_mode_has_no_current_and_ignores_commands() -> None:
    """§8.2.3: "the motor current is turned off and the motor will not react to any position/
    velocity commands"."""
    m = _motor(P_SOLL=100000, V_SOLL=30000)
    m.step(100)
    assert m.current_amplitude[0] == 0.0
    assert m.read("P_IST")[0] == 0 and m.read("V_IST")[0] == 0 and m.rotor_counts[0] == 0


@pytest.mark.statements("mis:8.2.3:3", "mis:8.2.5:2", "mis:8.2.11:2", "mis:6.2.1:1")
def test_velocity_mode_follows_v_soll_changed_at_any_time() -> None:
    """§8.2.3/§8.2.5: in velocity mode the motor runs at V_SOLL, which may be changed at any
    time; a negative V_SOLL runs the motor the other way, and V_IST is then negative
    (§8.2.11)."""
    m = _motor(V_SOLL=20000, A_SOLL=10000, D_SOLL=0, V_START=1000)
    m.write("MODE_REG", c.VELOCITY)
    m.step(100)
    assert m.read("V_IST")[0] == 20000
    m.write("V_SOLL", 5000)
    m.step(100)
    assert m.read("V_IST")[0] == 5000
    m.write("V_SOLL", -15000)
    m.step(200)
    assert m.read("V_IST")[0] == -15000
    p0 = m.read("P_IST")[0]
    m.step(100)
    assert m.read("P_IST")[0] < p0


@pytest.mark.statements("mis:8.2.3:6")
def test_position_mode_takes_new_p_soll_and_v_soll_during_a_move() -> None:
    """§8.2.3: "P_SOLL can be changed at any time and the motor will move accordingly. V_SOLL
    can also be changed during a movement." """
    m = _motor(P_SOLL=2_000_000, V_SOLL=30000, A_SOLL=10000, V_START=1000)
    m.write("MODE_REG", c.POSITION)
    m.step(200)
    assert m.read("V_IST")[0] == 30000
    m.write("V_SOLL", 10000)
    m.step(300)
    assert m.read("V_IST")[0] == 10000
    m.write("P_SOLL", 100000)  # behind the motor now: it turns back
    m.step(3000)
    assert m.read("P_IST")[0] == 100000 and m.read("V_IST")[0] == 0


@pytest.mark.statements("mis:8.2.3:12")
def test_safe_mode_is_entered_by_command_only_and_allows_flash_and_reset() -> None:
    """§8.2.3: safe mode "cannot be entered/exited directly; this must be done using the
    serial commands ENTER/EXIT SAFEMODE"; like passive mode it has no current, and it allows
    the save in flash and the reset."""
    m = _motor()
    with pytest.raises(ModeError):
        m.write("MODE_REG", c.SAFE)
    m.enter_safe_mode()
    assert m.read("MODE_REG")[0] == c.SAFE
    m.step(10)
    assert m.current_amplitude[0] == 0.0
    m.write("V_SOLL", 4321)
    m.write_flash()
    assert m.read("V_SOLL")[0] == 4321


@pytest.mark.statements(
    "mis:8.2.3:10", "mis:8.2.3:13", "mis:8.2.24:8", "mis:8.2.35:2", "mis:6.5.8:2")
def test_zero_search_mode_13_ends_in_startmode() -> None:
    """§8.2.3 example: "Writing MODE_REG = 13 will start a zero search … When the search is
    completed, the MODE_REG will automatically be changed to the mode specified in
    START_MODE"; §8.2.34: the zero point found is offset with P_HOME."""
    m = _motor(HOME_MASK=0b1, V_HOME=5000, STARTMODE=c.POSITION, P_HOME=1000,
               IN_POSITION_COUNT=0)
    m.write("MODE_REG", c.ZERO_SEARCH_1)
    m.step(100)
    assert m.read("P_IST")[0] > 0  # a positive V_HOME searches in the positive direction
    m.set_input(digital_inputs=0b1)
    for _ in range(20):
        m.step(100)
        if m.read("MODE_REG")[0] != c.ZERO_SEARCH_1:
            break
    assert m.read("MODE_REG")[0] == c.POSITION
    assert m.read("STATUSBITS")[0] & c.ST_ZERO_SEARCH_DONE


# --- §8.2.4–§8.2.12 the profile --------------------------------------------------------------
@pytest.mark.statements("mis:8.2.4:3")
def test_409600_counts_are_one_revolution() -> None:
    """§8.2.4: "The MISxxx motor family all have 409600 counts per motor revolution"."""
    m = _motor(P_SOLL=409600, V_SOLL=30000, A_SOLL=5000)
    m.write("MODE_REG", c.POSITION)
    m.step(1500)
    assert m.read("P_IST")[0] == 409600
    assert m.position_rad[0] == pytest.approx(2 * np.pi, abs=2 * np.pi / 500)


@pytest.mark.statements("mis:8.2.6:3")
def test_a_soll_is_in_rpm_per_second() -> None:
    """§8.2.6 example: "A_SOLL = 100, will set the acceleration to 100 RPM/s"."""
    m = _motor(A_SOLL=100, V_SOLL=10000, V_START=1000)
    m.write("MODE_REG", c.VELOCITY)
    v = m.trace(["V_IST"], 500)["V_IST"][:, 0]
    assert np.all(np.diff(v[:400]) == 100 * _UNITS_PER_MS)  # 1 RPM per 10 ms


@pytest.mark.statements(
    "mis:8.2.7:2", "mis:8.2.7:4", "mis:8.2.7:5", "mis:5.1.2:1", "mis:5.1.3:1", "mis:5.1.4:2")
def test_run_current_unit_instant_change_and_maximum_per_size() -> None:
    """§8.2.7: unit 5.87 mA ("RUN_CURRENT = 100, will set the running current to 0.587 ARMS");
    a new value is set instantly; the largest setting is 681 on an MIS17x (4 ARMS), 1022 on an
    MIS23x (6 ARMS), 1533 on an MIS34x (9 ARMS)."""
    m = _motor(RUN_CURRENT=100, V_SOLL=10000)
    m.write("MODE_REG", c.VELOCITY)
    m.step(5)
    assert m.current_amplitude[0] == pytest.approx(100 * _PEAK_AMPS_PER_UNIT, rel=1e-3)
    m.write("RUN_CURRENT", 300)
    m.step(1)
    assert m.current_amplitude[0] == pytest.approx(300 * _PEAK_AMPS_PER_UNIT, rel=1e-3)
    for motor, largest in (("MIS171", 681), ("MIS232", 1022), ("MIS340", 1533)):
        big = _motor(motor, RUN_CURRENT=1533, V_SOLL=10000)
        big.write("MODE_REG", c.VELOCITY)
        big.step(5)
        assert big.current_amplitude[0] == pytest.approx(largest * _PEAK_AMPS_PER_UNIT,
                                                         rel=1e-3), motor


@pytest.mark.statements(
    "mis:8.2.7:3", "mis:8.2.8:2", "mis:8.2.8:3", "mis:8.2.9:1", "mis:8.2.9:2", "mis:8.2.24:18",
    "mis:5.1:1")
def test_standby_current_and_its_status_bit() -> None:
    """§8.2.8–9: the standby current is used STANDBY_TIME ms after the last step, and a new
    move uses the running current without delay; STATUSBITS bit 18 tells that the standby
    current is used (§8.2.24); a new STANDBY_CURRENT is set instantly."""
    m = _motor(STANDBY_TIME=100, STANDBY_CURRENT=50, RUN_CURRENT=400, P_SOLL=20000,
               V_SOLL=30000, V_START=30000)
    m.write("MODE_REG", c.POSITION)
    tr = m.trace(["STATUSBITS", "P_IST"], 300)
    p, st = tr["P_IST"][:, 0], tr["STATUSBITS"][:, 0]
    last_step = int(np.flatnonzero(np.diff(p))[-1]) + 1
    first = int(np.flatnonzero(st & c.ST_STANDBY_CURRENT)[0])
    assert first - last_step == pytest.approx(100, abs=2)
    assert m.current_amplitude[0] == pytest.approx(50 * _PEAK_AMPS_PER_UNIT, rel=1e-3)
    m.write("STANDBY_CURRENT", 80)
    m.step(1)
    assert m.current_amplitude[0] == pytest.approx(80 * _PEAK_AMPS_PER_UNIT, rel=1e-3)
    m.write("P_SOLL", 0)
    m.step(1)
    assert m.current_amplitude[0] == pytest.approx(400 * _PEAK_AMPS_PER_UNIT, rel=1e-3)
    assert not m.read("STATUSBITS")[0] & c.ST_STANDBY_CURRENT


@pytest.mark.statements("mis:8.2.10:3")
def test_p_ist_wraps_at_2_to_the_31_in_velocity_mode() -> None:
    """§8.2.10: "When P_IST reaches 2^31 − 1, it will wrap around to −2^31"."""
    m = _motor(V_SOLL=100000, A_SOLL=100000, IN_POSITION_COUNT=0)
    m.write("P_IST", 2**31 - 10000)
    m.write("MODE_REG", c.VELOCITY)
    m.step(50)
    assert m.read("P_IST")[0] < -(2**31) + 400000


# --- §8.2.15–§8.2.19 encoder, inputs, outputs, follow error ----------------------------------
@pytest.mark.statements("mis:8.2.15:1", "mis:8.2.18:2")
def test_encoder_position_starts_at_zero_and_follows_the_shaft() -> None:
    """§8.2.15: ENCODER_POS shows the internal encoder's position, zero at power-up; §8.2.18:
    FLWERR is its deviation from P_IST."""
    m = _motor(P_SOLL=409600, V_SOLL=30000, A_SOLL=5000)
    assert m.read("ENCODER_POS")[0] == 0
    m.write("MODE_REG", c.POSITION)
    m.step(1500)
    assert m.read("ENCODER_POS")[0] == pytest.approx(m.rotor_counts[0], abs=200)
    assert m.read("FLWERR")[0] == m.read("P_IST")[0] - m.read("ENCODER_POS")[0]


@pytest.mark.statements("mis:8.2.16:2", "mis:8.2.16:3", "mis:8.2.69:2", "mis:2.2.5:1")
def test_inputs_show_io1_to_io8_and_nothing_above() -> None:
    """§8.2.16: bits 0–7 of INPUTS are IO1–IO8; bits 8–15 are always 0; the active level is
    set by IOSETUP bits 0–7 (§8.2.69)."""
    m = _motor()
    for level in (0b1, 0b1000_0000, 0b1010_0101, 0xFF):
        m.set_input(digital_inputs=level)
        m.step(1)
        assert m.read("INPUTS")[0] == level
    m.write("IOSETUP", 0b1000_0001)
    m.set_input(digital_inputs=0)
    m.step(1)
    assert m.read("INPUTS")[0] == 0b1000_0001


@pytest.mark.statements("mis:8.2.17:1", "mis:8.2.17:2")
def test_outputs_are_written_through_outputs() -> None:
    """§8.2.17: "The register can be changed in order to change the status of the outputs"
    (bits 0–7 = IO1–IO8)."""
    m = _motor(IOSETUP=0xFF00)
    m.write("OUTPUTS", 0b1001_0110)
    m.step(2)
    assert m.read("OUTPUTS")[0] == 0b1001_0110


@pytest.mark.statements("mis:8.2.19:2", "mis:8.2.19:3", "mis:8.2.31:3", "mis:8.2.31:4")
def test_flwerrmax_zero_disables_the_follow_error() -> None:
    """§8.2.19: "If FLWERRMAX = 0, the error is disabled"; otherwise a follow error beyond it
    sets ERR_BITS bit 1 with the general error bit 0 (§8.2.31)."""
    for limit in (0, 20000):
        m = _motor(FLWERRMAX=limit, P_SOLL=4_000_000, V_SOLL=100000, A_SOLL=1000)
        m.set_input(load_torque=5.0)
        m.write("MODE_REG", c.POSITION)
        m.step(300)
        err = m.read("ERR_BITS")[0]
        if limit == 0:
            assert err == 0 and abs(m.read("FLWERR")[0]) > 20000
        else:
            assert err & c.ERR_FOLLOW and err & c.ERR_GENERAL


# --- §8.2.20–§8.2.22 COMMAND -------------------------------------------------------------------
@pytest.mark.statements("mis:8.2.21:1", "mis:8.2.32:1", "mis:5.9.4:2", "mis:7.2.1:1")
def test_fastmac_1_clears_errors_and_warnings() -> None:
    """§8.2.21: FastMac 1 (97): "Clear errors and warnings"."""
    m = _motor(PL_MASK=0b1, V_SOLL=5000, V_START=10000)
    m.write("MODE_REG", c.VELOCITY)
    m.step(20)
    m.set_input(digital_inputs=0b1)
    m.step(5)
    m.set_input(digital_inputs=0)
    m.step(5)
    assert m.read("ERR_BITS")[0] and m.read("WARN_BITS")[0] & c.WARN_POS_LIMIT_SEEN
    m.write("COMMAND", c.CMD_CLEAR_ERRORS)
    assert m.read("ERR_BITS")[0] == 0 and m.read("WARN_BITS")[0] == 0


@pytest.mark.statements("mis:8.2.20:2", "mis:8.2.22:3", "mis:8.2.22:5", "mis:8.2.22:6")
def test_reset_and_save_commands() -> None:
    """§8.2.22: 267 resets the CPU (the registers come back from flash), 269 saves to flash and
    continues, 268 saves and resets."""
    m = _motor(V_SOLL=4321)
    m.write("COMMAND", c.CMD_RESET)
    assert m.read("V_SOLL")[0] == 10000  # not saved: the default again
    m.write("V_SOLL", 4321)
    m.write("COMMAND", c.CMD_SAVE)
    assert m.read("V_SOLL")[0] == 4321 and m.read("MODE_REG")[0] == c.PASSIVE
    m.write("V_SOLL", 1111)
    m.write("COMMAND", c.CMD_RESET)
    assert m.read("V_SOLL")[0] == 4321
    m.write("A_SOLL", 2222)
    m.write("COMMAND", c.CMD_SAVE_RESET)
    assert m.read("A_SOLL")[0] == 2222
    m.write("COMMAND", c.CMD_RESET)
    assert m.read("A_SOLL")[0] == 2222


# --- §8.2.24 STATUSBITS, §8.2.28, §8.2.31 ERR_BITS -------------------------------------------
@pytest.mark.statements("mis:8.2.24:12", "mis:8.2.31:3")
def test_general_error_status_bit_is_err_bits_bit_0() -> None:
    """§8.2.24 bit 12: "General Error (Same as register 35 bit 0)"; §8.2.31 bit 0: "always set
    together with one of the other bits"."""
    m = _motor(MAX_P_IST=50000, MIN_P_IST=-50000, V_SOLL=20000)
    m.write("MODE_REG", c.VELOCITY)
    for _ in range(60):
        m.step(10)
        err, st = m.read("ERR_BITS")[0], m.read("STATUSBITS")[0]
        assert bool(err & c.ERR_GENERAL) == bool(st & c.ST_GENERAL_ERROR)
        assert bool(err & c.ERR_GENERAL) == bool(err & ~c.ERR_GENERAL)
    assert err & c.ERR_POSITION_LIMIT


@pytest.mark.statements("mis:8.2.24:16", "mis:8.2.24:17", "mis:8.2.24:20", "mis:8.2.68:19")
def test_closed_loop_status_bits() -> None:
    """§8.2.24: bit 16 "Closed loop activated" follows SETUP_BITS bit 24; bit 17 "Internal
    encoder calibrated" and bit 20 "Internal encoder OK" with the encoder option."""
    m = _motor(SETUP_BITS=c.SETUP_CLOSED_LOOP, V_SOLL=10000)
    m.write("MODE_REG", c.VELOCITY)
    m.step(20)
    st = m.read("STATUSBITS")[0]
    assert st & c.ST_CLOSED_LOOP and st & c.ST_ENCODER_CALIBRATED and st & c.ST_ENCODER_OK
    open_loop = _motor(V_SOLL=10000)
    open_loop.write("MODE_REG", c.VELOCITY)
    open_loop.step(20)
    assert not open_loop.read("STATUSBITS")[0] & c.ST_CLOSED_LOOP


@pytest.mark.statements("mis:8.2.28:2", "mis:6.6:2")
def test_an_error_stop_decelerates_with_acc_emerg() -> None:
    """§8.2.28: "The motor will use this acceleration during an emergency stop" — a position
    limit error in velocity mode stops the motor with ACC_EMERG."""
    m = _motor(MAX_P_IST=400000, MIN_P_IST=-400000, V_SOLL=30000, A_SOLL=10000,
               ACC_EMERG=2000)
    m.write("MODE_REG", c.VELOCITY)
    tr = m.trace(["V_IST", "ERR_BITS"], 1200)
    v, err = tr["V_IST"][:, 0], tr["ERR_BITS"][:, 0]
    first = int(np.flatnonzero(err)[0])
    down = -np.diff(v[first:].astype(float))
    down = down[(down > 0)]
    assert np.median(down) == pytest.approx(2000 * _UNITS_PER_MS, abs=1)
    assert v[-1] == 0 and m.read("MODE_REG")[0] == c.PASSIVE


@pytest.mark.statements("mis:8.2.31:2", "mis:8.2.31:25", "mis:7.2.4:2")
def test_writing_zero_to_err_bits_clears_the_errors() -> None:
    """§8.2.31: "Some of the errors can be cleared by writing zero to this register"; the
    motor then takes an active mode again."""
    m = _motor(FLWERRMAX=1000, P_SOLL=4_000_000, V_SOLL=100000, A_SOLL=1000)
    m.set_input(load_torque=5.0)
    m.write("MODE_REG", c.POSITION)
    m.step(200)
    assert m.read("ERR_BITS")[0] & c.ERR_FOLLOW
    m.write("ERR_BITS", 0)
    assert m.read("ERR_BITS")[0] == 0
    m.set_input(load_torque=0.0)
    m.write("MODE_REG", c.POSITION)
    assert m.read("MODE_REG")[0] == c.POSITION


@pytest.mark.statements("mis:8.2.32:3", "mis:8.2.32:5", "mis:8.2.72:2")
def test_negative_limit_warning_bits() -> None:
    """§8.2.32 bits 1 and 3: the negative limit is active as long as its input is, and "has
    been active" is remembered after it is released."""
    m = _motor(NL_MASK=0b10, V_SOLL=-5000, V_START=10000, SETUP_BITS=c.SETUP_NO_LIMIT_ERROR)
    m.write("MODE_REG", c.VELOCITY)
    m.step(20)
    m.set_input(digital_inputs=0b10)
    m.step(5)
    warn = m.read("WARN_BITS")[0]
    assert warn & c.WARN_NEG_LIMIT and warn & c.WARN_NEG_LIMIT_SEEN
    m.write("V_SOLL", 5000)
    m.step(5)
    m.set_input(digital_inputs=0)
    m.step(5)
    warn = m.read("WARN_BITS")[0]
    assert not warn & c.WARN_NEG_LIMIT and warn & c.WARN_NEG_LIMIT_SEEN


# --- §8.2.33–§8.2.37, §8.2.126 zero search ---------------------------------------------------
def _search_on_input(p_home: int, at: int = 20000) -> MotorArray:
    """Zero search type 1 upwards on IO1, which goes active when P_IST passes ``at``."""
    m = _motor(HOME_MASK=0b1, V_HOME=5000, STARTMODE=c.POSITION, P_HOME=p_home,
               IN_POSITION_COUNT=0)
    m.write("MODE_REG", c.ZERO_SEARCH_1)
    for _ in range(5000):
        m.set_input(digital_inputs=int(m.rotor_counts[0] >= at))
        m.step(1)
        if m.read("MODE_REG")[0] != c.ZERO_SEARCH_1:
            break
    m.step(1000)
    return m


@pytest.mark.statements("mis:8.2.34:2", "mis:8.2.74:2", "mis:6.5.8:1", "mis:2.2.2:2")
def test_p_home_offsets_the_zero_point() -> None:
    """§8.2.34: "The zero point found is offset with this value": where P_IST = 0 lies on the
    shaft moves by P_HOME."""
    zeros = {}
    for p_home in (0, 30000):
        m = _search_on_input(p_home)
        assert m.read("MODE_REG")[0] == c.POSITION
        zeros[p_home] = m.rotor_counts[0] - m.read("P_IST")[0]
    # the input is seen in the next 1 ms sample: about 340 counts late at 50 RPM
    assert zeros[0] == pytest.approx(20000, abs=700)
    assert zeros[0] - zeros[30000] == pytest.approx(30000, abs=400)


@pytest.mark.statements("mis:8.2.15:2")
def test_zero_search_sets_the_encoder_with_p_ist() -> None:
    """§8.2.15: ENCODER_POS "is … modified by the firmware when a zero search is performed":
    after the search it counts from the new zero with P_IST."""
    m = _search_on_input(0)
    assert m.read("ENCODER_POS")[0] == pytest.approx(m.read("P_IST")[0], abs=300)
    # counted from power-on it would be about 20000 counts more
    assert m.rotor_counts[0] - m.read("ENCODER_POS")[0] == pytest.approx(20000, abs=700)


@pytest.mark.statements("mis:8.2.37:1", "mis:8.2.37:2", "mis:6.5.2:2")
def test_homemode_values() -> None:
    """§8.2.37: HOMEMODE takes 0, 13 and 14; 14 starts a type 2 search at power-up, 0 none."""
    for value in (1, 2, 12, 15):
        with pytest.raises(RegisterError):
            MotorArray("MIS232", n=1, setup={"HOMEMODE": value})
    assert MotorArray("MIS232", n=1, setup={"HOMEMODE": 14}).read("MODE_REG")[0] == 14
    assert MotorArray("MIS232", n=1, setup={"HOMEMODE": 0}).read("MODE_REG")[0] == 0


@pytest.mark.statements("mis:8.2.31:19", "mis:8.2.126:2")
def test_zero_search_time_out_is_60_s_by_default() -> None:
    """§8.2.126: "If 0, the Zero Search time out is 60000 ms. Else the value in this register is
    used"; the time-out sets ERR_BITS bit 16 (§8.2.31)."""
    m = _motor(HOME_MASK=0b1, V_HOME=-3000, MIN_P_IST=0, MAX_P_IST=0)
    m.write("MODE_REG", c.ZERO_SEARCH_1)
    m.step(59990)
    assert m.read("ERR_BITS")[0] == 0
    m.step(20)
    assert m.read("ERR_BITS")[0] & c.ERR_ZERO_SEARCH_TIMEOUT
    short = _motor(HOME_MASK=0b1, V_HOME=-3000, V_HOME_TIMEOUT=500)
    short.write("MODE_REG", c.ZERO_SEARCH_1)
    short.step(490)
    assert short.read("ERR_BITS")[0] == 0
    short.step(20)
    assert short.read("ERR_BITS")[0] & c.ERR_ZERO_SEARCH_TIMEOUT


@pytest.mark.statements(
    "mis:8.2.21:3", "mis:8.2.21:4", "mis:8.2.21:10", "mis:8.2.21:15", "mis:8.2.21:16",
    "mis:8.2.83:2")
def test_fastmac_position_and_velocity_commands() -> None:
    """§8.2.21: FastMac 3 (99) P_IST = 0, FastMac 5 (101) V_SOLL = 0, FastMac 23 (119) P_IST,
    P_SOLL and the encoder = P_NEW, FastMac 24 (120) each += P_NEW."""
    m = _motor(P_NEW=5000, V_SOLL=12345, P_SOLL=700, P_IST=300)
    m.write("COMMAND", 119)
    assert [m.read(k)[0] for k in ("P_IST", "P_SOLL", "ENCODER_POS")] == [5000] * 3
    m.write("P_NEW", -2000)
    m.write("COMMAND", 120)
    assert [m.read(k)[0] for k in ("P_IST", "P_SOLL", "ENCODER_POS")] == [3000] * 3
    m.write("COMMAND", 99)
    assert m.read("P_IST")[0] == 0 and m.read("P_SOLL")[0] == 3000
    m.write("COMMAND", 101)
    assert m.read("V_SOLL")[0] == 0


@pytest.mark.statements("mis:8.2.22:15", "mis:8.2.22:16", "mis:8.2.28:2")
def test_emergency_stop_commands() -> None:
    """§8.2.22: 398 "Emergency stop with deceleration" (ACC_EMERG, §8.2.28), 399 "Emergency
    stop without deceleration"; both leave the motor passive."""
    m = _motor(V_SOLL=20000, V_START=1000, A_SOLL=1000, ACC_EMERG=3000)
    m.write("MODE_REG", c.VELOCITY)
    m.step(300)
    m.write("COMMAND", 398)
    tr = m.trace(["V_IST", "MODE_REG"], 100)
    assert np.all(np.diff(tr["V_IST"][:60, 0]) == -3000 * _UNITS_PER_MS)
    assert tr["MODE_REG"][-1, 0] == c.PASSIVE and tr["V_IST"][-1, 0] == 0
    m.write("MODE_REG", c.VELOCITY)
    m.step(300)
    m.write("COMMAND", 399)
    assert m.read("MODE_REG")[0] == c.PASSIVE
    m.step(1)
    assert m.read("V_IST")[0] == 0


# --- §8.2.45–§8.2.49 analogue inputs, bus voltage, encoder type -------------------------------
@pytest.mark.statements("mis:8.2.46:2", "mis:2.3.1:1")
def test_analogue_input_full_scale_is_5_v() -> None:
    """§8.2.46: "An input voltage of 5.00 V" reads 4095 (1.221 mV per unit)."""
    m = _motor()
    m.set_input(analog3=5.0, analog5=2.5)
    m.step(5)
    assert m.read("ANALOGUE_INPUT3")[0] == 4095
    assert m.read("ANALOGUE_INPUT5")[0] == pytest.approx(2.5 / 1.221e-3, abs=2)


@pytest.mark.statements("mis:8.2.48:2", "mis:5.10.2:1")
def test_min_busvol_is_the_under_voltage_trigger() -> None:
    """§8.2.48: MIN_BUSVOL is the "Trigger point for under-voltage" (26.525 mV units): the
    warning (WARN_BITS bit 4) comes below it, not above."""
    m = _motor(MIN_BUSVOL=round(30.0 / 26.525e-3))
    m.set_input(supply_volts=32.0)
    m.step(50)
    assert not m.read("WARN_BITS")[0] & c.WARN_LOW_BUS
    m.set_input(supply_volts=28.0)
    m.step(50)
    assert m.read("WARN_BITS")[0] & c.WARN_LOW_BUS


@pytest.mark.statements("mis:8.2.49:2")
def test_encoder_type_codes() -> None:
    """§8.2.49: 0 no encoder, 1 H2 10 bit, 2 H3, 3 H2 12 bit, 4 H4; without an encoder there
    is no encoder position (§8.2.15)."""
    m = MotorArray("MIS232", n=5, encoder_type=np.arange(5))
    assert m.read("ENCODER_TYPE").tolist() == [0, 1, 2, 3, 4]
    m.write_many({"V_SOLL": 30000, "A_SOLL": 10000, "MODE_REG": c.VELOCITY})
    m.step(300)
    enc = m.read("ENCODER_POS")
    assert enc[0] == 0 and np.all(enc[1:] > 50000)
    # 10 bit (H2, and the H3's 1024 cpr, §5.8.1): 400 counts a step; 12 bit: 100 counts
    enc = m.trace(["ENCODER_POS"], 50)["ENCODER_POS"]
    steps = [set(enc[:, k] % step) for k, step in ((1, 400), (2, 400), (3, 100), (4, 100))]
    assert steps == [{0}] * 4


@pytest.mark.statements("mis:8.2.57:2")
def test_ssi_setup1_default() -> None:
    """§8.2.57: the default is "25bit, 100kHz frequency": bits 0–4 = 25 data bits, bits 8–15
    = 10 × 10 kHz."""
    value = int(_motor().read("SSI_SETUP1")[0])
    assert value & 0x1F == 25 and (value >> 8) & 0xFF == 10


# --- §8.2.58–§8.2.64 AutoCorrection settling time, sampling ----------------------------------
@pytest.mark.statements("mis:8.2.58:2", "mis:5.2.2:2")
def test_settling_time_delays_the_auto_correction() -> None:
    """§8.2.58: with AutoCorrection on, SETTLINGTIME ms pass after a move before the encoder
    is tested and a retry starts."""
    starts = {}
    for settle in (0, 200):
        m = _motor(IN_POSITION_COUNT=2, IN_POSITION_WINDOW=1000, SETTLINGTIME=settle,
                   V_SOLL=20000, A_SOLL=3000, V_START=10000)
        m.write("MODE_REG", c.POSITION)
        m.set_input(load_torque=1.3 * m.pull_out_torque(200.0)[0])
        m.write("P_SOLL", 409600)
        m.run(0.06)
        m.set_input(load_torque=0.0)
        v = m.trace(["V_IST"], 3000)["V_IST"][:, 0]
        stop = int(np.flatnonzero(v == 0)[0])
        starts[settle] = int(np.flatnonzero(v[stop:] != 0)[0])
    assert starts[200] - starts[0] == pytest.approx(200, abs=2)


@pytest.mark.statements("mis:8.2.61:3")
def test_rec_cnt_is_limited_to_buf_size() -> None:
    """§8.2.61: REC_CNT "must never be set larger than the value in the read-only register
    119" (BUF_SIZE)."""
    m = _motor()
    size = int(m.read("BUF_SIZE")[0])
    m.write("REC_CNT", size)
    with pytest.raises(RegisterError):
        m.write("REC_CNT", size + 1)
    assert m.read("REC_CNT")[0] == size


@pytest.mark.statements("mis:8.2.62:2")
def test_s_time_is_the_sample_period() -> None:
    """§8.2.62: S_TIME is "the time in milliseconds between samples"."""
    for period in (1, 3):
        m = _motor(SAMPLE1=10, REC_CNT=20, S_TIME=period, V_SOLL=6000, V_START=10000)
        m.write("MODE_REG", c.VELOCITY)
        m.step(5)
        m.write("S_CONTROL", 2)
        m.step(100)
        step = np.diff(m.sample_buffer()["P_IST"][0].astype(float))
        assert step == pytest.approx(6000 * _COUNTS_PER_MS_PER_UNIT * period, abs=1)


# --- §8.2.66–§8.2.83 Modbus set-up, low bus voltage, IO, turn table, P_NEW ---------------------
@pytest.mark.statements("mis:8.2.66:1", "mis:12.1:1", "mis:12.1:2", "mis:12.1:3")
def test_modbus_setup_layout() -> None:
    """§8.2.66 / §12.1: bit 0 enables Modbus on the MacTalk (RS-485) channel, bits 2–3 the
    parity (0 none, 1 odd, 2 even), bit 5 two stop bits; the register is stored."""
    from jvl_gym.protocol.modbus import codec as mb

    assert mb.decode_setup(0b1) == mb.ModbusSetup(True, False, "N", 1)
    assert mb.decode_setup(0b1000) == mb.ModbusSetup(False, False, "E", 1)
    assert mb.decode_setup(0b10_1001) == mb.ModbusSetup(True, False, "E", 2)
    assert mb.decode_setup(0b0100) == mb.ModbusSetup(False, False, "O", 1)
    m = _motor(MODBUS_SETUP=0b10_1001)
    assert m.read("MODBUS_SETUP")[0] == 0b10_1001


@pytest.mark.statements("mis:8.2.68:16", "mis:5.10.2:2")
def test_low_bus_voltage_without_bits_is_a_warning_only() -> None:
    """§8.2.68 bits 21–23 choose what low bus voltage does; with none of them it is only the
    warning (WARN_BITS bit 4), with bit 21 it is also the error (ERR_BITS bit 4)."""
    for bits, error in ((0, False), (1 << 21, True)):
        m = _motor(V_SOLL=10000, SETUP_BITS=bits)
        m.write("MODE_REG", c.VELOCITY)
        m.step(50)
        m.set_input(supply_volts=10.0)
        m.step(100)
        assert m.read("WARN_BITS")[0] & c.WARN_LOW_BUS
        assert bool(m.read("ERR_BITS")[0] & c.ERR_LOW_BUS) is error


@pytest.mark.statements("mis:8.2.69:3")
def test_outputs_need_their_iosetup_bit() -> None:
    """§8.2.69: bits 8–15 select the pins used as outputs: the in-position output drives IO3
    only when IOSETUP bit 10 is set."""
    for iosetup, driven in ((0, 0), (1 << 10, 0b100)):
        m = _motor(IOSETUP=iosetup, INPOS_MASK=0b100, P_SOLL=2000)
        m.write("MODE_REG", c.POSITION)
        m.step(300)
        assert m.read("OUTPUTS")[0] == driven


@pytest.mark.statements("mis:8.2.77:3")
def test_dedicated_output_masks_with_two_bits() -> None:
    """"Exactly one bit must be set" (§8.2.77): the simulator's reading drives every masked
    output pin and does not refuse the write."""
    m = _motor(IOSETUP=0xFF00, INPOS_MASK=0b101, P_SOLL=2000)
    m.write("MODE_REG", c.POSITION)
    m.step(300)
    assert m.read("INPOS_MASK")[0] == 0b101 and m.read("OUTPUTS")[0] == 0b101


@pytest.mark.statements("mis:8.2.70:3")
def test_turntable_mode_0_has_no_wrap() -> None:
    """§8.2.70: "If the value of this register is zero, the motor will not operate in turntable
    mode": a move beyond MAX_P_IST's range is no wrap (the limit stops it instead)."""
    m = _motor(MIN_P_IST=0, MAX_P_IST=409599, V_SOLL=300000, A_SOLL=100000,
               IN_POSITION_COUNT=0, SETUP_BITS=c.SETUP_NO_LIMIT_ERROR)
    m.write("MODE_REG", c.POSITION)
    m.write("P_SOLL", 500000)
    assert m.read("P_SOLL")[0] == 500000
    m.step(1000)
    assert m.read("P_IST")[0] == 409599 and m.read("TURNTAB_COUNT")[0] == 0


@pytest.mark.statements("mis:8.2.76:2", "mis:2.2.5:2")
def test_input_filter_count_is_the_time() -> None:
    """§8.2.76: a filtered input must be sampled at the same value for INPUT_FILTER_CNT ms."""
    for count in (3, 20):
        m = _motor(INPUT_FILTER_MASK=0b1, INPUT_FILTER_CNT=count)
        m.set_input(digital_inputs=0b1)
        inputs = m.trace(["INPUTS"], 40)["INPUTS"][:, 0]
        assert int(np.flatnonzero(inputs)[0]) + 1 == count


@pytest.mark.statements("mis:8.2.83:2")
def test_p_new_moves_nothing() -> None:
    """§8.2.83: P_NEW corrects or offsets the position "without performing a movement"."""
    m = _motor(P_NEW=100000)
    m.write("MODE_REG", c.POSITION)
    m.step(10)
    m.write("COMMAND", 120)
    m.step(300)
    assert m.read("P_IST")[0] == m.read("P_SOLL")[0] == 100000
    assert abs(m.rotor_counts[0]) < 200


# --- §8.2.84–§8.2.100 serial line, identification ---------------------------------------------
@pytest.mark.statements("mis:8.2.84:2", "mis:8.2.84:3", "mis:12.1:10")
def test_baud_rate_codes_of_the_modbus_line() -> None:
    """§8.2.84: 0 9600, 1 19200, 2 38400, 3 57600, 4 115200, 5 230400, 6 460800, 7 921600
    baud."""
    from jvl_gym.protocol.mactalk.twin16 import Twin
    from jvl_gym.protocol.modbus.twin import modbus_bus

    m = _motor()
    slave = modbus_bus(Twin(m)).slaves[0]
    for code, baud in enumerate((9600, 19200, 38400, 57600, 115200, 230400, 460800, 921600)):
        m.write("BAUD_RATE", code)
        assert slave.serial_format().baud == baud


def _ask(twin: object, raw: bytes) -> bytes:
    s = twin.session()  # type: ignore[attr-defined]
    return s.feed(raw) + s.flush()


@pytest.mark.statements("mis:8.2.88:2")
def test_my_addr_and_broadcast() -> None:
    """§8.2.88: data is accepted only when its address is MY_ADDR or 255 (broadcast)."""
    from jvl_gym.protocol.mactalk import codec32 as m32
    from jvl_gym.protocol.mactalk.twin16 import Twin

    m = MotorArray("MIS232", n=2)
    m.write("MY_ADDR", np.array([10, 11]))
    twin = Twin(m)
    assert _ask(twin, m32.encode_write_value(10, 5, 1234)) == m32.ACCEPT
    assert _ask(twin, m32.encode_write_value(12, 5, 4321)) == b""
    assert m.read("V_SOLL").tolist() == [1234, 10000]
    _ask(twin, m32.encode_write_value(255, 6, 777))
    assert m.read("A_SOLL").tolist() == [777, 777]


@pytest.mark.statements("mis:8.2.86:2")
def test_group_write_reaches_the_motors_of_the_group() -> None:
    """§8.2.86: a motor takes a group write only if the group matches its GROUP_ID."""
    from jvl_gym.protocol.mactalk import codec32 as m32
    from jvl_gym.protocol.mactalk.twin16 import Twin

    m = MotorArray("MIS232", n=3)
    m.write("MY_ADDR", np.array([1, 2, 3]))
    m.write("GROUP_ID", np.array([7, 8, 7]))
    twin = Twin(m)
    _ask(twin, m32.encode_group_write(7, 1, 5, (4321).to_bytes(4, "little")))
    assert m.read("V_SOLL").tolist() == [4321, 10000, 4321]


@pytest.mark.statements("mis:8.2.87:2")
def test_group_seq_holds_the_last_group_write_received() -> None:
    """§8.2.87: GROUP_SEQ, a register of the motor, is "the last received group write
    sequence" of a motor of the group; 0 on one that received none."""
    from jvl_gym.protocol.mactalk import codec32 as m32
    from jvl_gym.protocol.mactalk.twin16 import Twin

    m = MotorArray("MIS232", n=2)
    m.write("MY_ADDR", np.array([1, 2]))
    m.write("GROUP_ID", np.array([7, 8]))
    twin = Twin(m)
    _ask(twin, m32.encode_group_write(7, 42, 5, (4321).to_bytes(4, "little")))
    assert m.read("GROUP_SEQ").tolist() == [42, 0]
    _ask(twin, m32.encode_group_write(7, 43, 6, (500).to_bytes(4, "little")))
    assert m.read("GROUP_SEQ").tolist() == [43, 0]
    reply = m32.decode(_ask(twin, m32.encode_read(1, m.table.lookup("GROUP_SEQ").number)))
    assert m32.data_value(reply.data) == 43


@pytest.mark.statements("mis:8.2.89:2")
def test_motortype_codes() -> None:
    """§8.2.89: MIS171 121, MIS232 153, MIS340 81, MIS432 92, SMC66 150, SMC85 80."""
    for motor, code in (("MIS171", 121), ("MIS232", 153), ("MIS340", 81), ("MIS432", 92),
                        ("SMC66", 150), ("SMC85", 80)):
        assert MotorArray(motor, n=1).read("MOTORTYPE")[0] == code, motor


@pytest.mark.statements("mis:8.2.98:2", "mis:11.2.4:1", "mis:11.9.2:1")
def test_canopen_node_id_comes_from_the_register() -> None:
    """§8.2.98: FBUS_NODE_ID is the CANopen node id (default 5): the boot-up message is sent
    on 700h + the node id."""
    from canopen_rig import Rig

    m = MotorArray("MIS232", n=1)
    m.write("FBUS_NODE_ID", 12)
    rig = Rig(motors=m)
    try:
        assert rig.slave.node_id == 12
        rig.clear()
        rig.node(12).nmt.send_command(0x82)
        assert rig.sent(0x70C) == [b"\x00"]
    finally:
        rig.close()


# --- §8.2.103–§8.2.131 ------------------------------------------------------------------------
@pytest.mark.statements("mis:8.2.103:1")
def test_internal_encoder_setup_default() -> None:
    """§8.2.103's figure marks the defaults: hysteresis 1 (bits 0–1), resolution 4 = 12 bit
    (bits 2–4), filter time 1 (bit 5), filter cutoff 1 (bit 6)."""
    value = int(_motor().read("INTERNAL_ENCODER_SETUP")[0])
    assert value & 0b11 == 1 and (value >> 2) & 0b111 == 4
    assert (value >> 5) & 1 == 1 and (value >> 6) & 1 == 1


@pytest.mark.statements("mis:8.2.107:3")
def test_ticks_count_milliseconds() -> None:
    """§8.2.107: TICKS "Increments at a fixed rate of 1 count per millisecond. Starts at zero"."""
    m = _motor()
    assert m.read("TICKS")[0] == 0
    ticks = m.trace(["TICKS"], 250)["TICKS"][:, 0]
    assert np.all(np.diff(ticks) == 1) and ticks[-1] == 250


@pytest.mark.statements("mis:8.2.112:4", "mis:5.3.1:2")
def test_actual_torque_is_full_without_current_control() -> None:
    """§8.2.112: "In active mode without current control enabled = 100 %" (2047), with the
    closed loop on and off."""
    for bits in (0, c.SETUP_CLOSED_LOOP):
        m = _motor(SETUP_BITS=bits, V_SOLL=20000)
        m.write("MODE_REG", c.VELOCITY)
        m.step(300)
        assert m.read("ACTUAL_TORQUE")[0] == 2047


@pytest.mark.statements("mis:8.2.118:1", "mis:8.2.119:1")
def test_flexled_defaults_name_the_manual_bits() -> None:
    """§8.2.118–119: by default L2 shows STATUSBITS (25) bit 3, L3 bit 4, L1 red bit 15 and
    L1 green nothing."""
    m = _motor()
    led1, led2 = int(m.read("FLEXLEDSETUP1")[0]), int(m.read("FLEXLEDSETUP2")[0])
    assert (led1 & 0x1FF, (led1 >> 9) & 0x1F) == (25, 4)  # L3
    assert ((led1 >> 16) & 0x1FF, (led1 >> 25) & 0x1F) == (25, 3)  # L2
    assert ((led2 >> 16) & 0x1FF, (led2 >> 25) & 0x1F) == (25, 15)  # L1 red
    assert led2 & 0xFFFF == 0  # L1 green: off


@pytest.mark.statements("mis:8.2.125:2")
def test_type_2_crawls_at_v_home_over_64() -> None:
    """§8.2.125: "In Zero Search type 2, the "crawl" velocity is V_HOME/64 by default"."""
    m = MotorArray("MIS232", n=1, seed=0, home_position=-0.5)
    m.write_many({"HOME_MASK": 1, "V_HOME": -12800, "IN_POSITION_COUNT": 0})
    m.write("MODE_REG", c.ZERO_SEARCH_2)
    v = m.trace(["V_IST"], 3000)["V_IST"][:, 0]
    assert v.max() == 12800 // 64


@pytest.mark.statements("mis:8.2.1:2")
def test_d_soll_range() -> None:
    """D_SOLL (§8.2.1): 0 … 500 000 RPM/s, 0 included because 0 means "use A_SOLL"."""
    m = _motor(D_SOLL=0)
    m.write("D_SOLL", 500000)
    for bad in (-1, 500001):
        with pytest.raises(RegisterError):
            m.write("D_SOLL", bad)
    assert m.read("D_SOLL")[0] == 500000


@pytest.mark.statements("mis:5.12.5:2")
def test_turntab_count_is_writable() -> None:
    """§5.12.5: TURNTAB_COUNT "can be written … at any time" and counts on from the value."""
    m = _motor(TURNTABLE_MODE=c.TT_MULTI_CW, MIN_P_IST=0, MAX_P_IST=409599, V_SOLL=300000,
               A_SOLL=100000, IN_POSITION_COUNT=0, TURNTAB_COUNT=-5)
    m.write("MODE_REG", c.POSITION)
    m.write("P_SOLL", 970000)
    m.step(1500)
    assert m.read("TURNTAB_COUNT")[0] == -3


# --- §12.1 the Modbus registers ----------------------------------------------------------------
def _modbus(**regs: int) -> tuple[MotorArray, object]:
    from jvl_gym.protocol.mactalk.twin16 import Twin
    from jvl_gym.protocol.modbus.twin import modbus_bus

    m = _motor(MY_ADDR=42, **regs)
    return m, modbus_bus(Twin(m))


@pytest.mark.statements("mis:12.1:5", "mis:12.1:6")
def test_modbus_functions_and_registers() -> None:
    """§12.1: only 03h and 10h; "All other commands will result in Exception replies
    (exception type 1, Illegal Function)"; the slave address is register 150."""
    from jvl_gym.protocol.modbus import codec as mb

    m, bus = _modbus(V_SOLL=1234)
    reply, _ = bus.handle(mb.encode_read_request(42, 2 * 5, 2), now=0.0)
    assert mb.decode_response(reply) == mb.ReadResponse(42, (1234, 0))
    reply, _ = bus.handle(mb.encode_read_request(43, 2 * 5, 2), now=0.0)
    assert reply == b""
    single = mb.append_crc(bytes((42, 0x06, 0x00, 0x0A, 0x00, 0x01)))  # write single register
    reply, _ = bus.handle(single, now=0.0)
    assert reply == mb.encode_exception(42, 0x06, 1)


@pytest.mark.statements("mis:12.1:7", "mis:12.1:8")
def test_modbus_timeout_responses() -> None:
    """§12.1: register 199 the time-out in ms (0: never), 200 the response: 1 V_SOLL = 0,
    2 passive mode."""
    from jvl_gym.protocol.modbus import codec as mb

    for timeout, response in ((50, 1), (50, 2), (0, 2)):
        m, bus = _modbus(V_SOLL=5000, V_START=10000)
        for reg, value in ((2, c.VELOCITY), (199, timeout), (200, response)):
            bus.handle(mb.encode_write_request(42, 2 * reg, list(mb.words_of(value))), now=0.0)
        bus.poll(0.049)
        assert m.read("V_SOLL")[0] == 5000 and m.read("MODE_REG")[0] == c.VELOCITY
        bus.poll(0.051)
        if timeout == 0:
            assert m.read("V_SOLL")[0] == 5000 and m.read("MODE_REG")[0] == c.VELOCITY
        elif response == 1:
            assert m.read("V_SOLL")[0] == 0 and m.read("MODE_REG")[0] == c.VELOCITY
        else:
            assert m.read("MODE_REG")[0] in (c.PASSIVE, c.STOP)


@pytest.mark.statements("mis:12.1:9")
def test_modbus_frame_delay() -> None:
    """§12.1: register 201 delays the reply; 0 is the default of 2.5 characters."""
    m, bus = _modbus(BAUD_RATE=4)
    slave = bus.slaves[0]
    assert slave.reply_delay() == pytest.approx(2.5 * slave.serial_format().bits / 115200)
    m.write("MODBUS_FRAME_DELAY", 5)
    assert slave.reply_delay() == pytest.approx(5e-3)


# --- §5.1–§5.3 current, AutoCorrection, closed loop ----------------------------------------------
@pytest.mark.statements("mis:5.1.3:2", "mis:5.1.6:1", "mis:5.1.6:2", "mis:5.1.6:3")
def test_holding_torque_is_proportional_to_the_current() -> None:
    """§5.1.3/§5.1.6: an MIS232 gives 1.9 N·m at 6000 mA (RUN_CURRENT 1022); at low speed the
    torque is proportional to the current; at high speed less."""
    m = _motor(RUN_CURRENT=1022)
    assert m.pull_out_torque(1.0)[0] == pytest.approx(1.9, rel=0.02)
    m.write("RUN_CURRENT", 511)
    assert m.pull_out_torque(1.0)[0] == pytest.approx(0.95, rel=0.02)
    assert m.pull_out_torque(2000.0)[0] < 0.9 * m.pull_out_torque(1.0)[0]


def _blocked_move(motor: MotorArray, mode: int = c.POSITION) -> None:
    """A one-revolution move whose first 60 ms are overloaded (steps are lost)."""
    motor.write_many({"IN_POSITION_COUNT": 2, "IN_POSITION_WINDOW": 1000, "V_SOLL": 20000,
                      "A_SOLL": 3000, "V_START": 10000, "GEAR1": 409600, "GEAR2": 1})
    motor.write("MODE_REG", mode)
    motor.set_input(load_torque=1.3 * motor.pull_out_torque(200.0)[0])
    if mode == c.GEAR:
        motor.set_input(pulse_counts=1)
        motor.step(1)
        motor.set_input(pulse_counts=0)
    else:
        motor.write("P_SOLL", 409600)
    motor.run(0.06)
    motor.set_input(load_torque=0.0)
    motor.run(4.0)


@pytest.mark.statements("mis:8.2.15:3", "mis:5.2.1:1", "mis:5.2.1:2")
def test_auto_correction_needs_the_encoder() -> None:
    """§5.2.1: AutoCorrection needs an encoder option; §8.2.15: it retries a movement in
    position and gear mode."""
    bare = MotorArray("MIS232", n=1, seed=0, encoder_type=0)
    _blocked_move(bare)
    assert bare.read("P_IST")[0] == 409600
    assert abs(bare.rotor_counts[0] - 409600) > 100000  # the lost steps stay lost
    for mode in (c.POSITION, c.GEAR):
        m = _motor()
        _blocked_move(m, mode)
        assert abs(m.read("ENCODER_POS")[0] - 409600) <= 1000, mode


@pytest.mark.statements("mis:5.3.1:4")
def test_closed_loop_in_position_needs_the_encoder_in_the_window() -> None:
    """§5.3.1: with the closed loop on, the in-position bit tells that the encoder position and
    P_SOLL are within the in-position window; in open loop it is set when P_IST = P_SOLL."""
    seen = {}
    for bits in (0, c.SETUP_CLOSED_LOOP):
        m = _motor(SETUP_BITS=bits, P_SOLL=20000, IN_POSITION_WINDOW=100,
                   IN_POSITION_COUNT=0, STANDBY_TIME=65535)
        m.write("MODE_REG", c.POSITION)
        m.step(300)
        m.set_input(load_torque=0.6 * m.pull_out_torque(1.0)[0])  # pushes the rotor aside
        m.step(200)
        assert abs(m.read("ENCODER_POS")[0] - 20000) > 100
        seen[bits] = bool(m.read("STATUSBITS")[0] & c.ST_IN_POSITION)
    assert seen == {0: True, c.SETUP_CLOSED_LOOP: False}


@pytest.mark.statements("mis:5.3.3:1")
def test_closed_loop_current_control_uses_no_standby_current() -> None:
    """§5.3.3: "The "Standby current" and "Standby time" setting is not used at any time"
    with closed-loop current control."""
    for bits, standby in ((c.SETUP_CLOSED_LOOP, True),
                          (c.SETUP_CLOSED_LOOP | c.SETUP_CURRENT_CONTROL, False)):
        m = _motor(SETUP_BITS=bits, P_SOLL=20000, STANDBY_TIME=50, STANDBY_CURRENT=10)
        m.write("MODE_REG", c.POSITION)
        m.step(600)
        assert bool(m.read("STATUSBITS")[0] & c.ST_STANDBY_CURRENT) is standby
        if not standby:
            assert m.current_amplitude[0] > 10 * _PEAK_AMPS_PER_UNIT


@pytest.mark.statements("mis:5.3.4:2")
def test_closed_loop_switched_on_the_fly() -> None:
    """§5.3.4: the closed loop and its current control "Can be activated/deactivated on the fly
    and have immediate effect"."""
    m = _motor(V_SOLL=20000)
    m.write("MODE_REG", c.VELOCITY)
    m.step(300)
    assert not m.read("STATUSBITS")[0] & c.ST_CLOSED_LOOP
    m.write("SETUP_BITS", c.SETUP_CLOSED_LOOP | c.SETUP_CURRENT_CONTROL)
    m.step(1)
    assert m.read("STATUSBITS")[0] & c.ST_CLOSED_LOOP
    m.step(500)
    assert m.read("ACTUAL_TORQUE")[0] < 2047
    m.write("SETUP_BITS", 0)
    m.step(1)
    assert not m.read("STATUSBITS")[0] & c.ST_CLOSED_LOOP
    assert m.read("ACTUAL_TORQUE")[0] == 2047


@pytest.mark.statements("mis:5.3.5:1", "mis:5.3.7:1")
def test_actual_torque_is_the_share_of_the_running_current() -> None:
    """§5.3.5: "The actual torque read-out is based on the actual motor current as a percentage
    of the "Running current" setting" (2047 = 100 %, §8.2.112)."""
    m = _motor(SETUP_BITS=c.SETUP_CLOSED_LOOP | c.SETUP_CURRENT_CONTROL, RUN_CURRENT=800,
               V_SOLL=20000)
    m.write("MODE_REG", c.VELOCITY)
    m.set_input(load_torque=0.2)
    m.step(800)
    share = m.read("ACTUAL_TORQUE")[0] / 2047
    assert 0.0 < share < 1.0
    assert m.current_amplitude[0] == pytest.approx(share * 800 * _PEAK_AMPS_PER_UNIT, rel=0.01)


# --- §5.9–§5.12 limits, under voltage, turn table ---------------------------------------------
@pytest.mark.statements("mis:5.9.3:1")
def test_software_limits_off_at_zero_and_both_on_otherwise() -> None:
    """§5.9.3: "Default for both parameters is 0 meaning that the feature is disabled. Notice
    that if one of the parameters are different from 0, both values are activated"."""
    off = _motor(V_SOLL=-30000, A_SOLL=100000)
    off.write("MODE_REG", c.VELOCITY)
    off.step(300)
    assert off.read("ERR_BITS")[0] == 0 and off.read("P_IST")[0] < -100000
    on = _motor(MAX_P_IST=1_000_000, P_IST=100000, V_SOLL=-30000, A_SOLL=100000)
    on.write("MODE_REG", c.VELOCITY)  # MIN_P_IST stays 0, and is a limit now
    on.step(300)
    assert on.read("ERR_BITS")[0] & c.ERR_POSITION_LIMIT and on.read("P_IST")[0] > -100000
    assert on.read("WARN_BITS")[0] & c.WARN_NEG_LIMIT_SEEN


@pytest.mark.statements("mis:5.9.3:3", "mis:5.9.4:1")
def test_velocity_mode_stops_past_min_p_ist() -> None:
    """§5.9.3: "In velocity mode the speed will internally be set to 0 when passing Position
    Limit Min"; the negative warning bits are 1 and 3 (§5.9.4)."""
    m = _motor(MIN_P_IST=-100000, MAX_P_IST=100000, V_SOLL=-20000,
               SETUP_BITS=c.SETUP_NO_LIMIT_ERROR)
    m.write("MODE_REG", c.VELOCITY)
    tr = m.trace(["P_IST", "V_IST"], 800)
    p, v = tr["P_IST"][:, 0], tr["V_IST"][:, 0]
    passed = int(np.flatnonzero(p < -100000)[0])
    assert np.all(np.diff(np.abs(v[passed:])) <= 0) and v[-1] == 0
    assert m.read("MODE_REG")[0] == c.VELOCITY
    assert m.read("WARN_BITS")[0] & c.WARN_NEG_LIMIT_SEEN


@pytest.mark.statements("mis:5.9.5:2")
def test_limit_stop_in_velocity_mode_uses_acc_emerg() -> None:
    """§5.9.5: with SETUP_BITS bit 17 "the motor decelerates with the "Error deceleration" … on
    position limits in velocity mode"."""
    m = _motor(MIN_P_IST=-400000, MAX_P_IST=400000, V_SOLL=30000, A_SOLL=10000, D_SOLL=0,
               ACC_EMERG=2000, SETUP_BITS=c.SETUP_NO_LIMIT_ERROR)
    m.write("MODE_REG", c.VELOCITY)
    tr = m.trace(["P_IST", "V_IST"], 1500)
    p, v = tr["P_IST"][:, 0], tr["V_IST"][:, 0]
    passed = int(np.flatnonzero(p > 400000)[0])
    down = -np.diff(v[passed:].astype(float))
    assert np.median(down[down > 0]) == pytest.approx(2000 * _UNITS_PER_MS, abs=1)


def _under_voltage(bits: int) -> MotorArray:
    m = _motor(V_SOLL=10000, SETUP_BITS=bits)
    m.write("MODE_REG", c.VELOCITY)
    m.step(50)
    m.set_input(supply_volts=10.0)
    m.step(300)
    m.set_input(supply_volts=48.0)
    m.step(300)
    return m


@pytest.mark.statements("mis:5.10:1")
def test_under_voltage_error_stays_after_the_supply_returns() -> None:
    """§5.10: "When P+ is re-applied to the motor it will stay in Passive mode and report a
    "Low bus voltage" error"."""
    m = _under_voltage(1 << 21)
    assert m.read("MODE_REG")[0] == c.PASSIVE and m.read("ERR_BITS")[0] & c.ERR_LOW_BUS


@pytest.mark.statements("mis:5.10:2")
def test_under_voltage_passive_stays_after_the_supply_returns() -> None:
    """§5.10: "Stop controlled and go to passive … When P+ is re-applied the motor stays in
    Passive mode"."""
    m = _under_voltage(1 << 22)
    assert m.read("MODE_REG")[0] == c.PASSIVE and m.read("V_IST")[0] == 0


def _table(mode: int, **regs: int) -> MotorArray:
    return _motor(TURNTABLE_MODE=mode, MIN_P_IST=0, MAX_P_IST=409599, V_SOLL=300000,
                  A_SOLL=100000, IN_POSITION_COUNT=0, **regs)


@pytest.mark.statements("mis:5.12.1:4")
def test_turn_table_mode_2_always_turns_ccw() -> None:
    """§5.12.1 mode 2 "Singleturn CCW rotation": from 0 to 250000 the motor turns CCW
    (159600 counts back through MIN_P_IST)."""
    m = _table(c.TT_CCW)
    m.write("MODE_REG", c.POSITION)
    m.write("P_SOLL", 250000)
    m.step(600)
    assert m.read("P_IST")[0] == 250000
    assert m.rotor_counts[0] == pytest.approx(-159600, abs=600)


@pytest.mark.statements("mis:5.12.1:6", "mis:5.12.1:8")
def test_turn_table_multiturn_limits() -> None:
    """§5.12.1 mode 4: a target below the range is limited to its minimum (−1000 → 0); mode 5
    from 0 to −970000: the simulator's reading lands where the CCW move of 970000 ends."""
    m = _table(c.TT_MULTI_CW, P_SOLL=150000)
    m.write("MODE_REG", c.POSITION)
    m.step(400)
    m.write("P_SOLL", -1000)
    assert m.read("P_SOLL")[0] == 0
    w = _table(c.TT_MULTI_CCW)
    w.write("MODE_REG", c.POSITION)
    w.write("P_SOLL", -970000)
    w.step(1500)
    assert w.read("P_IST")[0] == (-970000) % 409600 == 258800
    assert w.rotor_counts[0] == pytest.approx(-970000, abs=600)


@pytest.mark.statements("mis:5.12.3:1")
def test_turn_table_swaps_a_reversed_range() -> None:
    """§5.12.3: "the firmware will swap the min. and max. values if the minimum is larger than
    the maximum"."""
    m = _motor(TURNTABLE_MODE=c.TT_CW, MIN_P_IST=409599, MAX_P_IST=0, V_SOLL=300000,
               A_SOLL=100000, IN_POSITION_COUNT=0)
    m.write("MODE_REG", c.POSITION)
    m.write("P_SOLL", 300000)
    m.step(400)
    m.write("P_SOLL", 100000)
    m.step(600)
    assert m.read("P_IST")[0] == 100000
    assert m.rotor_counts[0] == pytest.approx(300000 + 209600, abs=600)


@pytest.mark.statements("mis:5.12.5:4")
def test_absencoder_is_not_wrapped_by_the_turn_table() -> None:
    """§5.12.5: ABSENCODER (H3/H4) "Not corrected for the turn table"."""
    m = MotorArray("MIS232", n=1, seed=0, encoder_type=4)
    m.write_many({"TURNTABLE_MODE": c.TT_MULTI_CW, "MIN_P_IST": 0, "MAX_P_IST": 409599,
                  "V_SOLL": 300000, "A_SOLL": 100000, "IN_POSITION_COUNT": 0})
    m.write("MODE_REG", c.POSITION)
    m.write("P_SOLL", 970000)
    m.step(1500)
    assert m.read("P_IST")[0] == 150800
    assert m.read("ABSENCODER")[0] == pytest.approx(970000, abs=600)


# --- §6 modes and zero search, §7.2 errors, §8.1 -------------------------------------------------
@pytest.mark.statements("mis:6.4.1:1", "mis:6.4.1:2", "mis:6.4.7:2")
def test_gear_ratio_extremes() -> None:
    """§6.4.1: ratios from 1/2147483647 to 2147483647/1; §6.4.7: 500 pulses with output 100000
    and input 500 move 100000 counts."""
    m = _motor(GEAR1=100000, GEAR2=500, V_SOLL=300000, A_SOLL=500000)
    m.write("MODE_REG", c.GEAR)
    m.set_input(pulse_counts=50)
    m.step(10)
    assert m.read("P_SOLL")[0] == 100000
    big = _motor(GEAR1=2**31 - 1, GEAR2=1, V_SOLL=0)
    big.write("MODE_REG", c.GEAR)
    big.set_input(pulse_counts=1)
    big.step(1)
    assert big.read("P_SOLL")[0] == 2**31 - 1
    small = _motor(GEAR1=1, GEAR2=2**31 - 1, V_SOLL=0)
    small.write("MODE_REG", c.GEAR)
    small.set_input(pulse_counts=1000)
    small.step(5)
    assert small.read("P_SOLL")[0] == 0  # 5000/(2^31 − 1) of a count: kept as the remainder


@pytest.mark.statements("mis:6.4.7:1")
def test_gear_mode_respects_v_soll() -> None:
    """§6.4.7: "The value of the velocity register will be respected at any time when the motor
    is in gear mode"."""
    m = _motor(GEAR1=409600, GEAR2=2048, V_SOLL=5000, V_START=1000, A_SOLL=100000)
    m.write("MODE_REG", c.GEAR)
    m.set_input(pulse_counts=20)  # 4000 counts per ms: about 586 RPM asked
    v = m.trace(["V_IST"], 200)["V_IST"][:, 0]
    assert v.max() == 5000


@pytest.mark.statements("mis:6.5.2:1", "mis:9.1:1")
def test_a_stored_program_skips_the_power_up_zero_search() -> None:
    """§6.5.2: the power-up zero search runs "every time the MIS motor is powered up unless a
    eRXP program exist" (the program starts in position mode, §9.1)."""
    m = MotorArray("MIS232", n=1, setup={"HOMEMODE": 13, "STARTMODE": 2})
    assert m.read("MODE_REG")[0] == c.ZERO_SEARCH_1
    m.store_program("set_output output=2 state=high\njump line=2\n")
    m.write("MODE_REG", c.PASSIVE)
    m.step(300)
    m.write("COMMAND", c.CMD_RESET)
    assert m.read("MODE_REG")[0] == c.POSITION


@pytest.mark.statements("mis:6.5.8:1")
def test_zero_search_ends_at_position_0_after_an_offset() -> None:
    """§6.5.8: "the position counter is set to the value specified in the "Zero search position"
    field. If the zero search position value is different from [0], the motor will now move to
    position 0"."""
    m = _search_on_input(30000)
    assert m.read("P_IST")[0] == 0 and m.read("P_SOLL")[0] == 0
    assert m.read("MODE_REG")[0] == c.POSITION


@pytest.mark.statements("mis:7.2.4:1")
def test_follow_error_sets_the_motor_passive() -> None:
    """§7.2.4: "The Follow error (register 20) has exceeded the value specified in "Follow error
    max" (register 22)" — "Motor is set in Passive mode"."""
    m = _motor(FLWERRMAX=30000, P_SOLL=4_000_000, V_SOLL=100000, A_SOLL=1000)
    m.set_input(load_torque=5.0)
    m.write("MODE_REG", c.POSITION)
    tr = m.trace(["FLWERR", "ERR_BITS", "MODE_REG"], 300)
    first = int(np.flatnonzero(tr["ERR_BITS"][:, 0] & c.ERR_FOLLOW)[0])
    assert abs(tr["FLWERR"][first, 0]) > 30000 and abs(tr["FLWERR"][first - 1, 0]) <= 30000
    assert m.read("MODE_REG")[0] == c.PASSIVE


@pytest.mark.statements("mis:7.2.6:1", "mis:7.2.6:3")
def test_after_a_limit_error_only_the_way_back() -> None:
    """§7.2.6: after the position limit error is cleared "It is now only possible to run the
    motor in the opposite direction of the limit": towards it, the error comes back at once
    (the limit is still active, §7.2.6's error condition) and the motor does not move."""
    m = _motor(PL_MASK=0b1, V_SOLL=5000, V_START=10000)
    m.write("MODE_REG", c.VELOCITY)
    m.step(20)
    m.set_input(digital_inputs=0b1)
    m.step(5)
    assert m.read("ERR_BITS")[0] & c.ERR_POSITION_LIMIT and m.read("MODE_REG")[0] == 0
    m.write("COMMAND", c.CMD_CLEAR_ERRORS)
    m.write("MODE_REG", c.VELOCITY)
    held = m.read("P_IST")[0]
    m.step(20)
    assert m.read("P_IST")[0] == held  # not towards the active limit
    assert m.read("ERR_BITS")[0] & c.ERR_POSITION_LIMIT and m.read("MODE_REG")[0] == 0
    m.write("COMMAND", c.CMD_CLEAR_ERRORS)
    m.write_many({"V_SOLL": -5000, "MODE_REG": c.VELOCITY})
    m.step(20)
    assert m.read("P_IST")[0] < held and m.read("ERR_BITS")[0] == 0


@pytest.mark.statements("mis:7.2.7:2")
def test_low_bus_voltage_error_clears() -> None:
    """§7.2.7: "Reset the motor, clear the error bit(s) in register 35 or cycle the power"."""
    m = _under_voltage(1 << 21)
    m.write("ERR_BITS", 0)
    assert m.read("ERR_BITS")[0] == 0
    m.write("MODE_REG", c.VELOCITY)
    m.step(150)
    assert m.read("V_IST")[0] == 10000


@pytest.mark.statements("mis:8.1:1", "mis:8.1:2", "mis:11.4.6:1")
def test_canopen_register_objects() -> None:
    """§8.1: register n is object 2012h (32 bits) / 2014h (16 bits) sub-index n, with the same
    access as over RS485."""
    import canopen

    from canopen_rig import Rig

    rig = Rig()
    try:
        node = rig.node()
        node.sdo[0x2012][3].raw = 123456
        assert rig.m.read("P_SOLL")[0] == 123456
        node.sdo[0x2014][5].raw = 2500
        assert rig.m.read("V_SOLL")[0] == 2500
        assert node.sdo[0x2012][3].raw == 123456
        with pytest.raises(canopen.SdoAbortedError):
            node.sdo[0x2012][12].raw = 5  # V_IST is read-only
    finally:
        rig.close()


# --- §11 CANopen -------------------------------------------------------------------------------
SAVE, LOAD = 0x65766173, 0x64616F6C


@pytest.fixture
def rig():  # type: ignore[no-untyped-def]
    from canopen_rig import Rig

    r = Rig()
    yield r
    r.close()


@pytest.mark.statements("mis:11.3.2:1")
def test_canopen_sdo_example_of_the_manual(rig) -> None:  # type: ignore[no-untyped-def]
    """§11.3.2: MODE_REG 2, V_SOLL 10000 (100 RPM), P_SOLL 4096000 (10 revolutions); then
    MODE_REG 0 makes the motor passive."""
    node = rig.node()
    node.sdo[0x2012][2].raw = 2
    node.sdo[0x2012][5].raw = 10000
    node.sdo[0x2012][3].raw = 4096000
    rig.advance(7.0)
    assert rig.m.read("P_IST")[0] == 4096000
    assert rig.m.rotor_counts[0] == pytest.approx(4096000, abs=600)
    node.sdo[0x2012][2].raw = 0
    rig.advance(0.01)
    assert rig.m.read("MODE_REG")[0] == c.PASSIVE


@pytest.mark.statements("mis:11.4.1:1", "mis:11.9.7:2")
def test_canopen_communication_objects(rig) -> None:  # type: ignore[no-untyped-def]
    """§11.4.1: 1000h 0x40192, 1008h "JVL A/S", 1018h sub 1 117h (JVL), 1016h 3 entries, 1017h
    0; §11.9.7: no error control is on at start-up (1017h = 0, 100Ch = 0)."""
    node = rig.node()
    assert node.sdo[0x1000].raw == 0x40192 and node.sdo[0x1008].raw == "JVL A/S"
    assert node.sdo[0x1018][1].raw == 0x117 and node.sdo[0x1016][0].raw == 3
    assert node.sdo[0x1017].raw == 0 and node.sdo[0x100C].raw == 0
    rig.clear()
    rig.advance(1.0)
    assert rig.sent(0x705) == []


@pytest.mark.statements("mis:11.4.1:2", "mis:11.4.2:1", "mis:11.4.2:2", "mis:11.4.2:3")
def test_canopen_emcy_on_a_follow_error() -> None:
    """§11.4.2: a follow error sends one EMCY with code 1003h, the error register and ERR_BITS;
    1003h sub 0 counts it; writing 0 there clears the motor's errors and the buffer."""
    import struct

    from canopen_rig import Rig

    rig = Rig(encoder_type=1, end_stop_high=1.0)
    try:
        node = rig.node()
        node.sdo[0x2012][22].raw = 5000
        node.sdo[0x2012][2].raw = 2
        node.sdo[0x2012][3].raw = 409600
        rig.clear()
        rig.advance(1.0)
        [emcy] = rig.sent(0x85)
        code, _, err = struct.unpack_from("<HBH", emcy)
        assert code == 0x1003 and err & c.ERR_FOLLOW
        assert node.sdo[0x1003][0].raw == 1
        node.sdo[0x1003][0].raw = 0
        rig.advance(0.01)
        assert node.sdo[0x1003][0].raw == 0 and rig.m.read("ERR_BITS")[0] == 0
    finally:
        rig.close()


@pytest.mark.statements("mis:11.4.3:1", "mis:11.4.3:2", "mis:11.9.7:1", "mis:11.4.2:3")
def test_canopen_heartbeat_and_node_guarding(rig) -> None:  # type: ignore[no-untyped-def]
    """§11.4.3: heartbeat every 1017h ms; node guarding answers with a toggle bit starting at 0
    (§11.9.7); no guard request within 100Ch × 100Dh ms raises EMCY 8130h."""
    node = rig.node()
    node.sdo[0x1017].raw = 200
    rig.clear()
    rig.advance(1.0)
    assert rig.sent(0x705) == [b"\x7f"] * 5
    node.sdo[0x1017].raw = 0
    node.sdo[0x100C].raw = 100
    node.sdo[0x100D].raw = 2
    answers = []
    for _ in range(3):
        rig.clear()
        rig.send(0x705, remote=True)
        answers += rig.sent(0x705)
    assert answers == [b"\x7f", b"\xff", b"\x7f"]
    rig.clear()
    rig.advance(0.15)
    assert rig.sent(0x85) == []
    rig.advance(0.1)
    [emcy] = rig.sent(0x85)
    assert int.from_bytes(emcy[:2], "little") == 0x8130


@pytest.mark.statements("mis:11.4.4:1", "mis:11.4.5:1")
def test_canopen_store_and_restore(rig) -> None:  # type: ignore[no-untyped-def]
    """§11.4.5: "SAVE" to 1010h sub 1 stores the registers in flash (back after a reset node);
    §11.4.4: "LOAD" to 1011h sub 1 restores the DSP-402 parameters' factory defaults."""
    node = rig.node()
    node.sdo[0x2012][5].raw = 23456
    node.sdo[0x6094][1].raw = 3
    node.sdo[0x1010][1].raw = SAVE
    node.sdo[0x2012][5].raw = 111
    node.nmt.send_command(0x81)
    rig.settle()
    assert rig.m.read("V_SOLL")[0] == 23456 and node.sdo[0x6094][1].raw == 3
    node.sdo[0x1011][1].raw = LOAD
    assert node.sdo[0x6094][1].raw == 1


@pytest.mark.statements("mis:11.4.6:2")
def test_canopen_16_bit_access(rig) -> None:  # type: ignore[no-untyped-def]
    """§11.4.6: 2014h is 16-bit access; "If writing to a 32bit parameter, the lsb 16-bit value
    will be treated as signed"."""
    node = rig.node()
    node.sdo[0x2014][3].raw = 0xFFFF
    assert rig.m.read("P_SOLL")[0] == -1
    node.sdo[0x2014][5].raw = 12345
    assert rig.m.read("V_SOLL")[0] == 12345 and node.sdo[0x2014][5].raw == 12345


@pytest.mark.statements("mis:11.4.7:1")
def test_canopen_pdos_start_disabled_and_bit_31_enables(rig) -> None:  # type: ignore[no-untyped-def]
    """§11.4.7: "all PDOs are disabled when the module is booted up"; bit 31 of the COB-ID
    (sub 1) set disables, cleared enables."""
    node = rig.node()
    for comm in (0x1400, 0x1401, 0x1414, 0x1800, 0x1801, 0x1814):
        assert node.sdo[comm][1].raw & 0x80000000, hex(comm)
    node.sdo[0x1800][1].raw = 0x185
    assert node.sdo[0x1800][1].raw == 0x185
    node.sdo[0x1800][1].raw = 0x80000185
    assert node.sdo[0x1800][1].raw & 0x80000000


@pytest.mark.statements("mis:11.4.8:1")
def test_canopen_dynamic_mapping_procedure(rig) -> None:  # type: ignore[no-untyped-def]
    """§11.4.8 steps 1–9: TPDO 1 mapped to 2012h sub 5 (20120520h), type 255, event timer
    100 ms: sent every 100 ms in operational."""
    import struct

    node = rig.node()
    node.nmt.state = "PRE-OPERATIONAL"
    node.sdo[0x1800][1].raw = node.sdo[0x1800][1].raw | 0x80000000
    node.sdo[0x1A00][0].raw = 0
    node.sdo[0x1A00][1].raw = 0x20120520
    node.sdo[0x1A00][0].raw = 1
    node.sdo[0x1800][2].raw = 255
    node.sdo[0x1800][5].raw = 100
    node.sdo[0x1800][1].raw = 0x185
    node.nmt.state = "OPERATIONAL"
    rig.clear()
    rig.advance(1.0)
    frames = rig.sent(0x185)
    assert len(frames) == 10 and {struct.unpack("<l", f)[0] for f in frames} == {10000}


def _mapping(node, index: int) -> list[int]:  # type: ignore[no-untyped-def]
    return [node.sdo[index][k].raw for k in range(1, node.sdo[index][0].raw + 1)]


@pytest.mark.statements("mis:11.4.9:3", "mis:11.4.9:4", "mis:11.4.9:5")
def test_canopen_rpdo_21_to_23(rig) -> None:  # type: ignore[no-untyped-def]
    """§11.4.9: RPDO 21 P_SOLL (2012h sub 3), V_SOLL, A_SOLL (2014h sub 5, 6); RPDO 22
    RUN_CURRENT, MODE_REG (2014h sub 7, 2); RPDO 23 the command (2014h sub 18h)."""
    import struct

    node = rig.node()
    assert _mapping(node, 0x1614) == [0x20120320, 0x20140510, 0x20140610]
    assert _mapping(node, 0x1615) == [0x20140710, 0x20140210]
    assert _mapping(node, 0x1616) == [0x20141810]
    for k, cob in ((20, 0x215), (21, 0x315), (22, 0x415)):
        node.sdo[0x1400 + k][1].raw = cob
    node.nmt.state = "OPERATIONAL"
    rig.send(0x315, struct.pack("<hh", 300, c.POSITION))
    rig.send(0x215, struct.pack("<lhh", 409600, 30000, 5000))
    rig.advance(1.5)
    assert rig.m.read("RUN_CURRENT")[0] == 300 and rig.m.read("MODE_REG")[0] == c.POSITION
    assert rig.m.read("P_IST")[0] == 409600 and rig.m.read("V_SOLL")[0] == 30000
    rig.send(0x415, struct.pack("<h", c.CMD_V_SOLL_ZERO))
    rig.advance(0.001)
    assert rig.m.read("V_SOLL")[0] == 0


@pytest.mark.statements("mis:11.4.10:1", "mis:11.4.10:2", "mis:11.4.10:3", "mis:11.4.10:4")
def test_canopen_tpdo_21_to_24(rig) -> None:  # type: ignore[no-untyped-def]
    """§11.4.10: TPDO 21 P_IST (2012h sub 0Ah), V_IST (2014h sub 0Ch), ERR_BITS (2014h sub 23h);
    TPDO 22 V_IST; TPDO 23/24 analogue inputs 1–4 / 5–8 (2014h sub 59h–60h)."""
    import struct

    node = rig.node()
    assert _mapping(node, 0x1A14) == [0x20120A20, 0x20140C10, 0x20142310]
    assert _mapping(node, 0x1A15) == [0x20140C10]
    assert _mapping(node, 0x1A16) == [0x20145910, 0x20145A10, 0x20145B10, 0x20145C10]
    assert _mapping(node, 0x1A17) == [0x20145D10, 0x20145E10, 0x20145F10, 0x20146010]
    cob = 0x195
    node.sdo[0x1814][1].raw = cob
    node.nmt.state = "OPERATIONAL"
    rig.m.write("P_IST", 123456)
    rig.clear()
    rig.send(cob, remote=True)
    [frame] = rig.sent(cob)
    assert struct.unpack("<lhH", frame) == (123456, 0, 0)


@pytest.mark.statements(
    "mis:8.2.68:11", "mis:11.4.11:1", "mis:11.4.13:1", "mis:11.4.13:2", "mis:11.4.14:1")
def test_canopen_beckhoff_mode() -> None:
    """§11.4.11–14: with SETUP_BITS bit 14, PDOs 1–4 are enabled at power-up with the Beckhoff
    COB-IDs (RPDO 1 200h + node id, TPDO 4 480h + node id) and maps; RPDO 1 (P_SOLL, V_SOLL,
    A_SOLL) moves the motor, TPDO 1 sends P_IST, V_IST, ERR_BITS."""
    import struct

    from canopen_rig import Rig

    rig = Rig()
    try:
        node = rig.node()
        node.sdo[0x2012][124].raw = 1 << 14
        node.nmt.send_command(0x82)
        rig.settle()
        assert [node.sdo[0x1400 + k][1].raw for k in range(4)] == [0x205, 0x305, 0x405, 0x505]
        assert [node.sdo[0x1800 + k][1].raw for k in range(4)] == [0x185, 0x285, 0x385, 0x485]
        assert _mapping(node, 0x1600) == [0x20120320, 0x20140510, 0x20140610]
        assert _mapping(node, 0x1A00) == [0x20120A20, 0x20140C10, 0x20142310]
        node.sdo[0x2012][2].raw = 2
        node.nmt.state = "OPERATIONAL"
        rig.send(0x205, struct.pack("<lhh", 409600, 20000, 3000))
        rig.advance(1.0)
        rig.clear()
        rig.send(0x185, remote=True)
        assert struct.unpack("<lhH", rig.sent(0x185)[0]) == (409600, 0, 0)
    finally:
        rig.close()


def _node402(rig):  # type: ignore[no-untyped-def]
    node = rig.node()
    node.nmt.state = "PRE-OPERATIONAL"
    node.setup_402_state_machine()
    return node


@pytest.fixture
def rig402():  # type: ignore[no-untyped-def]
    from canopen.profiles.p402 import BaseNode402

    from canopen_rig import Rig

    r = Rig(node_class=BaseNode402)
    yield r
    r.close()


@pytest.mark.statements("mis:11.5.1:2", "mis:11.5.3:1")
def test_canopen_402_mode_change_only_while_not_enabled(rig402) -> None:  # type: ignore[no-untyped-def]
    """§11.5.3: the mode of operation changes only while the operation is not enabled;
    §11.5.1: 6502h lists profile position, velocity, torque, homing, interpolated position and
    the three cyclic synchronous modes."""
    import canopen

    node = _node402(rig402)
    node.op_mode = "PROFILED POSITION"
    node.state = "OPERATION ENABLED"
    with pytest.raises(canopen.SdoAbortedError):
        node.sdo[0x6060].raw = 3
    node.state = "SWITCHED ON"
    node.sdo[0x6060].raw = 3
    assert node.sdo[0x6061].raw == 3
    supported = node.sdo[0x6502].raw
    assert [mode for mode in range(1, 11) if supported >> (mode - 1) & 1] == [
        1, 3, 4, 6, 7, 8, 9, 10]


@pytest.mark.statements("mis:11.5.4:1")
def test_canopen_402_profile_position(rig402) -> None:  # type: ignore[no-untyped-def]
    """§11.5.4: a new set-point (bit 4) is acknowledged (status bit 12), the target reached
    sets status bit 10, and bit 6 makes the next move relative."""
    node = _node402(rig402)
    node.op_mode = "PROFILED POSITION"
    node.state = "OPERATION ENABLED"
    node.sdo[0x6081].raw = 30000
    node.sdo[0x6083].raw = 3000
    node.sdo[0x607A].raw = 2 * 409600
    node.controlword = 0x1F
    assert node.sdo[0x6041].raw & 0x1000
    node.controlword = 0x0F
    rig402.advance(2.0)
    assert node.sdo[0x6064].raw == 2 * 409600 and node.sdo[0x6041].raw & 0x400
    node.sdo[0x607A].raw = -409600
    node.controlword = 0x5F
    node.controlword = 0x4F
    rig402.advance(1.5)
    assert node.sdo[0x6064].raw == 409600


@pytest.mark.statements("mis:11.5.2:1")
def test_canopen_402_position_factor(rig) -> None:  # type: ignore[no-untyped-def]
    """§11.5.2's example: a 3.5:1 gear box and a 124 mm drive wheel, positions in mm: 6091h =
    35/10, 6092h = 38956/100."""
    node = rig.node()
    node.sdo[0x6091][1].raw = 35
    node.sdo[0x6091][2].raw = 10
    node.sdo[0x6092][1].raw = 38956
    node.sdo[0x6092][2].raw = 100
    rig.m.write("P_IST", round(100 * 3.5 * 409600 / 389.56))  # 100 mm
    assert node.sdo[0x6064].raw == 100


@pytest.mark.statements("mis:11.7.3:1")
def test_canopen_lss_configure_node_id(rig) -> None:  # type: ignore[no-untyped-def]
    """§11.7.3: "Configure Node-ID": 0 success, 1 inadmissible node-ID; §11.7.5 stores it and
    the device works with it after a reset."""
    lss = rig.net.lss
    lss.send_switch_state_global(lss.CONFIGURATION_STATE)
    assert lss.inquire_node_id() == 5
    with pytest.raises(Exception, match="(?i)error"):
        lss.configure_node_id(0)
    lss.configure_node_id(9)
    lss.store_configuration()
    lss.send_switch_state_global(lss.WAITING_STATE)
    assert rig.m.read("FBUS_NODE_ID")[0] == 9
    rig.clear()
    rig.node(5).nmt.send_command(0x81)
    assert rig.sent(0x709) == [b"\x00"]


@pytest.mark.statements("mis:11.9.6:1")
def test_canopen_stopped_node_answers_no_sdo(rig) -> None:  # type: ignore[no-untyped-def]
    """§11.9.6: "In the stopped state, the nodes can only process NMT instructions"."""
    node = rig.node()
    node.nmt.state = "STOPPED"
    assert rig.request(0x605, bytes([0x40, 0x00, 0x10, 0, 0, 0, 0, 0]), 0x585) is None
    node.nmt.state = "PRE-OPERATIONAL"
    assert node.sdo[0x1000].raw == 0x40192


# --- §11.8 J1939, §13 DMX512 --------------------------------------------------------------------
@pytest.mark.statements("mis:11.8.3:1", "mis:11.8.4:1", "mis:11.8.5:1", "mis:11.8.7:1")
def test_j1939_name_address_and_register_access() -> None:
    """§11.8.3–§11.8.7: node 5 claims with NAME FF FF FF FF 01 FF FE 80 (PGN 60928, broadcast);
    DM14 (PGN 55552) read of register 5 → DM15 proceed, DM16 10000, DM15 complete; a write →
    proceed, the tool's DM16, complete; an unknown pointer extension fails."""
    from jvl_gym.protocol.sae_j1939 import J1939Device
    from jvl_gym.protocol.sae_j1939.frames import can_id

    m = _motor()
    d = J1939Device(m, 0, 5)
    with pytest.raises(ValueError):
        J1939Device(m, 0, 253)
    [claim] = d.claim()
    assert (claim.arbitration_id, claim.data) == (0x18EEFF05, bytes.fromhex("ffffffff01fffe80"))

    def ask(pgn: int, data: str, now: float = 0.0) -> list[tuple[int, bytes]]:
        return [(f.arbitration_id, f.data)
                for f in d.handle(can_id(pgn, 0xF9, 5), bytes.fromhex(data), now)]

    assert ask(55552, "0403050000 80ffff") == [
        (0x18D8F905, bytes.fromhex("0411ffffffffffff")),
        (0x18D7F905, bytes.fromhex("0410270000ffffff")),
        (0x18D8F905, bytes.fromhex("0019ffffffffffff"))]
    assert ask(55552, "0405050000 80ffff") == [(0x18D8F905, bytes.fromhex("0411ffffffffffff"))]
    assert ask(55040, "04204e0000ffffff", 0.5) == [
        (0x18D8F905, bytes.fromhex("0019ffffffffffff"))]
    assert m.read("V_SOLL")[0] == 20000
    assert ask(55552, "0403050000 81ffff") == [(0x18D8F905, bytes.fromhex("001bffffffffffff"))]


@pytest.mark.statements("mis:13.1.6:1", "mis:13.1.7:1", "mis:13.1.8:1", "mis:13.1.10:1")
def test_dmx512_channels_scaling_and_control() -> None:
    """§13.1.6–§13.1.8, §13.1.10: SA1 position coarse/fine and control, SA2 acceleration and
    velocity, scaled by nom/den + offset; control 60–69 position mode, 0–9 passive; a packet of
    another start code is ignored."""
    from jvl_gym.protocol.dmx512 import DmxPacket, DmxReceiver, DmxSettings

    m = _motor(IN_POSITION_COUNT=0)
    r = DmxReceiver(m, 0, DmxSettings(start_address1=10, start_address2=300, homing=False,
                                      pos_nom=2, pos_den=1, pos_offset=100, vel_nom=100))
    slots = bytearray(512)
    slots[9:12] = bytes([0x01, 0x90, 65])  # position 400, control 65
    slots[299:301] = bytes([200, 150])
    r.packet(DmxPacket(0, bytes(slots)))
    got = [int(m.read(k)[0]) for k in ("MODE_REG", "P_SOLL", "A_SOLL", "V_SOLL")]
    assert got == [c.POSITION, 900, 200, 15000]
    slots[11] = 3
    r.packet(DmxPacket(0x17, bytes(slots)))
    assert m.read("MODE_REG")[0] == c.POSITION
    r.packet(DmxPacket(0, bytes(slots)))
    assert m.read("MODE_REG")[0] == c.PASSIVE


@pytest.mark.statements("mis:13.1.8:2", "mis:13.1.8:3")
def test_dmx512_homing_and_reset_error() -> None:
    """§13.1.8: homing after "10 identical values in the range 180..189", not aborted by other
    values, then position mode; 200–209 reset the errors."""
    from jvl_gym.protocol.dmx512 import DmxPacket, DmxReceiver, DmxSettings

    def frame(control: int) -> DmxPacket:
        slots = bytearray(512)
        slots[2] = control
        return DmxPacket(0, bytes(slots))

    m = MotorArray("MIS232", n=1, seed=0, home_position=-0.3)
    m.write_many({"HOME_MASK": 8, "V_HOME": -3000, "IN_POSITION_COUNT": 0})
    r = DmxReceiver(m, 0, DmxSettings(homing_mode=13))
    for _ in range(9):
        r.packet(frame(185))
    assert m.read("MODE_REG")[0] == c.PASSIVE
    r.packet(frame(185))
    assert m.read("MODE_REG")[0] == c.ZERO_SEARCH_1
    r.packet(frame(0))
    assert m.read("MODE_REG")[0] == c.ZERO_SEARCH_1
    for _ in range(100):
        m.step(50)
        r.poll()
        if not r.homing:
            break
    assert m.read("MODE_REG")[0] == c.POSITION
    m.write("ERR_BITS", c.ERR_GENERAL | c.ERR_POSITION_LIMIT)
    r.packet(frame(204))
    assert m.read("ERR_BITS")[0] == 0


@pytest.mark.statements("mis:11.5.5:1")
def test_canopen_402_velocity_halt(rig402) -> None:  # type: ignore[no-untyped-def]
    """§11.5.5: velocity mode runs at 60FFh; halt (bit 8) decelerates to 0, released the motor
    runs at 60FFh again."""
    node = _node402(rig402)
    node.sdo[0x60FF].raw = 10000
    node.sdo[0x6083].raw = 5000
    node.op_mode = "PROFILED VELOCITY"
    assert node.sdo[0x6061].raw == 3
    node.state = "OPERATION ENABLED"
    rig402.advance(0.5)
    assert node.sdo[0x606C].raw == 10000
    node.controlword = 0x10F
    rig402.advance(0.5)
    assert node.sdo[0x606C].raw == 0
    node.controlword = 0x0F
    rig402.advance(0.5)
    assert node.sdo[0x606C].raw == 10000


@pytest.mark.statements("mis:11.5.6:1", "mis:11.5.6:2", "mis:11.5.6:3")
def test_canopen_402_homing_methods() -> None:
    """§11.5.6: methods 1–6, −3, −4 supported, −2, −1, 35 not; method 19 (as 3, home switch,
    negative, without index) ends at the switch with the home offset 607Ch as its position,
    homing attained."""
    import canopen
    from canopen.profiles.p402 import BaseNode402

    from canopen_rig import Rig

    rig = Rig(node_class=BaseNode402, step_per_frame=0.01, home_position=-3.0)
    try:
        node = _node402(rig)
        for method in (1, 2, 3, 4, 5, 6, -3, -4):
            node.sdo[0x6098].raw = method
        for method in (-2, -1, 35):
            with pytest.raises(canopen.SdoAbortedError):
                node.sdo[0x6098].raw = method
        node.sdo[0x2012][132].raw = 8
        node.sdo[0x6098].raw = 19
        node.sdo[0x6099][1].raw = 5000
        node.sdo[0x607C].raw = 1000
        assert node.homing(timeout=30)
        assert node.sdo[0x6041].raw & 0x1000
        assert rig.m.read("P_HOME")[0] == 1000
        zero = rig.m.rotor_counts[0] - rig.m.read("P_IST")[0]
        assert zero == pytest.approx(-3.0 * 409600 / (2 * np.pi) - 1000, abs=700)
    finally:
        rig.close()


@pytest.mark.statements("mis:11.5.7:1", "mis:11.5.7:2")
def test_canopen_402_torque_is_current(rig402) -> None:  # type: ignore[no-untyped-def]
    """§11.5.7: torque in rated current/1000: 6071h = 500 runs the motor on half its running
    current at the target velocity 60FFh; profile torque is DSP-402's 6060h = 4 (the manual's
    3 is the velocity mode's number, docs/protocol.md)."""
    node = _node402(rig402)
    current = int(rig402.m.read("RUN_CURRENT")[0])
    node.sdo[0x6071].raw = 500
    node.sdo[0x6087].raw = 10000
    node.sdo[0x60FF].raw = 10000
    node.op_mode = "PROFILED TORQUE"
    assert node.sdo[0x6061].raw == 4
    node.state = "OPERATION ENABLED"
    rig402.advance(0.5)
    assert rig402.m.read("RUN_CURRENT")[0] == round(current / 2)
    assert rig402.m.read("V_IST")[0] == 10000


@pytest.mark.statements("mis:11.5.8:1")
def test_canopen_402_interpolated_position(rig402) -> None:  # type: ignore[no-untyped-def]
    """§11.5.8: 60C1h sub 1 is reached by the next SYNC within 60C2h's period; sub 2 = 1 is
    relative."""
    node = _node402(rig402)
    node.sdo[0x60C2][1].raw = 10
    node.op_mode = "INTERPOLATED POSITION"
    node.state = "OPERATION ENABLED"
    node.controlword = 0x1F
    node.sdo[0x60C1][1].raw = 2000
    assert rig402.m.read("P_SOLL")[0] == 0
    rig402.send(0x80)
    rig402.advance(0.01)
    assert rig402.m.read("P_IST")[0] == 2000
    node.sdo[0x60C1][2].raw = 1
    node.sdo[0x60C1][1].raw = 500
    for _ in range(2):
        rig402.send(0x80)
        rig402.advance(0.01)
    assert rig402.m.read("P_IST")[0] == 3000


@pytest.mark.statements("mis:11.4.2:3")
def test_canopen_emcy_codes(rig) -> None:  # type: ignore[no-untyped-def]
    """§11.4.2: position error 1002h and low bus voltage 1004h as EMCY codes, and 8210h for a
    PDO of the wrong length."""
    import struct

    node = rig.node()
    node.sdo[0x1400 + 20][1].raw = 0x215
    node.nmt.state = "OPERATIONAL"
    rig.clear()
    rig.send(0x215, b"\x01\x02")
    [emcy] = rig.sent(0x85)
    assert struct.unpack_from("<H", emcy)[0] == 0x8210
    node.sdo[0x1003][0].raw = 0
    rig.m.write_many({"MAX_P_IST": 50000, "MIN_P_IST": -50000, "V_SOLL": 30000,
                      "SETUP_BITS": 1 << 21})
    rig.m.write("MODE_REG", c.VELOCITY)
    rig.clear()
    rig.advance(0.5)
    codes = [struct.unpack_from("<H", f)[0] for f in rig.sent(0x85)]
    assert 0x1002 in codes
    node.sdo[0x1003][0].raw = 0
    rig.m.set_input(supply_volts=10.0)
    rig.clear()
    rig.advance(0.1)
    codes = [struct.unpack_from("<H", f)[0] for f in rig.sent(0x85)]
    assert 0x1004 in codes


# --- §2 inputs -----------------------------------------------------------------------------------
@pytest.mark.statements("mis:2.3.5:1")
def test_an_input_has_a_digital_state_and_an_analogue_value() -> None:
    """§2.3.5: "When an I/O is configured to be an input, it simultaneously has both a digital
    value (high or low) and an analogue value"."""
    m = _motor()
    m.set_input(digital_inputs=0b1, analog1=3.0)
    m.step(20)
    assert m.read("INPUTS")[0] & 1
    assert m.read("ANALOGUE_INPUT1")[0] == pytest.approx(3.0 / 1.221e-3, abs=2)


# --- §12.3–§12.6 Modbus frames -------------------------------------------------------------------
@pytest.mark.statements("mis:12.3:1", "mis:12.3:2", "mis:12.4:1", "mis:12.4:2", "mis:12.5:2")
def test_modbus_addressing_and_the_manual_frames() -> None:
    """§12.3: register n is Modbus 2n (low half), 2n+1 (high half), big-endian words, and
    40000 + n; writes only of whole registers; §12.4's example frame; at most 16 words; §12.5:
    address 0 is a broadcast write, not answered."""
    from jvl_gym.protocol.modbus import codec as mb

    m, bus = _modbus(P_IST=123456789)
    req = mb.append_crc(bytes((0x2A, 0x03, 0x00, 0x14, 0x00, 0x02)))
    reply, _ = bus.handle(req, now=0.0)
    assert reply == mb.append_crc(bytes((0x2A, 0x03, 0x04, 0xCD, 0x15, 0x07, 0x5B)))
    reply, _ = bus.handle(mb.encode_read_request(42, 40000 + 10, 2), now=0.0)
    assert mb.decode_response(reply).words == (0xCD15, 0x075B)
    for index, words in ((2 * 65 + 1, [1, 0]), (2 * 65, [1]), (2 * 65, [0] * 18)):
        reply, _ = bus.handle(mb.encode_write_request(42, index, words), now=0.0)
        assert isinstance(mb.decode_response(reply), mb.ExceptionResponse)
    assert m.read("V1")[0] == 25000
    reply, _ = bus.handle(mb.encode_write_request(0, 2 * 65, list(mb.words_of(-7))), now=0.0)
    assert reply == b"" and m.read("V1")[0] == -7
    reply, _ = bus.handle(mb.encode_read_request(0, 20, 2), now=0.0)
    assert reply == b""


@pytest.mark.statements("mis:12.6:1", "mis:12.6.2:1")
def test_modbus_pdo_registers() -> None:
    """§12.6: PDO1_TX_SETUP (F300h) = 10, 12, 25: PDO1_VALUE (F400h) [0..2] read P_IST, V_IST,
    STATUSBITS in one frame; PDO1_RX_SETUP (F200h) = 3, 5: writing VALUE[0..1] sets P_SOLL and
    V_SOLL; an unconfigured value register is an invalid address (§12.6.2)."""
    from jvl_gym.protocol.modbus import codec as mb

    m, bus = _modbus(P_IST=-5)

    def ask(frame: bytes) -> object:
        return mb.decode_response(bus.handle(frame, now=0.0)[0])

    value = 0xF400
    assert isinstance(ask(mb.encode_read_request(42, value, 2)), mb.ExceptionResponse)
    ask(mb.encode_write_request(42, 0xF300, [w for n in (10, 12, 25) for w in mb.words_of(n)]))
    out = ask(mb.encode_read_request(42, value, 6))
    assert out.words == (*mb.words_of(-5), *mb.words_of(0),  # type: ignore[attr-defined]
                         *mb.words_of(int(m.read("STATUSBITS")[0])))
    assert isinstance(ask(mb.encode_write_request(42, value, [1, 0])), mb.ExceptionResponse)
    ask(mb.encode_write_request(42, 0xF200, [3, 0, 5, 0]))
    ask(mb.encode_write_request(42, value, [*mb.words_of(100000), *mb.words_of(2500)]))
    assert m.read("P_SOLL")[0] == 100000 and m.read("V_SOLL")[0] == 2500


@pytest.mark.statements("mis:8.2.20:2")
def test_reserved_commands_change_nothing() -> None:
    """§8.2.20: "The values 128-255 are reserved": writing one changes no register."""
    m = _motor(V_SOLL=1234, P_IST=77, P_NEW=5)
    before = m.regs.copy()
    for command in (128, 200, 255):
        m.write("COMMAND", command)
    np.testing.assert_array_equal(m.regs, before)


@pytest.mark.statements("mis:5.2.2:3")
def test_auto_correction_starts_on_a_changed_p_soll_only() -> None:
    """§5.2.2: "changing P_SOLL (not just writing the same value again) will reload the maximum
    number of retries and set the Auto Correction Active status bit"."""
    m = _motor(IN_POSITION_COUNT=2, IN_POSITION_WINDOW=100, SETTLINGTIME=50,
               STANDBY_TIME=65535, P_SOLL=20000)
    m.write("MODE_REG", c.POSITION)
    m.step(300)
    assert not m.read("STATUSBITS")[0] & c.ST_AUTOCORRECTION
    m.set_input(load_torque=0.6 * m.pull_out_torque(1.0)[0])  # the rotor pushed aside
    m.step(100)
    m.write("P_SOLL", 20000)
    m.step(1)
    assert not m.read("STATUSBITS")[0] & c.ST_AUTOCORRECTION
    m.write("P_SOLL", 20001)
    m.step(1)
    assert m.read("STATUSBITS")[0] & c.ST_AUTOCORRECTION


@pytest.mark.statements("mis:11.9.3:1")
def test_canopen_synchronous_pdos(rig) -> None:  # type: ignore[no-untyped-def]
    """§11.9.3: a TPDO of type 1 after every SYNC, of type 2 after every second; an RPDO of a
    synchronous type is carried out at the next SYNC."""
    import struct

    node = rig.node()
    node.sdo[0x1800][1].raw = 0x185
    node.sdo[0x1802][2].raw = 2
    node.sdo[0x1802][1].raw = 0x385
    node.sdo[0x1414][1].raw = 0x215
    node.sdo[0x1414][2].raw = 1
    node.nmt.state = "OPERATIONAL"
    rig.clear()
    for _ in range(4):
        rig.send(0x80)
    assert (len(rig.sent(0x185)), len(rig.sent(0x385))) == (4, 2)
    rig.send(0x215, struct.pack("<lhh", 1234, 100, 100))
    assert rig.m.read("P_SOLL")[0] == 0
    rig.send(0x80)
    assert rig.m.read("P_SOLL")[0] == 1234


@pytest.mark.statements("mis:11.7.4:1")
def test_canopen_lss_bit_timing(rig) -> None:  # type: ignore[no-untyped-def]
    """§11.7.4: bit timing codes of the CiA table (5 reserved), stored by §11.7.5."""
    lss = rig.net.lss
    lss.send_switch_state_global(lss.CONFIGURATION_STATE)
    with pytest.raises(Exception, match="(?i)error"):
        lss.configure_bit_timing(5)
    lss.configure_bit_timing(4)  # 125 kbit/s
    lss.store_configuration()
    lss.send_switch_state_global(lss.WAITING_STATE)
    assert rig.m.read("FBUS_BAUD")[0] == 4 and rig.m.flash_image(0)[167] == 4


def _dmx(pos: int, control: int = 60, acc: int = 0, vel: int = 0):  # type: ignore[no-untyped-def]
    from jvl_gym.protocol.dmx512 import DmxPacket

    slots = bytearray(512)
    slots[0:3] = bytes([pos >> 8, pos & 0xFF, control])
    slots[499:501] = bytes([acc, vel])
    return DmxPacket(0, bytes(slots))


@pytest.mark.statements("mis:13.1.9:1")
def test_dmx512_jogging_by_inputs() -> None:
    """§13.1.9: input 1 on: velocity mode at 0 RPM, DMX ignored; input 2 +, input 3 − jog
    velocity; input 1 off: the default velocity, P_SOLL at the position reached, passive."""
    from jvl_gym.protocol.dmx512 import DmxReceiver, DmxSettings

    m = _motor(IN_POSITION_COUNT=0)
    r = DmxReceiver(m, 0, DmxSettings(homing=False, jog_velocity=5000,
                                      default_velocity=70000))
    r.packet(_dmx(1000))
    m.set_input(digital_inputs=0b001)
    m.step(1)
    r.poll()
    assert m.read("MODE_REG")[0] == c.VELOCITY and m.read("V_SOLL")[0] == 0
    r.packet(_dmx(2000))
    assert m.read("P_SOLL")[0] == 1000
    for bits, v in ((0b011, 5000), (0b001, 0), (0b101, -5000)):
        m.set_input(digital_inputs=bits)
        m.step(1)
        r.poll()
        assert m.read("V_SOLL")[0] == v
    m.step(200)
    m.set_input(digital_inputs=0)
    m.step(1)
    r.poll()
    assert m.read("V_SOLL")[0] == 70000 and m.read("P_SOLL")[0] == m.read("P_IST")[0]
    m.step(300)
    assert m.read("MODE_REG")[0] == c.PASSIVE


@pytest.mark.statements("mis:13.1.10:2")
def test_dmx512_values_only_with_a_new_position() -> None:
    """§13.1.10: velocity and acceleration "only when a new value for Position is received"."""
    from jvl_gym.protocol.dmx512 import DmxReceiver, DmxSettings

    m = _motor(IN_POSITION_COUNT=0)
    r = DmxReceiver(m, 0, DmxSettings(homing=False, values_with_position=True))
    r.packet(_dmx(10, vel=50))
    r.packet(_dmx(10, vel=90))
    assert m.read("V_SOLL")[0] == 500
    r.packet(_dmx(11, vel=90))
    assert m.read("V_SOLL")[0] == 900 and m.read("P_SOLL")[0] == 11


@pytest.mark.statements("mis:8.2.63:4")
def test_samples_are_read_with_command_53h() -> None:
    """§8.2.63: "The sampled values are read back using the command hex 53 SMC_READSAMPLE":
    each request gives the next sample of the four buffers."""
    from jvl_gym.protocol.mactalk import codec32 as m32
    from jvl_gym.protocol.mactalk.twin16 import Twin

    m = _motor(MY_ADDR=7, SAMPLE1=10, SAMPLE2=12, REC_CNT=3, V_SOLL=6000, V_START=10000)
    m.write("MODE_REG", c.VELOCITY)
    m.write("S_CONTROL", 2)
    m.step(10)
    want = m.sample_buffer()
    twin = Twin(m)
    for k in range(3):
        data = m32.decode(_ask(twin, m32.encode_read_sample(7))).data
        p_ist, v_ist = (int.from_bytes(data[j:j + 4], "little", signed=True) for j in (0, 4))
        assert (p_ist, v_ist) == (want["P_IST"][0][k], want["V_IST"][0][k])
