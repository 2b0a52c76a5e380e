"""Hardware supervision: control voltage, temperature, over-voltage, Safe Torque Off, the brake
and injected hardware faults (MIS manual §5.4.5, §5.6.4, §5.11, §7.2, §8.2.24–25, §8.2.31–32,
§8.2.79–82, §8.2.93, §8.2.106, §8.2.127, §8.2.129). Everything here runs once per outer sample
(1 ms), never in the plant's inner samples.

- Control voltage (CVI, world input ``control_volts``): CVI_VOLT reads it in 8.764 mV units.
  Below SAVE_VOLTAGE "the program shuts down and all motor activity stops" (§8.2.81): the
  bridge goes off at once, the motor passive, ERR_BITS bit 17 (CVI unstable, §7.2.20: "below
  what is specified as minimum voltage", which a reset clears) is set; P_IST stays where the
  motor stopped, so a later reset or power-down backs up that position (§5.4.4). The program then
  waits, as at a start with a low CVI, until the voltage has been measured above ACCEPT_VOLTAGE
  ACCEPT_COUNT times in a row, once per 1 ms (§5.4.5, §8.2.79–80); while it waits the firmware
  does nothing (TICKS stands still).
- Temperature, measured every 10 ms (``THERMAL_PERIOD_MS``): the electronics are at the
  ambient temperature (world input ``ambient_celsius``) plus a first-order rise from the
  bridge's conduction loss (the thermal constants of ``constants``); TEMP reads °C / 2.27
  (§8.2.25), TEMP_HIGHRES m°C (§8.2.129).
  Above TEMP_LIMITS bits 0–15 [°C] WARN_BITS bit 6 ("has been above", kept until cleared),
  above bits 16–31 ERR_BITS bit 6, set again at every measurement while it is still too hot
  (§7.2.9, §8.2.127).
- Over-voltage: a measured bus voltage (BUSVOL) above MAX_VOLTAGE bits 0–15 [V] (100 V,
  §7.2.8, §8.2.93) sets ERR_BITS bit 5.
- Safe Torque Off (world inputs ``sto_a``, ``sto_b`` [V]): a channel below 18 V (§7.2.18) takes
  the torque off at once (passive, no ramp), sets ERR_BITS bit 29 (STO) and WARN_BITS bit 9
  (active while a channel is off); STATUSBITS bits 23/24 show each channel on, bit 19 the
  torque safely off (§8.2.24).
- Injected faults (world input ``faults``, bits in ERR_BITS positions): each present fault sets
  its error bit every sample (a clear does not hold while the fault is there); the driver
  overload also WARN_BITS bit 8; the closed-loop error (bit 12) only while SETUP_BITS bit 24
  selects the closed loop (§7.2.15); the encoder COM and external memory errors (bits 10, 13)
  only at start-up (§7.2.13, §7.2.16, ``motors``). STATUSBITS bit 9 shows an internal
  encoder error and bit 20 (encoder OK) is off while one is set.
- Brake (§5.6.4, §5.11, §8.2.106): a motor has a brake when its ``brake_torque`` parameter is
  above 0 or BRAKE selects an output. The brake is told to hold in passive and safe mode (and
  while the program is shut down) and to release in an active mode, unless SETUP_BITS bit 19
  disables it (released in every mode). The brake output (the IO pins of BRAKE bits 0–7 set as
  outputs) follows at once, high while released (set when the brake is told to hold or to
  release). The brake itself holds BRAKE bits 8–15 ms
  (T_ON) after it was told to hold and releases bits 16–23 ms (T_OFF) after it was told to
  release; until then an active motor does not move. STATUSBITS bit 14: the brake holds.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .. import constants as c
from .. import layout as L
from ..units import (
    BUSVOL_VOLTS_PER_UNIT,
    CVI_VOLTS_PER_UNIT,
    OUTER_DT,
    TEMP_CELSIUS_PER_UNIT,
    TEMP_HIGHRES_CELSIUS_PER_UNIT,
)
from . import regs as R

#: the temperature is measured every THERMAL_PERIOD_MS outer samples (``constants``)
_PERIOD = c.THERMAL_PERIOD_MS
#: the first-order rise's step per measurement (exact for a loss held over the period)
_RISE_STEP = 1.0 - math.exp(-_PERIOD * OUTER_DT / c.THERMAL_TIME_CONSTANT)
_PER_CVI_UNIT = 1.0 / CVI_VOLTS_PER_UNIT
_PER_TEMP_UNIT = 1.0 / TEMP_CELSIUS_PER_UNIT
_PER_TEMP_HIGHRES_UNIT = 1.0 / TEMP_HIGHRES_CELSIUS_PER_UNIT
_FAULTS_IN_RUN = c.FAULT_BITS & ~c.FAULTS_AT_START & ~c.ERR_CLOSED_LOOP
_BRAKE_MASK = 0xFF
#: STATUSBITS the supervision sets (``monitor.status_bits`` keeps them from sample to sample)
STATUS_BITS = (c.ST_ENCODER_ERROR | c.ST_BRAKE_ACTIVE | c.ST_STO | c.ST_STO_A | c.ST_STO_B)


@njit(cache=True, inline="always")
def busvol_units(u) -> int:  # pragma: no cover - compiled
    """The bus (P+) voltage as BUSVOL reads it: 26.525 mV units, 0 … 4095 (§8.2.47)."""
    return int(min(max(np.floor(u[L.I_SUPPLY_VOLTS] / BUSVOL_VOLTS_PER_UNIT + 0.5), 0.0),
                   4095.0))


@njit(cache=True, inline="always")
def cvi_units(volts: float) -> int:  # pragma: no cover - compiled
    """A control voltage as CVI_VOLT reads it: 8.764 mV units, 0 … 4095 (§8.2.82)."""
    return int(min(max(np.floor(volts * _PER_CVI_UNIT + 0.5), 0.0), 4095.0))


@njit(cache=True, inline="always")
def temperature(regs, s, u) -> None:  # pragma: no cover - compiled
    """Every THERMAL_PERIOD_MS samples: the electronics' temperature in TEMP and TEMP_HIGHRES
    and its warning and error bits (module docstring); the loss is that of the phase current
    the bridge runs with."""
    if int(s[L.S_TICK]) % _PERIOD != 0:
        return
    amps = s[L.S_I_AMP] if s[L.S_BRIDGE] > 0.0 else 0.0
    loss = c.DRIVER_RESISTANCE * amps * amps
    s[L.S_TEMP_RISE] += (c.THERMAL_RESISTANCE * loss - s[L.S_TEMP_RISE]) * _RISE_STEP
    celsius = u[L.I_AMBIENT] + s[L.S_TEMP_RISE]
    regs[R.TEMP_HIGHRES] = int(np.floor(celsius * _PER_TEMP_HIGHRES_UNIT + 0.5))
    regs[R.TEMP] = int(min(max(np.floor(celsius * _PER_TEMP_UNIT + 0.5), 0.0), 127.0))
    limits = regs[R.TEMP_LIMITS]
    if celsius > (limits & 0xFFFF):
        regs[R.WARN_BITS] |= c.WARN_TEMPERATURE
    if celsius > ((limits >> 16) & 0xFFFF):
        regs[R.ERR_BITS] |= c.ERR_TEMPERATURE | c.ERR_GENERAL


@njit(cache=True, inline="always")
def control_voltage(regs, s, u) -> bool:  # pragma: no cover - compiled
    """CVI_VOLT of this sample and whether the program runs (module docstring)."""
    cvi = cvi_units(u[L.I_CONTROL_VOLTS])
    regs[R.CVI_VOLT] = cvi
    if s[L.S_CVI_WAIT] == 0.0:
        if cvi >= regs[R.SAVE_VOLTAGE]:
            return True
        regs[R.ERR_BITS] |= c.ERR_CVI | c.ERR_GENERAL
        regs[R.MODE_REG] = c.PASSIVE
        s[L.S_CVI_WAIT] = 1.0
        s[L.S_CVI_N] = 0.0
        return False
    s[L.S_CVI_N] = s[L.S_CVI_N] + 1.0 if cvi > regs[R.ACCEPT_VOLTAGE] else 0.0
    if s[L.S_CVI_N] >= regs[R.ACCEPT_COUNT]:
        s[L.S_CVI_WAIT] = 0.0
        s[L.S_CVI_N] = 0.0
        return True
    return False


@njit(cache=True)
def program_stopped(regs, s, p) -> None:  # pragma: no cover - compiled
    """The outer sample of a motor whose program is not running: bridge off, no command
    motion, the brake holding."""
    s[L.S_VEL] = 0.0
    s[L.S_EMERGENCY] = 0.0
    s[L.S_CMD_PREV] = s[L.S_CMD]
    s[L.S_I_AMP] = 0.0
    s[L.S_BRIDGE] = 0.0
    s[L.S_FIELD_STEP] = 0.0
    s[L.S_BRAKE_HELD] = 1.0
    s[L.S_BRAKE_MS] = 0.0
    regs[R.ACTUAL_TORQUE] = 0
    if p[L.P_BRAKE_TORQUE] > 0.0 or s[L.S_BRAKE_EXT] != 0.0:
        regs[R.STATUSBITS] |= c.ST_BRAKE_ACTIVE


@njit(cache=True, inline="always")
def sto_off(u) -> bool:  # pragma: no cover - compiled
    """True while a Safe Torque Off channel is below 18 V (§7.2.18)."""
    return u[L.I_STO_A] < c.STO_ON_VOLTS or u[L.I_STO_B] < c.STO_ON_VOLTS


@njit(cache=True, inline="always")
def supervise(regs, s, u) -> None:  # pragma: no cover - compiled
    """Safe Torque Off and the injected faults of this sample (module docstring): their
    error, warning and status bits, and the torque off at once by STO (the temperature:
    :func:`temperature`, the over-voltage: :func:`over_voltage`)."""
    word = int(u[L.I_FAULTS])
    a = u[L.I_STO_A] >= c.STO_ON_VOLTS
    b = u[L.I_STO_B] >= c.STO_ON_VOLTS
    if word == 0 and a and b:
        if regs[R.WARN_BITS] & c.WARN_STO:
            regs[R.WARN_BITS] &= ~c.WARN_STO
        return
    err = regs[R.ERR_BITS]
    warn = regs[R.WARN_BITS]
    if not (a and b):
        err |= c.ERR_STO
        warn |= c.WARN_STO
        mode = regs[R.MODE_REG]
        if mode != c.PASSIVE and mode != c.SAFE:
            regs[R.MODE_REG] = c.PASSIVE
            s[L.S_VEL] = 0.0
            s[L.S_EMERGENCY] = 0.0
            s[L.S_HOME_PHASE] = 0.0
    else:
        warn &= ~c.WARN_STO
    faults = word & _FAULTS_IN_RUN
    if word & c.ERR_CLOSED_LOOP and regs[R.SETUP_BITS] & c.SETUP_CLOSED_LOOP:
        faults |= c.ERR_CLOSED_LOOP  # "only occurs when activating the closed loop" (§7.2.15)
    err |= faults
    if faults & c.ERR_DRIVER_OVERLOAD:
        warn |= c.WARN_DRIVER_OVERLOAD
    if err & ~c.ERR_GENERAL:
        err |= c.ERR_GENERAL
    regs[R.ERR_BITS] = err
    regs[R.WARN_BITS] = warn


@njit(cache=True, inline="always")
def over_voltage(p, busvol: int) -> bool:  # pragma: no cover - compiled
    """True if the measured bus voltage ``busvol`` (BUSVOL units) is above the type's
    MAX_VOLTAGE bits 0–15 [V] (§8.2.93; a factory value, kept in ``params``)."""
    return busvol * BUSVOL_VOLTS_PER_UNIT > p[L.P_MAX_BUS_VOLTS]


@njit(cache=True, inline="always")
def brake(regs, s, p, active: bool) -> bool:  # pragma: no cover - compiled
    """The brake and its output in this sample (module docstring); True while an active motor
    waits for its brake to release (it does not move). BRAKE is read when the brake is told
    to hold or to release: the output and whether an external brake is fitted change then."""
    hold = not active and (regs[R.SETUP_BITS] & c.SETUP_BRAKE_OFF) == 0
    want = 1.0 if hold else 0.0
    if want == s[L.S_BRAKE_HELD] and want == s[L.S_BRAKE_CMD]:
        return False
    setup = regs[R.BRAKE]
    if want != s[L.S_BRAKE_CMD]:
        s[L.S_BRAKE_CMD] = want
        s[L.S_BRAKE_EXT] = 1.0 if setup & _BRAKE_MASK else 0.0
        out = setup & _BRAKE_MASK & ((regs[R.IOSETUP] >> 8) & 0xFF)
        if out:
            regs[R.OUTPUTS] = (regs[R.OUTPUTS] & ~out) | (0 if hold else out)
    if s[L.S_BRAKE_HELD] == want:
        s[L.S_BRAKE_MS] = 0.0
    else:
        s[L.S_BRAKE_MS] += 1.0
        delay = (setup >> 8) & 0xFF if hold else (setup >> 16) & 0xFF
        if s[L.S_BRAKE_MS] >= delay:
            s[L.S_BRAKE_HELD] = want
            s[L.S_BRAKE_MS] = 0.0
    fitted = p[L.P_BRAKE_TORQUE] > 0.0 or s[L.S_BRAKE_EXT] != 0.0
    st = regs[R.STATUSBITS] & ~c.ST_BRAKE_ACTIVE
    regs[R.STATUSBITS] = st | (c.ST_BRAKE_ACTIVE if fitted and s[L.S_BRAKE_HELD] != 0.0 else 0)
    return active and s[L.S_BRAKE_HELD] != 0.0 and fitted


@njit(cache=True, inline="always")
def supervision_status(regs, u) -> None:  # pragma: no cover - compiled
    """STATUSBITS bits 9, 19, 20, 23 and 24 of this sample (§8.2.24); bit 14 is the brake's
    (:func:`brake`)."""
    st = regs[R.STATUSBITS] & ~(c.ST_ENCODER_ERROR | c.ST_STO | c.ST_STO_A | c.ST_STO_B)
    if regs[R.ERR_BITS] & c.ERR_ENCODER_ANY:
        st = (st | c.ST_ENCODER_ERROR) & ~c.ST_ENCODER_OK
    a = u[L.I_STO_A] >= c.STO_ON_VOLTS
    b = u[L.I_STO_B] >= c.STO_ON_VOLTS
    if a:
        st |= c.ST_STO_A
    if b:
        st |= c.ST_STO_B
    if not (a and b):
        st |= c.ST_STO
    regs[R.STATUSBITS] = st
