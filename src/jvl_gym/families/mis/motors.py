"""The MIS/SMC motor array: the family's rules on top of the generic :class:`MotorArray`.

ROM images from the register table (MIS manual §8.2) with the type's MOTORTYPE; motor data
from the type's config (``config.py``); power-on (STARTMODE or HOMEMODE, §8.2.33, §8.2.37);
the firmware's write rules — MODE_REG values (§8.2.3; safe mode only by command, active modes
refused while ERR_BITS ≠ 0, §8.2.31), P_SOLL in a turn-table mode (§5.12), ENCODER_POS, the
COMMAND register's FastMac commands (§8.2.21), the sample buffer's S_CONTROL (§8.2.63) —,
world inputs and the physical truth of the plant.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterable
from typing import Any, ClassVar

import numpy as np
from numba import njit

from ...motor.arguments import InputValue, MotorIndex, as_index
from ...motor.array import ModeError, MotorArray
from ...motor.bank import StorePlan
from ...motor.inputs import InputRule, staged_inputs
from ...motor.keywords import FINITE, NONNEGATIVE, POSITIVE
from ...physics.fixed import wrap32
from ...registers import Register, RegisterError, RegisterRangeError
from . import constants as c
from . import layout as L
from .config import MisMotorConfig, load_motor
from .filter_setup import READ_INDEX_VALUES, FilterSetup
from .firmware import regs as R
from .firmware.start import start_rows
from .multifunction_port import MultifunctionOutput
from .plant.torque_curve import pull_out_torque
from .program.api import ProgramMixin
from .ssi_port import SSI_COMMANDS, SsiPort
from .table import CONFORMANCE, TABLE
from .units import (
    COUNTS_PER_RAD,
    COUNTS_PER_REV,
    CURRENT_AMPS_PER_UNIT,
)
from .user_commands import UserCommands

__all__ = ["MisMotorArray"]


_PARAMETERS: dict[str, int] = {
    "load_inertia": L.P_J_LOAD,  # kg·m²
    "rotor_inertia": L.P_J_MOTOR,  # kg·m²
    "phase_resistance": L.P_R,  # Ω
    "phase_inductance": L.P_L,  # H
    "torque_constant": L.P_KT,  # N·m/A of current amplitude
    "detent_torque": L.P_DETENT,  # N·m
    "viscous_friction": L.P_VISCOUS,  # N·m·s/rad
    "coulomb_friction": L.P_COULOMB,  # N·m
    "encoder_type": L.P_ENCODER,  # ENCODER_TYPE code 0 … 4 (§8.2.49)
    "home_position": L.P_HOME_POS,  # rad; the home input is active at or below it
    "damping_ratio": L.P_ZETA,  # rotor against the stator field (``plant``)
    "end_stop_low": L.P_STOP_LO,  # rad (−inf: none)
    "end_stop_high": L.P_STOP_HI,  # rad (inf: none)
    "brake_torque": L.P_BRAKE_TORQUE,  # N·m, the electromechanical brake's (0: none, §5.11)
}
_STATES: dict[str, int] = {"initial_angle": L.S_THETA}  # rad
_NONNEGATIVE = {"load_inertia", "detent_torque", "viscous_friction", "coulomb_friction",
                "encoder_type", "damping_ratio", "brake_torque"}
_POSITIVE = {"rotor_inertia", "phase_resistance", "phase_inductance", "torque_constant"}
_MAY_BE_INFINITE = {"home_position", "end_stop_low", "end_stop_high"}
_INPUT_COLUMNS: dict[str, int] = {"load_torque": L.I_LOAD_TORQUE,
                                  "supply_volts": L.I_SUPPLY_VOLTS,
                                  "pulse_counts": L.I_PULSE_COUNTS,
                                  "digital_inputs": L.I_DIGITAL,
                                  **{f"analog{k + 1}": L.I_ANALOG0 + k for k in range(8)},
                                  "ssi_word": L.I_SSI_WORD,
                                  "control_volts": L.I_CONTROL_VOLTS,
                                  "ambient_celsius": L.I_AMBIENT,
                                  "sto_a": L.I_STO_A, "sto_b": L.I_STO_B,
                                  "faults": L.I_FAULTS}
#: registers whose writes the firmware's rules handle one by one
_SPECIAL = frozenset({R.MODE_REG, R.P_SOLL, R.COMMAND, R.ENCODER_POS, R.S_CONTROL,
                      R.STARTMODE, R.HOMEMODE, R.TURNTABLE_MODE, R.AFZUP_WRITEBITS,
                      R.AFZUP_READINDEX, R.ERR_BITS})
#: registers a setup (a register set) may not hold: commands and mode requests
_NOT_IN_SETUP = frozenset({R.MODE_REG, R.COMMAND, R.S_CONTROL, R.ENCODER_POS})
#: registers that hold one of a set of codes: (allowed, where the manual says so)
_MEMBERS: dict[int, tuple[frozenset[int], str]] = {
    R.STARTMODE: (c.START_MODES, "§8.2.33"), R.HOMEMODE: (c.HOME_MODES, "§8.2.37"),
    R.TURNTABLE_MODE: (frozenset(range(6)), "§5.12.3: >5 is illegal"),
    R.AFZUP_READINDEX: (READ_INDEX_VALUES, "§8.2.51: 0, 1-8, 32768-32775")}
BUFFER_DEPTH = 1024  #: BUF_SIZE (§8.2.64)
#: the zero-search modes (§6.5.9) and the modes with the bridge off (§5.11.2, §8.2.3)
_SEARCHES = (c.ZERO_SEARCH_1, c.ZERO_SEARCH_2)
_OFF = (c.PASSIVE, c.SAFE)


def _member_table(members: Iterable[int]) -> np.ndarray:
    """A lookup table of the whole numbers ``members`` (≥ 0) for :func:`_among`: True at each
    member, False elsewhere and in its last entry (where larger values land)."""
    members = sorted(members)
    table = np.zeros(members[-1] + 2, dtype=np.bool_)
    table[members] = True
    return table


def _among(values: np.ndarray, table: np.ndarray) -> np.ndarray:
    """``np.isin(values, members)`` for whole numbers ``values`` and the members of ``table``
    (:func:`_member_table`), as one lookup (on a few motors ``np.isin`` costs many times
    more): a negative value, seen as a large unsigned one, and a value past the table land
    on its last entry."""
    return table[np.minimum(np.asarray(values, np.int64).view(np.uint64), table.size - 1)]


#: lookup tables (:func:`_member_table`) of the mode sets above
_IS_SEARCH = _member_table(_SEARCHES)
_IS_OFF = _member_table(_OFF)
#: MODE_REG values 0 … 15 stand for themselves in :data:`_MODE_CHANGES`, any other for 16
_OTHER_MODE = 16
#: bits of :data:`_MODE_CHANGES`: the change is refused; it requests a zero search; it requests
#: passive; it enters an active mode from passive or safe with SETUP_BITS bit 5 set
_REFUSED, _TO_SEARCH, _TO_PASSIVE, _SYNC = 1, 2, 4, 8


def _mode_changes() -> np.ndarray:
    """What writing MODE_REG := ``new`` means to a motor in mode ``old``, as bits by ``[old,
    new, errors, sync]`` (17 × 17 × 2 × 2 uint8; :data:`_OTHER_MODE` any other value;
    ``errors``: ERR_BITS ≠ 0; ``sync``: SETUP_BITS bit 5): refused when it leaves or enters
    safe mode (by command only) or is no writable mode (§8.2.3), or is an active mode while
    ERR_BITS ≠ 0 (§8.2.31); a zero search; passive; the encoder synchronised to P_IST
    (SETUP_BITS bit 5, §8.2.68)."""
    out = np.zeros((_OTHER_MODE + 1, _OTHER_MODE + 1, 2, 2), dtype=np.uint8)
    for old, new, errors, sync in itertools.product(range(_OTHER_MODE + 1),
                                                    range(_OTHER_MODE + 1), (0, 1), (0, 1)):
        allowed = new == c.SAFE if old == c.SAFE else new in c.WRITABLE_MODES
        refused = not allowed or (errors and new != c.PASSIVE)
        out[old, new, errors, sync] = (
            _REFUSED * refused | _TO_SEARCH * (new in _SEARCHES)
            | _TO_PASSIVE * (new == c.PASSIVE)
            | _SYNC * (sync and old in _OFF and new != c.PASSIVE))
    return out


_MODE_CHANGES = _mode_changes()


@njit(cache=True)
def _mode_change_bits(regs: np.ndarray, idx: np.ndarray, raw: np.ndarray,
                      changes: np.ndarray) -> np.ndarray:  # pragma: no cover - compiled
    """The bits of ``changes`` (:data:`_MODE_CHANGES`) of MODE_REG := ``raw[j]`` for motor
    ``idx[j]``, (M,) uint8: by its MODE_REG now and the new value (0 … 15 themselves, any
    other value :data:`_OTHER_MODE`), ERR_BITS ≠ 0 and SETUP_BITS bit 5. Where no change has
    any bit (a plain change of mode for every motor), MODE_REG := ``raw`` is stored here and
    the result is empty, (0,)."""
    out = np.empty(idx.size, dtype=np.uint8)
    plain = True
    for j in range(idx.size):
        i = idx[j]
        old, new = regs[i, R.MODE_REG], raw[j]
        out[j] = changes[old if 0 <= old < _OTHER_MODE else _OTHER_MODE,
                         new if 0 <= new < _OTHER_MODE else _OTHER_MODE,
                         1 if regs[i, R.ERR_BITS] != 0 else 0,
                         1 if regs[i, R.SETUP_BITS] & c.SETUP_SYNC_ENCODER else 0]
        if out[j] != 0:
            plain = False
    if not plain:
        return out
    for j in range(idx.size):
        regs[idx[j], R.MODE_REG] = raw[j]
    return out[:0]


#: the factory limits a power-on takes from ROM (flash holds the writable registers only)
_FACTORY = np.array([R.MAX_VOLTAGE, R.TEMP_LIMITS], dtype=np.int64)
#: the ends of a turn table's range (§5.12.1)
_TURN_TABLE_ENDS = np.array([R.MIN_P_IST, R.MAX_P_IST], dtype=np.int64)
#: the plant's state and the electronics' temperature, which a reset of the electronics leaves
#: alone
_PLANT_STATE = [L.S_THETA, L.S_OMEGA, L.S_ID, L.S_IQ, L.S_E_COPPER, L.S_E_LOAD, L.S_TEMP_RISE]
#: the ENCODER_TYPE codes (§8.2.49)
_ENCODER_CODES = frozenset(c.ENCODER_CPR)


class MisMotorArray(MultifunctionOutput, SsiPort, UserCommands, FilterSetup, ProgramMixin,
                    MotorArray, layout=L):
    """N simulated MIS/SMC integrated step motors (:class:`~jvl_gym.MotorArray` of the
    ``mis`` family).

    Parameters
    ----------
    motor, n, seed, setup
        As for :class:`~jvl_gym.MotorArray` (``setup``: a register set written after the ROM
        defaults, like the MACs').
    **params
        Per-motor parameters (scalars or (N,) arrays): :attr:`PARAMETER_KEYWORDS` (SI units)
        and ``initial_angle`` [rad].

    Examples
    --------
    >>> m = MotorArray("MIS231", n=2)
    >>> m.write_many({"V_SOLL": 25000, "MODE_REG": 1})  # 250 RPM
    >>> m.run(0.5)
    """

    FAMILY_KEY = "mis"
    TABLE = TABLE
    CONFORMANCE = CONFORMANCE
    BUFFER_SHAPE = (BUFFER_DEPTH, 4)
    OUTER_HZ = c.OUTER_HZ
    PARAMETER_KEYWORDS: ClassVar[dict[str, int]] = _PARAMETERS
    STATE_KEYWORDS: ClassVar[dict[str, int]] = _STATES
    VALUE_RULES: ClassVar[dict[str, int]] = {
        name: ((FINITE if name not in _MAY_BE_INFINITE else 0)
               | (NONNEGATIVE if name in _NONNEGATIVE else 0)
               | (POSITIVE if name in _POSITIVE else 0))
        for name in [*_PARAMETERS, *_STATES]}
    INPUTS: ClassVar[dict[str, int]] = _INPUT_COLUMNS
    INPUT_RULES: ClassVar[dict[str, InputRule]] = {
        # physical ranges beyond the firmware's thresholds (over-voltage at 100 V, §7.2.8)
        "supply_volts": InputRule(0.0, 150.0, unit="V"),
        "control_volts": InputRule(0.0, 48.0, unit="V"),
        "ambient_celsius": InputRule(-40.0, 150.0, unit="°C"),
        "sto_a": InputRule(0.0, 48.0, unit="V"),
        "sto_b": InputRule(0.0, 48.0, unit="V"),
        "faults": InputRule(0.0, float(c.FAULT_BITS), whole=True, unit="(ERR_BITS bits)"),
        "pulse_counts": InputRule(whole=True, unit="counts per outer sample"),
        "digital_inputs": InputRule(0.0, 255.0, whole=True, unit="(bits of IO1-IO8)"),
        "ssi_word": InputRule(0.0, 2.0**31 - 1, whole=True, unit="(the SSI encoder's word)")}
    PHYSICAL = frozenset({"speed_rpm", "speed_rad_s", "position_rad", "torque", "current_amplitude",
                          "lost_steps", "multifunction_output",
                          "multifunction_output_total"})
    SHAFT_ANGLE, SHAFT_SPEED = L.S_THETA, L.S_OMEGA
    #: the arrays a register write may change (``RegisterBank.TRANSACTION_ARRAYS``): the
    #: registers, the state, the parameters (AFZUP_WRITEBITS, command 316) and which motors
    #: hold a flash image (commands 268, 269); no write changes the world inputs
    TRANSACTION_ARRAYS: ClassVar[tuple[str, ...]] = ("regs", "state", "params", "_has_flash")
    #: P_IST of each motor at its last power-down or reset (§5.4.2), (N,) int64; None until
    #: the first power-on
    _position_backup: np.ndarray | None = None

    @staticmethod
    def load_motor(motor: Any) -> MisMotorConfig:
        """The validated motor config (``mis.config.load_motor``)."""
        return load_motor(motor)

    # ------------------------------------------------------------------ type pool
    def _rom_image(self, cfg: MisMotorConfig, setup: Any) -> np.ndarray:
        image = self.table.default_raw_array.astype(np.int64).copy()
        image[R.MOTORTYPE] = cfg.motor_type_code
        # MAX_VOLTAGE: bits 0-15 the bus voltage limit [V], 16-31 the full-scale current [mA
        # RMS] (§8.2.93)
        image[R.MAX_VOLTAGE] = c.MAX_BUS_VOLTS | (round(cfg.rated_current * 1000.0) << 16)
        if setup is not None:
            from ..config import load_setup

            row = image[None]
            for name, value in load_setup(setup).registers.items():
                reg = self._lookup(name)
                if reg.number in _NOT_IN_SETUP:
                    raise RegisterError(f"setup: {reg.name} is a command or a mode request; "
                                        "write it after power-on")
                raw = self._validated_raw(reg, value, 1)
                rule = _MEMBERS.get(reg.number)
                if rule is not None:
                    self._check_member(reg, raw, *rule)
                row[0, reg.number] = raw[0]
        return image

    def _config_params(self, cfg: MisMotorConfig) -> np.ndarray:
        p = np.zeros(L.N_PARAM)
        p[L.P_J_MOTOR] = cfg.rotor_inertia
        p[L.P_R] = cfg.phase_resistance
        p[L.P_L] = cfg.phase_inductance
        p[L.P_KT] = cfg.torque_constant
        p[L.P_DETENT] = cfg.detent_torque
        p[L.P_VISCOUS] = cfg.viscous_friction
        p[L.P_COULOMB] = cfg.coulomb_friction
        p[L.P_ENCODER] = cfg.encoder_type
        p[L.P_HOME_POS] = -math.inf
        p[L.P_AMPS_PER_UNIT] = CURRENT_AMPS_PER_UNIT
        p[L.P_RUN_MAX] = cfg.run_current_max
        p[L.P_STANDBY_MAX] = cfg.standby_current_limit
        p[L.P_ZETA] = cfg.damping_ratio
        p[L.P_STOP_LO] = -math.inf
        p[L.P_STOP_HI] = math.inf
        p[L.P_OVERLOAD] = float(cfg.name.startswith(c.OVERLOAD_TYPES))
        p[L.P_MAX_BUS_VOLTS] = c.MAX_BUS_VOLTS
        return p

    def _rest_inputs(self, cfg: MisMotorConfig) -> np.ndarray:
        u = np.zeros(L.N_INPUT)
        u[L.I_SUPPLY_VOLTS] = cfg.supply_voltage
        u[L.I_CONTROL_VOLTS] = u[L.I_STO_A] = u[L.I_STO_B] = c.NOMINAL_CVI_VOLTS
        u[L.I_AMBIENT] = c.NOMINAL_AMBIENT_CELSIUS
        return u

    def _reset_rows(self, idx: np.ndarray, cols: np.ndarray, to_state: np.ndarray,
                    values: np.ndarray) -> None:
        """Power on motors ``idx`` (``MotorArray._reset_rows``, here on (M, ·) blocks of the
        motors' rows): the registers from flash or ROM, the state 0, the type pool's parameters
        and inputs, the reset keywords' ``values`` (P, M) into columns ``cols`` (P,) of
        ``params`` or, where ``to_state``, of ``state``, then the firmware's start. An
        encoder_type that is no ENCODER_TYPE code (§8.2.49) is refused before anything
        changes."""
        col_list = cols.tolist()
        for q, col in enumerate(col_list):
            if col == L.P_ENCODER and not to_state[q] and not set(
                    values[q].tolist()) <= _ENCODER_CODES:
                raise ValueError(f"encoder_type must be one of {sorted(_ENCODER_CODES)} "
                                 f"(§8.2.49), got {values[q].tolist()}")
        types = self._type_of[idx]
        state = np.zeros((idx.size, L.N_STATE))
        if type(self)._initial_state is not MotorArray._initial_state:
            for row in state:
                self._initial_state(row)
        params = self._type_params[types]
        for q, col in enumerate(col_list):
            (state if to_state[q] else params)[:, col] = values[q]
        self.inputs[idx] = self._type_inputs[types]
        self._start(idx, self._memory_rows(idx, types), state, params, take_backup=True)

    def _memory_rows(self, idx: np.ndarray, types: np.ndarray | None = None) -> np.ndarray:
        """The registers motors ``idx`` (of types ``types``, by default their own) start with:
        their flash image where they have one, else their type's ROM image, (M, registers)
        int64 (a new array); MAX_VOLTAGE and TEMP_LIMITS hold the factory values from ROM
        (flash holds the writable registers only, §8.2.93)."""
        if types is None:
            types = self._type_of[idx]
        rows = self._rom[types]
        if self._flash is not None:
            flashed = self._has_flash[idx]
            if flashed.any():
                rows[flashed] = self._flash[idx[flashed]]
                rows[:, _FACTORY] = self._rom[types[:, None], _FACTORY]
        return rows

    def _power_on(self, idx: np.ndarray) -> None:
        """Firmware start of motors ``idx`` from their registers (the factory limits from ROM),
        state and parameters as they are (:meth:`_start`; a reset and a software reset start
        from flash or ROM, :meth:`_reset_rows`, :meth:`software_reset`)."""
        regs = self.regs[idx]
        regs[:, _FACTORY] = self._rom[self._type_of[idx][:, None], _FACTORY]
        self._start(idx, regs, self.state[idx], self.params[idx])

    def _start(self, idx: np.ndarray, regs: np.ndarray, s: np.ndarray, p: np.ndarray,
               take_backup: bool = False) -> None:
        """Firmware start of motors ``idx`` whose registers (MAX_VOLTAGE and TEMP_LIMITS the
        factory values), state (at a reset 0 but for the plant's) and parameters before it are
        the (M, ·) blocks ``regs``, ``s`` and ``p`` (worked on in place, then stored in their
        rows):
        positions, counters, NOTSAVED (§8.2.96) and error bits cleared (P_IST = P_SOLL =
        ENCODER_POS = 0, or the position SETUP_BITS bits 10/11 take from the encoder or the
        position back-up of §5.4.2–5.4.3; P_SOLL = P_IST, so a saved P_SOLL makes no move at
        power-on), EXT_ENCODER too unless SETUP_BITS bit 12 keeps it, the mode from HOMEMODE
        or else STARTMODE (§8.2.33, §8.2.37), the hardware supervision's start (CVI_VOLT,
        TEMP, the brake, the faults only a start sees, §7.2.13, §7.2.16, §8.2.79–80), the
        analogue filter settings (§8.2.50–55) and EXTENCODER2 (§8.2.68): the compiled
        :func:`.firmware.start.start_rows`, which stores the blocks in the motors' rows (with
        ``take_backup``, after it has taken P_IST as the position back-up of §5.4.2: the
        position a power-down or reset leaves, which a later power-up with SETUP_BITS bit 11
        restores); then the user commands' flags, the SSI port, a stored program and the
        multifunction output start."""
        if self._position_backup is None:  # (P_IST is 0 here)
            self._position_backup = np.zeros(self.n, dtype=np.int64)
        start_rows(idx, regs, s, p, self.regs, self.state, self.params, self.inputs,
                   self._position_backup, take_backup)
        self._commands_power_on(idx)
        self._ssi_power_on(idx)
        self._program_power_on(idx)
        self._mf_power_on(idx, s)

    @property
    def time(self) -> np.ndarray:
        """Time since power-on of each motor [s], (N,)."""
        return self.state[:, L.S_TICK] * (1.0 / c.OUTER_HZ)

    # ------------------------------------------------------------------ write rules
    def _store_rows(self, plan: StorePlan, idx: np.ndarray, raws: np.ndarray) -> None:
        for k, reg in enumerate(plan.regs):
            num = reg.number
            if num not in _SPECIAL:
                self.regs[idx, num] = raws[k]
            elif num == R.P_SOLL:
                self._store_p_soll(idx, raws[k])
            elif num == R.MODE_REG:
                self._store_mode(idx, raws[k])
            else:
                self._store_one(reg, idx, raws[k])

    def _store_special(self, reg: Register, idx: np.ndarray, raw: np.ndarray) -> bool:
        if reg.number in _SPECIAL:
            self._store_one(reg, idx, raw)
            return True
        return False

    def _store_one(self, reg: Register, idx: np.ndarray, raw: np.ndarray) -> None:
        """One register with write rules (module docstring); a refusal raises first."""
        num = reg.number
        regs, s = self.regs, self.state
        if num == R.MODE_REG:
            self._store_mode(idx, raw)
        elif num == R.AFZUP_READINDEX:
            self._check_member(reg, raw, *_MEMBERS[num])
            self._afzup_read_index(idx, raw)
        elif num in _MEMBERS:
            self._check_member(reg, raw, *_MEMBERS[num])
            regs[idx, num] = raw
        elif num == R.AFZUP_WRITEBITS:
            self._afzup_write_bits(idx, raw)
        elif num == R.P_SOLL:
            self._store_p_soll(idx, raw)
        elif num == R.ENCODER_POS:
            for i, value in zip(idx.tolist(), raw.tolist()):
                self._set_encoder(i, value)
        elif num == R.S_CONTROL:
            if np.any(raw == 2):
                self._ensure_buffer()
            start = raw != 0
            s[idx[start], L.S_REC_N] = 0.0
            s[idx[start], L.S_REC_MS] = 0.0
            regs[idx, num] = raw
        elif num == R.COMMAND:
            self._commands(idx, raw)
        elif num == R.ERR_BITS:
            self._store_err_bits(idx, raw)

    def _store_err_bits(self, idx: np.ndarray, raw: np.ndarray) -> None:
        """ERR_BITS := ``raw``, but the errors only a reset clears stay (``ERR_NEEDS_RESET``:
        §7.2.5, §7.2.10, §7.2.17, §7.2.20, §7.2.21; "Other errors will require hardware fixes
        or intervention", §8.2.31), with the general error bit 0 while any error is left."""
        kept = self.regs[idx, R.ERR_BITS] & c.ERR_NEEDS_RESET
        value = np.asarray(raw, dtype=np.int64) | kept
        value = np.where(value & ~c.ERR_GENERAL, value | c.ERR_GENERAL, value)
        self.regs[idx, R.ERR_BITS] = value

    def _check_member(self, reg: Register, raw: np.ndarray, allowed: frozenset[int],
                      where: str) -> None:
        bad = [v for v in raw.tolist() if v not in allowed]
        if bad:
            raise RegisterRangeError(f"{reg.name} (register {reg.number}) = {bad[0]} refused: "
                                     f"allowed {sorted(allowed)} ({where}). Nothing was "
                                     "changed.")

    # ------------------------------------------------------------------ safe mode, flash
    def enter_safe_mode(self, index: MotorIndex = None) -> None:
        """The serial command ENTER SAFEMODE: the bridge off, flash and reset allowed
        (§8.2.3: safe mode is entered and left by command only)."""
        idx = as_index(index, self.n)
        self.regs[idx, R.MODE_REG] = c.SAFE
        self.state[idx, L.S_VEL] = 0.0

    def exit_safe_mode(self, index: MotorIndex = None) -> None:
        """The serial command EXIT SAFEMODE: back to passive."""
        idx = as_index(index, self.n)
        self._in_safe(idx, "exit_safe_mode")
        self.regs[idx, R.MODE_REG] = c.PASSIVE

    def write_flash(self, index: MotorIndex = None) -> None:
        """Save the register set in flash and reset the motors (safe mode only, §8.2.3; user
        command 268, §8.2.22)."""
        idx = as_index(index, self.n)
        self._in_safe(idx, "write_flash")
        self._save_flash(idx)
        self.software_reset(idx)

    def software_reset(self, index: MotorIndex = None) -> None:
        """Reset the electronics (user command 267, §8.2.22): registers from flash or ROM and
        the power-on of the firmware (:meth:`_power_on`); the rotor keeps its angle and speed,
        and the drive restarts with its commanded position at the rotor (no jump)."""
        idx = as_index(index, self.n)
        ssi = self.regs[idx, R.EXTENCODER2]
        state = np.zeros((idx.size, L.N_STATE))
        state[:, _PLANT_STATE] = self.state[idx][:, _PLANT_STATE]
        self._start(idx, self._memory_rows(idx), state, self.params[idx], take_backup=True)
        self._ssi_keep(idx, ssi)
        rotor = self.state[idx, L.S_THETA] * COUNTS_PER_REV / (2.0 * math.pi)
        for col in (L.S_CMD, L.S_CMD_PREV, L.S_FIELD):
            self.state[idx, col] = rotor
        self._mf_power_on(idx)

    def _in_safe(self, idx: np.ndarray, what: str) -> None:
        bad = idx[self.regs[idx, R.MODE_REG] != c.SAFE]
        if bad.size:
            raise ModeError(f"{what} needs safe mode (§8.2.3); motor {int(bad[0])} is in "
                            f"{c.MODE_NAMES.get(int(self.regs[bad[0], R.MODE_REG]), '?')}")

    def _store_mode(self, idx: np.ndarray, raw: np.ndarray) -> None:
        """MODE_REG := ``raw`` for motors ``idx`` by the firmware's rules (§8.2.3, §8.2.31;
        :data:`_MODE_CHANGES`), refused for all if one is refused: safe mode is left and
        entered by command only, a value must be a writable mode, an active mode needs ERR_BITS
        = 0. A zero search entered starts afresh; passive requested of a running motor stops
        it on its deceleration ramp first; an active mode entered from passive or safe with
        SETUP_BITS bit 5 sets the encoder to P_IST."""
        regs, s = self.regs, self.state
        change = _mode_change_bits(regs, idx, raw, _MODE_CHANGES)
        if not change.size:  # stored there: no motor's change has a rule to follow
            return
        new = raw
        mode = regs[idx, R.MODE_REG]
        refused = (change & _REFUSED) != 0
        if refused.any():
            j = int(np.argmax(refused))
            self._refuse_mode(int(idx[j]), int(raw[j]))
        enter_home = ((change & _TO_SEARCH) != 0) & (mode != raw)
        if enter_home.any():
            entering = idx[enter_home]
            s[entering, L.S_HOME_PHASE] = 0.0
            s[entering, L.S_HOME_MS] = 0.0
            # the mode a time-out sets back (§7.2.19): the one before the search started
            first = enter_home & ~_among(mode, _IS_SEARCH)
            s[idx[first], L.S_HOME_PREV] = mode[first]
        off = (change & _TO_PASSIVE) != 0
        if off.any():
            # §5.11.2: "When changing to Passive mode the motor goes into Stop mode to
            # decelerate according to the 'Deceleration'-ramp" (an error stop keeps its
            # own)
            running = (off & (s[idx, L.S_VEL] != 0.0) & (s[idx, L.S_EMERGENCY] == 0.0)
                       & ~_among(mode, _IS_OFF))
            halt = idx[off & ~running]
            s[halt, L.S_VEL] = 0.0
            s[halt, L.S_EMERGENCY] = 0.0
            new = np.where(running, c.STOP, raw)
        # SETUP_BITS bit 5 (§8.2.68): "Synchronize encoder position to P_IST after change
        # to active mode. Follow error = 0"
        for i in idx[(change & _SYNC) != 0].tolist():
            self._set_encoder(i, int(regs[i, R.P_IST]))
            regs[i, R.FLWERR] = 0
        regs[idx, R.MODE_REG] = new

    def _refuse_mode(self, i: int, value: int) -> None:
        """Raise the ModeError of MODE_REG := ``value`` refused for motor ``i``
        (:meth:`_store_mode`)."""
        if self.regs[i, R.MODE_REG] == c.SAFE and value != c.SAFE:
            raise ModeError(f"MODE_REG = {value} refused for motor {i}: safe mode is left "
                            "by command only (exit_safe_mode, §8.2.3). Nothing was changed.")
        if value not in c.WRITABLE_MODES and not (
                value == c.SAFE and self.regs[i, R.MODE_REG] == c.SAFE):
            why = ("safe mode is entered by command only" if value == c.SAFE
                   else f"allowed {sorted(c.WRITABLE_MODES)}")
            raise ModeError(f"MODE_REG = {value} refused for motor {i}: {why} (MIS manual "
                            "§8.2.3). Nothing was changed.")
        raise ModeError(f"MODE_REG = {value} refused for motor {i}: ERR_BITS = "
                        f"{int(self.regs[i, R.ERR_BITS])}; clear the errors first "
                        "(§8.2.31). Nothing was changed.")

    def _store_p_soll(self, idx: np.ndarray, raw: np.ndarray) -> None:
        """P_SOLL := ``raw`` for motors ``idx``, limited or reduced into a turn table's range
        (§5.12.1): kept inside [min, max] of MIN_P_IST and MAX_P_IST (and always without a turn
        table or with max ≤ min), reduced modulo the range past its end in the direction of a
        multi-turn mode (the travel beyond P_IST kept for the profile), otherwise limited to
        the range."""
        regs, s = self.regs, self.state
        if idx.size == 1:  # (one motor: scalar indexing costs a fraction of numpy's fancy one)
            i = idx[0]
            s[i, L.S_TT_TRAVEL] = 0.0
            if regs[i, R.TURNTABLE_MODE] == c.TT_OFF:
                regs[i, R.P_SOLL] = raw[0]
                return
        s[idx, L.S_TT_TRAVEL] = 0.0
        mode = regs[idx, R.TURNTABLE_MODE]
        if not mode.any():  # TT_OFF everywhere
            regs[idx, R.P_SOLL] = raw
            return
        ends = regs[idx[:, None], _TURN_TABLE_ENDS]
        lo, hi = ends.min(axis=1), ends.max(axis=1)
        inside = (mode == c.TT_OFF) | (hi <= lo) | ((lo <= raw) & (raw <= hi))
        wrap = ~inside & (((mode == c.TT_MULTI_CW) & (raw > hi))
                          | ((mode == c.TT_MULTI_CCW) & (raw < lo)))
        size = np.where(wrap, hi - lo + 1, 1)
        regs[idx, R.P_SOLL] = np.where(inside, raw, np.where(
            wrap, lo + np.mod(raw - lo, size), np.minimum(np.maximum(raw, lo), hi)))
        if wrap.any():
            s[idx[wrap], L.S_TT_TRAVEL] = (raw - regs[idx, R.P_IST])[wrap].astype(np.float64)

    def _firmware_angle(self, idx: np.ndarray) -> np.ndarray:
        """Rotor angles [rad] in the firmware's direction (``firmware.monitor.firmware_angle``:
        mirrored by SETUP_BITS bit 0), (len(idx),)."""
        theta = self.state[idx, L.S_THETA]
        return np.where(self.regs[idx, R.SETUP_BITS] & c.SETUP_INVERT_DIRECTION, -theta, theta)

    def _set_encoder(self, i: int, value: int) -> None:
        """ENCODER_POS := ``value`` at the present rotor angle."""
        cpr = c.ENCODER_CPR[int(self.params[i, L.P_ENCODER])]
        if cpr > 0:
            per = COUNTS_PER_REV // cpr
            q = math.floor(self._firmware_angle(np.array([i]))[0] * COUNTS_PER_REV
                           / (2 * math.pi) / per) * per
            self.state[i, L.S_ENC_OFFSET] = value - q
            self.state[i, L.S_ENC_PREV] = value
        self.regs[i, R.ENCODER_POS] = value

    def _preset_h3(self, i: int, value: int) -> None:
        """User command 316 (§8.2.22, §5.8.4): the H3 encoder's position := ``value``:
        ABSENCODER and ENCODER_POS read it at once, P_IST and P_SOLL stay. The encoder keeps
        the preset over commands 267 and 268 (its own memory); ``reset`` starts the motor
        anew with its type's parameters and clears it."""
        cpr = c.ENCODER_CPR[c.ENCODER_H3]
        per = COUNTS_PER_REV // cpr
        q = math.floor(self._firmware_angle(np.array([i]))[0] * COUNTS_PER_REV
                       / (2 * math.pi) / per) * per
        self.params[i, L.P_H3_PRESET] = value - q
        self.regs[i, R.ABSENCODER] = value
        self._set_encoder(i, value)

    def _commands(self, idx: np.ndarray, raw: np.ndarray) -> None:
        """FastMac commands (§8.2.21) and the user commands 257, 267–269, 342, 354, 398, 399
        (§8.2.22; reset and save only in passive or safe mode, which "allows the save in flash
        and reset commands", §8.2.3; 342 erases the stored program,
        :meth:`~.program.api.ProgramMixin.erase_program`), the SSI commands 320–322
        (:mod:`.ssi_port`), 999 and the protected commands, the RelativeMove flag and the
        K-phase flash (:mod:`.user_commands`); other numbers do nothing. COMMAND reads 0
        afterwards."""
        regs = self.regs
        for i, cmd in zip(idx.tolist(), raw.tolist()):
            if cmd in c.CMD_PASSIVE_ONLY and regs[i, R.MODE_REG] not in (c.PASSIVE, c.SAFE):
                raise RegisterError(f"COMMAND = {cmd} refused for motor {i}: reset and save "
                                    "need passive or safe mode (§8.2.3). Nothing was changed.")
        for i, cmd in zip(idx.tolist(), raw.tolist()):
            if self._user_command(i, cmd):
                pass  # 999, the protected commands, RelativeMove, K-phase (.user_commands)
            elif cmd in SSI_COMMANDS:
                self._ssi_command(i, cmd)
            elif cmd == c.CMD_CLEAR_ERRORS:
                self._store_err_bits(np.array([i]), np.array([0]))
                regs[i, R.WARN_BITS] = 0
            elif cmd == c.CMD_P_SOLL_ZERO:
                self._store_p_soll(np.array([i]), np.array([0]))
            elif cmd == c.CMD_P_IST_ZERO:
                regs[i, R.P_IST] = 0
                self.state[i, L.S_FRAC] = 0.0
            elif cmd == c.CMD_V_SOLL_ZERO:
                regs[i, R.V_SOLL] = 0
            elif cmd == c.CMD_CLEAR_FLAGS:
                regs[i, R.STATUSBITS] &= ~(c.ST_IN_POSITION | c.ST_ACCELERATING
                                           | c.ST_DECELERATING)
            elif cmd in c.CMD_REGISTER_SET:
                k = c.CMD_REGISTER_SET.index(cmd)
                pn = TABLE.lookup(f"P{k + 1}").number
                self._store_p_soll(np.array([i]), np.array([regs[i, pn]]))
                # Vn holds any 32-bit value (§12.5's example writes V1 = 409 600); V_SOLL takes
                # it within its own range (§8.2.5)
                v_soll = TABLE.lookup("V_SOLL")
                regs[i, R.V_SOLL] = min(max(int(regs[i, TABLE.lookup(f"V{k + 1}").number]),
                                            int(v_soll.minimum)), int(v_soll.maximum))
                regs[i, R.A_SOLL] = regs[i, TABLE.lookup(f"A{k + 1}").number]
                regs[i, R.RUN_CURRENT] = regs[i, TABLE.lookup(f"T{k + 1}").number]
            elif cmd in c.CMD_RELATIVE:
                pn = TABLE.lookup(f"P{7 + c.CMD_RELATIVE.index(cmd)}").number
                self._store_p_soll(np.array([i]),
                                   np.array([wrap32(int(regs[i, R.P_IST] + regs[i, pn]))]))
            elif cmd in (c.CMD_SET_POSITION, c.CMD_ADD_POSITION, c.CMD_ADD_ACTUAL,
                         c.CMD_PRESET_POSITION):
                # 354 presets "encoder …, P_IST and P_SOLL with P_NEW" as FastMac 119 does;
                # the follow error is 0 with the encoder set to P_IST (§8.2.22)
                new = int(regs[i, R.P_NEW])
                add = cmd in (c.CMD_ADD_POSITION, c.CMD_ADD_ACTUAL)
                regs[i, R.P_IST] = wrap32(int(regs[i, R.P_IST]) * add + new)
                if cmd != c.CMD_ADD_ACTUAL:
                    regs[i, R.P_SOLL] = wrap32(int(regs[i, R.P_SOLL]) * add + new)
                self._set_encoder(i, wrap32(int(regs[i, R.ENCODER_POS]) * add + new))
                if cmd == c.CMD_PRESET_POSITION:
                    # "Reset the position (special command 354 …)" clears the H3/H4's lost
                    # position and reed errors (§7.2.11, §7.2.12)
                    self._store_err_bits(np.array([i]), np.array(
                        [int(regs[i, R.ERR_BITS]) & ~c.ERR_CLEARED_BY_PRESET & ~c.ERR_GENERAL]))
            elif cmd == c.CMD_PRESET_H3 and self.params[i, L.P_ENCODER] == c.ENCODER_H3:
                self._preset_h3(i, int(regs[i, R.P_NEW]))
            elif cmd == c.CMD_RESYNC and self.params[i, L.P_ENCODER] > 0:
                regs[i, R.P_IST] = regs[i, R.ENCODER_POS]
                self.state[i, L.S_FRAC] = 0.0
            elif cmd in (c.CMD_SAVE, c.CMD_SAVE_RESET):
                self._save_flash(np.array([i]))
            elif cmd == c.CMD_ERASE_PROGRAM:
                self.erase_program(i)
            elif cmd == c.CMD_EMERGENCY_STOP and regs[i, R.MODE_REG] not in (c.PASSIVE,
                                                                              c.SAFE):
                self.state[i, L.S_EMERGENCY] = 1.0
            elif cmd == c.CMD_EMERGENCY_HALT:
                regs[i, R.MODE_REG] = c.PASSIVE
                self.state[i, L.S_VEL] = 0.0
            regs[i, R.COMMAND] = 0
            if cmd in (c.CMD_RESET, c.CMD_SAVE_RESET):
                self.software_reset(np.array([i]))

    # ------------------------------------------------------------------ sample buffer
    def _sample_counts(self) -> np.ndarray:
        """Samples taken by each motor (§8.2.60–63), (N,)."""
        return self.state[:, L.S_REC_N]

    # ------------------------------------------------------------------ world inputs
    def set_input(self, index: MotorIndex = None, **inputs: InputValue) -> None:
        """Set world inputs, held from the next outer sample on (per motor).

        Keywords: ``load_torque`` [N·m, opposing positive rotation], ``supply_volts`` [V,
        0 … 150; above 100 V the over-voltage error, §7.2.8], ``pulse_counts`` (whole
        gear-input counts per outer sample), ``digital_inputs`` (IO1–IO8 levels as bits 0–7,
        0 … 255), ``analog1`` … ``analog8`` [V] (the ADC reads 0 … 5 V, §2.3.5), ``ssi_word``
        (the word the SSI encoder sends, 0 … 2³¹ − 1, Gray or binary as it codes it; read by
        commands 321/322, §5.7), ``control_volts`` [V, 0 … 48] (the CVI terminal, nominal 24 V,
        §8.2.79–82), ``ambient_celsius`` [°C, −40 … 150, at rest 25], ``sto_a``, ``sto_b``
        [V, 0 … 48] (the Safe Torque Off channels, nominal 24 V, off below 18 V, §7.2.18),
        ``faults`` (injected hardware faults as ERR_BITS bits: 2 output driver, 7 internal, 8–10
        H3/H4 encoder lost position / reed / COM, 12 closed loop (H2/H4), 13 external memory,
        14 H2/H4 single turn, 15 H4, 18 driver overload (SMC85, MIS34x, MIS43x), 27 STO alarm;
        an encoder fault needs its encoder option). All are checked before any is set
        (``firmware.supervision`` describes their effects).
        """
        if inputs.get("faults") is not None:
            self._check_faults(as_index(index, self.n), inputs["faults"])
        super().set_input(index, **inputs)

    def _check_faults(self, idx: np.ndarray, value: InputValue) -> None:
        """Refuse fault bits that are not injectable or that the motor's hardware lacks."""
        ((_, bits),) = staged_inputs({"faults": value}, {"faults": 0}, self.INPUT_RULES,
                                     idx.size)
        for i, word in zip(idx.tolist(), bits.astype(np.int64).tolist()):
            if word & ~c.FAULT_BITS:
                raise ValueError(f"faults: bits {word & ~c.FAULT_BITS:#x} of motor {i} are no "
                                 f"injectable fault (allowed {c.FAULT_BITS:#x}, ERR_BITS bits)")
            code = int(self.params[i, L.P_ENCODER])
            for bit, codes in c.FAULT_ENCODERS.items():
                if word & bit and code not in codes:
                    raise ValueError(f"faults: bit {bit.bit_length() - 1} needs encoder option "
                                     f"{sorted(codes)} (ENCODER_TYPE, §8.2.49); motor {i} has "
                                     f"{code}")
            if word & c.ERR_DRIVER_OVERLOAD and not self.params[i, L.P_OVERLOAD]:
                raise ValueError(f"faults: bit 18 (driver overload) exists on SMC85, MIS34x and "
                                 f"MIS43x only (§8.2.31); motor {i} is a "
                                 f"{self._configs[self._type_of[i]].name}")

    # ------------------------------------------------------------------ physical truth
    @property
    def rotor_counts(self) -> np.ndarray:
        """Rotor angle from power-on in motor counts (409 600 per revolution), (N,)."""
        return self.state[:, L.S_THETA] * COUNTS_PER_REV / (2.0 * math.pi)

    @property
    def lost_steps(self) -> np.ndarray:
        """Full steps the rotor has lost against the commanded position (positive: behind),
        whole electrical turns of 4 full steps, (N,) int64: the lag rounded half up, in the
        arithmetic of the compiled step's ``lost_steps`` (:mod:`.task`), so that the count an
        env reports is the one its termination saw."""
        lag = (self.state[:, L.S_CMD] - self.state[:, L.S_THETA] * COUNTS_PER_RAD) / (
            c.COUNTS_PER_ELECTRICAL_TURN)
        return 4 * np.floor(lag + 0.5).astype(np.int64)

    @property
    def current_amplitude(self) -> np.ndarray:
        """Phase current amplitude [A], (N,)."""
        return np.hypot(self.state[:, L.S_ID], self.state[:, L.S_IQ])

    @property
    def torque(self) -> np.ndarray:
        """Electromagnetic torque at the end of the last inner sample [N·m], (N,)."""
        lag = (self.rotor_counts - self.state[:, L.S_CMD]) * (
            2 * math.pi / c.COUNTS_PER_ELECTRICAL_TURN)
        return self.params[:, L.P_KT] * (self.state[:, L.S_IQ] * np.cos(lag)
                                         - self.state[:, L.S_ID] * np.sin(lag))

    @property
    def energy(self) -> dict[str, np.ndarray]:
        """Energy since power-on [J], (N,) each: copper loss and work against the load."""
        return {"copper": self.state[:, L.S_E_COPPER].copy(),
                "load": self.state[:, L.S_E_LOAD].copy()}


    def pull_out_torque(self, rpm: float) -> np.ndarray:
        """Steady-state pull-out torque [N·m] of each motor at ``rpm`` with its RUN_CURRENT
        and supply (:func:`.torque_curve.pull_out_torque`), (N,)."""
        p, u = self.params, self.inputs
        amps = np.sqrt(2.0) * np.minimum(self.regs[:, R.RUN_CURRENT], p[:, L.P_RUN_MAX]) * p[
            :, L.P_AMPS_PER_UNIT]
        return np.array([pull_out_torque(rpm, amps[i], p[i, L.P_KT], p[i, L.P_R], p[i, L.P_L],
                                         u[i, L.I_SUPPLY_VOLTS]) for i in range(self.n)])
