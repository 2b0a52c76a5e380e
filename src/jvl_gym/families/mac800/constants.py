"""Fixed facts of the MAC800 firmware: rates, modes, status and control bits (public module).

Sources: the MAC800 register overview (§1.2: MODE_REG register 2, ERR_STAT register 35,
CNTRL_BITS register 36, UV_HANDLE register 23, HW_SETUP register 39, HOME_MODE register 42)
and the unit figures of :mod:`.units` (sample rate, counts per revolution, scalings). What the
overview leaves open is decided here and in ``docs/families/mac800.md``; each decision says so.
"""

from __future__ import annotations

import math

from ...registers.bits import bit_masks, mask_of
from .units import (
    ANINP_VOLTS_PER_UNIT,
    COUNTS_PER_REV,
    DEGC_CELSIUS_PER_UNIT,
    OVERSPEED_RPM,
    OVERVOLTAGE_VOLTS,
    SAMPLE_HZ,
    T_SOLL_FULL,
    U_24V_VOLTS_PER_UNIT,
    U_BUS_VOLTS_PER_UNIT,
    V_IST_COUNTS_PER_RPM,
)

# --- timing -------------------------------------------------------------------------------
OUTER_HZ = SAMPLE_HZ  #: servo (outer-loop) sample rate [Hz], derived in :mod:`.units`
OUTER_DT = 1.0 / OUTER_HZ
#: current-loop samples per servo sample: OUTLOOPDIV (register 157), read as the outer-loop
#: divider of the current-loop rate, 15 as on the MAC050–141 (7812.5 Hz / 520.8 Hz): the same
#: firmware on a faster clock (decision; the unit figures fix the servo rate, so the divider is
#: a constant of the firmware and the register is read-only)
INNER_PER_OUTER = 15
INNER_HZ = OUTER_HZ * INNER_PER_OUTER  #: 11550 Hz current loop
INNER_DT = 1.0 / INNER_HZ

# --- units --------------------------------------------------------------------------------
RAD_PER_COUNT = 2.0 * math.pi / COUNTS_PER_REV
VF_FULL = T_SOLL_FULL  #: VF_OUT / T_SOLL full scale = peak torque (register 7)
#: ELDEG_IST units per electrical turn (decision: a 12-bit angle; the overview gives no scale)
ELDEG_PER_TURN = 4096
ADC_FULL = 1023  #: IA_IST..IC_IST range ±1023 (decision, as the MAC050–141)
PWM_FULL = 1023  #: UA_VAL..UC_VAL ±1023 = ±U_BUS/2 phase to bus midpoint (decision)
ANINP_FULL = 2047  #: ANINP ±2047 ↔ ±10 V (register 170: V = ANINP × 0.0048828)
ANINP_VOLTS = ANINP_FULL * ANINP_VOLTS_PER_UNIT
REC_CNT_MAX = 895  #: sample buffer depth (register 162; decision, as the MAC050–141)
#: 100 % of I2T / UIT (registers 17, 19: "100 %" levels; decision: 65536)
PERCENT_100 = 65536
#: V_IST (counts/sample) of the over-speed limit, ERR_STAT bit 13 (3600 RPM)
OVERSPEED_COUNTS = OVERSPEED_RPM * V_IST_COUNTS_PER_RPM
#: the 24 V control supply is too low below this voltage (ERR_STAT bit 17; decision: −25 %)
U24V_MIN_VOLTS = 18.0
#: under-voltage of the high-voltage bus (ERR_STAT bits 9, 10; decision: UVMIN is "not used",
#: so a fixed level of 60 % of the 325 V nominal bus)
UV_BUS_VOLTS = 195.0
#: speed below which a stop ramp counts as finished [counts/sample] (decision: 10 RPM)
STOP_SPEED_COUNTS = 10.0 * V_IST_COUNTS_PER_RPM
#: ambient temperature of the motor model [°C] (decision)
AMBIENT_CELSIUS = 25.0

# --- modes (register 2, MODE_REG) -----------------------------------------------------------
PASSIVE_MODE = 0
VELOCITY_MODE = 1
POSITION_MODE = 2
GEAR_MODE = 3
ANALOG_TORQUE_MODE = 4
ANALOG_VELOCITY_MODE = 5
ANALOG_VELOCITY_GEAR_MODE = 6
TORQUE_ZERO_SEARCH = 12
SENSOR1_ZERO_SEARCH = 13
SENSOR2_ZERO_SEARCH = 14
ANALOG_VELOCITY_DEADBAND_MODE = 16
VELOCITY_ANALOG_TORQUE_MODE = 17
ANALOG_GEAR_MODE = 18
COIL_MODE = 19
AIR_CYLINDER_MODE = 20
ANALOG_POSITION_MODE = 21
#: MODE_REG value → name (register 2)
MODE_NAMES: dict[int, str] = {
    PASSIVE_MODE: "Passive", VELOCITY_MODE: "Velocity", POSITION_MODE: "Position",
    GEAR_MODE: "Gear", ANALOG_TORQUE_MODE: "Analog torque",
    ANALOG_VELOCITY_MODE: "Analog velocity", ANALOG_VELOCITY_GEAR_MODE: "Analog velocity/gear",
    TORQUE_ZERO_SEARCH: "Torque zero search", SENSOR1_ZERO_SEARCH: "Sensor type 1 zero search",
    SENSOR2_ZERO_SEARCH: "Sensor type 2 zero search",
    ANALOG_VELOCITY_DEADBAND_MODE: "Analog velocity with deadband",
    VELOCITY_ANALOG_TORQUE_MODE: "Velocity/analog torque", ANALOG_GEAR_MODE: "Analog gear",
    COIL_MODE: "Coil", AIR_CYLINDER_MODE: "Air cylinder",
    ANALOG_POSITION_MODE: "Analog to position"}
