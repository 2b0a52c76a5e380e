"""The MIS hardware supervision as the manual describes it: over-voltage (MIS manual §7.2.8,
§8.2.93), the control voltage CVI (§5.4.5, §7.2.20, §8.2.79–82), the electronics' temperature
(§7.2.9, §8.2.25, §8.2.127, §8.2.129), Safe Torque Off (§7.2.18, §8.2.24, §8.2.31–32) and the
electromechanical brake (§5.6.4, §5.11, §8.2.106). Injected faults: test_mis_supervision_faults;
the world inputs' checks: test_mis_supervision_inputs."""

from __future__ import annotations

import math

import numpy as np
import pytest

from jvl_gym import MotorArray
from jvl_gym.families.mis import constants as c
from jvl_gym.families.mis import layout as L


def _running(motor: str = "MIS232", setup: dict | None = None, **params: float) -> MotorArray:
    """One motor running at 300 RPM in velocity mode."""
    m = MotorArray(motor, n=1, seed=0, setup=setup, **params)
    m.write_many({"V_SOLL": 30000, "A_SOLL": 10000, "ACC_EMERG": 20000})
    m.write("MODE_REG", c.VELOCITY)
    m.step(100)
    assert m.read("V_IST")[0] == 30000
    return m


def _err(m: MotorArray) -> int:
    return int(m.read("ERR_BITS")[0])


def _warn(m: MotorArray) -> int:
    return int(m.read("WARN_BITS")[0])


def _status(m: MotorArray) -> int:
    return int(m.read("STATUSBITS")[0])


# --- over-voltage ----------------------------------------------------------------------------
@pytest.mark.statements("mis:8.2.31:8", "mis:8.2.93:2", "mis:8.2.93:3", "mis:7.2.8:1")
def test_over_voltage_above_100_v_is_an_error_and_the_motor_goes_passive() -> None:
    """§7.2.8: "A too high P+ voltage (> 100 V)": ERR_BITS bit 5, "Motor is set in Passive
    mode"; "Reset the motor, clear the error bit(s) in register 35 or cycle the power".
    §8.2.93: MAX_VOLTAGE bits 0–15 hold the bus voltage limit, bits 16–31 the full-scale motor
    current in mA RMS (the MIS232's 1022 × 5.87 mA)."""
    m = _running()
    assert m.read("MAX_VOLTAGE")[0] & 0xFFFF == 100
    assert m.read("MAX_VOLTAGE")[0] >> 16 == round(1022 * 5.87)
    m.set_input(supply_volts=99.0)
    m.step(20)
    assert _err(m) == 0
    m.set_input(supply_volts=101.0)
    m.step(1)
    assert _err(m) == c.ERR_OVER_VOLTAGE | c.ERR_GENERAL
    # the error stop with ACC_EMERG (20000 RPM/s: 300 RPM in 15 ms), then passive
    m.step(30)
    assert m.read("MODE_REG")[0] == c.PASSIVE and m.read("V_IST")[0] == 0
    m.write("ERR_BITS", 0)  # still too high: set again at the next sample
    m.step(1)
    assert _err(m) & c.ERR_OVER_VOLTAGE
    m.set_input(supply_volts=48.0)
    m.write("ERR_BITS", 0)
    m.step(5)
    assert _err(m) == 0
    m.write("MODE_REG", c.VELOCITY)  # back to normal operation


# --- control voltage (CVI) -------------------------------------------------------------------
@pytest.mark.statements("mis:8.2.82:2")
def test_cvi_volt_reads_the_control_voltage_in_8_764_mv_units() -> None:
    """§8.2.82: CVI_VOLT is "The measured control voltage" in 8.764 mV units."""
    m = MotorArray("MIS232", n=2, seed=0)
    assert list(m.read("CVI_VOLT")) == [round(24.0 / 8.764e-3)] * 2  # the nominal 24 V
    m.set_input(control_volts=np.array([20.0, 30.0]))
    m.step(1)
    assert list(m.read("CVI_VOLT")) == [round(20.0 / 8.764e-3), round(30.0 / 8.764e-3)]


