"""Column layout of the simulator's per-motor arrays.

The simulator keeps N motors in four 2-D arrays, one row per motor, so that the compiled kernel
can loop over motors and every motor's arithmetic is independent of the others (which makes an
N-motor array bit-for-bit equal to N one-motor arrays):

- ``regs``   int64  (N, 165): the register bank, raw stored integers indexed by register number
  (manual 3.2); a LongInt holds its full 32-bit value at its low number.
- ``state``  float64 (N, N_STATE): physical state of the plant and hidden firmware state
  (filter histories, profile generator memory, monitors, energy accounts).
- ``params`` float64 (N, N_PARAM): per-motor physical parameters in SI units and derived
  per-step constants (recomputed on reset).
- ``inputs`` float64 (N, N_INPUT): world signals held over one outer sample.

Only this module defines the column numbers.
"""

from __future__ import annotations

from ..servo_layout import *  # noqa: F403  (P_J_MOTOR … P_PWM_DELAY: the servo columns)
from ..servo_layout import N_SERVO_PARAM

N_REGS = 165

# --- state -----------------------------------------------------------------------------------
(
    S_THETA,  # mechanical angle [rad]
    S_OMEGA,  # mechanical speed [rad/s]
    S_I_RE,  # stator current space vector, real part [A] (phase a axis)
    S_I_IM,  # stator current space vector, imaginary part [A]
    S_ACC,  # last mechanical acceleration [rad/s²] (mid-step speed predictor)
    S_UBUS,  # DC bus voltage [V]
    S_DUMP_ON,  # power dump switch state (0/1)
    S_ENC0,  # encoder count at power-on (P_IST = 0 there)
    S_ENC_PREV,  # encoder count at the previous outer sample
    S_ELDEG_PREV,  # absolute encoder count at the previous inner sample (V_ELDEG)
    S_TICK,  # inner samples since power-on (noise stream counter)
    S_ELDEG_OFS,  # ELDEG_IST = (encoder count + offset) mod 2048 when hall-synchronised
    S_HALL_SYNCED,  # 1 after the first hall zero transition (or when aligned at power-on)
    S_HALL_SECTOR,  # hall sector index floor((θe − hall angle)/60°) at the last inner sample
    # firmware: profile generator
    S_V_OLD,  # V_OLD of the function blocks [1/16 count/sample]
    S_G_FNC,  # G_FNC of the gear blocks [1/16 count]
    S_FLW16,  # FLWERR accumulator [1/16 count]
    S_INPOS_CNT,  # consecutive samples inside INPOSWIN
    S_PENDING_MODE,  # mode to enter when STOP_MODE / AT exit completes
    S_EMERG,  # 1 while an error stop decelerates with ACC_EMERG
    S_TEST_CNT,  # samples recorded by TESTU/TESTA so far
    S_BREAK_DIR,  # sign of the speed when BREAK_MODE started
    S_AT_EXIT,  # 1 while AT_MODE waits for low speed before INIT
    S_REC_LEN,  # record length of the test modes [samples]
    # speed loop filter histories (FF input f, VB input v, VF input e and output y)
    S_F1, S_F2, S_F3,
    S_V1, S_V2, S_V3,
    S_E1, S_E2, S_E3,
    S_Y1, S_Y2, S_Y3, S_Y4,
    # current loop, per phase a, b, c
    S_IE1_A, S_IE1_B, S_IE1_C,  # previous error e(k-1)
    S_IU1_A, S_IU1_B, S_IU1_C,  # U(k-1) as stored
    S_IU2_A, S_IU2_B, S_IU2_C,  # U(k-2) as stored
    S_IIST1_A, S_IIST1_B, S_IIST1_C,  # I_IST(k-1) for the IB filter
    S_UPEND_A, S_UPEND_B, S_UPEND_C,  # PWM values of the last sample (the delayed ones)
    # monitors
    S_I2T_Q,  # filtered sum of squared phase currents [ADC counts²]
    S_UIT_Q,  # filtered regenerative power [W]
    S_I2_SUM,  # sum over this outer sample of Ia²+Ib²+Ic² [ADC counts²]
    S_PREG_SUM,  # sum over this outer sample of the regenerative power [W]
    S_UV_TIMER,  # undervoltage timer [outer samples]
    # energy accounts since power-on [J]
    S_E_ELEC,  # electrical energy delivered to the windings by the PWM stage
    S_E_COPPER,  # copper loss
    S_E_FRICTION,  # viscous + Coulomb friction loss
    S_E_LOAD,  # work done against the external load torque
    S_E_DUMP,  # energy burnt in the power dump
    S_E_SUPPLY,  # energy drawn from the supply source
    # mode-specific memory (home search, analogue hysteresis, coil direction, ...)
    S_AUX0, S_AUX1, S_AUX2, S_AUX3, S_AUX4, S_AUX5, S_AUX6, S_AUX7,
    # load behind an elastic coupling (docs/model.md §5.2); equal to S_THETA, S_OMEGA when rigid
    S_LOAD_THETA,  # load angle [rad]
    S_LOAD_OMEGA,  # load speed [rad/s]
    N_STATE,
) = range(74)

