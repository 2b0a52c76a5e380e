"""MotorArray: N simulated motors of one family, read and written by register name or number.

The array holds the register banks, plant and firmware state of N motors as (N, ·) arrays and
advances them with the engine's compiled driver (``jvl_gym.engine``), bound to the motor
family's compiled step. This module is the family-independent part a user talks to: validated
register access (formats and ranges from the family's register table), the store plans, flash
images, resets with per-motor parameters, stepping and the world inputs' schedule.
What depends on the family — its ROM image and parameters, the firmware's write and mode rules,
SAFE_MODE and test modes, world inputs and the physical observables — is the family's subclass
(``MotorArray("MAC140")`` returns one, see :func:`jvl_gym.families.family_of_motor`).
"""

from __future__ import annotations

import functools
import math
import os
from collections.abc import Mapping, Sequence
from typing import Any, ClassVar, NamedTuple

import numpy as np

from .config import load_setup
from .engine import MotorDriver
from .families import Family, family, family_of_motor
from .keywords import BINARY, RULE_TEXT, first_bad_value
from .noise import motor_keys
from .registers import (
    Access,
    Format,
    ReadOnlyRegisterError,
    Register,
    RegisterError,
    RegisterRangeError,
    RegisterShapeError,
    RegisterTable,
)
from .registers.formats import (
    from_raw,
    raw_bounds,
    raws_of_floats,
    raws_of_rows,
    real_values,
    to_raw,
)

__all__ = ["MotorArray", "ModeError", "driver"]

#: up to this many int64 indices are checked with Python ints (``_as_index``)
_FEW = 8
#: register-key tuples whose store plan a MotorArray keeps (``MotorArray._key_plan``)
_PLAN_CACHE_SIZE = 256


@functools.cache
def driver(family_key: str) -> MotorDriver:
    """The stepping driver of a family (specialised and compiled once per process)."""
    return MotorDriver(family(family_key))


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


class _StorePlan(NamedTuple):
    """Registers stored together, with the arrays of the family's compiled store."""

    regs: tuple[Register, ...]
    nums: np.ndarray  #: (K,) int64 register numbers
    high: np.ndarray  #: (K,) bool: a LongInt's high word
    mode_rows: tuple[int, ...]  #: positions of the mode register
    one_by_one: bool  #: stored register by register (the family's special registers)
    writable: bool  #: every register is read-write
    bounds: np.ndarray  #: (K, 6) conversion constants (``registers.formats.raw_bounds``)

    @classmethod
    def of(cls, regs: tuple[Register, ...], mode_number: int,
           one_by_one: frozenset[int]) -> _StorePlan:
        """The plan of storing ``regs`` in this order (``mode_number``: the mode register;
        ``one_by_one``: registers the family stores one at a time)."""
        nums = [reg.number for reg in regs]
        writable = all(reg.access == Access.RW for reg in regs)
        return cls(regs, np.array(nums, dtype=np.int64),
                   np.array([reg.format == Format.LONGINT_HIGH for reg in regs], dtype=np.bool_),
                   tuple(k for k, num in enumerate(nums) if num == mode_number),
                   any(num in one_by_one for num in nums), writable,
                   np.array([raw_bounds(reg) for reg in regs] if writable else [],
                            dtype=np.float64).reshape(-1, 6))


def _bad_index(index: Any, n: int, why: str) -> RegisterShapeError:
    """The error of a motor index ``index`` that is not one (``why``), nothing changed."""
    return RegisterShapeError(
        f"index {index!r} {why}: a motor index is None (all motors), an integer in "
        f"{-n}..{n - 1}, a sequence or integer array of distinct ones, a slice, or a boolean mask "
        f"of shape ({n},). Nothing was changed.")