@pytest.mark.statements("mis:8.2.81:2", "mis:8.2.31:20", "mis:7.2.20:1")
def test_below_save_voltage_all_motor_activity_stops_with_the_cvi_error() -> None:
    """§8.2.81: below SAVE_VOLTAGE "the program shuts down and all motor activity stops";
    §7.2.20: the CVI below its minimum sets ERR_BITS bit 17, "Motor is set in Passive mode",
    back to normal by "Cycle power / Make a software reset" (a write of 0 does not clear it)."""
    m = _running()
    save = int(m.read("SAVE_VOLTAGE")[0])  # 1710 = 15 V
    m.set_input(control_volts=(save + 5) * 8.764e-3)
    m.step(10)
    assert _err(m) == 0 and m.read("V_IST")[0] == 30000
    m.set_input(control_volts=(save - 5) * 8.764e-3)
    m.step(1)
    ticks = int(m.read("TICKS")[0])
    assert m.read("MODE_REG")[0] == c.PASSIVE
    assert _err(m) == c.ERR_CVI | c.ERR_GENERAL
    assert m.state[0, L.S_BRIDGE] == 0.0 and m.state[0, L.S_I_AMP] == 0.0  # at once, no ramp
    p_ist = int(m.read("P_IST")[0])
    m.step(50)
    assert m.read("TICKS")[0] == ticks and m.read("P_IST")[0] == p_ist  # the program stopped
    assert m.current_amplitude[0] < 1e-3
    m.set_input(control_volts=24.0)
    m.step(200)  # accepted again after ACCEPT_COUNT = 100 ms: the program runs, in error
    assert m.read("TICKS")[0] > ticks
    m.write("ERR_BITS", 0)
    assert _err(m) == c.ERR_CVI | c.ERR_GENERAL
    with pytest.raises(Exception, match="ERR_BITS"):
        m.write("MODE_REG", c.VELOCITY)
    m.write("COMMAND", c.CMD_RESET)
    assert _err(m) == 0
    m.write("MODE_REG", c.VELOCITY)


@pytest.mark.statements("mis:8.2.79:2", "mis:8.2.80:2", "mis:5.4.5:1")
def test_the_start_waits_for_accept_count_measurements_above_accept_voltage() -> None:
    """§8.2.79: the acceptance voltage is "required at the CVI supply terminal … for the
    program to start up"; §8.2.80: "the number of times a voltage above the acceptance voltage
    must have been measured before the program starts" (1 ms each, §5.4.5)."""
    m = MotorArray("MIS232", n=1, seed=0,
                   setup={"ACCEPT_COUNT": 30, "STARTMODE": c.VELOCITY, "V_SOLL": 10000})
    accept = int(m.read("ACCEPT_VOLTAGE")[0])  # 2052 = 18 V
    m.set_input(control_volts=accept * 8.764e-3)  # at the acceptance voltage: not above it
    m.software_reset()
    m.step(100)
    assert m.read("TICKS")[0] == 0 and m.read("V_IST")[0] == 0
    m.set_input(control_volts=(accept + 3) * 8.764e-3)
    m.step(29)
    assert m.read("TICKS")[0] == 0 and m.read("V_IST")[0] == 0
    m.set_input(control_volts=(accept - 3) * 8.764e-3)  # a dip: the count starts again
    m.step(1)
    m.set_input(control_volts=24.0)
    m.step(29)
    assert m.read("TICKS")[0] == 0
    m.step(1)  # the 30th measurement above: the program starts in STARTMODE
    assert m.read("TICKS")[0] == 1 and m.read("MODE_REG")[0] == c.VELOCITY
    m.step(50)
    assert m.read("V_IST")[0] > 0


