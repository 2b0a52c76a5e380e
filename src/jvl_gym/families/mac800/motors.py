"""The MAC800 motor array: the family's rules on top of the generic :class:`MotorArray`.

ROM images from the register table and the type's setup, motor parameters from the motor
configs (:mod:`.config`), power-on (START_MODE, HOME_MODE), the write rules (MODE_REG requests,
the register-set selectors P/V/A/T/L/Z_REG_P, the main filter's validity), the sample buffer,
the world inputs and the physical truth of the plant (MAC800 register overview §1.2).
"""

from __future__ import annotations

import math
from typing import Any, ClassVar

import numpy as np

from ...motor.arguments import InputValue, MotorIndex
from ...motor.array import ModeError, MotorArray
from ...motor.bank import StorePlan
from ...motor.inputs import InputRule
from ...motor.keywords import BINARY, FINITE, NONNEGATIVE
from ...registers import Register, RegisterRangeError
from ..servo_data import servo_parameters
from . import constants as c
from . import layout as L
from .config import Mac800Config, load_motor, setup_path
from .firmware import regs as R
from .firmware.main_filter import filter_valid
from .firmware.modes import enter_mode, start_mode
from .firmware.monitor import filter_gain
from .kernel import derive_constants
from .plant.encoder import encoder_count, turn
from .table import CONFORMANCE, TABLE

__all__ = ["Mac800MotorArray"]

#: a world input: a real number (every selected motor) or one per selected motor, or None

_PARAMETERS: dict[str, int] = {
    "load_inertia": L.P_J_LOAD,  # kg·m²
    "viscous_friction": L.P_VISCOUS,  # N·m·s/rad
    "coulomb_friction": L.P_COULOMB,  # N·m
    "pwm_delay_samples": L.P_PWM_DELAY,  # 0 or 1
    "end_stop_low": L.P_STOP_LO,  # rad
    "end_stop_high": L.P_STOP_HI,  # rad
    "end_stop_stiffness": L.P_STOP_K,  # N·m/rad
    "end_stop_damping": L.P_STOP_D,  # N·m·s/rad
    "home_position": L.P_HOME_POS,  # rad (inf: no sensor)
    "index_angle": L.P_INDEX_POS,  # rad
    "position_noise": L.P_POSITION_NOISE,  # encoder counts (std)
}
_STATES: dict[str, int] = {
    "initial_angle": L.S_THETA,  # rad
    "initial_speed": L.S_OMEGA,  # rad/s
    "initial_temperature": L.S_TEMP,  # °C
}
_NONNEGATIVE = {"load_inertia", "viscous_friction", "coulomb_friction", "end_stop_stiffness",
                "end_stop_damping", "position_noise"}
#: the register-set selectors (register → first register of its set, step between them,
#: the register they set), overview §1.2 "Registers (P0-7, V0-7 etc.)"
_SELECTORS: dict[int, tuple[int, int, str]] = {
    TABLE.lookup("P_REG_P").number: (TABLE.lookup("POS0").number, 2, "P_SOLL"),
    TABLE.lookup("V_REG_P").number: (TABLE.lookup("VEL0").number, 1, "V_SOLL"),
    TABLE.lookup("A_REG_P").number: (TABLE.lookup("ACC0").number, 1, "A_SOLL"),
    TABLE.lookup("T_REG_P").number: (TABLE.lookup("TQ0").number, 1, "T_SOLL"),
    TABLE.lookup("L_REG_P").number: (TABLE.lookup("LOAD0").number, 1, "KVOUT"),
    TABLE.lookup("Z_REG_P").number: (TABLE.lookup("ZERO0").number, 1, "INPOSWIN"),
}
#: the registers of the main filter's validity (KVFY5 … KVFY0, S_ORDER)
_FILTER = frozenset(range(R.KVFY5, R.KVFY5 + 6)) | {R.S_ORDER}


def _aliases() -> dict[str, Register]:
    """MacTalk names (the table's ``alias`` column) that name exactly one register (not the
    MacTalk places printed in parentheses, such as "(Error monitor)")."""
    seen: dict[str, list[Register]] = {}
    for reg in TABLE:
        if reg.alias and not reg.alias.startswith("("):
            seen.setdefault(reg.alias.strip().upper(), []).append(reg)
    return {k: v[0] for k, v in seen.items() if len(v) == 1 and k not in TABLE}


_ALIASES = _aliases()


