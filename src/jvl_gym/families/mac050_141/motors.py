"""The MAC050–141 motor array: the family's rules on top of the generic :class:`MotorArray`.

ROM images from the register table and the type's setup (manual 3, "Parameter and Data
Description"), motor parameters from the motor configs (docs/model.md §15), power-on
(3.2.37), the firmware's write and mode-change rules (4.4, ``firmware/write_rules.py``,
``firmware/modes.py``), SAFE_MODE and flash (4.4.16, 5.1), the test modes' sample buffer
(3.2.112–116), the world inputs and the physical truth of the plant.
"""

from __future__ import annotations

import os
from typing import Any, ClassVar

import numpy as np

from ...motor.arguments import InputValue, MotorIndex, MotorSpec, Seed, as_index
from ...motor.array import ModeError, MotorArray
from ...motor.bank import StorePlan
from ...motor.inputs import InputRule, staged_inputs
from ...motor.keywords import BINARY, FINITE, NONNEGATIVE, POSITIVE
from ...physics.mechanics import coupling_problem
from ...registers import Format, Register, RegisterError
from ..servo_data import servo_parameters
from . import constants as c
from . import layout as L
from .config import SETUPS_DIR, MotorConfig, load_motor
from .firmware import modes as M
from .firmware import regs as R
from .firmware import write_rules as W
from .firmware.monitor import filter_gain
from .power_on import power_on_from_memory, reset_rows, start_loaded_rows
from .store import store_rows
from .table import CONFORMANCE, TABLE

__all__ = ["MacMotorArray"]

#: a world input: a real number (every selected motor) or one per selected motor, or None

#: per-motor parameter keywords of the constructor and :meth:`MacMotorArray.reset` (SI units)
_PARAMETERS: dict[str, int] = {
    "load_inertia": L.P_J_LOAD,  # kg·m²
    "viscous_friction": L.P_VISCOUS,  # N·m·s/rad
    "coulomb_friction": L.P_COULOMB,  # N·m
    "current_noise": L.P_CURRENT_NOISE,  # ADC counts (std)
    "position_noise": L.P_POSITION_NOISE,  # encoder counts (std)
    "torque_noise": L.P_TORQUE_NOISE,  # N·m (std per inner sample)
    "pwm_delay_samples": L.P_PWM_DELAY,  # 0 or 1
    "end_stop_low": L.P_STOP_LO,  # rad
    "end_stop_high": L.P_STOP_HI,  # rad
    "end_stop_stiffness": L.P_STOP_K,  # N·m/rad
    "end_stop_damping": L.P_STOP_D,  # N·m·s/rad
    "home_position": L.P_HOME_POS,  # rad
    "hall_start": L.P_HALL_START,  # 0: commutation aligned at power-on, 1: hall sector estimate
    "hall_angle": L.P_HALL_ANGLE,  # electrical angle of the hall zero transition [rad]
    "phase_resistance": L.P_R,  # Ω (overrides the motor config)
    "phase_inductance": L.P_L,  # H
    "rotor_inertia": L.P_J_MOTOR,  # kg·m²
    "flux_linkage": L.P_LAMBDA,  # V·s
    "coupling_stiffness": L.P_K_COUPLING,  # N·m/rad; 0: rigid load, > 0: load behind a coupling
    "coupling_damping": L.P_D_COUPLING,  # N·m·s/rad
}
_NONNEGATIVE = {"load_inertia", "viscous_friction", "coulomb_friction", "current_noise",
                "position_noise", "torque_noise", "end_stop_stiffness", "end_stop_damping",
                "coupling_stiffness", "coupling_damping"}
_POSITIVE = {"phase_resistance", "phase_inductance", "rotor_inertia", "flux_linkage"}
_BINARY = {"pwm_delay_samples", "hall_start"}
#: per-motor initial state keywords of the constructor and :meth:`MacMotorArray.reset`
_STATES: dict[str, int] = {
    "initial_angle": L.S_THETA,  # rad
    "initial_speed": L.S_OMEGA,  # rad/s
}
#: modes that record into the sample buffer (allocated on first use)
_RECORDING_MODES = frozenset({c.TESTU_MODE, c.TESTA_MODE, c.TESTKI_MODE, c.TESTTQ_MODE})


