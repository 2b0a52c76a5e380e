"""MotorArray: N simulated motors of one family, read and written by register name or number.

The array holds the register banks, plant and firmware state of N motors as (N, ·) arrays. It
is made of parts of one concept each: register access (:mod:`.bank`), flash images
(:mod:`.flash`) and stepping by the engine (:mod:`.stepping`); this module adds
the pool of motor types, resets with per-motor parameters and the hooks a family fills in.
What depends on the family — its ROM image and parameters, the firmware's write and mode rules,
SAFE_MODE and test modes, world inputs and the physical observables — is the family's subclass
(``MotorArray("MAC140")`` returns one, see :func:`jvl_gym.families.family_of_motor`).

The operations every family offers under one name and one signature are declared here
(:mod:`jvl_gym.families.contract`): ``torque``, ``energy``, ``mode_name(index)``,
``sample_buffer(index)``, ``sample_buffer_raw(index)``, ``enter_safe_mode``,
``exit_safe_mode``, ``go_init_mode``, ``software_reset``, ``write_flash`` (flash save), and
``flash_image`` / ``load_flash_image`` (:mod:`jvl_gym.motor.flash`). One that the family does not
declare in its :class:`~jvl_gym.families.Capability` set raises
:class:`~jvl_gym.families.UnsupportedOperation` naming the capability, and changes nothing.
"""

from __future__ import annotations

import functools
import os
from abc import ABC, abstractmethod
from collections.abc import Sequence
from pathlib import Path
from types import ModuleType
from typing import Any, ClassVar

import numpy as np

from ..compat import renamed_method
from ..engine import two_cores
from ..families import Capability, Family, UnsupportedOperation, family, family_of_motor
from ..families.capability import motors_of
from ..registers import Register, RegisterError, RegisterTable
from ..registers.formats import from_raw
from .arguments import InputValue, MotorIndex, MotorSpec, Seed, as_index, motor_index, real_array
from .bank import RegisterBank, StorePlan
from .flash import FlashStorage
from .inputs import InputRule, staged_inputs
from .keywords import BINARY, RULE_TEXT, first_bad_value
from .noise import motor_keys
from .stepping import Stepping, driver

__all__ = ["MotorArray", "ModeError", "driver"]


