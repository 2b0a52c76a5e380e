"""Fixed facts of the MAC800: sample rate, counts per revolution and register unit scalings.

Source: the MAC800 register overview (§1.2) and serial quick guide (§1.3). The overview gives
its scalings as figures ("1 RPM = 2.77056 counts/sample", "1000 RPM/s = 3.598133
counts/sample²", ...) but states neither the sample rate nor the encoder resolution; both follow
from the velocity and acceleration figures (:func:`derive_sample_rate_and_counts`):

* V_SOLL is in 1/16 count/sample and 1 RPM = 2.77056 units, so 1 RPM = 2.77056/16 =
  0.17316 counts/sample (the overview's V_IST figure, register 12, agrees). With N counts per
  revolution and a sample rate f: N/(60·f) = 0.17316, so N/f = 10.3896 s.
* A_SOLL is in 1/16 count/sample² and 1000 RPM/s = 3.598133 units, so 1000 RPM/s =
  0.2248833 counts/sample²: 1000·N/(60·f²) = 0.2248833, so N/f² = 0.013493 s².
* Dividing, f = 10.3896/0.013493 = 770.0 Hz (sample time 1.2987 ms) and N = 10.3896·770 = 8000
  counts/rev. Forward check: 16·8000/(60·770) = 2.770563 and 16·8000·1000/(60·770²) =
  3.598133, both as printed; the figures' 6–7 digits fix f to ±0.002 Hz and N to ±0.03.

The other scalings are the overview's own (register 21 U_24V, 29 DEGC, 198 U_BUS, 170 ANINP,
7 T_SOLL, 35 ERR_STAT bits 11 and 13). U_BUS: the overview says "1VDC = 0.888798" but its
example (U_BUS = 366 is 325 V) only holds as 1 unit = 0.888798 V (366·0.888798 = 325.3); the
example is followed.
"""

from __future__ import annotations

from pathlib import Path

from ...registers.scaling import linear_units

__all__ = [
    "V_SOLL_UNITS_PER_RPM",
    "A_SOLL_UNITS_PER_1000_RPM_S",
    "V_IST_COUNTS_PER_RPM",
    "SAMPLE_HZ",
    "SAMPLE_DT",
    "COUNTS_PER_REV",
    "U_24V_VOLTS_PER_UNIT",
    "DEGC_CELSIUS_PER_UNIT",
    "U_BUS_VOLTS_PER_UNIT",
    "ANINP_VOLTS_PER_UNIT",
    "T_SOLL_FULL",
    "T_SOLL_FULL_PERCENT_OF_NOMINAL",
    "OVERVOLTAGE_VOLTS",
    "OVERSPEED_RPM",
    "derive_sample_rate_and_counts",
    "rpm_per_s_to_a_soll",
    "a_soll_to_rpm_per_s",
    "t_soll_to_percent_of_nominal",
]

# --- the overview's figures (§1.2) -----------------------------------------------------------
#: V_SOLL units (1/16 count/sample) per RPM (register 5: "1 RPM = 2.77056", "100 RPM -> 277")
V_SOLL_UNITS_PER_RPM = 2.77056
#: A_SOLL units (1/16 count/sample²) per 1000 RPM/s (register 6: "100 000 RPM/s -> 360")
A_SOLL_UNITS_PER_1000_RPM_S = 3.598133
#: V_IST counts/sample per RPM (register 12: "1RPM=0.17316 counts/sample")
V_IST_COUNTS_PER_RPM = 0.17316


def derive_sample_rate_and_counts(v_units_per_rpm: float = V_SOLL_UNITS_PER_RPM,
                                  a_units_per_1000_rpm_s: float = A_SOLL_UNITS_PER_1000_RPM_S
                                  ) -> tuple[float, float]:
    """Sample rate and counts per revolution implied by the V_SOLL and A_SOLL figures.

    Both registers are in sixteenths of a count per sample (per sample²), so
    ``v/16 = N/(60·f)`` and ``a/16 = 1000·N/(60·f²)``; hence ``f = 1000·v/a`` and
    ``N = 60·f·v/16``.

    Parameters
    ----------
    v_units_per_rpm : float
        V_SOLL units per RPM (overview register 5).
    a_units_per_1000_rpm_s : float
        A_SOLL units per 1000 RPM/s (overview register 6).

    Returns
    -------
    (float, float)
        Sample rate [Hz] and counts per revolution: about (770.0, 8000.0) for the overview's
        figures.
    """
    f = 1000.0 * v_units_per_rpm / a_units_per_1000_rpm_s
    n = 60.0 * f * v_units_per_rpm / 16.0
    return f, n


