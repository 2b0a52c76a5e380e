"""Fixed facts of the MIS/SMC step motors: resolution, timing and register unit scalings.

Source: the MIS/SMC user manual (MIS17x, 23x, 34x, 43x; SMC66/SMC85). Section numbers below are
that manual's: §8.2 is the register list, §5.3 the closed loop (§5.3.3 current control,
§5.3.7 special settings), §5.8 the absolute encoder options, §2.3.5 the analogue filter.

Resolution: "The MISxxx motor family all have 409600 counts per motor revolution" (§8.2.4);
"2048 counts (1 full step)" (§5.3.3) gives 409600/2048 = 200 full steps per revolution, in line
with "the motor can only stall in multiples of a 1/50 shaft revolution" (§5.8.1: 4 full steps of a
two-phase hybrid stepper).

Timing: the manual states no profile-generator sample rate. It gives millisecond-based registers
(TICKS, S_TIME, STANDBY_TIME, INPUT_FILTER_CNT) and the 1 ms update of the unfiltered analogue
inputs (§8.2.46); :data:`OUTER_DT` = 1 ms is the simulator's decision built on those.
"""

from __future__ import annotations

import math
from pathlib import Path

from ...registers.scaling import linear_units

__all__ = [
    "COUNTS_PER_REV",
    "COUNTS_PER_RAD",
    "FULL_STEPS_PER_REV",
    "COUNTS_PER_FULL_STEP",
    "OUTER_DT",
    "VELOCITY_RPM_PER_UNIT",
    "VELOCITY_MAX_UNITS",
    "ACCEL_MAX_RPM_PER_S",
    "CURRENT_AMPS_PER_UNIT",
    "CURRENT_AMPS_PER_UNIT_BY_DRIVER",
    "RUN_CURRENT_MAX",
    "ANALOGUE_VOLTS_PER_UNIT",
    "ANALOGUE_FULL",
    "ANALOGUE_RAW_PERIOD_S",
    "ANALOGUE_FILTERED_PERIOD_S",
    "BUSVOL_VOLTS_PER_UNIT",
    "BUSVOL_VOLTS_PER_UNIT_DETAIL",
    "CVI_VOLTS_PER_UNIT",
    "TEMP_CELSIUS_PER_UNIT",
    "TEMP_HIGHRES_CELSIUS_PER_UNIT",
    "TEMP_WARNING_CELSIUS",
    "TEMP_ERROR_CELSIUS",
    "CUR_SCALE_FULL",
    "CUR_SCALE_CLOCK_HZ",
    "EXT_ENCODER_VEL_WINDOW_S",
    "DIGITAL_INPUT_UNFILTERED_PERIOD_S",
    "LOWBUSCVI_PERIOD_S",
    "ZERO_SEARCH_TIMEOUT_DEFAULT_S",
    "MOTOR_TYPE_CODES",
    "ENCODER_TYPES",
    "cur_scale_inc_step_s",
    "cur_scale_dec_step_s",
]

# --- resolution (§8.2.4, §5.3.3) ------------------------------------------------------------
COUNTS_PER_REV = 409600  #: motor counts (positions, P_IST, GEAR1 default) per revolution
COUNTS_PER_RAD = COUNTS_PER_REV / (2.0 * math.pi)  #: motor counts per radian of the rotor
FULL_STEPS_PER_REV = 200  #: two-phase hybrid stepper, 1.8° per full step
COUNTS_PER_FULL_STEP = COUNTS_PER_REV // FULL_STEPS_PER_REV  #: 2048 microsteps per full step

# --- timing (decision, see the module docstring) ---------------------------------------------
OUTER_DT = 1e-3  #: profile/firmware step of the simulator [s]

# --- motion units (§8.2.5, §8.2.6) ----------------------------------------------------------
VELOCITY_RPM_PER_UNIT = 0.01  #: V_SOLL, V_IST, V_START, V_HOME, Vn: "25000 = 250 RPM"
VELOCITY_MAX_UNITS = 300000  #: ±300000 = ±3000 RPM
ACCEL_MAX_RPM_PER_S = 500000  #: A_SOLL, D_SOLL, ACC_EMERG, An in RPM/s, 1 … 500000

