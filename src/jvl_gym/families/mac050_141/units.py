"""Sample rates, counts per revolution and unit scalings of the MAC050–141 (public module).

Sources: manual 1.2 (sampled systems), 3.2.5/3.2.6/3.2.12 (velocity and acceleration units),
3.2.7, 3.2.116, 3.2.122, 3.2.139, 3.2.143, 3.2.151 and docs/model.md §2–3.
"""

from __future__ import annotations

import math

# --- timing (manual 1.2, docs/model.md §2) ---------------------------------------------------
INNER_HZ = 7812.5  #: current loops, commutation, electrics [Hz]
INNER_PER_OUTER = 15  #: one velocity/position sample = 15 current samples
OUTER_HZ = INNER_HZ / INNER_PER_OUTER  #: 520.833 Hz
INNER_DT = 1.0 / INNER_HZ  #: 128 µs
OUTER_DT = 1.0 / OUTER_HZ  #: 1.92 ms

# --- units (docs/model.md §3) ----------------------------------------------------------------
COUNTS_PER_REV = 4096  #: encoder counts per revolution
ELDEG_PER_TURN = 2048  #: ELDEG_IST / MAN_ALPHA units per electrical turn (3.2.143)
RAD_PER_COUNT = 2.0 * math.pi / COUNTS_PER_REV
VF_FULL = 1023  #: VF_OUT / T_SOLL full scale = peak torque (3.2.7)
ADC_FULL = 1023  #: IA_IST.. measurement range ±1023 (3.2.139)
PWM_FULL = 1023  #: UA_VAL.. ±1023 = ±U_SUPPLY/2 phase-to-midpoint (docs/model.md §3 decision)
ANINP_FULL = 1023  #: ±10 V ↔ ±1023 (3.2.122)
ANINP_VOLTS = 10.0
U_SUPPLY_VOLTS_PER_UNIT = 0.0537  #: U_SUPPLY register unit (3.2.151)
STOP_SPEED_COUNTS = 300.0 / 60.0 * COUNTS_PER_REV / OUTER_HZ  #: 300 rpm in counts/sample (4.1.8)
REC_CNT_MAX = 895  #: sample buffer depth (3.2.116)
TEST_RECORD_SAMPLES = 11  #: TESTU / TESTA record length (4.4.9, 4.4.10)
UIT_SUPPLY_THRESHOLD = 52.0  #: UIT trips only above this supply voltage [V] (3.2.18)
I2T_FULL_SCALE_AMPLITUDE = 0.83  #: I2T = 65535 ↔ three-phase mean square at 1023·0.83 counts
UIT_FULL_SCALE_WATTS = 100.0  #: UIT = 65535 ↔ 100 W filtered regenerative power (decision)


def v_soll_to_rpm(v_soll: float) -> float:
    """Velocity in 1/16 count/sample → rpm (manual 3.2.5: 1600 ↔ 762.9 rpm)."""
    return v_soll / 16.0 * OUTER_HZ / COUNTS_PER_REV * 60.0


def rpm_to_v_soll(rpm: float) -> float:
    """rpm → velocity in 1/16 count/sample (inverse of :func:`v_soll_to_rpm`)."""
    return rpm / 60.0 * COUNTS_PER_REV / OUTER_HZ * 16.0


def v_ist_to_rpm(v_ist: float) -> float:
    """Measured velocity in counts/sample → rpm (manual 3.2.12: 100 ↔ 762.9 rpm)."""
    return v_ist * OUTER_HZ / COUNTS_PER_REV * 60.0


def a_soll_to_rpm_per_s(a_soll: float) -> float:
    """Acceleration in 1/16 count/sample² → rpm/s (manual 3.2.6: 160 ↔ 39731 rpm/s)."""
    return a_soll / 16.0 * OUTER_HZ**2 / COUNTS_PER_REV * 60.0


# --- engineering units the studio shows (the conversions above, as factors) -------------------
#: register unit (or register name, which wins) → the engineering units it is shown in, first
#: the default: (unit, factor per register unit) or (unit, factor, motor-data field the factor
#: is multiplied by); a register in no entry is shown in its own unit. Positions in turns or
#: degrees (COUNTS_PER_REV), velocities in rpm (3.2.5, 3.2.12), accelerations in rpm/s (3.2.6),
#: torques in N·m of the motor's peak torque (3.2.7: 1023 = peak), currents in A of the motor's
#: A per ADC count (3.2.139), U_SUPPLY in V (3.2.151), ANINP in V (3.2.122: ±1023 ↔ ±10 V),
#: electrical angles in electrical degrees (3.2.143).
ENGINEERING_UNITS: dict[str, tuple[tuple, ...]] = {
    "counts": (("turns", 1.0 / COUNTS_PER_REV), ("°", 360.0 / COUNTS_PER_REV)),
    "1/16 count": (("turns", 1.0 / 16.0 / COUNTS_PER_REV), ("°", 360.0 / 16.0 / COUNTS_PER_REV)),
    "1/16 count/sample": (("rpm", v_soll_to_rpm(1.0)),),
    "counts/sample": (("rpm", v_ist_to_rpm(1.0)),),
    "1/16 count/sample^2": (("rpm/s", a_soll_to_rpm_per_s(1.0)),),
    "1/1023 peak torque": (("N·m", 1.0 / VF_FULL, "peak_torque"),),
    "ADC counts": (("A", 1.0, "amps_per_count"),),
    "ANINP": (("V", ANINP_VOLTS / ANINP_FULL),),
    "ANINP_OFFSET": (("V", ANINP_VOLTS / ANINP_FULL),),
    "53.7 mV": (("V", U_SUPPLY_VOLTS_PER_UNIT),),
    "1/2048 electrical turn": (("°el", 360.0 / ELDEG_PER_TURN),),
}
