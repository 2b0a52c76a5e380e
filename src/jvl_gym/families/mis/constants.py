"""Mode numbers, status and error bits and the profile units of the MIS/SMC firmware.

The public constants a task or a tool may use (``constants``, ``table`` and ``task`` are what the
family shows the other layers). Resolution, timing and register scalings are in :mod:`.units`;
this module derives the firmware's internal units from them.

Sources (MIS manual): §8.2.3 (MODE_REG), §8.2.24 (STATUSBITS), §8.2.31 (ERR_BITS), §8.2.32
(WARN_BITS), §8.2.21 (FastMac commands), §5.12.3 (TURNTABLE_MODE), §5.3.6 (SETUP_BITS closed
loop bits), §8.2.49 (ENCODER_TYPE).
"""

from __future__ import annotations

from .units import (
    ACCEL_MAX_RPM_PER_S,
    COUNTS_PER_FULL_STEP,
    COUNTS_PER_REV,
    CUR_SCALE_FULL,
    ENCODER_TYPES,
    FULL_STEPS_PER_REV,
    OUTER_DT,
    VELOCITY_RPM_PER_UNIT,
)

# --- timing -------------------------------------------------------------------------------
OUTER_HZ = 1.0 / OUTER_DT  #: firmware (profile) samples per second
#: plant samples per outer sample (``plant`` docstring: why 10 kHz is enough in the frame of the
#: commanded electrical angle)
INNER_PER_OUTER = 10
INNER_DT = OUTER_DT / INNER_PER_OUTER  #: 100 µs

# --- motor geometry -------------------------------------------------------------------------
#: rotor teeth of a 200-step two-phase hybrid stepper: electrical turns per revolution
POLE_PAIRS = FULL_STEPS_PER_REV // 4
COUNTS_PER_ELECTRICAL_TURN = COUNTS_PER_REV // POLE_PAIRS  #: 8192 counts = 4 full steps

# --- profile units ---------------------------------------------------------------------------
#: 0.01 RPM (V_SOLL …) → counts per outer sample: 25000 → 1706.67 counts/ms
VEL_UNIT_TO_COUNTS = VELOCITY_RPM_PER_UNIT / 60.0 * COUNTS_PER_REV * OUTER_DT
#: RPM/s (A_SOLL, D_SOLL, ACC_EMERG) → counts per outer sample²: 1000 → 6.827 counts/ms²
ACC_UNIT_TO_COUNTS = 1.0 / 60.0 * COUNTS_PER_REV * OUTER_DT * OUTER_DT

# --- MODE_REG (§8.2.3) ------------------------------------------------------------------
PASSIVE = 0
VELOCITY = 1
POSITION = 2
GEAR = 3
STOP = 11
ZERO_SEARCH_1 = 13
ZERO_SEARCH_2 = 14
SAFE = 15
MODE_NAMES: dict[int, str] = {PASSIVE: "passive", VELOCITY: "velocity", POSITION: "position",
                              GEAR: "gear", STOP: "stop", ZERO_SEARCH_1: "zero search type 1",
                              ZERO_SEARCH_2: "zero search type 2", SAFE: "safe"}
#: MODE_REG values a write may request (safe mode only by command, §8.2.3)
WRITABLE_MODES = frozenset({PASSIVE, VELOCITY, POSITION, GEAR, STOP, ZERO_SEARCH_1,
                            ZERO_SEARCH_2})
#: STARTMODE / HOMEMODE values (§8.2.33, §8.2.37)
START_MODES = frozenset({PASSIVE, VELOCITY, POSITION, GEAR})
HOME_MODES = frozenset({0, ZERO_SEARCH_1, ZERO_SEARCH_2})

# --- STATUSBITS (§8.2.24) ----------------------------------------------------------------
ST_AUTOCORRECTION = 1 << 1
ST_IN_PHYSICAL_POSITION = 1 << 2
ST_AT_VELOCITY = 1 << 3
ST_IN_POSITION = 1 << 4
ST_ACCELERATING = 1 << 5
ST_DECELERATING = 1 << 6
ST_ZERO_SEARCH_DONE = 1 << 7
ST_ENCODER_ERROR = 1 << 9
ST_GENERAL_ERROR = 1 << 12
ST_BRAKE_ACTIVE = 1 << 14
ST_CLOSED_LOOP_LAG = 1 << 15
ST_CLOSED_LOOP = 1 << 16
ST_ENCODER_CALIBRATED = 1 << 17
ST_STANDBY_CURRENT = 1 << 18
ST_STO = 1 << 19
ST_ENCODER_OK = 1 << 20
ST_IN_TARGET_POSITION = 1 << 22
ST_STO_A = 1 << 23
ST_STO_B = 1 << 24
#: INPOS_MASK bit 8: the in-position output shows "in physical position" (§5.6.3)
INPOS_PHYSICAL = 1 << 8