# --- currents (§8.2.7, overview §8.2.1) -----------------------------------------------------
CURRENT_AMPS_PER_UNIT = 5.87e-3  #: RUN_CURRENT, STANDBY_CURRENT, Tn: 5.87 mA RMS (§8.2.7)
#: the overview's driver-dependent units (C = 9 A, B = 6 A, A = 3 A drivers); §8.2.7 uses
#: 5.87 mA for every motor with a lower maximum setting, which the table follows
CURRENT_AMPS_PER_UNIT_BY_DRIVER = {"C": 5.87e-3, "B": 3.91e-3, "A": 1.96e-3}
#: maximum RUN_CURRENT per motor size (§8.2.7: 4, 6, 9, 9, 6 A RMS / 5.87 mA)
RUN_CURRENT_MAX = {"MIS17x": 681, "MIS23x": 1022, "MIS34x": 1533, "MIS43x": 1533,
                   "MIL34x": 1022}

# --- analogue inputs (§2.3.5, §8.2.45, §8.2.46) ----------------------------------------------
ANALOGUE_FULL = 4095  #: 12-bit ADC: 5.00 V reads 4095
ANALOGUE_VOLTS_PER_UNIT = 5.0 / 4095  #: 1.221 mV per count
ANALOGUE_RAW_PERIOD_S = 1e-3  #: unfiltered inputs (89–96) updated about every 1 ms
ANALOGUE_FILTERED_PERIOD_S = 10e-3  #: filtered inputs (81–88) updated every 10 ms

# --- supply and temperature (§8.2.47, §8.2.79–82, §8.2.25, §8.2.129, §8.2.31–32) ------------
BUSVOL_VOLTS_PER_UNIT = 26.525e-3  #: BUSVOL, MIN_BUSVOL (overview; 565 ↔ 14.99 V)
BUSVOL_VOLTS_PER_UNIT_DETAIL = 26.67e-3  #: the same unit as printed in §8.2.47/48 (not used)
CVI_VOLTS_PER_UNIT = 8.764e-3  #: ACCEPT_VOLTAGE, SAVE_VOLTAGE, CVI_VOLT (2052 ↔ 18 V)
TEMP_CELSIUS_PER_UNIT = 2.27  #: TEMP: "Tc = 2.27 * Value" (§8.2.25)
TEMP_HIGHRES_CELSIUS_PER_UNIT = 1e-3  #: TEMP_HIGHRES in °C/1000 (§8.2.129)
TEMP_WARNING_CELSIUS = 80.0  #: WARN_BITS bit 6
TEMP_ERROR_CELSIUS = 90.0  #: ERR_BITS bit 6

# --- closed loop current scaling (§5.3.7, §8.2.108–114) ------------------------------------
CUR_SCALE_FULL = 2047  #: CUR_SCALE_MAX/MIN, ACTUAL_TORQUE: 2047 = 100 % of RUN_CURRENT
CUR_SCALE_CLOCK_HZ = 36e6  #: T_INC = CUR_SCALE_INC / 36 MHz, T_DEC = DEC_CNT / 36 MHz

# --- other timing (§8.2.102, §8.2.75, §8.2.130, §8.2.126) -----------------------------------
EXT_ENCODER_VEL_WINDOW_S = 16e-3  #: EXT_ENCODER_VEL is counts per 16 ms
DIGITAL_INPUT_UNFILTERED_PERIOD_S = 100e-6  #: unfiltered digital inputs update every 100 µs
LOWBUSCVI_PERIOD_S = 50e-6  #: LOWBUSCVI_CNT measurement period (§8.2.130; overview: 100 µs)
ZERO_SEARCH_TIMEOUT_DEFAULT_S = 60.0  #: V_HOME_TIMEOUT = 0 means 60 000 ms


# --- identification (§8.2.89, §8.2.49, §5.8.1) ---------------------------------------------
#: MOTORTYPE (register 151) code of each stepper type (§8.2.89)
MOTOR_TYPE_CODES: dict[str, int] = {
    "SMC85": 80,
    **{f"MIS34{k}": 81 + k for k in range(6)},
    **{f"MIS43{k}": 90 + k for k in range(6)},
    **{f"MIS51{k}": 100 + k - 1 for k in range(1, 6)},
    **{f"MIS17{k}": 120 + k for k in range(7)},
    "SMC66": 150,
    **{f"MIS23{k}": 151 + k for k in range(5)},
    **{f"MIL23{k}": 200 + k for k in range(5)},
    **{f"MIL34{k}": 250 + k for k in range(5)},
}