@pytest.mark.statements("mis:5.4.5:1")
def test_save_voltage_stops_the_motor_where_the_position_back_up_keeps_it() -> None:
    """§5.4.5: SAVE_VOLTAGE "will trigger the flash backup save operation (and stop all other
    motor operation)"; the next power-up with SETUP_BITS bit 11 and no encoder takes the last
    stored value (§5.4.3's table); the start after power-up waits for ACCEPT_VOLTAGE
    ACCEPT_COUNT times."""
    m = _running(setup={"SETUP_BITS": c.SETUP_MULTI_TURN_AT_POWER_UP}, encoder_type=0)
    m.set_input(control_volts=10.0)
    m.step(1)
    stored = int(m.read("P_IST")[0])
    assert stored != 0
    m.step(100)  # the shaft coasts to a stop; P_IST stays
    m.software_reset()  # power-up with the CVI still low: the program waits
    m.step(10)
    assert m.read("P_IST")[0] == stored and m.read("TICKS")[0] == 0
    m.set_input(control_volts=24.0)
    m.step(int(m.read("ACCEPT_COUNT")[0]) + 5)
    assert m.read("P_IST")[0] == stored and m.read("TICKS")[0] == 6


# --- temperature -----------------------------------------------------------------------------
@pytest.mark.statements("mis:8.2.25:2", "mis:8.2.129:2")
def test_temp_and_temp_highres_follow_the_electronics_temperature() -> None:
    """§8.2.25: "Tc = 2.27 * Value"; §8.2.129: TEMP_HIGHRES in °C/1000. The electronics sit at
    the ambient temperature and rise by first order with the bridge's loss (constants),
    measured every THERMAL_PERIOD_MS."""
    period = c.THERMAL_PERIOD_MS
    m = MotorArray("MIS340", n=1, seed=0)
    m.step(1)
    assert m.read("TEMP_HIGHRES")[0] == 25000 and m.read("TEMP")[0] == round(25 / 2.27)
    m.set_input(ambient_celsius=40.0)
    m.step(period)
    assert m.read("TEMP_HIGHRES")[0] == 40000 and m.read("TEMP")[0] == round(40 / 2.27)
    m.write_many({"RUN_CURRENT": 1533, "V_SOLL": 30000, "A_SOLL": 100000})
    m.write("MODE_REG", c.VELOCITY)
    m.step(5000 - period)
    amps = math.sqrt(2.0) * 1533 * 5.87e-3
    rise = c.THERMAL_RESISTANCE * c.DRIVER_RESISTANCE * amps**2 * (
        1.0 - math.exp(-5.0 / c.THERMAL_TIME_CONSTANT))
    assert rise > 0.2
    assert m.read("TEMP_HIGHRES")[0] == pytest.approx(1000 * (40.0 + rise), abs=3)
    m.write("MODE_REG", c.PASSIVE)
    m.step(500)  # the stop ramp, then passive: the bridge off
    hot = int(m.read("TEMP_HIGHRES")[0])
    m.step(3000)  # cooling: the rise decays with the time constant
    assert m.read("TEMP_HIGHRES")[0] == pytest.approx(
        40000 + (hot - 40000) * math.exp(-3.0 / c.THERMAL_TIME_CONSTANT), abs=1)
    assert m.read("TEMP_HIGHRES")[0] < hot