#: the state fields the SIMD lanes of the inner samples carry (``lanes.py``): gathered into a
#: block's scratch before its 15 inner samples and scattered back after them, in this order
LANE_STATE = (
    S_THETA, S_OMEGA, S_ACC, S_I_RE, S_I_IM, S_UBUS, S_DUMP_ON, S_ELDEG_PREV, S_HALL_SECTOR,
    S_IE1_A, S_IE1_B, S_IE1_C, S_IU1_A, S_IU1_B, S_IU1_C, S_IU2_A, S_IU2_B, S_IU2_C, S_IIST1_A,
    S_IIST1_B, S_IIST1_C, S_UPEND_A, S_UPEND_B, S_UPEND_C, S_E_ELEC, S_E_COPPER, S_E_FRICTION,
    S_E_LOAD, S_E_DUMP, S_E_SUPPLY, S_I2_SUM, S_PREG_SUM, S_LOAD_THETA, S_LOAD_OMEGA,
)

# --- parameters ------------------------------------------------------------------------------
(
    P_K_THERMAL,  # I2T filter gain per outer sample, monitor.filter_gain(thermal time constant)
    P_K_REGEN,  # UIT filter gain per outer sample, monitor.filter_gain(regen time constant)
    P_C_BUS,  # [F]
    P_R_SUPPLY,  # [Ω]
    P_U_DUMP,  # [V]
    P_R_DUMP,  # [Ω]
    P_CURRENT_NOISE,  # std of current sensing noise [ADC counts]
    P_POSITION_NOISE,  # std of encoder reading noise [counts]
    P_TORQUE_NOISE,  # std of process torque noise per inner sample [N·m]
    P_STOP_LO,  # lower mechanical end stop [rad] (inactive if > P_STOP_HI)
    P_STOP_HI,  # upper mechanical end stop [rad]
    P_STOP_K,  # end stop stiffness [N·m/rad]
    P_STOP_D,  # end stop damping [N·m·s/rad]
    P_HOME_POS,  # world position of the home sensor edge [rad]
    P_THETA_E0,  # electrical angle at mechanical angle 0 [rad]
    P_HALL_START,  # 0: commutation aligned at power-on; 1: hall sector estimate until first edge
    P_HALL_ANGLE,  # electrical angle of the hall zero transition [rad]
    P_K_COUPLING,  # stiffness of the coupling to the load [N·m/rad] (0: rigid)
    P_D_COUPLING,  # damping of the coupling to the load [N·m·s/rad]
    N_PARAM,
) = range(N_SERVO_PARAM, 30)

# --- inputs ----------------------------------------------------------------------------------
(
    I_LOAD_TORQUE,  # external load torque opposing positive rotation [N·m]
    I_ANALOG_VOLTS,  # analogue input [V]
    I_PULSE_COUNTS,  # pulse input counts during this outer sample (V_EXT)
    I_HOME,  # home sensor level forced by the user (-1: from P_HOME_POS, 0/1: forced)
    I_SUPPLY_VOLTS,  # supply source voltage [V]
    N_INPUT,
) = range(6)