# --- ERR_BITS (§8.2.31) --------------------------------------------------------------------
ERR_GENERAL = 1 << 0
ERR_FOLLOW = 1 << 1
ERR_POSITION_LIMIT = 1 << 3
ERR_LOW_BUS = 1 << 4
ERR_OVER_VOLTAGE = 1 << 5
ERR_OUTPUT_DRIVER = 1 << 2
ERR_TEMPERATURE = 1 << 6
ERR_INTERNAL = 1 << 7
ERR_ENCODER_LOST_POSITION = 1 << 8
ERR_ENCODER_REED = 1 << 9
ERR_ENCODER_COM = 1 << 10
ERR_CLOSED_LOOP = 1 << 12
ERR_EXTERNAL_MEMORY = 1 << 13
ERR_SINGLE_TURN_ENCODER = 1 << 14
ERR_H4_ENCODER = 1 << 15
ERR_ZERO_SEARCH_TIMEOUT = 1 << 16
ERR_CVI = 1 << 17
ERR_DRIVER_OVERLOAD = 1 << 18
ERR_STO_ALARM = 1 << 27
ERR_STO = 1 << 29
#: the internal encoder's errors (§7.2.11–13, §7.2.17, §8.2.31 bits 8–10, 14, 15): STATUSBITS
#: bit 9 while any is set
ERR_ENCODER_ANY = (ERR_ENCODER_LOST_POSITION | ERR_ENCODER_REED | ERR_ENCODER_COM
                   | ERR_SINGLE_TURN_ENCODER | ERR_H4_ENCODER)
#: errors a write of ERR_BITS (or FastMac 97) does not clear: the manual's way back is a reset
#: or a power cycle (§7.2.5 output driver, §7.2.10 internal, §7.2.15 closed loop (after a
#: calibration), §7.2.17 single turn encoder,
#: §7.2.20 CVI unstable, §7.2.21 driver overload; §8.2.31: "Other errors will require hardware
#: fixes or intervention")
ERR_NEEDS_RESET = (ERR_OUTPUT_DRIVER | ERR_INTERNAL | ERR_CLOSED_LOOP | ERR_SINGLE_TURN_ENCODER
                   | ERR_CVI | ERR_DRIVER_OVERLOAD)
#: errors user command 354 (preset the encoder position) clears (§7.2.11, §7.2.12)
ERR_CLEARED_BY_PRESET = ERR_ENCODER_LOST_POSITION | ERR_ENCODER_REED

# --- WARN_BITS (§8.2.32) -------------------------------------------------------------------
WARN_POS_LIMIT = 1 << 0
WARN_NEG_LIMIT = 1 << 1
WARN_POS_LIMIT_SEEN = 1 << 2
WARN_NEG_LIMIT_SEEN = 1 << 3
WARN_LOW_BUS = 1 << 4
WARN_TEMPERATURE = 1 << 6
WARN_DRIVER_OVERLOAD = 1 << 8
WARN_STO = 1 << 9

# --- ZERO_SEARCH_BITS (§8.2.67) --------------------------------------------------------------
ZS_USE_INDEX = 1 << 0  #: after the sensor, on to the encoder index, which is the zero
ZS_TURN_AT_LIMIT = 1 << 1  #: the search turns at a limit input instead of stopping
ZS_OPPOSITE_SIDE = 1 << 2  #: the zero on the sensor's back side
ZS_IGNORE_SWITCH = 1 << 4  #: the zero where the motor is, no input looked at
ZS_NO_TIME_OUT = 1 << 5  #: no zero-search time-out

# --- SETUP_BITS (§5.3.6, §8.2.68) ------------------------------------------------------------
SETUP_INVERT_DIRECTION = 1 << 0
SETUP_SYNC_ENCODER = 1 << 5
SETUP_IN_PHYS_POS_CONTINUOUS = 1 << 6
#: SETUP_BITS 10/11: at power-up P_IST from the single-turn encoder / the multi-turn position
#: (§8.2.68, §5.4.3)
SETUP_SINGLE_TURN_AT_POWER_UP = 1 << 10
SETUP_MULTI_TURN_AT_POWER_UP = 1 << 11
SETUP_KEEP_EXT_ENCODER = 1 << 12
SETUP_EXT_ENCODER_INVERSE = 1 << 16
SETUP_NO_LIMIT_ERROR = 1 << 17
SETUP_BRAKE_OFF = 1 << 19  #: "Disable brake" (§5.11.6, §8.2.68)
SETUP_CLOSED_LOOP = 1 << 24
SETUP_CURRENT_CONTROL = 1 << 25
SETUP_LIMITS_WITHOUT_MEMORY = 1 << 28

