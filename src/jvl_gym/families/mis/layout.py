"""Columns of the MIS family's ``state``, ``params`` and ``inputs`` arrays (one row per motor).

Plant state is in SI units (rotor angle [rad], speed [rad/s], currents [A] in the frame of the
commanded electrical angle); firmware state is in motor counts and counts per outer sample
(1 ms), the units of :mod:`.constants`.
"""

from __future__ import annotations

# --- state ----------------------------------------------------------------------------------
(
    S_THETA,  # rotor angle from power-on [rad], unwrapped
    S_OMEGA,  # rotor speed [rad/s]
    S_ID,  # phase current along the commanded electrical angle [A]
    S_IQ,  # phase current 90° ahead of it [A]
    S_CMD,  # commanded (microstep) position at the end of the last outer sample [counts]
    S_CMD_PREV,  # the same at its start [counts]
    S_VEL,  # profile velocity [counts/outer sample], signed
    S_VS,  # active start/stop velocity [counts/outer sample] (latched at standstill)
    S_ACC,  # active acceleration [counts/outer sample²] (latched at standstill)
    S_DEC,  # active deceleration [counts/outer sample²] (latched at standstill)
    S_SEEN_PIST,  # P_IST as the firmware left it (a different value: the user wrote it)
    S_FRAC,  # commanded position's fraction of a count carried to the next sample
    S_STILL_MS,  # outer samples since the last step (standby current)
    S_I_AMP,  # phase current amplitude the chopper aims at [A peak]
    S_BRIDGE,  # 0 bridge off (passive), 1 chopper on, 2 on with closed-loop commutation
    S_CUR_SCALE,  # closed-loop current scale, 0 … 2047 (ACTUAL_TORQUE)
    S_SCALE_CLOCK,  # 36 MHz ticks carried to the next current-scale step
    S_GEAR_REM,  # gear remainder (§8.2.3, gear mode), units of GEAR2
    S_ENC_OFFSET,  # ENCODER_POS minus the quantised rotor position [counts]
    S_ENC_PREV,  # ENCODER_POS of the last sample (V_ENCODER)
    S_EMERGENCY,  # 1 while the error stop decelerates
    S_HOME_PHASE,  # zero search phase (firmware.homing), 0 before it starts
    S_HOME_MS,  # zero search time [outer samples]
    S_HOME_DIR,  # zero search direction: +1 as V_HOME, −1 turned at a limit
    S_AC_LEFT,  # auto-correction retries left
    S_AC_WAIT,  # auto-correction settling time left [outer samples]
    S_SEEN_PSOLL,  # P_SOLL as the firmware last saw it (a change reloads auto-correction)
    S_AF_MS,  # outer samples since the last analogue filter update
    S_REC_MS,  # outer samples since the last sample-buffer sample
    S_TICK,  # outer samples since power-on
    S_E_COPPER,  # copper loss energy since power-on [J]
    S_E_LOAD,  # work done against the load torque since power-on [J]
    S_TT_TRAVEL,  # turn table: counts of a multiturn move still to go (0: none)
    S_REC_N,  # samples taken by the sample buffer
    S_DIN_STATE,  # filtered digital inputs (bits 0-7)
    S_FIELD,  # closed loop: the position the currents are commutated to [counts]
    S_FIELD_STEP,  # closed loop: its largest advance per inner sample [counts]
) = range(37)
S_AF0 = 37  #: analogue filtered values of IO1 … IO8 (units of 1.221 mV, fractional)
S_DIN0 = S_AF0 + 8  #: input filter: ms the raw level of IO1 … IO8 has differed from the state
#: counts run since MOTOR_REV last counted a revolution (§8.2.122)
S_REV_ACC = S_DIN0 + 8
#: the mode a zero search was started from, which a time-out sets back (§7.2.19)
S_HOME_PREV = S_REV_ACC + 1
#: external encoder counts since EXT_ENCODER_VEL was last measured (§8.2.102)
S_EXT_VEL_ACC = S_HOME_PREV + 1
#: analogue filter samples of IO1 … IO8 outside the confidence limits this second (§8.2.56)
S_AF_CONF0 = S_EXT_VEL_ACC + 1
#: analogue filter samples of IO1 … IO8 slope limited this second (§8.2.56)
S_AF_SLOPE0 = S_AF_CONF0 + 8
#: under-voltage measurements in a row (one per 50 µs, §8.2.130)
S_LOW_BUS_N = S_AF_SLOPE0 + 8
#: zero search with the index: the encoder's revolution where the sensor was found, and the
#: direction it goes on in to the index (§8.2.65, §8.2.67 bit 0)
S_INDEX_TURN = S_LOW_BUS_N + 1
S_INDEX_DIR = S_INDEX_TURN + 1
#: hardware supervision (``firmware.supervision``): 1 while the program waits for the control
#: voltage (CVI) at start-up or after it fell below SAVE_VOLTAGE (§8.2.79–81), the measurements
#: at or above ACCEPT_VOLTAGE in a row, the electronics' temperature above ambient [K], the
#: brake (1: holding), the ms since the brake was last told to hold or to release (§8.2.106)
S_CVI_WAIT = S_INDEX_DIR + 1
S_CVI_N = S_CVI_WAIT + 1
S_TEMP_RISE = S_CVI_N + 1
S_BRAKE_HELD = S_TEMP_RISE + 1
S_BRAKE_MS = S_BRAKE_HELD + 1
#: the brake as last told (1: hold) and whether BRAKE then selected an external brake output
S_BRAKE_CMD = S_BRAKE_MS + 1
S_BRAKE_EXT = S_BRAKE_CMD + 1
N_STATE = S_BRAKE_EXT + 1