@pytest.mark.statements("mis:8.2.127:2", "mis:8.2.31:9", "mis:8.2.32:7", "mis:7.2.9:1")
def test_temperature_warning_above_80_and_error_above_90_degrees() -> None:
    """§8.2.127: TEMP_LIMITS bits 0–15 the warning limit, 16–31 the error limit [°C]; §8.2.32
    bit 6 "Temperature has been above 80°C" (kept: "remembered state"); §7.2.9: "higher than
    90°C", ERR_BITS bit 6, passive; "Reset the motor, clear the error bit(s) …" once cooled."""
    m = _running()
    limits = int(m.read("TEMP_LIMITS")[0])
    assert (limits & 0xFFFF, limits >> 16) == (80, 90)
    period = c.THERMAL_PERIOD_MS  # one temperature measurement
    m.set_input(ambient_celsius=79.5)
    m.step(period)
    assert _warn(m) & c.WARN_TEMPERATURE == 0
    m.set_input(ambient_celsius=85.0)
    m.step(period)
    assert _warn(m) & c.WARN_TEMPERATURE and _err(m) == 0
    m.set_input(ambient_celsius=50.0)
    m.step(period)
    assert _warn(m) & c.WARN_TEMPERATURE  # has been above 80 °C
    m.write("WARN_BITS", 0)
    m.step(period)
    assert _warn(m) & c.WARN_TEMPERATURE == 0
    m.set_input(ambient_celsius=95.0)
    m.step(period)
    assert _err(m) == c.ERR_TEMPERATURE | c.ERR_GENERAL
    m.step(30)
    assert m.read("MODE_REG")[0] == c.PASSIVE
    m.write("ERR_BITS", 0)  # still too hot
    m.step(period)
    assert _err(m) & c.ERR_TEMPERATURE
    m.set_input(ambient_celsius=30.0)
    m.write("ERR_BITS", 0)
    m.step(1)
    assert _err(m) == 0


# --- Safe Torque Off -------------------------------------------------------------------------
@pytest.mark.statements("mis:8.2.24:19", "mis:8.2.24:23", "mis:8.2.24:24", "mis:8.2.31:23",
                        "mis:8.2.32:10", "mis:7.2.18:1")
def test_an_sto_channel_below_18_v_takes_the_torque_off_at_once() -> None:
    """§7.2.18: "One of the two inputs STO channel A or STO channel B has been measured less than
    18 V": passive; back by "Apply a stable 24 V to both STO channels and clear the error
    bit(s)". §8.2.31 bit 29 STO, §8.2.32 bit 9 "Safe torque off is active", §8.2.24 bits 19
    (STO), 23/24 (channel A/B)."""
    m = _running()
    assert _status(m) & (c.ST_STO_A | c.ST_STO_B | c.ST_STO) == c.ST_STO_A | c.ST_STO_B
    m.set_input(sto_b=18.0)
    m.step(5)
    assert _err(m) == 0
    m.set_input(sto_b=17.9)
    m.step(1)
    assert m.read("MODE_REG")[0] == c.PASSIVE and m.read("V_IST")[0] == 0  # no ramp
    assert m.state[0, L.S_BRIDGE] == 0.0
    assert _err(m) == c.ERR_STO | c.ERR_GENERAL
    assert _warn(m) & c.WARN_STO
    assert _status(m) & (c.ST_STO_A | c.ST_STO_B | c.ST_STO) == c.ST_STO_A | c.ST_STO
    m.write("ERR_BITS", 0)  # the channel still off
    m.step(1)
    assert _err(m) & c.ERR_STO
    m.set_input(sto_b=24.0)
    m.write("ERR_BITS", 0)
    m.step(1)
    assert _err(m) == 0 and _warn(m) & c.WARN_STO == 0
    assert _status(m) & (c.ST_STO_A | c.ST_STO_B | c.ST_STO) == c.ST_STO_A | c.ST_STO_B
    m.write("MODE_REG", c.VELOCITY)
    m.step(100)
    assert m.read("V_IST")[0] == 30000


# --- brake -----------------------------------------------------------------------------------
def _braked(**regs: int) -> MotorArray:
    m = MotorArray("MIS232", n=1, seed=0, brake_torque=2.0)
    m.write_many({"V_SOLL": 30000, "A_SOLL": 10000, **regs})
    return m


