"""Column layout of the MAC800 motor array's per-motor arrays (the one place defining them).

- ``regs``   int64 (N, 207): the register bank, the stored 32-bit integer of every register at
  its number (MAC800 register overview §1.2; Fixed16 = value·65536, Fixed24 = value·2²⁴);
- ``state``  float64 (N, N_STATE): plant state and hidden firmware state;
- ``params`` float64 (N, N_PARAM): physical parameters (SI units);
- ``inputs`` float64 (N, N_INPUT): world signals held over one outer sample.
"""

from __future__ import annotations

from ..servo_layout import *  # noqa: F403  (P_J_MOTOR … P_PWM_DELAY: the servo columns)
from ..servo_layout import N_SERVO_PARAM

# --- state -----------------------------------------------------------------------------------
(
    S_THETA,  # mechanical angle [rad]
    S_OMEGA,  # mechanical speed [rad/s]
    S_ACC,  # last mechanical acceleration [rad/s²] (mid-step speed predictor)
    S_I_RE,  # stator current space vector, real part [A]
    S_I_IM,  # stator current space vector, imaginary part [A]
    S_UBUS,  # DC bus voltage [V]
    S_DUMP_ON,  # power dump switch (0/1)
    S_ENC_PREV,  # firmware encoder count at the previous outer sample
    S_ELDEG_PREV,  # absolute encoder count at the previous inner sample (V_ELDEG)
    S_TICK,  # inner samples since power-on
    S_SLIP,  # counts the encoder has lost (encoder fault input)
    S_INDEX_TURN,  # revolution number floor(θ/2π) at the last outer sample
    S_INDEX_COUNT,  # firmware count latched at the last index pulse (NaN before the first)
    # firmware: profile generator and errors
    S_V_OLD,  # V_OLD of the function blocks [1/16 count/sample]
    S_G_FNC,  # gear follow error [1/16 count]
    S_FLW16,  # FLWERR accumulator [1/16 count]
    S_INPOS_CNT,  # consecutive samples inside INPOSWIN
    S_EMERG,  # 1 while an error stop decelerates with ACC_EMERG
    S_HOME_PHASE,  # zero search: detection counter / phase
    S_HOME_LEVEL,  # zero search: sensor level at the previous sample (−1 before the first)
    S_HOME_AFTER,  # mode to enter after a power-on zero search (−1: none)
    S_A2P_LEVEL,  # analogue-to-position input level (0/1)
    S_PF16,  # function position P_FUNC in 1/16 count
    S_GEAR_REM,  # remainder of the gear division GEARF_1/GEARF_2 [1/16 count·GEARF_2]
    S_FILT_BAD,  # 1 when the main filter setting is not valid (checked when it is written)
    S_PARAMS_NEW,  # 1 after a reset: the current-loop lanes copy the parameters again
    S_VH_POS,  # next slot of the V_IST history ring (V_IST16)
    S_VH0, S_VH1, S_VH2, S_VH3, S_VH4, S_VH5, S_VH6, S_VH7,  # V_IST history ring, 16 samples
    S_VH8, S_VH9, S_VH10, S_VH11, S_VH12, S_VH13, S_VH14, S_VH15,
    # main filter histories: FF input f(k−1..k−5), VB input (k−1..k−4), VF input (k−1..k−5)
    # and VF output (k−1..k−6)
    S_F1, S_F2, S_F3, S_F4, S_F5,
    S_B1, S_B2, S_B3, S_B4,
    S_E1, S_E2, S_E3, S_E4, S_E5,
    S_Y1, S_Y2, S_Y3, S_Y4, S_Y5, S_Y6,
    # current loop, per phase a, b, c
    S_IE1_A, S_IE1_B, S_IE1_C,  # e(k−1)
    S_IU1_A, S_IU1_B, S_IU1_C,  # U(k−1) as stored
    S_IU2_A, S_IU2_B, S_IU2_C,  # U(k−2) as stored
    S_IIST1_A, S_IIST1_B, S_IIST1_C,  # I_IST(k−1)
    S_UPEND_A, S_UPEND_B, S_UPEND_C,  # PWM values of the last sample (the delayed ones)
    # monitors
    S_I2T_Q,  # filtered mean square phase current [A²]
    S_UIT_Q,  # filtered regenerative power [W]
    S_TEMP,  # winding temperature [°C]
    S_I2_SUM,  # Σ over the outer sample of ia²+ib²+ic² [A²] / 1.5 (space-vector |i|²)
    S_PREG_SUM,  # Σ over the outer sample of the regenerated power [W]
    S_PCU_SUM,  # Σ over the outer sample of the copper loss [W]
    S_IPEAK,  # samples of this outer sample with a saturated current reading
    # energy accounts since power-on [J]
    S_E_ELEC, S_E_COPPER, S_E_FRICTION, S_E_LOAD, S_E_DUMP, S_E_SUPPLY,
    N_STATE,
) = range(92)