#: ENCODER_TYPE (register 99) → (option, internal encoder counts per revolution or 0): §8.2.49
#: lists the options, §5.8.1 gives the H3's internal 1024 cpr; every option reports positions in
#: 409600 counts/rev
ENCODER_TYPES: dict[int, tuple[str, int]] = {
    0: ("none", 0),
    1: ("H2", 1024),  # absolute single turn, 10 bit
    2: ("H3", 1024),  # absolute multi turn
    3: ("H2", 4096),  # absolute single turn, 12 bit
    4: ("H4", 4096),  # 12-bit single turn + absolute multi turn
}


def cur_scale_inc_step_s(cur_scale_inc: float) -> float:
    """Time of one current step up in closed loop [s]: 2000 → 55.56 µs (§5.3.7).

    Parameters
    ----------
    cur_scale_inc : float
        CUR_SCALE_INC (register 218).

    Returns
    -------
    float
        ``CUR_SCALE_INC / 36 MHz``; 2048 steps take 113 ms at the default.
    """
    return cur_scale_inc / CUR_SCALE_CLOCK_HZ


def cur_scale_dec_step_s(rpm: float, cur_scale_dec: float, cur_scale_factor: float) -> float:
    """Time of one current step down in closed loop at a velocity [s] (§5.3.7).

    Parameters
    ----------
    rpm : float
        Motor velocity [RPM] (its magnitude is used).
    cur_scale_dec : float
        CUR_SCALE_DEC (register 219), the count at 0 RPM.
    cur_scale_factor : float
        CUR_SCALE_FACTOR (register 215), the slope.

    Returns
    -------
    float
        ``DEC_CNT / 36 MHz`` with ``DEC_CNT = |rpm|·100/4096 · CUR_SCALE_FACTOR +
        CUR_SCALE_DEC``: 111 µs at 0 RPM and 1.13 ms at 3000 RPM for the defaults.
    """
    dec_cnt = abs(rpm) * 100.0 / 4096.0 * cur_scale_factor + cur_scale_dec
    return dec_cnt / CUR_SCALE_CLOCK_HZ


#: the register unit conversions of ``units.csv`` by name, each also a name of this module
CONVERSIONS = linear_units(Path(__file__).with_name("units.csv"), globals())
globals().update(CONVERSIONS)
__all__ += list(CONVERSIONS) + ["ENGINEERING_UNITS"]


# --- engineering units the studio shows (the conversions above, as factors) -------------------
#: register unit (or register name, which wins) → the engineering units it is shown in, first
#: the default: (unit, factor per register unit) or (unit, factor, motor-data field the factor
#: is multiplied by); a register in no entry is shown in its own unit. Positions in turns or
#: degrees (§8.2.4: 409600 counts a revolution), velocities in rpm (§8.2.5), accelerations in
#: rpm/s (§8.2.6), currents in A RMS (§8.2.7, the C driver's 5.87 mA), voltages in V
#: (§8.2.45, §8.2.47), temperatures in °C (§8.2.25, §8.2.129).
ENGINEERING_UNITS: dict[str, tuple[tuple, ...]] = {
    "counts (1/409600 rev)": (("turns", CONVERSIONS["counts_to_rev"](1.0)),
                              ("°", 360.0 * CONVERSIONS["counts_to_rev"](1.0))),
    "0.01 RPM": (("rpm", CONVERSIONS["v_soll_to_rpm"](1.0)),),
    "RPM/s": (("rpm/s", 1.0),),
    "5.87 mA": (("A", CONVERSIONS["run_current_to_amps"](1.0)),),
    "1.221 mV": (("V", CONVERSIONS["analogue_to_volts"](1.0)),),
    "26.525 mV": (("V", CONVERSIONS["busvol_to_volts"](1.0)),),
    "8.764 mV": (("V", CONVERSIONS["cvi_to_volts"](1.0)),),
    "2.27 degC": (("°C", CONVERSIONS["temp_to_celsius"](1.0)),),
    "0.001 degC": (("°C", TEMP_HIGHRES_CELSIUS_PER_UNIT),),
}