class MacMotorArray(MotorArray, layout=L):
    """N simulated MAC50–141 motors (:class:`~jvl_gym.MotorArray` of the MAC050–141 family).

    Parameters
    ----------
    motor, n, seed, setup
        As for :class:`~jvl_gym.MotorArray`.
    record_length : int
        Samples recorded by TESTU / TESTA (manual: 11), up to 895.
    **params
        Per-motor parameters (scalars or (N,) arrays), see :attr:`PARAMETER_KEYWORDS`, plus
        ``initial_angle`` [rad] and ``initial_speed`` [rad/s].
    """

    FAMILY_KEY = "mac050_141"
    TABLE = TABLE
    CONFORMANCE = CONFORMANCE
    BUFFER_SHAPE = (c.REC_CNT_MAX, 4)
    OUTER_HZ = c.OUTER_HZ
    SETUPS_DIR = SETUPS_DIR
    PARAMETER_KEYWORDS: ClassVar[dict[str, int]] = _PARAMETERS
    STATE_KEYWORDS: ClassVar[dict[str, int]] = _STATES
    #: finite but for the home position (inf: none), then >= 0, > 0 or 0/1
    VALUE_RULES: ClassVar[dict[str, int]] = {
        name: ((FINITE if name != "home_position" else 0)
               | (NONNEGATIVE if name in _NONNEGATIVE else 0)
               | (POSITIVE if name in _POSITIVE else 0) | (BINARY if name in _BINARY else 0))
        for name in [*_PARAMETERS, *_STATES]
    }
    INPUTS: ClassVar[dict[str, int]] = {
        "load_torque": L.I_LOAD_TORQUE, "analog_volts": L.I_ANALOG_VOLTS,
        "pulse_counts": L.I_PULSE_COUNTS, "home": L.I_HOME, "supply_volts": L.I_SUPPLY_VOLTS}
    INPUT_RULES: ClassVar[dict[str, InputRule]] = {
        "pulse_counts": InputRule(whole=True, unit="counts per outer sample"),
        "home": InputRule(allow_bool=True),
        "supply_volts": InputRule(0.0, 60.0, unit="V")}
    PHYSICAL = frozenset({"speed_rpm", "speed_rad_s", "position_rad", "torque", "bus_voltage",
                          "load_angle", "load_speed", "phase_currents"})
    SHAFT_ANGLE, SHAFT_SPEED = L.S_THETA, L.S_OMEGA
    ONE_BY_ONE = frozenset(W.POINTERS) | {R.CNTRL_BITS}
    #: the control bits latched at power-on change when a SAFE_MODE request resets a motor
    TRANSACTION_ARRAYS = (*MotorArray.TRANSACTION_ARRAYS, "_latched_cntrl")
    #: the compiled store (:meth:`_store_rows`) changes register and state rows only
    ROWS_STORE_ARRAYS = ("regs", "state")

    def __init__(self, motor: MotorSpec = "MAC140", n: int = 1, seed: Seed = None,
                 setup: str | os.PathLike[str] | dict[str, Any] | None = None,
                 record_length: int = c.TEST_RECORD_SAMPLES,
                 **params: Any) -> None:
        self._record_length = record_length
        super().__init__(motor, n, seed, setup, **params)

    @staticmethod
    def load_motor(motor: Any) -> MotorConfig:
        """The validated motor config (:func:`.config.load_motor`)."""
        return load_motor(motor)

    def _before_reset(self) -> None:
        self._latched_cntrl = np.zeros(self.n, dtype=np.int64)
        self.set_record_length(self._record_length)

    def _reset_rows(self, idx: np.ndarray, cols: np.ndarray, to_state: np.ndarray,
                    values: np.ndarray) -> None:
        """The power-on of :meth:`jvl_gym.MotorArray._reset_rows`, compiled
        (:func:`.power_on.reset_rows`); first refuses, changing nothing, an elastic coupling the
        inner step cannot carry (:meth:`_check_coupling`)."""
        self._check_coupling(idx, cols, to_state, values)
        reset_rows(self.regs, self.state, self.params, self.inputs, self._latched_cntrl, idx,
                   self._type_of[idx], self._rom, self._type_params, self._type_inputs,
                   self._rom if self._flash is None else self._flash, self._has_flash,
                   cols, to_state, values)

    def _check_coupling(self, idx: np.ndarray, cols: np.ndarray, to_state: np.ndarray,
                        values: np.ndarray) -> None:
        """Raise ValueError naming the parameter when a motor's coupling to its load is one the
        inner step cannot integrate (docs/model.md §5.2)."""
        if (L.P_K_COUPLING not in cols.tolist()
                and not self._type_params[:, L.P_K_COUPLING].any()):
            return  # no stiffness given and every type of the pool rigid: rigid shafts pass
        p = self._type_params[self._type_of[idx]]  # (a new array)
        for q, col in enumerate(cols.tolist()):
            if not to_state[q]:
                p[:, col] = values[q]
        coupled = p[:, L.P_K_COUPLING] > 0.0
        if not coupled.any():  # rigid shafts pass
            return
        for j in np.flatnonzero(coupled).tolist():
            row = p[j]
            problem = coupling_problem(row[L.P_J_MOTOR], row[L.P_J_LOAD], row[L.P_K_COUPLING],
                                       row[L.P_D_COUPLING], c.INNER_DT)
            if problem is not None:
                raise ValueError(f"motor {int(idx[j])}: {problem}. Nothing was changed.")

    def _special_request(self, raw: np.ndarray) -> bool:
        """A SAFE_MODE command (256..258) or a test mode that records (allocates the sample
        buffer): stored by :meth:`_request_modes`."""
        return any(r >= 256 or r in _RECORDING_MODES for r in raw.tolist())

    def _store_special(self, reg: Any, idx: np.ndarray, raw: np.ndarray) -> bool:
        """MODE_REG commands and recording modes, register-set pointers (3.2.43–48), and the
        sample buffer allocated when CNTRL_BITS starts recording."""
        num = reg.number
        if num == R.MODE_REG and self._special_request(raw):
            self._request_modes(reg, idx, raw)
            return True
        if num in W.POINTERS:
            self._check_refusal(reg, idx, raw)
            W.apply_pointer(self.regs, idx, num, raw)
            return True
        if num == R.CNTRL_BITS and np.any(raw & c.RECORDBIT):
            self._ensure_buffer()
        return False

    def _rom_image(self, cfg: MotorConfig, setup: Any) -> np.ndarray:
        """ROM defaults of one motor type: the table defaults with the type's setup applied.

        The setup is validated as :meth:`load_setup` validates it (no MODE_REG, no read-only
        register, values in range, the firmware's write rules in the order given); a refusal
        raises the :class:`RegisterError` naming the setup.
        """
        image = self._setup_rom_image(setup if setup is not None else cfg.setup, self._rom_store)
        image[R.MOTOR_TYPE] = cfg.motor_type_code
        return image

    @staticmethod
    def _rom_store(image: np.ndarray, reg: Register, value: Any, raw: np.ndarray) -> None:
        """Store a setup's validated ``raw`` in the ROM ``image`` under the firmware's write
        rules (register-set pointers, a LongInt's high word)."""
        row = image[None]  # a one-motor register bank over ``image``
        first = np.zeros(1, dtype=np.int64)
        problem = W.check_write(row, first, reg.number, raw)
        if problem is not None:
            raise RegisterError(f"{reg.name} (register {reg.number}) = {value!r} refused: "
                                f"{problem}")
        if reg.number in W.POINTERS:
            W.apply_pointer(row, first, reg.number, raw)
        elif reg.format == Format.LONGINT_HIGH:
            full = (int(raw[0]) << 16) | (int(image[reg.number - 1]) & 0xFFFF)
            image[reg.number - 1] = ((full + 2**31) % 2**32) - 2**31
        else:
            image[reg.number] = raw[0]

    def _rest_inputs(self, cfg: MotorConfig) -> np.ndarray:
        """World inputs at rest: supply on, home sensor from the position, nothing else."""
        inputs = np.zeros(L.N_INPUT)
        inputs[L.I_SUPPLY_VOLTS] = cfg.supply_voltage
        inputs[L.I_HOME] = -1.0
        return inputs

    def _config_params(self, cfg: MotorConfig) -> np.ndarray:
        p = servo_parameters(L, cfg, stop_stiffness=50.0, stop_damping=0.05)
        p[L.P_K_THERMAL] = filter_gain(cfg.thermal_time_constant)
        p[L.P_K_REGEN] = filter_gain(cfg.regen_time_constant)
        return p

    def set_record_length(self, n_samples: int, index: MotorIndex = None) -> None:
        """Samples recorded by TESTU/TESTA (manual default 11; up to REC_CNT_MAX = 895)."""
        try:
            whole = (not isinstance(n_samples, (bool, np.bool_, str, bytes))
                     and int(n_samples) == n_samples)
        except (TypeError, ValueError, OverflowError):
            whole = False
        if not whole or not 1 <= n_samples <= c.REC_CNT_MAX:
            raise ValueError(f"record length must be an integer in 1..{c.REC_CNT_MAX}, "
                             f"got {n_samples!r}")
        self.state[as_index(index, self.n), L.S_REC_LEN] = float(n_samples)

    def _power_on(self, idx: np.ndarray) -> None:
        """Registers from flash or ROM, counters cleared, mode from STARTMODE (3.2.37)."""
        power_on_from_memory(self.regs, self.state, self.params, self._latched_cntrl, idx,
                             self._type_of[idx], self._rom,
                             self._rom if self._flash is None else self._flash, self._has_flash)

    @property
    def interface_bits(self) -> np.ndarray:
        """CNTRL_BITS latched at the last power-on (PULSEDIR, INPSIGN, HICLK, USERINTF act
        only after a reset, manual 3.2.36), (N,)."""
        return self._latched_cntrl.copy()

    def pulse_decoding(self) -> tuple[np.ndarray, np.ndarray]:
        """``(pulse_dir, inverted)`` per motor from the CNTRL_BITS PULSEDIR and INPSIGN latched
        at the last power-on (manual 3.2.36), (N,) bool arrays."""
        bits = self._latched_cntrl
        return (bits & c.PULSEDIR) != 0, (bits & c.INPSIGN) != 0

    def start_under_load(self, torque: float | np.ndarray, index: MotorIndex = None) -> None:
        """Let the motors ``index`` start under a standing load of ``torque`` [N·m], as motors
        that already hold it: the load torque input is set (as
        ``set_input(load_torque=torque)``) and the speed regulator's integrating state is set
        to the output that gives this torque (VF_OUT = torque / peak torque · 1023, manual
        3.2.7, through KVOUT, manual 4.2), so that the motor does not first sag and recover.

        Parameters
        ----------
        torque : float or (M,) array
            Load torque per selected motor [N·m], finite.
        index : int, slice, bool mask or int array, optional
            The motors (default all).
        """
        idx = as_index(index, self.n)
        [(_, load)] = staged_inputs({"load_torque": torque}, self.INPUTS, self.INPUT_RULES,
                                    idx.size)  # checked as set_input checks it
        start_loaded_rows(self.regs, self.state, self.inputs, idx, load,
                          self._type_peak[self._type_of[idx]])

    def _add_type(self, cfg: MotorConfig) -> None:
        super()._add_type(cfg)
        #: peak torque of each type of the pool [N·m]
        self._type_peak = np.append(getattr(self, "_type_peak", np.zeros(0)), cfg.peak_torque)

    @property
    def time(self) -> np.ndarray:
        """Time since power-on of each motor [s], (N,)."""
        return self.state[:, L.S_TICK] * c.INNER_DT

    def _store_rows(self, plan: StorePlan, idx: np.ndarray, raws: np.ndarray) -> None:
        """Compiled check and store (:func:`mac050_141.store.store_rows`); a refusal raises with
        the registers before the refused one stored."""
        k = store_rows(self.regs, self.state, idx, plan.nums, plan.high, raws)
        if k >= 0:
            self._check_refusal(plan.regs[k], idx, raws[k])
            raise AssertionError(f"{plan.regs[k].name}: compiled store refused a write the "
                                 "rules accept")  # pragma: no cover - the rules are shared

    def _check_refusal(self, reg: Register, idx: np.ndarray, raw: np.ndarray) -> None:
        """Raise the firmware's refusal of storing ``raw`` in register ``reg`` of motors
        ``idx`` (mode-change rules of manual 4.4 and ``mac050_141.firmware.write_rules``), if any.

        Raises
        ------
        ModeError
            A MODE_REG request the mode rules or the register rules refuse.
        RegisterError
            Another register's write the rules refuse.
        """
        num = reg.number
        if num != R.MODE_REG:
            problem = W.check_write(self.regs, idx, num, raw)
            if problem is not None:
                raise RegisterError(f"{reg.name} (register {reg.number}) = {raw.tolist()[:4]} "
                                    f"refused: {problem}. Nothing was changed.")
            return
        codes = M.check_requests(self.regs, self.state, idx, raw)
        bad = np.flatnonzero(codes != M.OK)
        if bad.size:
            k = bad[0]
            name = c.MODE_NAMES.get(int(raw[k]))
            named = f" ({name})" if name else ""
            cur = c.MODE_NAMES.get(int(self.regs[idx[k], R.MODE_REG]), "?")
            raise ModeError(
                f"MODE_REG = {int(raw[k])}{named} refused for motor {int(idx[k])} in {cur}: "
                f"{M.REQUEST_MESSAGES[int(codes[k])]}. Nothing was changed.")
        problem = W.check_mode_request(self.regs, idx, raw)
        if problem is not None:
            raise ModeError(f"MODE_REG write refused: {problem}. Nothing was changed.")

    def _request_modes(self, reg: Register, idx: np.ndarray, req: np.ndarray) -> None:
        """MODE_REG requests with SAFE_MODE commands (256..258) or test modes that record."""
        self._check_refusal(reg, idx, req)
        special = req >= 256
        if special.any():
            self._safe_special(idx[special], req[special])
            idx, req = idx[~special], req[~special]
        if not _RECORDING_MODES.isdisjoint(req.tolist()):
            self._ensure_buffer()
        M.apply_requests(self.regs, self.state, idx, req)

    def _safe_special(self, idx: np.ndarray, req: np.ndarray) -> None:
        """MODE_REG 256/257/258 in SAFE_MODE (manual 4.4.16)."""
        for i, r in zip(idx, req):
            if r == c.SAFE_LOAD_FLASH:
                if self._flash is not None and self._has_flash[i]:
                    self._load_rw(i, self._flash[i])
                else:
                    self._load_rw(i, self._rom[self._type_of[i]])
            else:
                self._load_rw(i, self._rom[self._type_of[i]])
                if r == c.SAFE_LOAD_DEFAULTS_SAVE:
                    self._save_flash(np.array([i]))
                    self.software_reset(np.array([i]))

    def _indices_in(self, idx: np.ndarray, modes: tuple[int, ...], what: str) -> None:
        bad = idx[~M.member(self.regs[idx, R.MODE_REG], modes)]
        if bad.size:
            names = " or ".join(c.MODE_NAMES[m] for m in modes)
            raise ModeError(f"{what} needs {names} (manual 4.4.16); motor {int(bad[0])} is in "
                            f"{c.MODE_NAMES.get(int(self.regs[bad[0], R.MODE_REG]), '?')}")

    def enter_safe_mode(self, index: MotorIndex = None) -> None:
        """MacTalk 'go safe mode' (5.1): stop if moving, then SAFE_MODE (4.4.16)."""
        M.go_safe(self.regs, self.state, as_index(index, self.n))

    def go_init_mode(self, index: MotorIndex = None) -> None:
        """MacTalk 'go init mode' (5.1): the protective path to INIT_MODE."""
        M.go_init(self.regs, self.state, as_index(index, self.n))

    def exit_safe_mode(self, index: MotorIndex = None) -> None:
        """Leave SAFE_MODE; the motor always goes to INIT_MODE (manual 2.2)."""
        idx = as_index(index, self.n)
        self._indices_in(idx, (c.SAFE_MODE,), "exit_safe_mode")
        M.go_init(self.regs, self.state, idx)

    def _save_flash(self, idx: np.ndarray) -> None:
        """The registers flash holds, and the firmware's PROG_VERSION of the type's ROM."""
        super()._save_flash(idx)
        assert self._flash is not None
        self._flash[idx, R.PROG_VERSION] = self._rom[self._type_of[idx], R.PROG_VERSION]

    def write_flash(self, index: MotorIndex = None) -> None:
        """Save the register set to flash and reset; only in SAFE_MODE (manual 2.2, 5.1)."""
        idx = as_index(index, self.n)
        self._indices_in(idx, (c.SAFE_MODE,), "write_flash")
        self._save_flash(idx)
        self.software_reset(idx)

    def software_reset(self, index: MotorIndex = None) -> None:
        """Reset the electronics (registers from flash/ROM, P_IST = 0); INIT or SAFE only.

        The rotor keeps its physical angle and speed: only the firmware restarts.
        """
        idx = as_index(index, self.n)
        self._indices_in(idx, (c.INIT_MODE, c.SAFE_MODE), "software_reset")
        keep = [L.S_THETA, L.S_OMEGA, L.S_LOAD_THETA, L.S_LOAD_OMEGA, L.S_I_RE, L.S_I_IM,
                L.S_ACC, L.S_UBUS, L.S_DUMP_ON,
                L.S_TICK, L.S_REC_LEN, L.S_E_ELEC, L.S_E_COPPER, L.S_E_FRICTION, L.S_E_LOAD,
                L.S_E_DUMP, L.S_E_SUPPLY, L.S_I2T_Q, L.S_UIT_Q]
        saved = self.state[np.ix_(idx, keep)].copy()
        self.state[idx] = 0.0
        self.state[np.ix_(idx, keep)] = saved
        self._power_on(idx)

    def set_input(self, index: MotorIndex = None, *, load_torque: InputValue = None,
                  analog_volts: InputValue = None, pulse_counts: InputValue = None,
                  home: InputValue = None, supply_volts: InputValue = None) -> None:
        """Set world inputs, held from the next outer sample on (per motor).

        Parameters
        ----------
        load_torque : float or (N,) array
            External load torque opposing positive rotation [N·m].
        analog_volts : float or array
            Analogue input [V], −10..10 (clipped by the ADC).
        pulse_counts : int or array
            Pulse/encoder input counts per outer sample (V_EXT).
        home : bool or array
            Home sensor level.
        supply_volts : float or array
            Supply source voltage [V].
        """
        super().set_input(index, load_torque=load_torque, analog_volts=analog_volts,
                          pulse_counts=pulse_counts, home=home, supply_volts=supply_volts)

    @property
    def load_angle(self) -> np.ndarray:
        """Angle of the load [rad], (N,): behind an elastic coupling its own, else the
        shaft's (docs/model.md §5.2)."""
        return self.state[:, L.S_LOAD_THETA].copy()

    @property
    def load_speed(self) -> np.ndarray:
        """Speed of the load [rad/s], (N,) (the shaft's when the load is rigid)."""
        return self.state[:, L.S_LOAD_OMEGA].copy()

    def _current_vector(self) -> np.ndarray:
        """Stator current space vector [A], (N,) complex (``jvl_gym.physics.coil``)."""
        return self.state[:, L.S_I_RE] + 1j * self.state[:, L.S_I_IM]

    @property
    def phase_currents(self) -> np.ndarray:
        """Phase currents ia, ib, ic [A], (N, 3)."""
        s = self._current_vector()
        k = np.exp(1j * 2.0 * np.pi / 3.0 * np.arange(3))
        return np.real(s[:, None] * k[None, :])

    @property
    def bus_voltage(self) -> np.ndarray:
        """DC bus voltage [V], (N,)."""
        return self.state[:, L.S_UBUS].copy()

    @property
    def torque(self) -> np.ndarray:
        """Electromagnetic torque at the current instant [N·m], (N,)."""
        s = self._current_vector()
        th = self.params[:, L.P_POLE_PAIRS] * self.state[:, L.S_THETA] + self.params[:,
                                                                                    L.P_THETA_E0]
        return 1.5 * self.params[:, L.P_POLE_PAIRS] * self.params[:, L.P_LAMBDA] * np.real(
            s * np.exp(-1j * th))

    @property
    def energy(self) -> dict[str, np.ndarray]:
        """Energy accounts since power-on [J], (N,) each, the kinetic energy of rotor and load
        now and the energy stored in the twist of an elastic coupling ("coupling"; 0 when
        rigid). "friction" includes the coupling's damping."""
        s, p = self.state, self.params
        rigid = p[:, L.P_K_COUPLING] <= 0.0
        j_shaft = p[:, L.P_J_MOTOR] + np.where(rigid, p[:, L.P_J_LOAD], 0.0)
        j_load = np.where(rigid, 0.0, p[:, L.P_J_LOAD])
        twist = s[:, L.S_THETA] - s[:, L.S_LOAD_THETA]
        return {
            "electrical": s[:, L.S_E_ELEC].copy(),
            "copper": s[:, L.S_E_COPPER].copy(),
            "friction": s[:, L.S_E_FRICTION].copy(),
            "load": s[:, L.S_E_LOAD].copy(),
            "dump": s[:, L.S_E_DUMP].copy(),
            "supply": s[:, L.S_E_SUPPLY].copy(),
            "kinetic": 0.5 * j_shaft * s[:, L.S_OMEGA] ** 2
            + 0.5 * j_load * s[:, L.S_LOAD_OMEGA] ** 2,
            "coupling": np.where(rigid, 0.0, 0.5 * p[:, L.P_K_COUPLING] * twist**2),
        }