@functools.lru_cache(maxsize=256)
def _keyword_plan(cls: type[MotorArray], names: tuple[str, ...]
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:meth:`MotorArray._keyword_plan`, kept per class and keyword tuple."""
    cols = [cls.PARAMETER_KEYWORDS.get(name, cls.STATE_KEYWORDS.get(name)) for name in names]
    return (np.array(cols, dtype=np.int64),
            np.array([name in cls.STATE_KEYWORDS for name in names], dtype=np.bool_),
            np.array([cls.VALUE_RULES[name] for name in names], dtype=np.int64))


class ModeError(RegisterError):
    """A MODE_REG write or a mode command that the firmware's rules refuse (manual 4.4)."""


class MotorArray(RegisterBank, FlashStorage, Stepping, ABC):
    """N simulated motors of one family sharing one compiled kernel.

    ``MotorArray(motor, ...)`` returns an array of the family the motor type belongs to (the
    family's subclass, e.g. :class:`jvl_gym.families.mac050_141.motors.MacMotorArray`).

    Parameters
    ----------
    motor : str, path, motor config, or a sequence of those of length ``n``
        Motor type name (``"MAC140"``), config path, or one per motor (mixed arrays of one
        family).
    n : int
        Number of motors N.
    seed : int, sequence of int, or None
        Noise seeding. An int gives motor ``i`` the key ``motor_keys(seed, n)[i]``; a sequence
        gives the keys directly (so one motor of an array can be reproduced on its own).
    setup : str, path, dict, or None
        Register set written over the ROM defaults at power-on; default: the motor type's
        setup (``families/mac050_141/configs/setups/<TYPE>.yaml``).
    **params
        Per-motor parameters (scalars or (N,) arrays): the family's
        :attr:`PARAMETER_KEYWORDS` and :attr:`STATE_KEYWORDS`, and the family's own keyword
        arguments.

    Examples
    --------
    >>> m = MotorArray("MAC140", n=4, seed=0, load_inertia=0.0)
    >>> m.write("MODE_REG", 1); m.write("V_SOLL", 1600); m.run(seconds=0.3)
    >>> m.speed_rpm  # ≈ 762.9 rpm for every motor
    """

    # --- what a family's subclass declares ------------------------------------------------
    #: the family's key (``jvl_gym.families``)
    FAMILY_KEY: ClassVar[str] = ""
    #: the family's register table
    TABLE: ClassVar[RegisterTable]
    #: columns of ``state``, ``params`` and ``inputs`` (the ``layout`` class keyword sets them)
    N_STATE: ClassVar[int] = 0
    N_PARAM: ClassVar[int] = 0
    N_INPUT: ClassVar[int] = 0
    #: depth and channels of the sample buffer
    BUFFER_SHAPE: ClassVar[tuple[int, int]] = (1, 1)
    #: outer samples per second [Hz]
    OUTER_HZ: ClassVar[float] = 1.0
    #: the register that holds the operating mode
    MODE_REGISTER: ClassVar[str] = "MODE_REG"
    #: the folder of the family's named setups (``load_setup("<name>")``), or None
    SETUPS_DIR: ClassVar[Path | None] = None
    #: reset keyword → column of ``params`` (SI units), and → column of ``state``
    PARAMETER_KEYWORDS: ClassVar[dict[str, int]] = {}
    STATE_KEYWORDS: ClassVar[dict[str, int]] = {}
    #: reset keyword → value rules (``jvl_gym.motor.keywords``)
    VALUE_RULES: ClassVar[dict[str, int]] = {}
    #: world-input name → column of ``inputs`` (``set_input`` keywords, ``jvl_gym.world``)
    INPUTS: ClassVar[dict[str, int]] = {}
    #: world-input name → what it accepts beyond a finite real number (``jvl_gym.motor.inputs``)
    INPUT_RULES: ClassVar[dict[str, InputRule]] = {}
    #: columns of ``state`` holding the shaft's angle [rad] and speed [rad/s] (−1: none)
    SHAFT_ANGLE: ClassVar[int] = -1
    SHAFT_SPEED: ClassVar[int] = -1
    #: the physical quantities :meth:`trace` records (names of properties)
    PHYSICAL: ClassVar[frozenset[str]] = frozenset()
    #: the registers naming what each channel of the sample buffer records
    SAMPLE_REGISTERS: ClassVar[tuple[str, ...]] = ("SAMPLE1", "SAMPLE2", "SAMPLE3", "SAMPLE4")

    def __init_subclass__(cls, *, layout: ModuleType | None = None, **kwargs: Any) -> None:
        """A family's subclass names its layout module (``class X(MotorArray, layout=L)``):
        :attr:`N_STATE`, :attr:`N_PARAM` and :attr:`N_INPUT` are the layout's."""
        super().__init_subclass__(**kwargs)
        if layout is not None:
            cls.N_STATE, cls.N_PARAM, cls.N_INPUT = layout.N_STATE, layout.N_PARAM, layout.N_INPUT

    def __new__(cls, motor: MotorSpec = "MAC140", *args: Any, **kwargs: Any) -> MotorArray:
        if cls is MotorArray:
            first = motor[0] if isinstance(motor, (list, tuple)) and motor else motor
            cls = family_of_motor(first).array_class
        return super().__new__(cls)

    def __init__(self, motor: MotorSpec = "MAC140", n: int = 1, seed: Seed = None,
                 setup: str | os.PathLike[str] | dict[str, Any] | None = None,
                 **params: Any) -> None:
        if isinstance(n, (bool, np.bool_)) or int(n) != n or n < 1:
            raise ValueError(f"n must be a positive integer, got {n!r}")
        self.n = int(n)
        self.table = self.TABLE
        motors = list(motor) if isinstance(motor, (list, tuple)) else [motor] * self.n
        if len(motors) != self.n:
            raise ValueError(f"got {len(motors)} motor types for n={self.n}")
        configs: dict[str, Any] = {}
        self._type_of = np.zeros(self.n, dtype=np.int64)
        for i, mtype in enumerate(motors):
            cfg = self.load_motor(mtype)
            configs.setdefault(cfg.name, cfg)
            self._type_of[i] = list(configs).index(cfg.name)
        n_regs = self.table.last + 1
        self._mode_number = self.table.lookup(self.MODE_REGISTER).number
        self._setup_arg = setup
        self._configs: list[Any] = []
        self._type_codes: dict[str, int] = {}  #: type name -> index in the pool
        self._rom = np.zeros((0, n_regs), dtype=np.int64)
        self._type_params = np.zeros((0, self.N_PARAM))
        self._type_inputs = np.zeros((0, self.N_INPUT))
        #: store plans by register-name tuple (``write_many``) and by number (``_store``)
        self._plans: dict[Any, StorePlan] = {}
        #: register column and LongInt high word by name (``read_raw``)
        self._read_columns: dict[str, tuple[int, bool]] = {}
        for cfg in configs.values():
            self._add_type(cfg)
        if isinstance(seed, (list, tuple, np.ndarray)):
            given = np.asarray(seed)
            if given.shape != (self.n,) or given.dtype.kind not in "iu" or (
                    given.dtype.kind == "i" and given.size and given.min() < 0):
                raise ValueError(f"a seed sequence gives {self.n} noise keys: integers "
                                 f"0..2**64-1, got {seed!r}")
            keys = given.astype(np.uint64)
        else:
            keys = motor_keys(seed, self.n)
        self.keys = keys
        self.regs = np.zeros((self.n, n_regs), dtype=np.int64)
        self.state = np.zeros((self.n, self.N_STATE), dtype=np.float64)
        self.params = np.zeros((self.n, self.N_PARAM), dtype=np.float64)
        self.inputs = np.zeros((self.n, self.N_INPUT), dtype=np.float64)
        self._buf = np.zeros((1, *self.BUFFER_SHAPE), dtype=np.int64)
        self._buf_allocated = False
        self._no_schedule = np.zeros((0, self.n, self.N_INPUT), dtype=np.float64)
        self._scratch = self.family.compiled.scratch(self.n)
        #: world signal sources (``jvl_gym.world.World``) sampled every outer sample, or None
        self.world = None
        self._flash: np.ndarray | None = None
        self._has_flash = np.zeros(self.n, dtype=np.bool_)
        self._fmt = self.table.fmt_code_array
        #: register numbers whose not-modelled warning has been given (``_note_not_modelled``)
        self._not_modelled_warned: set[int] = set()
        # on a cold start, a second process compiles the family's inner samples meanwhile
        two_cores.start(self.family.compiled, self.engine_view())
        self._before_reset()
        self.reset(**params)

    @property
    @abstractmethod
    def time(self) -> np.ndarray:
        """Time since power-on of each motor [s], (N,)."""

    @property
    def family(self) -> Family:
        """The motor family of this array (:mod:`jvl_gym.families`)."""
        return family(self.FAMILY_KEY)

    # ------------------------------------------------------------------ family hooks
    @staticmethod
    @abstractmethod
    def load_motor(motor: Any) -> Any:
        """The validated motor config of ``motor`` (a type name, path or config object)."""

    @abstractmethod
    def _rom_image(self, cfg: Any, setup: Any) -> np.ndarray:
        """ROM defaults (number of registers,) int64 of one motor type with ``setup``."""

    @abstractmethod
    def _config_params(self, cfg: Any) -> np.ndarray:
        """Parameters (N_PARAM,) of a motor of type ``cfg`` before reset keywords."""

    @abstractmethod
    def _rest_inputs(self, cfg: Any) -> np.ndarray:
        """World inputs (N_INPUT,) of a motor of type ``cfg`` at rest."""

    def _before_reset(self) -> None:
        """Family set-up after the arrays exist, before the first power-on."""

    def set_input(self, index: MotorIndex = None, **inputs: InputValue) -> None:
        """Set world inputs (:attr:`INPUTS` by name), held from the next outer sample on, per
        motor of ``index``. Every value is checked (:attr:`INPUT_RULES`) before any is set.

        Raises
        ------
        TypeError
            An input the family does not have.
        ValueError
            A value that is not a real number, a wrong shape, or a value that is not finite,
            not whole or out of range.
        """
        idx = as_index(index, self.n)
        for col, values in staged_inputs(inputs, self.INPUTS, self.INPUT_RULES, idx.size):
            self.inputs[idx, col] = values

    # ------------------------------------------------------------------ the shaft
    def _shaft(self, column: int) -> np.ndarray:
        if column < 0:
            raise AttributeError(f"{motors_of(self.family.title)} declare no shaft state "
                                 "(SHAFT_ANGLE, SHAFT_SPEED)")
        return self.state[:, column]

    @property
    def speed_rad_s(self) -> np.ndarray:
        """Shaft (rotor) speed [rad/s], (N,)."""
        return self._shaft(self.SHAFT_SPEED).copy()

    @property
    def speed_rpm(self) -> np.ndarray:
        """Shaft (rotor) speed [RPM], (N,)."""
        return self._shaft(self.SHAFT_SPEED) * 60.0 / (2.0 * np.pi)

    @property
    def position_rad(self) -> np.ndarray:
        """Shaft (rotor) angle from the world zero at power-on [rad], (N,)."""
        return self._shaft(self.SHAFT_ANGLE).copy()

    def pulse_decoding(self) -> tuple[np.ndarray, np.ndarray]:
        """How each motor decodes its pulse input: ``(pulse_dir, inverted)``, (N,) bool
        arrays (pulse + direction rather than quadrature; count reversed). Families with a
        pulse input define it (:class:`jvl_gym.world.PulseInput` uses it)."""
        raise NotImplementedError(f"{self.family.title}: the decoding of a pulse source is not "
                                  "modelled; drive the input with set_input(pulse_counts=...)")

    def _reset_rows(self, idx: np.ndarray, cols: np.ndarray, to_state: np.ndarray,
                    values: np.ndarray) -> None:
        """Power on motors ``idx`` from flash or ROM with the type pool's parameters and
        inputs, then the reset keywords' ``values`` (P, M) into columns ``cols`` (P,) of
        ``params`` or, where ``to_state``, of ``state``.

        By default: the registers from flash (a motor with a saved image) or else its type's
        ROM, the state zero but for :meth:`_initial_state`, the type's parameters and inputs,
        the keywords' values, then the firmware's start (:meth:`_power_on`).
        """
        memory = self._rom if self._flash is None else self._flash
        for j, i in enumerate(idx.tolist()):
            t = self._type_of[i]
            self.regs[i] = memory[i] if self._has_flash[i] else self._rom[t]
            self.state[i] = 0.0
            self._initial_state(self.state[i])
            self.params[i] = self._type_params[t]
            self.inputs[i] = self._type_inputs[t]
            for q in range(cols.size):
                (self.state if to_state[q] else self.params)[i, cols[q]] = values[q, j]
        self._power_on(idx)

    def _initial_state(self, row: np.ndarray) -> None:
        """Set the state ``row`` (N_STATE,) of a motor at power-on where it is not 0 (the
        reset keywords may still override it)."""

    def _power_on(self, idx: np.ndarray) -> None:
        """The firmware's start of motors ``idx`` after :meth:`_reset_rows` (default:
        nothing)."""

    # ------------------------------------------------------------------ configuration
    def _add_type(self, cfg: Any) -> None:
        """Join motor type ``cfg`` to the pool: its ROM image, parameters and inputs at rest."""
        self._configs.append(cfg)
        self._rom = np.concatenate([self._rom, self._rom_image(cfg, self._setup_arg)[None]])
        self._type_params = np.concatenate([self._type_params, self._config_params(cfg)[None]])
        self._type_inputs = np.concatenate([self._type_inputs, self._rest_inputs(cfg)[None]])

    def _type_code(self, name: str) -> int:
        """Index of motor type ``name`` in the pool of types, adding it on first use."""
        code = self._type_codes.get(name)
        if code is not None:
            return code
        names = [known.name for known in self._configs]
        if name in names:
            code = self._type_codes[name] = names.index(name)  # a type name: kept
            return code
        cfg = self.load_motor(name)  # raises on an unknown type, before any motor changes
        if cfg.name not in names:
            self._add_type(cfg)
            names.append(cfg.name)
        return names.index(cfg.name)

    @property
    def motor_configs(self) -> list[Any]:
        """Motor config of each motor (length N)."""
        return [self._configs[k] for k in self._type_of]

    @property
    def parameters(self) -> dict[str, np.ndarray]:
        """Per-motor physical parameters in SI units, as (N,) arrays (copies)."""
        return {name: self.params[:, col].copy()
                for name, col in self.PARAMETER_KEYWORDS.items()}

    # ------------------------------------------------------------------ reset
    def reset(self, index: MotorIndex = None, motor_type: str | Sequence[str] | None = None,
              **params: Any) -> None:
        """Power-on reset of the motors in ``index`` with optional new per-motor parameters.

        Registers come from flash (if written) or the ROM defaults; the family's power-on
        clears the firmware state and counters (for the MACs P_IST = 0 and the rotor at
        ``initial_angle`` [rad] turning at ``initial_speed`` [rad/s]); world inputs return to
        rest. Other motors are untouched.
        ``motor_type`` (one name, or one per motor of ``index``) first replaces the motors by
        motors of that type (its parameters and ROM defaults; the type joins the array's pool).
        A value the family refuses (a keyword out of its range, a coupling the inner step cannot
        carry, an unknown encoder option) raises and changes nothing, the motors' types
        included.
        """
        idx = as_index(index, self.n)
        names, values = self._check_params(params, idx.size)
        types = None
        if motor_type is not None:
            if isinstance(motor_type, str):
                codes = self._type_code(motor_type)  # one code for every motor of idx
            else:
                names_of = list(motor_type)
                if len(names_of) != idx.size:
                    raise ValueError(f"got {len(names_of)} motor types for {idx.size} motors")
                codes = np.array([self._type_code(name) for name in names_of], dtype=np.int64)
            types = self._type_of[idx]
            self._type_of[idx] = codes
        cols, to_state, _ = self._keyword_plan(names)
        try:
            self._reset_rows(idx, cols, to_state, values)
        except (TypeError, ValueError):  # a value the family refuses: the motors' types stay
            if types is not None:
                self._type_of[idx] = types
            raise

    def _check_params(self, params: dict[str, Any], size: int
                      ) -> tuple[tuple[str, ...], np.ndarray]:
        """The keywords of ``params`` and their values as rows of a (P, size) float64 array,
        checked (:attr:`VALUE_RULES`); raises on the first bad keyword, in order."""
        names = tuple(params)
        values = np.empty((len(names), size))
        for q, (name, val) in enumerate(params.items()):
            if (type(val) is np.ndarray and val.dtype == np.float64 and val.shape == (size,)
                    and (name in self.PARAMETER_KEYWORDS or name in self.STATE_KEYWORDS)):
                values[q] = val  # a keyword's (size,) floats: the rules are checked below
                continue
            try:
                if name not in self.PARAMETER_KEYWORDS and name not in self.STATE_KEYWORDS:
                    known = ", ".join(sorted([*self.PARAMETER_KEYWORDS, *self.STATE_KEYWORDS]))
                    raise TypeError(f"unknown motor parameter {name!r}; known: {known}")
                arr = real_array(name, val,
                                  allow_bool=bool(self.VALUE_RULES[name] & BINARY))
                if arr.ndim > 1 or (arr.ndim == 1 and arr.shape[0] != size):
                    raise ValueError(f"{name}: expected a scalar or shape ({size},), "
                                     f"got {arr.shape}")
            except (TypeError, ValueError):
                self._raise_bad_value(names[:q], values[:q], list(params.values()))
                raise
            values[q] = arr
        self._raise_bad_value(names, values, list(params.values()))
        return names, values

    @classmethod
    def _keyword_plan(cls, names: tuple[str, ...]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Columns (P,) int64 of reset keywords ``names`` in ``params`` or, where the (P,) bool
        is set, in ``state``, and their value rules (P,) int64 (:attr:`VALUE_RULES`)."""
        return _keyword_plan(cls, names)

    @classmethod
    def _raise_bad_value(cls, names: tuple[str, ...], values: np.ndarray,
                         given: list[Any]) -> None:
        """Raise ValueError for the first of the reset keywords ``names`` whose values (rows
        of ``values``, as ``given``) break their rules (:attr:`VALUE_RULES`)."""
        bad = first_bad_value(values, cls._keyword_plan(names)[2])
        if bad < 0:
            return
        q, rule = divmod(bad, 16)
        name, val = names[q], given[q]
        if rule == BINARY:
            raise ValueError(f"{name} must be 0 or 1, got {val!r}")
        raise ValueError(f"{name}: values must be {RULE_TEXT[rule]}, got {val!r}")

    # ------------------------------------------------------------------ the contract's operations
    def _require(self, capability: Capability) -> None:
        """:class:`UnsupportedOperation` unless the family declares ``capability``."""
        self.family.require(capability)

    @property
    def torque(self) -> np.ndarray:
        """Electromagnetic torque now [N·m], (N,) (:attr:`Capability.TORQUE`)."""
        raise UnsupportedOperation(self.family.title, Capability.TORQUE)

    @property
    def energy(self) -> dict[str, np.ndarray]:
        """Energy accounts since power-on [J], {account: (N,)} (:attr:`Capability.ENERGY`);
        every family has ``"copper"`` and ``"load"``."""
        raise UnsupportedOperation(self.family.title, Capability.ENERGY)

    def mode_name(self, index: int = 0) -> str:
        """Name of the current mode of motor ``index`` (the family constants' ``MODE_NAMES``;
        ``"?"`` for a value it does not name)."""
        i = motor_index(index, self.n, "mode_name")
        return self.family.constants.MODE_NAMES.get(int(self.regs[i, self._mode_number]), "?")

    def enter_safe_mode(self, index: MotorIndex = None) -> None:
        """Safe mode: the bridge off, flash save and reset allowed (:attr:`Capability.SAFE_MODE`;
        MAC050–141 manual 4.4.16, MIS manual §8.2.3)."""
        raise UnsupportedOperation(self.family.title, Capability.SAFE_MODE)

    #: the previous release's name of :meth:`enter_safe_mode` (the MacTalk command's name)
    go_safe_mode = renamed_method("enter_safe_mode", "go_safe_mode")

    def exit_safe_mode(self, index: MotorIndex = None) -> None:
        """Leave safe mode (:attr:`Capability.SAFE_MODE`); a motor not in safe mode raises
        :class:`ModeError`."""
        raise UnsupportedOperation(self.family.title, Capability.SAFE_MODE)

    def go_init_mode(self, index: MotorIndex = None) -> None:
        """The MacTalk "go init mode" path (:attr:`Capability.INIT_MODE`; MAC050–141 manual
        5.1)."""
        raise UnsupportedOperation(self.family.title, Capability.INIT_MODE)

    def software_reset(self, index: MotorIndex = None) -> None:
        """Restart the firmware from flash (or ROM): the rotor keeps its angle and speed
        (:attr:`Capability.SOFTWARE_RESET`). Families without it restart by :meth:`reset`."""
        raise UnsupportedOperation(self.family.title, Capability.SOFTWARE_RESET)

    def write_flash(self, index: MotorIndex = None) -> None:
        """Save the register set in flash, then :meth:`software_reset` (in safe mode only;
        :attr:`Capability.FLASH`). :meth:`flash_image` and :meth:`load_flash_image` read and
        load a flash image of every family."""
        raise UnsupportedOperation(self.family.title, Capability.FLASH)

    @property
    def interface_bits(self) -> np.ndarray:
        """The user-interface bits latched at power-on, (N,) int64
        (:attr:`Capability.USER_INTERFACE`; MAC050–141 manual 3.2.36)."""
        raise UnsupportedOperation(self.family.title, Capability.USER_INTERFACE)

    # ------------------------------------------------------------------ sample buffer
    def _ensure_buffer(self) -> None:
        """Allocate the sample buffer, (N, *BUFFER_SHAPE) int64, on the first recording."""
        if not self._buf_allocated:
            self._buf = np.zeros((self.n, *self.BUFFER_SHAPE), dtype=np.int64)
            self._buf_allocated = True

    def _sample_counts(self) -> np.ndarray:
        """Samples recorded so far by each motor, (N,) (default: the REC_CNT register)."""
        return self.regs[:, self.table.lookup("REC_CNT").number]

    def _sample_register(self, number: int) -> Register | None:
        """The register a channel records, or None where ``number`` names none."""
        if number not in self.table:
            return None
        reg = self.table.lookup(number)
        return None if reg.access.value == "reserved" else reg

    def sample_buffer_raw(self, index: int) -> np.ndarray:
        """Raw samples of motor ``index``, (samples, channels) int64, one channel per
        :attr:`SAMPLE_REGISTERS` (:attr:`Capability.SAMPLE_BUFFER`)."""
        self._require(Capability.SAMPLE_BUFFER)
        i = motor_index(index, self.n, "sample_buffer_raw")
        if not self._buf_allocated:
            return np.zeros((0, self.BUFFER_SHAPE[1]), dtype=np.int64)
        return self._buf[i, :int(self._sample_counts()[i])].copy()

    def sample_buffer(self, index: int | None = None) -> dict[str, np.ndarray]:
        """The sample buffer in user units (:attr:`Capability.SAMPLE_BUFFER`).

        Parameters
        ----------
        index : int or None
            One motor: {name: (samples,)}; None: every motor, {name: (N, samples)} with the
            entries past a motor's count 0.

        Returns
        -------
        dict of str to ndarray
            Channels named after the registers :attr:`SAMPLE_REGISTERS` select (of the first
            motor given); a channel whose register differs between the motors, is no register
            or is named twice is ``SAMPLEk`` in raw units.
        """
        self._require(Capability.SAMPLE_BUFFER)
        rows = (np.arange(self.n) if index is None
                else np.array([motor_index(index, self.n, "sample_buffer")]))
        counts = (self._sample_counts()[rows].astype(np.int64) if self._buf_allocated
                  else np.zeros(rows.size, dtype=np.int64))
        count = int(counts.max())
        valid = np.arange(count)[None, :] < counts[:, None]
        out: dict[str, np.ndarray] = {}
        for ch, name in enumerate(self.SAMPLE_REGISTERS):
            nums = self.regs[rows, self.table.lookup(name).number]
            raw = (np.where(valid, self._buf[rows, :count, ch], 0) if count
                   else np.zeros((rows.size, 0), dtype=np.int64))
            reg = self._sample_register(int(nums[0]))
            if reg is None or np.any(nums != nums[0]) or reg.name in out:
                out[f"SAMPLE{ch + 1}"] = raw
            else:
                out[reg.name] = from_raw(reg, raw)
        return out if index is None else {key: value[0] for key, value in out.items()}

    def __repr__(self) -> str:
        types = sorted({cfg.name for cfg in self._configs})
        return f"MotorArray({'/'.join(types)}, n={self.n})"