# --- params ---------------------------------------------------------------------------------
(
    P_J_MOTOR,  # rotor inertia [kg·m²]
    P_J_LOAD,  # load inertia [kg·m²]
    P_R,  # phase resistance [Ω]
    P_L,  # phase inductance [H]
    P_KT,  # torque per ampere of phase current amplitude [N·m/A] (= back-EMF [V·s/rad])
    P_DETENT,  # detent torque amplitude [N·m]
    P_VISCOUS,  # viscous friction [N·m·s/rad]
    P_COULOMB,  # Coulomb friction [N·m]
    P_ENCODER,  # ENCODER_TYPE code (units.ENCODER_TYPES)
    P_HOME_POS,  # home sensor: active while the rotor angle is at or below this [rad]
    P_AMPS_PER_UNIT,  # RUN_CURRENT unit [A RMS]
    P_RUN_MAX,  # largest RUN_CURRENT of the type
    P_ZETA,  # damping ratio of the rotor against the stator field
    P_STOP_LO,  # mechanical end stop below this rotor angle [rad] (−inf: none)
    P_STOP_HI,  # mechanical end stop above this rotor angle [rad] (inf: none)
    P_STANDBY_MAX,  # largest STANDBY_CURRENT of the type
    P_BRAKE_TORQUE,  # holding torque of the electromechanical brake [N·m] (0: none)
    P_OVERLOAD,  # 1 on the types with the driver overload error (§8.2.31 bit 18)
    P_MAX_BUS_VOLTS,  # MAX_VOLTAGE bits 0-15, the over-voltage threshold [V] (§8.2.93)
    P_H3_PRESET,  # H3 encoder: its preset minus the rotor's count at the preset (command 316)
    P_AF0,  # analogue filter settings of IO1 … IO8 as the firmware holds them (4 per input)
) = range(21)
#: one input's analogue filter settings at P_AF0 + 4·k + column: the firmware's copies of
#: AFZUP_CONFMIN, AFZUP_CONFMAX, AFZUP_MAXSLOPE and AFZUP_FILTER (§8.2.50–55)
AF_CONFMIN, AF_CONFMAX, AF_MAXSLOPE, AF_FILTER = range(4)
AF_SETTINGS = 4
N_PARAM = P_AF0 + AF_SETTINGS * 8

# --- inputs ---------------------------------------------------------------------------------
(
    I_LOAD_TORQUE,  # external torque opposing positive rotation [N·m]
    I_SUPPLY_VOLTS,  # P+ supply [V]
    I_PULSE_COUNTS,  # gear input counts during the next outer sample
    I_DIGITAL,  # IO1-IO8 levels (bits 0-7)
    I_ANALOG0,  # IO1 … IO8 analogue levels [V] (8 columns)
) = range(5)
#: the word the SSI encoder sends, Gray or binary as it codes it (§5.7; read on command 321/322)
I_SSI_WORD = I_ANALOG0 + 8
I_CONTROL_VOLTS = I_SSI_WORD + 1  #: control supply at the CVI terminal [V]
I_AMBIENT = I_CONTROL_VOLTS + 1  #: ambient temperature [°C]
I_STO_A = I_AMBIENT + 1  #: Safe Torque Off channel A [V]
I_STO_B = I_STO_A + 1  #: Safe Torque Off channel B [V]
I_FAULTS = I_STO_B + 1  #: injected hardware faults (ERR_BITS positions of constants.FAULT_BITS)
N_INPUT = I_FAULTS + 1