def _as_index(index: Any, n: int) -> np.ndarray:
    """Normalise ``index`` to (M,) int64 indices of distinct motors, in the order given.

    Accepted: None (all motors), a Python or numpy integer in ``-n..n-1`` (negative counts from
    the end), a slice, a sequence or integer array (0-d or 1-d) of such integers without
    repeats, a boolean mask of shape (n,).

    Raises
    ------
    RegisterShapeError
        For anything else: a float, bool, str, complex, an integer out of range, a repeated
        motor, a mask of the wrong shape, a multi-dimensional array.
    """
    if (type(index) is np.ndarray and index.dtype == np.int64 and index.ndim == 1
            and 0 < index.size <= _FEW):  # a few indices (an env's reset): no numpy reductions
        few = index.tolist()
        if min(few) >= 0 and max(few) < n and len(set(few)) == len(few):
            return index
    if index is None:
        return np.arange(n, dtype=np.int64)
    if isinstance(index, slice):
        try:
            return np.arange(n, dtype=np.int64)[index]
        except (TypeError, ValueError, IndexError) as exc:
            raise _bad_index(index, n, "is not a slice of whole numbers") from exc
    if isinstance(index, (bool, np.bool_)):
        raise _bad_index(index, n, "is a truth value, not a motor")
    if isinstance(index, (int, np.integer)):
        k = int(index)
        if not -n <= k < n:
            raise _bad_index(index, n, f"is out of range for {n} motors")
        return np.array([k + n if k < 0 else k], dtype=np.int64)
    if isinstance(index, (str, bytes, bytearray, float, complex, np.floating,
                          np.complexfloating)):
        raise _bad_index(index, n, "is not an integer")
    try:
        arr = np.asarray(index)
    except (TypeError, ValueError) as exc:  # a ragged sequence
        raise _bad_index(index, n, "is not a sequence of integers") from exc
    if arr.dtype == np.bool_:
        if arr.shape != (n,):
            raise RegisterShapeError(f"boolean index must have shape ({n},), got {arr.shape}. "
                                     "Nothing was changed.")
        return np.flatnonzero(arr).astype(np.int64)
    if arr.ndim > 1:
        raise _bad_index(index, n, f"has shape {arr.shape}, not one dimension")
    if arr.size == 0:
        return np.zeros(0, dtype=np.int64)
    if arr.dtype.kind not in "iu":
        raise _bad_index(index, n, f"is not made of integers (dtype {arr.dtype})")
    arr = arr.reshape(-1)
    low, high = int(arr.min()), int(arr.max())
    if low < -n or high >= n:
        raise _bad_index(index, n, f"is out of range for {n} motors")
    out = arr.astype(np.int64)
    if low < 0:
        out = np.where(out < 0, out + n, out)
    if out.size > 1 and not np.all(out[1:] > out[:-1]) and np.unique(out).size != out.size:
        raise _bad_index(index, n, "names a motor more than once")
    return out


def _real_array(name: str, val: Any, allow_bool: bool = False) -> np.ndarray:
    """``val`` as a float64 array if it is a real number or an array of them (bools only if
    ``allow_bool``); ValueError naming ``name`` for a str, bytes, complex or other value."""
    kinds = "iufb" if allow_bool else "iuf"
    arr = None
    if not isinstance(val, (str, bytes, bytearray)):
        try:
            arr = np.asarray(val)
        except (TypeError, ValueError):  # a ragged sequence
            arr = None
    if arr is None or arr.dtype.kind not in kinds:
        what = "a real number or 0/1/bool" if allow_bool else "a real number"
        raise ValueError(f"{name}: expected {what} or an array of them, got {val!r}")
    return arr.astype(np.float64)


def _motor_index(index: Any, n: int, what: str) -> int:
    """The one motor ``index`` (an integer in ``-n..n-1``) as 0..n-1, for method ``what``."""
    if isinstance(index, (bool, np.bool_)) or not isinstance(index, (int, np.integer)):
        raise RegisterShapeError(f"{what}: the motor index must be an integer in {-n}..{n - 1}, "
                                 f"got {index!r}")
    k = int(index)
    if not -n <= k < n:
        raise RegisterShapeError(f"{what}: motor {k} is out of range for {n} motors "
                                 f"({-n}..{n - 1})")
    return k % n