#: the modes the simulator runs (the others are refused with a message naming them)
RUNNABLE_MODES = frozenset({0, 1, 2, 3, 4, 5, 6, 12, 13, 14, 16, 17, 18, 21})

# --- ERR_STAT bits (register 35) ------------------------------------------------------------
#: ERR_STAT bits by name, bit 0 first; each name is a constant of this module too
ERR_STAT_BITS = bit_masks("I2T_ERR FLW_ERR FNC_ERR UIT_ERR IN_POS ACC_FLAG DEC_FLAG PLIM_ERR "
                          "DEGC_ERR UV_ERR UV_DETECT OV_ERR IPEAK_ERR SPEED_ERR DIS_P_LIM "
                          "INDEX_ERR OLD_FILT_ERR U24V_ERR")
globals().update(ERR_STAT_BITS)
#: errors after which the motor stops with ACC_EMERG, then goes passive (decision)
STOPPING_ERRORS = mask_of(ERR_STAT_BITS, "I2T_ERR FLW_ERR FNC_ERR UIT_ERR PLIM_ERR DEGC_ERR "
                                         "SPEED_ERR")
#: errors after which the motor goes passive at once: the power stage or the feedback cannot
#: be trusted, or braking would feed the fault (decision)
PASSIVE_ERRORS = mask_of(ERR_STAT_BITS, "OV_ERR IPEAK_ERR INDEX_ERR OLD_FILT_ERR U24V_ERR")
#: errors that keep the motor passive until cleared in ERR_STAT (decision)
BLOCKING_ERRORS = STOPPING_ERRORS | PASSIVE_ERRORS | ERR_STAT_BITS["UV_ERR"]
#: the error bits (the blocking ones) by mask, in bit order
ERROR_NAMES: dict[int, str] = {mask: name for name, mask in ERR_STAT_BITS.items()
                               if mask & BLOCKING_ERRORS}

# --- CNTRL_BITS (register 36), UV_HANDLE (register 23), HW_SETUP (register 39) -------------
#: each register's bits by name, bit 0 first; each name is a constant of this module too
CNTRL_BITS_BITS = bit_masks("RECORDBIT REWINDBIT RECINNERBIT RELPOSPSOLL RELPOSPFNC SYNCPOSAUTO "
                            "SYNCPOSMAN MAN_NO_BRAKE SYNCPOSREL INDEX_HOME")
UV_HANDLE_BITS = bit_masks("SET_UV_ERR UV_GO_PASSIVE UV_VSOLL0")
HW_SETUP_BITS = bit_masks("DIRAWR DIRBWR PULSEOUT XSEL1 XPRINP NOFILT INVXDIR")
globals().update(CNTRL_BITS_BITS, **UV_HANDLE_BITS, **HW_SETUP_BITS)

# --- HOME_MODE (register 42) ----------------------------------------------------------------
HOME_DONE = 1 << 16
HOME_MODE_MASK = 0xFFFF

# --- measurement scalings used by the firmware (from :mod:`.units`) -------------------------
U_BUS_VOLTS = U_BUS_VOLTS_PER_UNIT
U_24V_VOLTS = U_24V_VOLTS_PER_UNIT
DEGC_CELSIUS = DEGC_CELSIUS_PER_UNIT
OVERVOLTAGE = OVERVOLTAGE_VOLTS

# --- serial line (quick guide §1.3) ----------------------------------------------------------
#: MacTalk of the 32-bit register families: data always 4 bytes, LSB first
#: (protocol.mactalk.dialect)
MACTALK_DIALECT = "mactalk32"

# --- the motion panel of jvl-gym studio: the modes and registers behind it (overview §1.2) ---
#: motion → MODE_REG value(s): passive, velocity (jog and run at V_SOLL, its sign the
#: direction), position (a move to P_SOLL at most V_SOLL) and the zero searches (register 2)
MOTION_MODES: dict[str, tuple[int, ...]] = {
    "passive": (PASSIVE_MODE,), "velocity": (VELOCITY_MODE,), "position": (POSITION_MODE,),
    "home": (TORQUE_ZERO_SEARCH, SENSOR1_ZERO_SEARCH, SENSOR2_ZERO_SEARCH)}
#: the registers of a motion: speed, target position, actual position and velocity, software
#: position limits (registers 5, 3, 10, 11: V_IST16, in V_SOLL's finer unit, 28, 30)
MOTION_REGISTERS: dict[str, str] = {
    "speed": "V_SOLL", "target": "P_SOLL", "position": "P_IST", "velocity": "V_IST16",
    "min_position": "MIN_P_IST", "max_position": "MAX_P_IST"}
#: registers whose value is a MODE_REG value (register 37 START_MODE), shown as the modes
MODE_VALUED_REGISTERS: tuple[str, ...] = ("START_MODE",)