# --- derived timing and resolution (see the module docstring) --------------------------------
SAMPLE_HZ = 770.0  #: servo sample rate [Hz], derived from the V_SOLL and A_SOLL figures
SAMPLE_DT = 1.0 / SAMPLE_HZ  #: sample time [s], 1.2987 ms
COUNTS_PER_REV = 8000  #: encoder counts per revolution, derived likewise

# --- measurement scalings (§1.2) ------------------------------------------------------------
U_24V_VOLTS_PER_UNIT = 0.013428  #: register 21: V = U_24V × 0.013428 (unit "VDC/74.4713")
DEGC_CELSIUS_PER_UNIT = 0.12207  #: registers 29/31: °C = DEGC × 0.12207
U_BUS_VOLTS_PER_UNIT = 0.888798  #: register 198: V = U_BUS × 0.888798 (366 ↔ 325 V)
ANINP_VOLTS_PER_UNIT = 0.0048828  #: registers 170/171: V = ANINP × 0.0048828
T_SOLL_FULL = 1023  #: register 7: T_SOLL range 0–1023
T_SOLL_FULL_PERCENT_OF_NOMINAL = 300.0  #: register 7: "1023 = 300% (full peak torque)"
OVERVOLTAGE_VOLTS = 450.0  #: ERR_STAT bit 11 OV_ERR: "UB>450V"
OVERSPEED_RPM = 3600.0  #: ERR_STAT bit 13 SPEED_ERR: ">3600RPM"


def rpm_per_s_to_a_soll(rpm_per_s: float) -> float:
    """Acceleration [RPM/s] → A_SOLL units (1/16 count/sample²): 100 000 → 359.81 (register 6);
    also ACC_EMERG and ACCn."""
    return rpm_per_s / 1000.0 * A_SOLL_UNITS_PER_1000_RPM_S


def a_soll_to_rpm_per_s(a_soll: float) -> float:
    """A_SOLL units → RPM/s (inverse of :func:`rpm_per_s_to_a_soll`): 360 → 100 052."""
    return a_soll * 1000.0 / A_SOLL_UNITS_PER_1000_RPM_S


def t_soll_to_percent_of_nominal(t_soll: float) -> float:
    """T_SOLL / VF_OUT units → torque in % of nominal (register 7: 1023 = 300 %)."""
    return t_soll / T_SOLL_FULL * T_SOLL_FULL_PERCENT_OF_NOMINAL


#: the register unit conversions of ``units.csv`` by name, each also a name of this module
CONVERSIONS = linear_units(Path(__file__).with_name("units.csv"), globals())
globals().update(CONVERSIONS)
__all__ += list(CONVERSIONS) + ["ENGINEERING_UNITS"]


# --- engineering units the studio shows (the conversions above, as factors) -------------------
#: register unit (or register name, which wins) → the engineering units it is shown in, first
#: the default: (unit, factor per register unit) or (unit, factor, motor-data field the factor
#: is multiplied by); a register in no entry is shown in its own unit. Positions in turns or
#: degrees (COUNTS_PER_REV), velocities in rpm (registers 5, 12), accelerations in rpm/s
#: (register 6), torques in N·m of the motor's peak torque (register 7: 1023 = peak), the
#: measurements in V and °C (registers 21, 29, 170, 198).
ENGINEERING_UNITS: dict[str, tuple[tuple, ...]] = {
    "counts": (("turns", 1.0 / COUNTS_PER_REV), ("°", 360.0 / COUNTS_PER_REV)),
    "1/16 count/sample": (("rpm", CONVERSIONS["v_soll_to_rpm"](1.0)),),
    "counts/sample": (("rpm", CONVERSIONS["v_ist_to_rpm"](1.0)),),
    "1/16 count/sample^2": (("rpm/s", a_soll_to_rpm_per_s(1.0)),),
    "1/1023 peak torque": (("N·m", 1.0 / T_SOLL_FULL, "peak_torque"),),
    "0.0048828 V": (("V", CONVERSIONS["aninp_to_volts"](1.0)),),
    "0.013428 V": (("V", CONVERSIONS["u_24v_to_volts"](1.0)),),
    "0.12207 degC": (("°C", CONVERSIONS["degc_to_celsius"](1.0)),),
    "0.888798 V": (("V", CONVERSIONS["u_bus_to_volts"](1.0)),),
}