class Mac800MotorArray(MotorArray, layout=L):
    """N simulated MAC800-family motors (:class:`~jvl_gym.MotorArray` of the ``mac800``
    family).

    Parameters
    ----------
    motor, n, seed, setup
        As for :class:`~jvl_gym.MotorArray` (motor types: ``MAC800``, ``MAC400``).
    **params
        Per-motor parameters (scalars or (N,) arrays): :attr:`PARAMETER_KEYWORDS` (SI units)
        and ``initial_angle`` [rad], ``initial_speed`` [rad/s], ``initial_temperature`` [°C].

    Examples
    --------
    >>> m = MotorArray("MAC800", n=2, seed=0)
    >>> m.write_many({"V_SOLL": 277, "MODE_REG": 1}); m.run(seconds=0.5)
    >>> m.speed_rpm  # ≈ 100 RPM
    """

    FAMILY_KEY = "mac800"
    TABLE = TABLE
    CONFORMANCE = CONFORMANCE
    BUFFER_SHAPE = (c.REC_CNT_MAX, 4)
    OUTER_HZ = c.OUTER_HZ
    PARAMETER_KEYWORDS: ClassVar[dict[str, int]] = _PARAMETERS
    STATE_KEYWORDS: ClassVar[dict[str, int]] = _STATES
    VALUE_RULES: ClassVar[dict[str, int]] = {
        name: ((FINITE if name != "home_position" else 0)
               | (NONNEGATIVE if name in _NONNEGATIVE else 0)
               | (BINARY if name == "pwm_delay_samples" else 0))
        for name in [*_PARAMETERS, *_STATES]}
    INPUTS: ClassVar[dict[str, int]] = {
        "load_torque": L.I_LOAD_TORQUE, "analog_volts": L.I_ANALOG_VOLTS,
        "pulse_counts": L.I_PULSE_COUNTS, "home": L.I_HOME, "supply_volts": L.I_SUPPLY_VOLTS,
        "control_volts": L.I_CONTROL_VOLTS, "encoder_fault": L.I_ENCODER_FAULT}
    INPUT_RULES: ClassVar[dict[str, InputRule]] = {
        "pulse_counts": InputRule(-2.0**31, 2.0**31 - 1, whole=True,
                                  unit="counts per servo sample"),
        "home": InputRule(0.0, 1.0, allow_bool=True),
        "supply_volts": InputRule(0.0, 600.0, unit="V"),
        "control_volts": InputRule(0.0, 40.0, unit="V"),
        "encoder_fault": InputRule(0.0, 1.0, allow_bool=True)}
    PHYSICAL = frozenset({"speed_rpm", "speed_rad_s", "position_rad", "torque", "bus_voltage",
                          "temperature"})
    SHAFT_ANGLE, SHAFT_SPEED = L.S_THETA, L.S_OMEGA
    ONE_BY_ONE = frozenset(_SELECTORS) | {R.CNTRL_BITS}

    @staticmethod
    def load_motor(motor: Any) -> Mac800Config:
        """The validated motor config (:func:`jvl_gym.families.mac800.config.load_motor`)."""
        return load_motor(motor)

    def _lookup(self, key: Any) -> Register:
        """A register by name, number or unique MacTalk name (the overview's last column)."""
        if isinstance(key, str) and key.strip().upper() in _ALIASES:
            return _ALIASES[key.strip().upper()]
        return super()._lookup(key)

    # ------------------------------------------------------------------ configuration
    def _rom_image(self, cfg: Mac800Config, setup: Any) -> np.ndarray:
        """Table defaults with the type's setup (validated as :meth:`load_setup` does)."""
        image = self._setup_rom_image(setup if setup is not None else setup_path(cfg.setup),
                                      self._rom_store)
        image[R.MOTOR_TYPE] = cfg.motor_type_code
        return image

    def _rom_store(self, image: np.ndarray, reg: Register, value: Any, raw: np.ndarray
                   ) -> None:
        """Store a setup's validated ``raw`` in the ROM ``image``: START_MODE checked, a
        register-set selector copies the selected set's value to the register it sets."""
        if reg.number == R.START_MODE:
            self._check_start_modes(raw)
        if reg.number in _SELECTORS:
            start, step, target = _SELECTORS[reg.number]
            k = int(raw[0])
            if k > 0:
                image[self._lookup(target).number] = image[start + step * (k - 1)]
        image[reg.number] = raw[0]

    def _config_params(self, cfg: Mac800Config) -> np.ndarray:
        p = servo_parameters(L, cfg, stop_stiffness=500.0, stop_damping=0.5)
        p[L.P_I2T_SCALE] = c.PERCENT_100 / cfg.rated_current**2
        p[L.P_K_I2T] = filter_gain(cfg.thermal_time_constant)
        p[L.P_UIT_SCALE] = c.PERCENT_100 / cfg.regen_power
        p[L.P_K_UIT] = filter_gain(cfg.regen_time_constant)
        p[L.P_R_TH] = cfg.thermal_resistance
        p[L.P_K_TEMP] = filter_gain(cfg.winding_time_constant)
        return p

    def _rest_inputs(self, cfg: Mac800Config) -> np.ndarray:
        """Inputs at rest: mains and the 24 V control supply on, home sensor from the shaft."""
        u = np.zeros(L.N_INPUT)
        u[L.I_SUPPLY_VOLTS] = cfg.supply_voltage
        u[L.I_CONTROL_VOLTS] = 24.0
        u[L.I_HOME] = -1.0
        return u

    # ------------------------------------------------------------------ power-on
    def _initial_state(self, row: np.ndarray) -> None:
        """The winding at the ambient temperature."""
        row[L.S_TEMP] = c.AMBIENT_CELSIUS

    def _power_on(self, idx: np.ndarray) -> None:
        """Firmware start of motors ``idx``: counters from the shaft, bus charged, START_MODE."""
        for i in idx.tolist():
            s, p = self.state[i], self.params[i]
            derive_constants(p)
            s[L.S_UBUS] = self.inputs[i, L.I_SUPPLY_VOLTS]
            s[L.S_ENC_PREV] = encoder_count(s[L.S_THETA])
            s[L.S_ELDEG_PREV] = s[L.S_ENC_PREV]
            s[L.S_INDEX_TURN] = turn(s[L.S_THETA], p[L.P_INDEX_POS])
            s[L.S_INDEX_COUNT] = math.nan
            s[L.S_HOME_AFTER] = -1.0
            s[L.S_A2P_LEVEL] = -1.0
            s[L.S_PARAMS_NEW] = 1.0
            self._check_filter(np.array([i]))
            self.regs[i, R.U_BUS] = round(s[L.S_UBUS] / c.U_BUS_VOLTS)
            self.regs[i, R.U_24V] = round(self.inputs[i, L.I_CONTROL_VOLTS] / c.U_24V_VOLTS)
            self.regs[i, R.DEGC] = round(s[L.S_TEMP] / c.DEGC_CELSIUS)
            start_mode(self.regs[i], s)

    def _check_filter(self, idx: np.ndarray) -> None:
        """S_FILT_BAD of motors ``idx`` from their main filter (OLD_FILT_ERR's condition)."""
        for i in idx.tolist():
            ok = filter_valid(self.regs[i, R.KVFY5:R.KVFY5 + 6], int(self.regs[i, R.S_ORDER]))
            self.state[i, L.S_FILT_BAD] = 0.0 if ok else 1.0

    @property
    def time(self) -> np.ndarray:
        """Time since power-on of each motor [s], (N,)."""
        return self.state[:, L.S_TICK] * c.INNER_DT

    # ------------------------------------------------------------------ writes
    def _store_rows(self, plan: StorePlan, idx: np.ndarray, raws: np.ndarray) -> None:
        """Store ``raws`` register by register in motors ``idx``: MODE_REG through the mode
        rules, P_FUNC into the function position, the main filter's validity re-checked."""
        for k, num in enumerate(plan.nums.tolist()):
            if num == R.MODE_REG:
                self._request_modes(idx, raws[k])
                continue
            if num == R.START_MODE:
                self._check_start_modes(raws[k])
            self.regs[idx, num] = raws[k]
            if num == R.P_FUNC:
                self.state[idx, L.S_PF16] = 16.0 * raws[k]
        if not _FILTER.isdisjoint(plan.nums.tolist()):
            self._check_filter(idx)

    @staticmethod
    def _check_start_modes(raw: np.ndarray) -> None:
        """START_MODE (register 37) takes the modes MODE_REG takes (a MODE_REG value, overview
        §1.2): a reserved mode or one the simulator does not run is refused, not left to power
        up passive."""
        for mode in raw.tolist():
            if mode not in c.RUNNABLE_MODES:
                what = c.MODE_NAMES.get(mode)
                why = "not modelled by the simulator" if what else "reserved (overview §1.2)"
                raise RegisterRangeError(
                    f"START_MODE = {mode} ({what or 'reserved'}) refused: {why}; allowed: "
                    f"{sorted(c.RUNNABLE_MODES)}. Nothing was changed.")

    def _request_modes(self, idx: np.ndarray, req: np.ndarray) -> None:
        """MODE_REG requests: a mode the simulator runs, and no blocking error set."""
        for i, mode in zip(idx.tolist(), req.tolist()):
            if mode not in c.RUNNABLE_MODES:
                what = c.MODE_NAMES.get(mode)
                why = "not modelled by the simulator" if what else "reserved (overview §1.2)"
                raise ModeError(f"MODE_REG = {mode} ({what or 'reserved'}) refused for motor "
                                f"{i}: {why}; runnable: {sorted(c.RUNNABLE_MODES)}. Nothing was "
                                "changed.")
            errors = int(self.regs[i, R.ERR_STAT]) & c.BLOCKING_ERRORS
            if mode != c.PASSIVE_MODE and errors:
                names = ", ".join(n for b, n in c.ERROR_NAMES.items() if errors & b)
                raise ModeError(f"MODE_REG = {mode} refused for motor {i}: error bits set in "
                                f"ERR_STAT ({names}); clear them first. Nothing was changed.")
        for i, mode in zip(idx.tolist(), req.tolist()):
            enter_mode(self.regs[i], self.state[i], int(mode))

    def _store_special(self, reg: Any, idx: np.ndarray, raw: np.ndarray) -> bool:
        """The register-set selectors (copy the k-th register of the set, k = 1 …; with
        CNTRL_BITS RELPOSPSOLL a position is added to P_SOLL, with RELPOSPFNC to the function
        position) and the sample buffer allocated when recording starts."""
        num = reg.number
        if num in _SELECTORS:
            start, step, target = _SELECTORS[num]
            tnum = self._lookup(target).number
            for i, k in zip(idx.tolist(), raw.tolist()):
                if k > 0:
                    value = int(self.regs[i, start + step * (k - 1)])
                    if target == "P_SOLL":
                        cb = int(self.regs[i, R.CNTRL_BITS])
                        if cb & c.RELPOSPFNC:
                            value += round(self.state[i, L.S_PF16] / 16.0)
                        elif cb & c.RELPOSPSOLL:
                            value += int(self.regs[i, R.P_SOLL])
                        value = ((value + 2**31) % 2**32) - 2**31
                    self.regs[i, tnum] = value
                self.regs[i, num] = k
            return True
        if num == R.CNTRL_BITS and np.any(raw & c.RECORDBIT):
            self._ensure_buffer()
        return False

    # ------------------------------------------------------------------ world inputs
    def set_input(self, index: MotorIndex = None, *, load_torque: InputValue = None,
                  analog_volts: InputValue = None, pulse_counts: InputValue = None,
                  home: InputValue = None, supply_volts: InputValue = None,
                  control_volts: InputValue = None, encoder_fault: InputValue = None) -> None:
        """Set world inputs, held from the next servo sample on (per motor).

        Parameters
        ----------
        load_torque : float or array
            External load torque opposing positive rotation [N·m].
        analog_volts : float or array
            Analogue input [V], limited by the converter to ±10 V.
        pulse_counts : int or array
            External pulse input counts per servo sample (V_EXT).
        home : bool or array
            Zero-search sensor level (overrides ``home_position``).
        supply_volts : float or array
            DC source of the power bus (rectified mains) [V], 0 … 600.
        control_volts : float or array
            24 V control supply [V], 0 … 40.
        encoder_fault : bool or array
            The encoder loses every second count while set.
        """
        super().set_input(index, load_torque=load_torque, analog_volts=analog_volts,
                          pulse_counts=pulse_counts, home=home, supply_volts=supply_volts,
                          control_volts=control_volts, encoder_fault=encoder_fault)

    # ------------------------------------------------------------------ physical truth
    @property
    def bus_voltage(self) -> np.ndarray:
        """DC bus voltage [V], (N,)."""
        return self.state[:, L.S_UBUS].copy()

    @property
    def temperature(self) -> np.ndarray:
        """Winding temperature of the motor model [°C], (N,)."""
        return self.state[:, L.S_TEMP].copy()

    @property
    def torque(self) -> np.ndarray:
        """Electromagnetic torque now [N·m], (N,): ``1.5·p·λ·Re(i·e^{−jθe})``."""
        i = self.state[:, L.S_I_RE] + 1j * self.state[:, L.S_I_IM]
        pp = self.params[:, L.P_POLE_PAIRS]
        return 1.5 * pp * self.params[:, L.P_LAMBDA] * np.real(
            i * np.exp(-1j * pp * self.state[:, L.S_THETA]))

    @property
    def energy(self) -> dict[str, np.ndarray]:
        """Energy accounts since power-on [J], (N,) each, and the kinetic energy now."""
        s = self.state
        j = self.params[:, L.P_J_MOTOR] + self.params[:, L.P_J_LOAD]
        return {"electrical": s[:, L.S_E_ELEC].copy(), "copper": s[:, L.S_E_COPPER].copy(),
                "friction": s[:, L.S_E_FRICTION].copy(), "load": s[:, L.S_E_LOAD].copy(),
                "dump": s[:, L.S_E_DUMP].copy(), "supply": s[:, L.S_E_SUPPLY].copy(),
                "kinetic": 0.5 * j * s[:, L.S_OMEGA] ** 2}