def _outer_count(n_outer: Any, what: str) -> int:
    """``n_outer`` as a non-negative whole number of outer samples (ValueError otherwise)."""
    if type(n_outer) is int and n_outer >= 0:
        return n_outer
    try:
        ok = (not isinstance(n_outer, (bool, np.bool_, str, bytes)) and n_outer >= 0
              and int(n_outer) == n_outer)
    except (TypeError, ValueError, OverflowError):
        ok = False
    if not ok:
        raise ValueError(f"{what}: n_outer must be a non-negative whole number of outer "
                         f"samples, got {n_outer!r}")
    return int(n_outer)


class MotorArray:
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
        setup (``configs/setups/<TYPE>.yaml``).
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
    #: columns of ``state``, ``params`` and ``inputs``
    N_STATE: ClassVar[int] = 0
    N_PARAM: ClassVar[int] = 0
    N_INPUT: ClassVar[int] = 0
    #: depth and channels of the sample buffer
    BUFFER_SHAPE: ClassVar[tuple[int, int]] = (1, 1)
    #: outer samples per second [Hz]
    OUTER_HZ: ClassVar[float] = 1.0
    #: the register that holds the operating mode
    MODE_REGISTER: ClassVar[str] = "MODE_REG"
    #: reset keyword → column of ``params`` (SI units), and → column of ``state``
    PARAMETER_KEYWORDS: ClassVar[dict[str, int]] = {}
    STATE_KEYWORDS: ClassVar[dict[str, int]] = {}
    #: reset keyword → value rules (``jvl_gym.keywords``)
    VALUE_RULES: ClassVar[dict[str, int]] = {}
    #: world-input name → column of ``inputs`` (``set_input`` keywords, ``jvl_gym.world``)
    INPUTS: ClassVar[dict[str, int]] = {}
    #: the physical quantities :meth:`trace` records (names of properties)
    PHYSICAL: ClassVar[frozenset[str]] = frozenset()

    def __new__(cls, motor: Any = "MAC140", *args: Any, **kwargs: Any) -> MotorArray:
        if cls is MotorArray:
            first = motor[0] if isinstance(motor, (list, tuple)) and motor else motor
            cls = family_of_motor(first).array_class
        return super().__new__(cls)

    def __init__(self, motor: Any = "MAC140", n: int = 1, seed: Any = None,
                 setup: Any = None, **params: Any) -> None:
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
        self._plans: dict[Any, _StorePlan] = {}
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
        self._before_reset()
        self.reset(**params)

    @property
    def time(self) -> np.ndarray:
        """Time since power-on of each motor [s], (N,)."""
        raise NotImplementedError

    @property
    def family(self) -> Family:
        """The motor family of this array (:mod:`jvl_gym.families`)."""
        return family(self.FAMILY_KEY)

    # ------------------------------------------------------------------ family hooks
    @staticmethod
    def load_motor(motor: Any) -> Any:
        """The validated motor config of ``motor`` (a type name, path or config object)."""
        raise NotImplementedError

    def _rom_image(self, cfg: Any, setup: Any) -> np.ndarray:
        """ROM defaults (number of registers,) int64 of one motor type with ``setup``."""
        raise NotImplementedError

    def _config_params(self, cfg: Any) -> np.ndarray:
        """Parameters (N_PARAM,) of a motor of type ``cfg`` before reset keywords."""
        raise NotImplementedError

    def _rest_inputs(self, cfg: Any) -> np.ndarray:
        """World inputs (N_INPUT,) of a motor of type ``cfg`` at rest."""
        raise NotImplementedError

    def _before_reset(self) -> None:
        """Family set-up after the arrays exist, before the first power-on."""

    def _reset_rows(self, idx: np.ndarray, cols: np.ndarray, to_state: np.ndarray,
                    values: np.ndarray) -> None:
        """Power on motors ``idx`` from flash or ROM with the type pool's parameters and
        inputs, then the reset keywords' ``values`` (P, M) into columns ``cols`` (P,) of
        ``params`` or, where ``to_state``, of ``state``."""
        raise NotImplementedError

    def _power_on(self, idx: np.ndarray) -> None:
        """Registers of motors ``idx`` from flash or ROM and the firmware's power-on."""
        raise NotImplementedError

    def _store_rows(self, plan: _StorePlan, idx: np.ndarray, raws: np.ndarray) -> None:
        """Check the firmware's write rules and store the (K, M) stored integers ``raws`` of
        ``plan``'s registers in motors ``idx``; a refusal raises with the registers before
        the refused one stored (the caller restores the motors)."""
        raise NotImplementedError

    def _store_special(self, reg: Register, idx: np.ndarray, raw: np.ndarray) -> bool:
        """Store a write the family handles itself (a mode command, a register-set pointer);
        True when it did. By default, nothing is special."""
        return False

    def _special_request(self, raw: np.ndarray) -> bool:
        """The mode-register values ``raw`` need :meth:`_store_special` (default: never)."""
        return False

    #: registers stored one at a time through :meth:`_store_special` (numbers)
    ONE_BY_ONE: ClassVar[frozenset[int]] = frozenset()

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
    def reset(self, index: Any = None, motor_type: str | Sequence[str] | None = None,
              **params: Any) -> None:
        """Power-on reset of the motors in ``index`` with optional new per-motor parameters.

        Registers come from flash (if written) or the ROM defaults; the family's power-on
        clears the firmware state and counters (for the MACs P_IST = 0 and the rotor at
        ``initial_angle`` [rad] turning at ``initial_speed`` [rad/s]); world inputs return to
        rest. Other motors are untouched.
        ``motor_type`` (one name, or one per motor of ``index``) first replaces the motors by
        motors of that type (its parameters and ROM defaults; the type joins the array's pool).
        """
        idx = _as_index(index, self.n)
        names, values = self._check_params(params, idx.size)
        if motor_type is not None:
            names_of = [motor_type] * idx.size if isinstance(motor_type, str) else list(motor_type)
            if len(names_of) != idx.size:
                raise ValueError(f"got {len(names_of)} motor types for {idx.size} motors")
            codes = np.array([self._type_code(name) for name in names_of], dtype=np.int64)
            self._type_of[idx] = codes
        cols, to_state, _ = self._keyword_plan(names)
        self._reset_rows(idx, cols, to_state, values)

    def _check_params(self, params: dict[str, Any], size: int
                      ) -> tuple[tuple[str, ...], np.ndarray]:
        """The keywords of ``params`` and their values as rows of a (P, size) float64 array,
        checked (:attr:`VALUE_RULES`); raises on the first bad keyword, in order."""
        names = tuple(params)
        values = np.empty((len(names), size))
        for q, (name, val) in enumerate(params.items()):
            try:
                if name not in self.PARAMETER_KEYWORDS and name not in self.STATE_KEYWORDS:
                    known = ", ".join(sorted([*self.PARAMETER_KEYWORDS, *self.STATE_KEYWORDS]))
                    raise TypeError(f"unknown motor parameter {name!r}; known: {known}")
                arr = _real_array(name, val,
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

    # ------------------------------------------------------------------ stepping
    def step(self, n_outer: int = 1) -> None:
        """Advance all motors by ``n_outer`` outer samples (:attr:`OUTER_HZ`)."""
        n_outer = _outer_count(n_outer, "step")
        if n_outer == 0:
            return
        plan = self._no_schedule if self.world is None else self.world.schedule(self, n_outer)
        driver(self.FAMILY_KEY).run(self.engine_view(plan), int(n_outer))

    def engine_view(self, plan: np.ndarray | None = None) -> tuple:
        """The arrays of the motors as the engine's compiled drivers take them (the arrays
        themselves, not copies): the fields of a :class:`~jvl_gym.engine.EngineView` as a
        plain tuple, the handle a compiled task's driver is given (numba dispatches on a plain
        tuple without Python; the driver makes the named view of it).

        A task that advances the motors itself (``jvl_gym.engine.TaskDriver``) holds the
        inputs over each outer sample and sets them between samples; the :attr:`world`
        schedule applies to :meth:`step` only. ``plan`` (T, N, inputs): world inputs per outer
        sample, default none (inputs held).
        """
        return (self.regs, self.state, self.params, self.inputs, self.keys, self._buf,
                self._buf_allocated, self._fmt, self._no_schedule if plan is None else plan,
                self._scratch)

    def reseed(self, keys: np.ndarray, index: Any = None) -> None:
        """Give the motors ``index`` new noise keys (one uint64 per motor, as the ``seed``
        sequence of the constructor): their noise streams restart from these keys.

        Parameters
        ----------
        keys : (M,) array of uint64
            One key per selected motor.
        index : int, slice, bool mask or int array, optional
            The motors (default all).
        """
        idx = _as_index(index, self.n)
        arr = np.asarray(keys)
        if arr.dtype != np.uint64 or arr.shape != (idx.size,):
            raise ValueError(f"keys must be a uint64 array of shape ({idx.size},), got "
                             f"{arr.dtype} {arr.shape}")
        self.keys[idx] = arr

    def run(self, seconds: float) -> None:
        """Advance by ``seconds`` (rounded to whole outer samples of the family's outer
        rate)."""
        real = (int, float, np.integer, np.floating)
        if (isinstance(seconds, (bool, np.bool_)) or not isinstance(seconds, real)
                or not math.isfinite(seconds) or seconds < 0):
            raise ValueError(f"seconds must be a finite number >= 0, got {seconds!r}")
        self.step(int(round(seconds * self.OUTER_HZ)))

    def trace(self, keys: list[str | int], n_outer: int) -> dict[str, np.ndarray]:
        """Step ``n_outer`` outer samples and record registers and physical quantities.

        ``keys`` are register names/numbers or the family's physical properties
        (:attr:`PHYSICAL`, e.g. ``speed_rpm``, ``position_rad``). Returns
        ``{"t": (T,), key: (T, N)}`` (user units; ``t`` from :attr:`time`), like a scope
        attached to every motor at the outer rate.
        """
        n_outer = _outer_count(n_outer, "trace")
        physical = self.PHYSICAL
        regs = [k for k in keys if k not in physical]
        for k in regs:
            self._lookup(k)  # unknown names fail before anything runs
        out: dict[str, list] = {"t": []}
        out.update({str(k): [] for k in keys})
        for _ in range(int(n_outer)):
            self.step()
            out["t"].append(float(self.time[0]))
            for k in keys:
                out[str(k)].append(getattr(self, k) if k in physical else self.read(k))
        return {k: np.asarray(v) for k, v in out.items()}

    # ------------------------------------------------------------------ registers
    def _lookup(self, key: str | int) -> Register:
        if isinstance(key, (bool, np.bool_)) or not isinstance(key, (str, int, np.integer)):
            raise RegisterError(f"register key must be a name or number, got {key!r}")
        return self.table.lookup(int(key) if isinstance(key, np.integer) else key)

    def read_raw(self, key: str | int) -> np.ndarray:
        """Stored integers of a register, (N,) int64 (a LongInt's full 32-bit value)."""
        reg = self._lookup(key)
        if reg.format == Format.LONGINT_HIGH:
            return (self.regs[:, reg.number - 1] >> 16) & 0xFFFF
        return self.regs[:, reg.number].copy()

    def read(self, key: str | int) -> np.ndarray:
        """Register value in user units, (N,): Fixed formats as float, others as int64."""
        reg = self._lookup(key)
        return from_raw(reg, self.read_raw(reg.number))

    def write(self, key: str | int, value: Any, index: Any = None) -> None:
        """Write a register by name or number, in user units (manual 3.2).

        ``value`` is a scalar (broadcast) or an array with one value per selected motor. The
        write is validated completely first: an unknown register, a read-only one, a value out
        of range or NaN, a wrong shape, or a MODE_REG value the firmware refuses raises a
        :class:`RegisterError` and changes nothing.
        """
        plan = self._key_plan((key,))
        self._write_plan(plan, (value,), _as_index(index, self.n))

    def write_many(self, values: Mapping[str | int, Any], index: Any = None) -> None:
        """Write several registers (key → value in user units, in this order) to the motors
        ``index`` as one transaction.

        Every value is validated before the first is stored, as by :meth:`write`, and a store
        the firmware refuses restores the motors: either all registers are written or nothing
        is changed. Writing in order matters where the manual's rules depend on other
        registers (a mode request after the registers it uses, manual 4.4).

        Examples
        --------
        >>> m.write_many({"V_SOLL": 1600, "P_SOLL": 40960, "MODE_REG": 2}, index=[0, 1])
        """
        idx = _as_index(index, self.n)
        self._write_plan(self._key_plan(tuple(values)), tuple(values.values()), idx)

    def _write_plan(self, plan: _StorePlan, values: tuple[Any, ...], idx: np.ndarray) -> None:
        """Validate ``values`` (user units, one per register of ``plan``) for motors ``idx``,
        then store them (:meth:`_store_many`)."""
        raws = self._batch_raws(plan, values, idx.size)
        if raws is None:  # not plain numbers, or a bad one: validated one by one
            raws = np.empty((len(plan.regs), idx.size), dtype=np.int64)
            for k, (reg, value) in enumerate(zip(plan.regs, values)):
                raws[k] = self._validated_raw(reg, value, idx.size)
        self._store_many(plan, idx, raws)

    def _batch_raws(self, plan: _StorePlan, values: tuple[Any, ...], size: int
                    ) -> np.ndarray | None:
        """Stored integers (K, size) of ``values`` (one per register of ``plan``), converted
        in one compiled pass (:func:`~jvl_gym.registers.formats.raws_of_rows`); None unless
        every register is writable and every value a Python int or float or a real numpy array
        of shape () or (size,) in range (:meth:`_validated_raw` then words the error)."""
        if not plan.writable:
            return None
        floats = np.empty((len(plan.regs), size))
        try:
            for k, value in enumerate(values):
                if type(value) not in (int, float) and not (
                        type(value) is np.ndarray and value.dtype.kind in "iuf"
                        and (value.ndim == 0 or value.shape == (size,))):
                    return None
                floats[k] = value
        except (OverflowError, ValueError, TypeError):
            return None
        raws = np.empty((len(plan.regs), size), dtype=np.int64)
        return raws if raws_of_rows(floats, plan.bounds, raws) < 0 else None

    def write_raw(self, key: str | int, raw: Any, index: Any = None) -> None:
        """Write stored integers (Fixed4 = value·4096, …) with the same validation as write."""
        reg = self._lookup(key)
        idx = _as_index(index, self.n)
        arr = None if isinstance(raw, (bool, np.bool_, str, bytes)) else np.asarray(raw)
        if arr is None or arr.dtype.kind not in "iu":
            raise RegisterRangeError(
                f"{reg.name} (register {reg.number}): raw values must be integers (the stored "
                f"integer: Fixed4 = value·4096, Fixed8 = value·256), got {raw!r}")
        self._validated_raw(reg, arr / reg.scale, idx.size)
        self._store(reg, idx, np.broadcast_to(arr.astype(np.int64), (idx.size,)).copy())

    def _validated_raw(self, reg: Register, value: Any, size: int) -> np.ndarray:
        if reg.access != Access.RW:
            raise ReadOnlyRegisterError(
                f"{reg.name} (register {reg.number}) is {reg.access.value} (manual "
                f"{reg.section}); it cannot be written")
        if type(value) in (int, float):  # a Python scalar: convert it once, then broadcast
            try:
                raw = raws_of_floats(reg, [float(value)])
            except OverflowError:  # an int beyond float range: to_raw words the error
                raw = None
            if raw is not None:
                return np.full(size, raw[0], dtype=np.int64)
        arr = real_values(reg, value)
        if arr.ndim > 1 or (arr.ndim == 1 and arr.shape[0] != size):
            raise RegisterShapeError(
                f"{reg.name} (register {reg.number}): expected a scalar or shape ({size},), "
                f"got shape {arr.shape}")
        if arr.ndim == 0:  # one value, checked once, then one copy per motor
            return np.full(size, to_raw(reg, arr), dtype=np.int64)
        return to_raw(reg, arr)

    def _key_plan(self, keys: tuple[Any, ...]) -> _StorePlan:
        """The store plan of the registers ``keys`` (names are cached, other keys looked up)."""
        try:
            plan = self._plans.get(keys)
        except TypeError:  # an unhashable key: _lookup words the error
            plan = None
        if plan is None:
            plan = _StorePlan.of(tuple(self._lookup(key) for key in keys), self._mode_number,
                                 self.ONE_BY_ONE)
            if all(type(key) is str for key in keys) and len(self._plans) < _PLAN_CACHE_SIZE:
                self._plans[keys] = plan
        return plan

    def _store(self, reg: Register, idx: np.ndarray, raw: np.ndarray) -> None:
        """Check and store the validated stored integers ``raw`` (one per motor of ``idx``) of
        one register; a refused write raises and changes nothing."""
        num = reg.number
        if self._store_special(reg, idx, raw):
            return
        plan = self._plans.get(num)
        if plan is None:
            plan = self._plans[num] = _StorePlan.of((reg,), self._mode_number, self.ONE_BY_ONE)
        self._store_rows(plan, idx, raw.reshape(1, -1))

    def _store_many(self, plan: _StorePlan, idx: np.ndarray, raws: np.ndarray) -> None:
        """Check and store the (K, M) validated stored integers ``raws`` of the registers of
        ``plan`` (in order) in motors ``idx``; if one is refused, the motors are restored."""
        saved = (self.regs[idx], self.state[idx]) if len(plan.regs) > 1 else None
        try:
            if plan.one_by_one or any(self._special_request(raws[k]) for k in plan.mode_rows):
                for reg, raw in zip(plan.regs, raws):
                    self._store(reg, idx, raw)
            else:
                self._store_rows(plan, idx, raws)
        except RegisterError:
            if saved is not None:  # (one register is checked for every motor before it is stored)
                self.regs[idx], self.state[idx] = saved
            raise

    # ------------------------------------------------------------------ flash
    def _load_rw(self, i: int, image: np.ndarray) -> None:
        """Registers of motor ``i`` that flash holds from ``image`` (number of registers,)."""
        rw = self._rw_numbers()
        self.regs[i, rw] = image[rw]

    def _rw_numbers(self) -> np.ndarray:
        """Numbers of the registers flash holds: read-write, not the mode register, not a
        LongInt's high word."""
        return np.array([r.number for r in self.table if r.access == Access.RW
                         and r.number != self._mode_number
                         and r.format != Format.LONGINT_HIGH])

    def flash_image(self, index: int) -> dict[int, int]:
        """The flash contents of one motor (register number → raw), or {} if never written.

        Raises
        ------
        RegisterShapeError
            ``index`` is not an integer in ``-N..N-1``.
        """
        i = _motor_index(index, self.n, "flash_image")
        if self._flash is None or not self._has_flash[i]:
            return {}
        return {int(n): int(self._flash[i, n]) for n in self._rw_numbers()}

    def load_flash_image(self, index: int, image: Mapping[int, int]) -> None:
        """Restore a flash image saved by :meth:`flash_image` (e.g. from a file).

        Registers missing from ``image`` get the ROM defaults. The whole image is checked
        before the flash is touched: a refused image leaves the flash (and the registers) as
        they were.

        Parameters
        ----------
        index : int
            The motor, ``-N..N-1``.
        image : mapping of int to int
            Register number → stored integer (a LongInt as its 32-bit value), for registers
            the flash holds (read-write, not MODE_REG, not a LongInt's high word).

        Raises
        ------
        RegisterShapeError
            ``index`` is not a motor.
        RegisterError
            ``image`` is not a mapping; a key is not a register number the flash holds
            (:class:`~jvl_gym.registers.UnknownRegisterError`, or
            :class:`~jvl_gym.registers.ReadOnlyRegisterError` for a read-only one); a value is
            not an integer or is out of its register's range
            (:class:`~jvl_gym.registers.RegisterRangeError`).
        """
        i = _motor_index(index, self.n, "load_flash_image")
        if not isinstance(image, Mapping):
            raise RegisterError(f"load_flash_image: the image must be a mapping register number "
                                f"→ stored integer (as flash_image returns), got {image!r}. "
                                "Nothing was changed.")
        stored = set(self._rw_numbers().tolist())
        staged = self._rom[self._type_of[i]].copy()
        for num, raw in image.items():
            if isinstance(num, (bool, np.bool_)) or not isinstance(num, (int, np.integer)):
                raise RegisterError(f"load_flash_image: key {num!r} is not a register number. "
                                    "Nothing was changed.")
            reg = self.table.lookup(int(num))
            if reg.access != Access.RW:
                raise ReadOnlyRegisterError(
                    f"load_flash_image: {reg.name} (register {reg.number}) is "
                    f"{reg.access.value} (manual {reg.section}); flash holds read-write "
                    "registers only. Nothing was changed.")
            if reg.number not in stored:
                raise RegisterError(
                    f"load_flash_image: {reg.name} (register {reg.number}) is not stored in "
                    "flash (MODE_REG and a LongInt's high word are not; a LongInt is stored as "
                    "its 32-bit value under its first number). Nothing was changed.")
            if isinstance(raw, (bool, np.bool_)) or not isinstance(raw, (int, np.integer)):
                raise RegisterRangeError(
                    f"load_flash_image: {reg.name} (register {reg.number}) = {raw!r}: a flash "
                    "image holds stored integers. Nothing was changed.")
            to_raw(reg, float(np.clip(int(raw), -2.0**63, 2.0**63)) / reg.scale)  # range
            staged[reg.number] = int(raw)
        if self._flash is None:
            self._flash = np.zeros_like(self.regs)
        self._flash[i] = staged
        self._has_flash[i] = True

    def _check_setup_keys(self, registers: Mapping[str, Any]) -> None:
        """Refuse a setup that contains MODE_REG (a setup is parameters, not a command)."""
        if any(self._lookup(name).number == self._mode_number for name in registers):
            raise RegisterError("a setup must not contain MODE_REG (manual 3.2.2: a mode is "
                                "requested after the parameters are written)")

    def load_setup(self, setup: str | os.PathLike[str] | dict[str, Any], index: Any = None
                   ) -> None:
        """Write a register set (name → value) to the selected motors, validated as a whole."""
        cfg = load_setup(setup)
        self._check_setup_keys(cfg.registers)
        self.write_many(cfg.registers, index)

    def __repr__(self) -> str:
        types = sorted({cfg.name for cfg in self._configs})
        return f"MotorArray({'/'.join(types)}, n={self.n})"