@pytest.mark.statements("mis:8.2.24:14", "mis:5.11.2:1", "mis:8.2.106:2", "mis:5.6.4:1")
def test_the_brake_releases_after_t_off_in_an_active_mode_and_holds_in_passive() -> None:
    """§5.11.2: "The brake is always active in Passive mode"; entering an active mode "there
    will be a short delay (typically ~40 ms) before the motor can move"; §8.2.106: BRAKE bits
    0–7 the output, 8–15 T_ON, 16–23 T_OFF (the manual's example: output 4, 40 ms, 50 ms);
    §5.6.4: the output "goes high when the brake is released, and … low when the brake is
    engaged"; §8.2.24 bit 14: brake active."""
    m = _braked(BRAKE=0x00322808, IOSETUP=0x08 << 8)  # T_ON 40 ms, T_OFF 50 ms, IO4 out
    m.step(5)
    assert _status(m) & c.ST_BRAKE_ACTIVE and m.read("OUTPUTS")[0] & 0x08 == 0
    m.write("MODE_REG", c.VELOCITY)
    m.step(1)
    assert m.read("OUTPUTS")[0] & 0x08  # the output at once
    m.step(48)
    assert _status(m) & c.ST_BRAKE_ACTIVE and m.read("V_IST")[0] == 0  # still releasing
    m.step(1)
    assert _status(m) & c.ST_BRAKE_ACTIVE == 0  # 50 ms after the activation
    m.step(5)
    assert m.read("V_IST")[0] > 0
    m.step(100)
    m.write("MODE_REG", c.PASSIVE)  # the stop ramp (D_SOLL 1000 RPM/s), then the brake
    m.step(600)
    assert m.read("MODE_REG")[0] == c.PASSIVE and m.read("OUTPUTS")[0] & 0x08 == 0
    assert _status(m) & c.ST_BRAKE_ACTIVE


@pytest.mark.statements("mis:8.2.68:14", "mis:5.11.4:1", "mis:8.2.24:14")
def test_the_brake_holds_the_shaft_in_passive_unless_setup_bit_19_disables_it() -> None:
    """§5.11.1: the brake holds "the position in Passive mode"; §5.11.6: SETUP_BITS bit 19
    "will disable the brake which will allow the machine operator to move the shaft", and
    STATUSBITS bit 14 "If Bit14 is 0 the brake is not active"."""
    m = _braked()
    m.set_input(load_torque=1.0)  # below the brake's 2 N·m
    m.step(300)
    assert abs(m.position_rad[0]) < 1e-6 and _status(m) & c.ST_BRAKE_ACTIVE
    m.write("SETUP_BITS", c.SETUP_BRAKE_OFF)
    m.step(300)
    assert _status(m) & c.ST_BRAKE_ACTIVE == 0
    assert m.position_rad[0] < -1.0  # the load turns the free shaft
    free = MotorArray("MIS232", n=1, seed=0)  # no brake: bit 14 never set
    free.step(10)
    assert int(free.read("STATUSBITS")[0]) & c.ST_BRAKE_ACTIVE == 0


def test_the_factory_limits_survive_a_save_in_flash_and_a_reset() -> None:
    """Flash holds the writable registers; the read-only factory limits MAX_VOLTAGE (§8.2.93)
    and TEMP_LIMITS (§8.2.127: "They are factory settings") stay, so a motor saved and reset
    starts without an over-voltage or temperature error."""
    m = MotorArray("MIS232", n=1, seed=0)
    limits = (int(m.read("MAX_VOLTAGE")[0]), int(m.read("TEMP_LIMITS")[0]))
    m.write_many({"STARTMODE": c.VELOCITY, "V_SOLL": 1000})
    m.write("COMMAND", c.CMD_SAVE_RESET)
    m.step(5)
    assert (int(m.read("MAX_VOLTAGE")[0]), int(m.read("TEMP_LIMITS")[0])) == limits
    assert _err(m) == 0 and m.read("MODE_REG")[0] == c.VELOCITY
    m.reset()
    m.step(5)
    assert _err(m) == 0 and m.read("MODE_REG")[0] == c.VELOCITY