# --- hardware supervision (§7.2, §5.4.5, §5.11, ``firmware.supervision``) -------------------
#: the P+ level above which the over-voltage error is set (§7.2.8: "> 100 V"), the maximum
#: bus voltage of MAX_VOLTAGE bits 0–15 (§8.2.93) on every type
MAX_BUS_VOLTS = 100
#: a Safe Torque Off channel below this is off (§7.2.18: "measured less than 18 V")
STO_ON_VOLTS = 18.0
#: nominal control (CVI) and STO supply [V] (§8.2.79: "The typical and recommended nominal
#: voltage is 24VDC"): the world inputs' values at rest
NOMINAL_CVI_VOLTS = 24.0
#: ambient temperature at rest [°C]
NOMINAL_AMBIENT_CELSIUS = 25.0
#: Thermal model of the electronics (the manual gives no thermal data, MIS manual §7.2.9 only the
#: limits and the 40 °C ambient maximum): temperature = ambient + a first-order rise to
#: ``THERMAL_RESISTANCE × loss`` with time constant ``THERMAL_TIME_CONSTANT``; the loss is the
#: bridge's conduction loss ``DRIVER_RESISTANCE × I²`` of the phase current amplitude I while
#: the bridge is on (two phases, RMS² = I²/2 each). The values are chosen so that a MIS34x at
#: its largest current (12.7 A amplitude, 16 W) settles 32 K above ambient: within the limits at
#: the 40 °C ambient the manual allows, above 80 °C (warning) at 48 °C and above.
DRIVER_RESISTANCE = 0.1  #: Ω, the two conducting MOSFETs of one phase's H-bridge
THERMAL_RESISTANCE = 2.0  #: K/W, electronics to ambient through the motor's housing
THERMAL_TIME_CONSTANT = 600.0  #: s, the housing's heat capacity × THERMAL_RESISTANCE
#: ms between two temperature measurements (the manual gives none; a temperature with a time
#: constant of minutes needs no faster one)
THERMAL_PERIOD_MS = 10
#: bits of the ``faults`` world input (ERR_BITS positions, §8.2.31) that inject a hardware fault
FAULT_BITS = (ERR_OUTPUT_DRIVER | ERR_INTERNAL | ERR_ENCODER_LOST_POSITION | ERR_ENCODER_REED
              | ERR_ENCODER_COM | ERR_CLOSED_LOOP | ERR_EXTERNAL_MEMORY | ERR_SINGLE_TURN_ENCODER
              | ERR_H4_ENCODER | ERR_DRIVER_OVERLOAD | ERR_STO_ALARM)
#: faults the firmware finds only at its start (§7.2.13 encoder COM, §7.2.16 external memory:
#: "This error will only be set during startup and can be cleared afterwards")
FAULTS_AT_START = ERR_ENCODER_COM | ERR_EXTERNAL_MEMORY
#: the encoder options (ENCODER_TYPE codes, §8.2.49) a fault of the internal encoder needs:
#: the multi-turn H3/H4 (§7.2.11–13), the single-turn H2/H4 (§7.2.17; the closed loop's
#: encoder, §7.2.15, §5.3), the H4 (§8.2.31 bit 15)
FAULT_ENCODERS: dict[int, frozenset[int]] = {
    ERR_ENCODER_LOST_POSITION: frozenset({2, 4}), ERR_ENCODER_REED: frozenset({2, 4}),
    ERR_ENCODER_COM: frozenset({2, 4}), ERR_CLOSED_LOOP: frozenset({1, 3, 4}),
    ERR_SINGLE_TURN_ENCODER: frozenset({1, 3, 4}), ERR_H4_ENCODER: frozenset({4})}
#: the types with the driver overload error (§8.2.31 bit 18: "only available in
#: SMC85/MIS34x/MIS43x")
OVERLOAD_TYPES = ("SMC85", "MIS34", "MIS43")

# --- TURNTABLE_MODE (§5.12.3) -------------------------------------------------------------
TT_OFF, TT_CW, TT_CCW, TT_SHORTEST, TT_MULTI_CW, TT_MULTI_CCW = range(6)