#: index of the k-th entry (k = 1 … 5) of the FF input history, etc.
S_F = (S_F1, S_F2, S_F3, S_F4, S_F5)
S_B = (S_B1, S_B2, S_B3, S_B4)
S_E = (S_E1, S_E2, S_E3, S_E4, S_E5)
S_Y = (S_Y1, S_Y2, S_Y3, S_Y4, S_Y5, S_Y6)

# --- parameters ------------------------------------------------------------------------------
(
    P_I2T_SCALE,  # 65536 / rated phase current amplitude² [1/A²] (I2T's 100 %)
    P_K_I2T,  # I2T filter gain per outer sample
    P_UIT_SCALE,  # 65536 / continuous regenerative power of the dump [1/W] (UIT's 100 %)
    P_K_UIT,  # UIT filter gain per outer sample
    P_R_TH,  # thermal resistance winding → ambient [K/W]
    P_K_TEMP,  # winding temperature filter gain per outer sample
    P_C_BUS,  # [F]
    P_R_SUPPLY,  # [Ω]
    P_U_DUMP,  # [V]
    P_R_DUMP,  # [Ω]
    P_STOP_LO,  # lower mechanical end stop [rad] (inactive if >= P_STOP_HI)
    P_STOP_HI,  # upper mechanical end stop [rad]
    P_STOP_K,  # end stop stiffness [N·m/rad]
    P_STOP_D,  # end stop damping [N·m·s/rad]
    P_HOME_POS,  # world angle of the home sensor edge [rad] (inf: none)
    P_INDEX_POS,  # world angle of the encoder index within a turn [rad]
    P_POSITION_NOISE,  # std of the encoder reading's noise [counts]
    # per-sample constants derived from the above at reset (``kernel.derive_constants``)
    P_CPA,  # ADC counts per ampere
    P_KC0, P_KC1, P_KC2, P_KC3,  # coil_constants(R, L, λ, h)
    P_KM0, P_KM1,  # mech_constants(J, 0, b, 0, 0, h)[:2] (a rigid shaft)
    P_KB0, P_KB1, P_KB2, P_KB3, P_KB4, P_KB5, P_KB6,  # bus_constants(C, R_src, R_dump, h)
    N_PARAM,
) = range(N_SERVO_PARAM, 42)

# --- inputs ----------------------------------------------------------------------------------
(
    I_LOAD_TORQUE,  # external load torque opposing positive rotation [N·m]
    I_ANALOG_VOLTS,  # analogue input [V]
    I_PULSE_COUNTS,  # external pulse input counts during this outer sample (V_EXT)
    I_HOME,  # home sensor level forced by the user (−1: from P_HOME_POS, 0/1: forced)
    I_SUPPLY_VOLTS,  # DC source voltage of the rectified mains [V]
    I_CONTROL_VOLTS,  # 24 V control supply [V]
    I_ENCODER_FAULT,  # 1: the encoder loses every second count
    N_INPUT,
) = range(8)
