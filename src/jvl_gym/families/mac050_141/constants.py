"""Fixed facts of the MAC50–141 firmware: rates, units, modes and status bits.

Sources: manual 1.2 (sampled systems), 3.2.2 (MODE_REG), 3.2.35 (ERR_STAT), 3.2.36 (CNTRL_BITS),
3.2.5/3.2.6/3.2.12 (velocity and acceleration units) and docs/model.md §2–3.
"""

from __future__ import annotations

from ...registers.bits import bit_masks, mask_of
from .firmware.mode_table import MODE_NAMES as _MODE_NAMES
from .firmware.mode_table import number as _mode
from .units import (  # noqa: F401  (re-exported: the constants module names them too)
    ADC_FULL,
    ANINP_FULL,
    ANINP_VOLTS,
    COUNTS_PER_REV,
    ELDEG_PER_TURN,
    I2T_FULL_SCALE_AMPLITUDE,
    INNER_DT,
    INNER_HZ,
    INNER_PER_OUTER,
    OUTER_DT,
    OUTER_HZ,
    PWM_FULL,
    RAD_PER_COUNT,
    REC_CNT_MAX,
    STOP_SPEED_COUNTS,
    TEST_RECORD_SAMPLES,
    U_SUPPLY_VOLTS_PER_UNIT,
    UIT_FULL_SCALE_WATTS,
    UIT_SUPPLY_THRESHOLD,
    VF_FULL,
    a_soll_to_rpm_per_s,
    rpm_to_v_soll,
    v_ist_to_rpm,
    v_soll_to_rpm,
)

# --- modes (manual 3.2.2, 4.4): numbers and names from the mode table --------------------
INIT_MODE = _mode("INIT_MODE")
V_MODE = _mode("V_MODE")
P_MODE = _mode("P_MODE")
GP_MODE = _mode("GP_MODE")
AT_MODE = _mode("AT_MODE")
AV_MODE = _mode("AV_MODE")
AVG_MODE = _mode("AVG_MODE")
MANI_MODE = _mode("MANI_MODE")
TESTU_MODE = _mode("TESTU_MODE")
TESTA_MODE = _mode("TESTA_MODE")
BREAK_MODE = _mode("BREAK_MODE")
STOP_MODE = _mode("STOP_MODE")
HOME1_MODE = _mode("HOME1_MODE")
HOME2_MODE = _mode("HOME2_MODE")
HOME3_MODE = _mode("HOME3_MODE")
SAFE_MODE = _mode("SAFE_MODE")
AVZ_MODE = _mode("AVZ_MODE")
VAT_MODE = _mode("VAT_MODE")
AG_MODE = _mode("AG_MODE")
COIL_MODE = _mode("COIL_MODE")
A2POS_MODE = _mode("A2POS_MODE")
APOS_MODE = _mode("APOS_MODE")
TESTKI_MODE = _mode("TESTKI_MODE")
TESTTQ_MODE = _mode("TESTTQ_MODE")
GF_MODE = _mode("GF_MODE")
SAFE_LOAD_DEFAULTS_SAVE = 256  #: in SAFE_MODE: ROM defaults → flash, reset (4.4.16)
SAFE_LOAD_DEFAULTS = 257  #: in SAFE_MODE: ROM defaults, not saved
SAFE_LOAD_FLASH = 258  #: in SAFE_MODE: last saved user parameters

MODE_NAMES = _MODE_NAMES  #: MODE_REG value → mode name (mac050_141.firmware.mode_table)

# --- ERR_STAT bits (3.2.35) ------------------------------------------------------------------
#: ERR_STAT bits by name, bit 0 first; each name is a constant of this module too
ERR_STAT_BITS = bit_masks("I2T_ERR FLW_ERR FNC_ERR UIT_ERR IN_POS ACC_FLAG DEC_FLAG PLIM_ERR "
                          "FRAME_ERR_TX RELPOSPSOLL RELPOSPFNC IX_ERR UV_ERR UV_DETECT DIS_P_LIM")
globals().update(ERR_STAT_BITS)
#: must be cleared in INIT (4.4.1)
BLOCKING_ERRORS = mask_of(ERR_STAT_BITS, "I2T_ERR FLW_ERR FNC_ERR UIT_ERR")

# --- CNTRL_BITS (3.2.36) ---------------------------------------------------------------------
USERINTF_MASK = 0b11  #: bits 0–1: the user interface
#: CNTRL_BITS bits by name, bit 0 first; each name is a constant of this module too
CNTRL_BITS_BITS = bit_masks("- - PULSEDIR INPSIGN HICLK HALL_INT RECORDBIT REWINDBIT RECINNERBIT "
                            "AUTO_RESYNC MAN_RESYNC INDEX_HOME REL_RESYNC")
globals().update(CNTRL_BITS_BITS)
HALL_STATUS_SHIFT = 13

# --- UV_HANDLE (3.2.160) ---------------------------------------------------------------------
#: UV_HANDLE bits by name, bit 0 first; each name is a constant of this module too
UV_HANDLE_BITS = bit_masks("SET_UV_ERR UV_GO_PASSIVE - UV_SOLL0")
globals().update(UV_HANDLE_BITS)
MACTALK_DIALECT = "mactalk16"  #: MacTalk of manual 5.1, 16-bit registers (protocol.mactalk.dialect)

#: the manual's register groups, (title, first, last register number) (manual 3.2: "The
#: Parameter and Data Registers can be categorised into the following groups")
REGISTER_GROUPS: tuple[tuple[str, int, int], ...] = (
    ("Main Control", 1, 15),
    ("Error handling", 16, 35),
    ("Power on", 36, 42),
    ("Register mode", 43, 88),
    ("Filters", 89, 111),
    ("Data acquisition", 112, 116),
    ("Position / velocity-loop", 117, 123),
    ("Current-loops", 124, 152),
    ("Diverse", 153, 163),
)

# --- the motion panel of jvl-gym studio: the modes and registers behind it (manual 4.4) ------
#: motion → MODE_REG value(s): passive (INIT_MODE, 4.4.1), velocity (V_MODE, 4.4.2: jog and
#: run at V_SOLL, its sign the direction), position (P_MODE, 4.4.3: a move to P_SOLL at most
#: V_SOLL) and the home modes (HOME1–3_MODE, 4.4.13–4.4.15)
MOTION_MODES: dict[str, tuple[int, ...]] = {
    "passive": (INIT_MODE,), "velocity": (V_MODE,), "position": (P_MODE,),
    "home": (HOME1_MODE, HOME2_MODE, HOME3_MODE)}
#: the registers of a motion: speed (signed in velocity mode, the maximum of a move), target
#: position, actual position and velocity, software position limits (3.2.28, 3.2.30)
MOTION_REGISTERS: dict[str, str] = {
    "speed": "V_SOLL", "target": "P_SOLL", "position": "P_IST", "velocity": "V_IST",
    "min_position": "MIN_P_IST", "max_position": "MAX_P_IST"}
#: registers whose value is a MODE_REG value (3.2.37 STARTMODE), shown as the list of modes
MODE_VALUED_REGISTERS: tuple[str, ...] = ("STARTMODE",)