# --- COMMAND: FastMac commands (§8.2.21) --------------------------------------------------
CMD_CLEAR_ERRORS = 97
CMD_P_SOLL_ZERO = 98
CMD_P_IST_ZERO = 99
CMD_V_SOLL_ZERO = 101
CMD_CLEAR_FLAGS = 103
CMD_REGISTER_SET = (108, 109, 110, 111)  #: P_SOLL/V_SOLL/A_SOLL/RUN_CURRENT = Pn/Vn/An/Tn
CMD_RELATIVE = (113, 114)  #: P_SOLL = P_IST + P7 / P8
CMD_SET_POSITION = 119  #: P_IST = P_SOLL = encoder = P_NEW
CMD_ADD_POSITION = 120  #: P_IST, P_SOLL, encoder += P_NEW
CMD_ADD_ACTUAL = 121  #: P_IST, encoder += P_NEW
# --- COMMAND: user commands (§8.2.22) ---------------------------------------------------------
CMD_RESYNC = 257  #: P_IST := encoder position
CMD_PRESET_H3 = 316  #: the H3 encoder's position := P_NEW
CMD_PRESET_POSITION = 354  #: encoder, P_IST and P_SOLL := P_NEW (follow error 0)
CMD_RESET = 267  #: reset the CPU
CMD_SAVE_RESET = 268  #: save to flash, then reset
CMD_SAVE = 269  #: save to flash, continue
CMD_ERASE_PROGRAM = 342  #: clear all flash sectors in the RXP area: erase the stored program
CMD_EMERGENCY_STOP = 398  #: emergency stop with deceleration (ACC_EMERG)
CMD_EMERGENCY_HALT = 399  #: emergency stop without deceleration
#: user commands only a passive or safe motor takes
CMD_PASSIVE_ONLY = (CMD_RESET, CMD_SAVE_RESET, CMD_SAVE)

# --- encoders (§8.2.49, units.ENCODER_TYPES) ----------------------------------------------
#: encoder counts per revolution of each ENCODER_TYPE code (0: no encoder)
ENCODER_CPR = {code: cpr for code, (_, cpr) in ENCODER_TYPES.items()}
ENCODER_H3 = 2  #: ENCODER_TYPE of the H3 absolute multi-turn encoder (§8.2.49)

# --- serial line (§18.2) ---------------------------------------------------------------------
#: MacTalk of the 32-bit register families: registers 1–255, data always 4 bytes
#: (protocol.mactalk.dialect)
MACTALK_DIALECT = "mactalk32"

#: the J1939 NAME the motor claims its address with (§11.8.4): "Identity number: FFFFh,
#: Manufacturer code: FFFh, ECU instance: 1, Function instance: 0, Function: FFh, Vehicle
#: system: 7Fh, Vehicle system instance: 0, Industry group: 0, Arbitrary address capable: 1".
#: The manual's explorer shows the bytes FF FF FF FF 01 FF FE 80 (byte 0 first): the identity
#: number's 21 bits and the manufacturer code's 11 bits all set. The bytes are followed
#: (identity 1FFFFFh, manufacturer 7FFh) rather than the shorter values of the list.
J1939_NAME = 0x80FE_FF01_FFFF_FFFF

# --- the motion panel of jvl-gym studio: the modes and registers behind it (§6, §8.2.3) ------
#: motion → MODE_REG value(s): passive, velocity (jog and run at V_SOLL, its sign the
#: direction), position (a move to P_SOLL at most V_SOLL) and the zero searches (§8.2.3)
MOTION_MODES: dict[str, tuple[int, ...]] = {
    "passive": (PASSIVE,), "velocity": (VELOCITY,), "position": (POSITION,),
    "home": (ZERO_SEARCH_1, ZERO_SEARCH_2)}
#: the registers of a motion: speed, target position, actual position and velocity, software
#: position limits (§8.2.5, §8.2.4, §8.2.10, §8.2.11, §8.2.26, §8.2.27)
MOTION_REGISTERS: dict[str, str] = {
    "speed": "V_SOLL", "target": "P_SOLL", "position": "P_IST", "velocity": "V_IST",
    "min_position": "MIN_P_IST", "max_position": "MAX_P_IST"}
#: registers whose value is a MODE_REG value (§8.2.33 STARTMODE), shown as the modes
MODE_VALUED_REGISTERS: tuple[str, ...] = ("STARTMODE",)

__all__ = [name for name in dir() if name.isupper() and not name.startswith("_")] + [
    "COUNTS_PER_FULL_STEP", "ACCEL_MAX_RPM_PER_S", "CUR_SCALE_FULL"]

