"""MotorArray: N simulated MAC motors, read and written by register name or number.

The array holds the register banks, plant and firmware state of N motors as (N, ·) arrays
(``jvl_gym.layout``) and advances them with one compiled kernel (``jvl_gym.kernel``). Everything
else here is the thin Python layer a user talks to: validated register access (manual 3.2),
mode requests (4.4), world inputs, power-on / partial reset with new per-motor parameters, the
sample buffer, flash, and the physical truth for plots and tests.
"""

from __future__ import annotations

import functools
import math
import os
from collections.abc import Mapping, Sequence
from typing import Any, NamedTuple

import numpy as np

from . import constants as c
from . import layout as L
from .config import MotorConfig, load_motor, load_setup
from .firmware import modes as M
from .firmware import regs as R
from .firmware import write_rules as W
from .firmware.monitor import filter_gain
from .firmware.noise import motor_keys
from .lanes import compile_first, lane_scratch, run_parallel, run_serial
from .power_on import (
    BINARY,
    FINITE,
    NONNEGATIVE,
    POSITIVE,
    first_bad_value,
    power_on_from_memory,
    reset_rows,
)
from .registers import (
    MAC050_141,
    Access,
    Format,
    ReadOnlyRegisterError,
    Register,
    RegisterError,
    RegisterRangeError,
    RegisterShapeError,
)
from .registers.formats import (
    from_raw,
    raw_bounds,
    raws_of_floats,
    raws_of_rows,
    real_values,
    to_raw,
)
from .store import store_rows

__all__ = ["MotorArray", "ModeError", "PARAMETER_KEYWORDS"]

#: per-motor parameter keywords of the constructor and :meth:`MotorArray.reset` (SI units)
PARAMETER_KEYWORDS: dict[str, int] = {
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
}
_NONNEGATIVE = {"load_inertia", "viscous_friction", "coulomb_friction", "current_noise",
                "position_noise", "torque_noise", "end_stop_stiffness", "end_stop_damping"}
_POSITIVE = {"phase_resistance", "phase_inductance", "rotor_inertia", "flux_linkage"}
_BINARY = {"pwm_delay_samples", "hall_start"}
#: per-motor initial state keywords of the constructor and :meth:`MotorArray.reset`
_STATE_KEYWORDS: dict[str, int] = {
    "initial_angle": L.S_THETA,  # rad
    "initial_speed": L.S_OMEGA,  # rad/s
}
#: value rules of each reset keyword (``jvl_gym.power_on.first_bad_value``): finite but for
#: the home position (inf: none), then >= 0, > 0 or 0/1
_VALUE_RULES: dict[str, int] = {
    name: ((FINITE if name != "home_position" else 0) | (NONNEGATIVE if name in _NONNEGATIVE else 0)
           | (POSITIVE if name in _POSITIVE else 0) | (BINARY if name in _BINARY else 0))
    for name in [*PARAMETER_KEYWORDS, *_STATE_KEYWORDS]
}
_RULE_TEXT = {FINITE: "finite", NONNEGATIVE: ">= 0", POSITIVE: "> 0"}

_PARALLEL_MIN_MOTORS = 32
#: up to this many int64 indices are checked with Python ints (``_as_index``)
_FEW = 8
#: register-key tuples whose store plan a MotorArray keeps (``MotorArray._key_plan``)
_PLAN_CACHE_SIZE = 256
#: modes that record into the sample buffer (allocated on first use)
_RECORDING_MODES = frozenset({c.TESTU_MODE, c.TESTA_MODE, c.TESTKI_MODE, c.TESTTQ_MODE})


class ModeError(RegisterError):
    """A MODE_REG write or a mode command that the firmware's rules refuse (manual 4.4)."""


def _special_modes(req: np.ndarray) -> bool:
    """A MODE_REG request in ``req`` is a SAFE_MODE command (256..258) or a test mode that
    records (allocates the sample buffer): stored by ``MotorArray._request_modes``."""
    return any(r >= 256 or r in _RECORDING_MODES for r in req.tolist())


class _StorePlan(NamedTuple):
    """Registers stored together, with the arrays of :func:`jvl_gym.store.store_rows`."""

    regs: tuple[Register, ...]
    nums: np.ndarray  #: (K,) int64 register numbers
    high: np.ndarray  #: (K,) bool: a LongInt's high word
    mode_rows: tuple[int, ...]  #: positions of MODE_REG
    one_by_one: bool  #: stored register by register (a register-mode pointer, CNTRL_BITS)
    writable: bool  #: every register is read-write
    bounds: np.ndarray  #: (K, 6) conversion constants (``registers.formats.raw_bounds``)

    @classmethod
    def of(cls, regs: tuple[Register, ...]) -> _StorePlan:
        """The plan of storing ``regs`` in this order."""
        nums = [reg.number for reg in regs]
        writable = all(reg.access == Access.RW for reg in regs)
        return cls(regs, np.array(nums, dtype=np.int64),
                   np.array([reg.format == Format.LONGINT_HIGH for reg in regs], dtype=np.bool_),
                   tuple(k for k, num in enumerate(nums) if num == R.MODE_REG),
                   any(num in W.POINTERS or num == R.CNTRL_BITS for num in nums), writable,
                   np.array([raw_bounds(reg) for reg in regs] if writable else [],
                            dtype=np.float64).reshape(-1, 6))


@functools.lru_cache(maxsize=64)
def _keyword_plan(names: tuple[str, ...]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Columns (P,) int64 of reset keywords ``names`` in ``params`` or, where the (P,) bool
    is set, in ``state``, and their value rules (P,) int64 (:data:`_VALUE_RULES`)."""
    cols = [PARAMETER_KEYWORDS.get(name, _STATE_KEYWORDS.get(name)) for name in names]
    return (np.array(cols, dtype=np.int64),
            np.array([name in _STATE_KEYWORDS for name in names], dtype=np.bool_),
            np.array([_VALUE_RULES[name] for name in names], dtype=np.int64))


def _raise_bad_value(names: tuple[str, ...], values: np.ndarray, given: list[Any]) -> None:
    """Raise ValueError for the first of the reset keywords ``names`` whose values (rows of
    ``values``, as ``given``) break their rules (:data:`_VALUE_RULES`)."""
    bad = first_bad_value(values, _keyword_plan(names)[2])
    if bad < 0:
        return
    q, rule = divmod(bad, 16)
    name, val = names[q], given[q]
    if rule == BINARY:
        raise ValueError(f"{name} must be 0 or 1, got {val!r}")
    raise ValueError(f"{name}: values must be {_RULE_TEXT[rule]}, got {val!r}")


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
    """N simulated MAC50–141 motors sharing one compiled kernel.

    Parameters
    ----------
    motor : str, path, MotorConfig, or a sequence of those of length ``n``
        Motor type name (``"MAC140"``), config path, or one per motor (mixed arrays).
    n : int
        Number of motors N.
    seed : int, sequence of int, or None
        Noise seeding. An int gives motor ``i`` the key ``motor_keys(seed, n)[i]``; a sequence
        gives the keys directly (so one motor of an array can be reproduced on its own).
    setup : str, path, dict, or None
        Register set written over the ROM defaults at power-on; default: the motor type's
        ``configs/setups/<TYPE>.yaml``.
    record_length : int
        Samples recorded by TESTU / TESTA (manual: 11), up to 895.
    **params
        Per-motor parameters (scalars or (N,) arrays), see :data:`PARAMETER_KEYWORDS`, plus
        ``initial_angle`` [rad] and ``initial_speed`` [rad/s].

    Examples
    --------
    >>> m = MotorArray("MAC140", n=4, seed=0, load_inertia=0.0)
    >>> m.write("MODE_REG", 1); m.write("V_SOLL", 1600); m.run(seconds=0.3)
    >>> m.speed_rpm  # ≈ 762.9 rpm for every motor
    """

    def __init__(self, motor: Any = "MAC140", n: int = 1, seed: Any = None,
                 setup: Any = None, record_length: int = c.TEST_RECORD_SAMPLES,
                 **params: Any) -> None:
        if isinstance(n, (bool, np.bool_)) or int(n) != n or n < 1:
            raise ValueError(f"n must be a positive integer, got {n!r}")
        self.n = int(n)
        self.table = MAC050_141
        motors = list(motor) if isinstance(motor, (list, tuple)) else [motor] * self.n
        if len(motors) != self.n:
            raise ValueError(f"got {len(motors)} motor types for n={self.n}")
        configs: dict[str, MotorConfig] = {}
        self._type_of = np.zeros(self.n, dtype=np.int64)
        for i, mtype in enumerate(motors):
            cfg = load_motor(mtype)
            configs.setdefault(cfg.name, cfg)
            self._type_of[i] = list(configs).index(cfg.name)
        self._setup_arg = setup
        self._configs: list[MotorConfig] = []
        self._type_codes: dict[str, int] = {}  #: type name -> index in the pool
        self._rom = np.zeros((0, L.N_REGS), dtype=np.int64)
        self._type_params = np.zeros((0, L.N_PARAM))
        self._type_inputs = np.zeros((0, L.N_INPUT))
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
        self.regs = np.zeros((self.n, L.N_REGS), dtype=np.int64)
        self.state = np.zeros((self.n, L.N_STATE), dtype=np.float64)
        self.params = np.zeros((self.n, L.N_PARAM), dtype=np.float64)
        self.inputs = np.zeros((self.n, L.N_INPUT), dtype=np.float64)
        self._buf = np.zeros((1, c.REC_CNT_MAX, 4), dtype=np.int64)
        self._buf_allocated = False
        self._no_schedule = np.zeros((0, self.n, L.N_INPUT), dtype=np.float64)
        self._scratch = lane_scratch(self.n)
        self._latched_cntrl = np.zeros(self.n, dtype=np.int64)
        #: world signal sources (``jvl_gym.world.World``) sampled every outer sample, or None
        self.world = None
        self._flash: np.ndarray | None = None
        self._has_flash = np.zeros(self.n, dtype=np.bool_)
        self._fmt = self.table.fmt_code_array
        #: store plans by register-name tuple (``_write_many``) and by number (``_store``)
        self._plans: dict[Any, _StorePlan] = {}
        self.set_record_length(record_length)
        self.reset(**params)

    # ------------------------------------------------------------------ configuration
    def _rom_image(self, cfg: MotorConfig, setup: Any) -> np.ndarray:
        """ROM defaults of one motor type: the table defaults with the type's setup applied.

        The setup is validated as :meth:`load_setup` validates it (no MODE_REG, no read-only
        register, values in range, the firmware's write rules in the order given); a refusal
        raises the :class:`RegisterError` naming the setup.
        """
        image = self.table.default_raw_array.astype(np.int64).copy()
        source = setup if setup is not None else cfg.setup
        setup_cfg = load_setup(source)
        row = image[None]  # a one-motor register bank over ``image``
        first = np.zeros(1, dtype=np.int64)
        try:
            self._check_setup_keys(setup_cfg.registers)
            for name, value in setup_cfg.registers.items():
                reg = self._lookup(name)
                raw = self._validated_raw(reg, value, 1)
                problem = W.check_write(row, first, reg.number, raw)
                if problem is not None:
                    raise RegisterError(f"{reg.name} (register {reg.number}) = {value!r} "
                                        f"refused: {problem}")
                if reg.number in W.POINTERS:
                    W.apply_pointer(row, first, reg.number, raw)
                elif reg.format == Format.LONGINT_HIGH:
                    full = (int(raw[0]) << 16) | (int(image[reg.number - 1]) & 0xFFFF)
                    image[reg.number - 1] = ((full + 2**31) % 2**32) - 2**31
                else:
                    image[reg.number] = raw[0]
        except RegisterError as exc:
            where = "setup mapping" if isinstance(source, Mapping) else f"setup {source}"
            raise type(exc)(f"{where}: {exc}") from exc
        image[R.MOTOR_TYPE] = cfg.motor_type_code
        return image

    def _add_type(self, cfg: MotorConfig) -> None:
        """Join motor type ``cfg`` to the pool: its ROM image, parameters and inputs at rest."""
        self._configs.append(cfg)
        self._rom = np.concatenate([self._rom, self._rom_image(cfg, self._setup_arg)[None]])
        self._type_params = np.concatenate([self._type_params, self._config_params(cfg)[None]])
        self._type_inputs = np.concatenate([self._type_inputs, self._rest_inputs(cfg)[None]])

    def _rest_inputs(self, cfg: MotorConfig) -> np.ndarray:
        """World inputs at rest: supply on, home sensor from the position, nothing else."""
        inputs = np.zeros(L.N_INPUT)
        inputs[L.I_SUPPLY_VOLTS] = cfg.supply_voltage
        inputs[L.I_HOME] = -1.0
        return inputs

    def _config_params(self, cfg: MotorConfig) -> np.ndarray:
        p = np.zeros(L.N_PARAM)
        p[L.P_J_MOTOR] = cfg.rotor_inertia
        p[L.P_R] = cfg.phase_resistance
        p[L.P_L] = cfg.phase_inductance
        p[L.P_LAMBDA] = cfg.flux_linkage
        p[L.P_AMPS_PER_COUNT] = cfg.amps_per_count
        p[L.P_POLE_PAIRS] = cfg.pole_pairs
        p[L.P_PWM_DELAY] = cfg.pwm_delay_samples
        p[L.P_K_THERMAL] = filter_gain(cfg.thermal_time_constant)
        p[L.P_K_REGEN] = filter_gain(cfg.regen_time_constant)
        p[L.P_C_BUS] = cfg.bus_capacitance
        p[L.P_R_SUPPLY] = cfg.supply_resistance
        p[L.P_U_DUMP] = cfg.dump_voltage
        p[L.P_R_DUMP] = cfg.dump_resistance
        p[L.P_STOP_LO] = 1.0
        p[L.P_STOP_HI] = -1.0
        p[L.P_STOP_K] = 50.0
        p[L.P_STOP_D] = 0.05
        p[L.P_HOME_POS] = math.inf
        return p

    def _type_code(self, name: str) -> int:
        """Index of motor type ``name`` in the pool of types, adding it on first use."""
        code = self._type_codes.get(name)
        if code is not None:
            return code
        names = [known.name for known in self._configs]
        if name in names:
            code = self._type_codes[name] = names.index(name)  # a type name: kept
            return code
        cfg = load_motor(name)  # raises on an unknown type, before any motor changes
        if cfg.name not in names:
            self._add_type(cfg)
            names.append(cfg.name)
        return names.index(cfg.name)

    @property
    def motor_configs(self) -> list[MotorConfig]:
        """Motor config of each motor (length N)."""
        return [self._configs[k] for k in self._type_of]

    @property
    def parameters(self) -> dict[str, np.ndarray]:
        """Per-motor physical parameters in SI units, as (N,) arrays (copies)."""
        return {name: self.params[:, col].copy() for name, col in PARAMETER_KEYWORDS.items()}

    def set_record_length(self, n_samples: int, index: Any = None) -> None:
        """Samples recorded by TESTU/TESTA (manual default 11; up to REC_CNT_MAX = 895)."""
        try:
            whole = (not isinstance(n_samples, (bool, np.bool_, str, bytes))
                     and int(n_samples) == n_samples)
        except (TypeError, ValueError, OverflowError):
            whole = False
        if not whole or not 1 <= n_samples <= c.REC_CNT_MAX:
            raise ValueError(f"record length must be an integer in 1..{c.REC_CNT_MAX}, "
                             f"got {n_samples!r}")
        self.state[_as_index(index, self.n), L.S_REC_LEN] = float(n_samples)

    # ------------------------------------------------------------------ reset
    def reset(self, index: Any = None, motor_type: str | Sequence[str] | None = None,
              **params: Any) -> None:
        """Power-on reset of the motors in ``index`` with optional new per-motor parameters.

        Registers come from flash (if written) or the ROM defaults; P_IST = 0; the rotor is at
        ``initial_angle`` [rad] turning at ``initial_speed`` [rad/s] (default 0); all firmware
        state is cleared; world inputs return to rest. Other motors are untouched.
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
        cols, to_state, _ = _keyword_plan(names)
        reset_rows(self.regs, self.state, self.params, self.inputs, self._latched_cntrl, idx,
                   self._type_of[idx], self._rom, self._type_params, self._type_inputs,
                   self._rom if self._flash is None else self._flash, self._has_flash,
                   cols, to_state, values)

    def _check_params(self, params: dict[str, Any], size: int
                      ) -> tuple[tuple[str, ...], np.ndarray]:
        """The keywords of ``params`` and their values as rows of a (P, size) float64 array,
        checked (:data:`_VALUE_RULES`); raises on the first bad keyword, in order."""
        names = tuple(params)
        values = np.empty((len(names), size))
        for q, (name, val) in enumerate(params.items()):
            try:
                if name not in PARAMETER_KEYWORDS and name not in _STATE_KEYWORDS:
                    known = ", ".join(sorted([*PARAMETER_KEYWORDS, *_STATE_KEYWORDS]))
                    raise TypeError(f"unknown motor parameter {name!r}; known: {known}")
                arr = _real_array(name, val, allow_bool=name in _BINARY)
                if arr.ndim > 1 or (arr.ndim == 1 and arr.shape[0] != size):
                    raise ValueError(f"{name}: expected a scalar or shape ({size},), "
                                     f"got {arr.shape}")
            except (TypeError, ValueError):
                _raise_bad_value(names[:q], values[:q], list(params.values()))
                raise
            values[q] = arr
        _raise_bad_value(names, values, list(params.values()))
        return names, values

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

    # ------------------------------------------------------------------ stepping
    def step(self, n_outer: int = 1) -> None:
        """Advance all motors by ``n_outer`` outer samples (1.92 ms each, 15 inner samples)."""
        n_outer = _outer_count(n_outer, "step")
        if n_outer == 0:
            return
        compile_first(self.regs, self.state, self.params, self.inputs, self.keys, self._buf,
                      self._fmt, self._scratch)
        run = run_parallel if self.n >= _PARALLEL_MIN_MOTORS else run_serial
        plan = self._no_schedule if self.world is None else self.world.schedule(self, n_outer)
        run(self.regs, self.state, self.params, self.inputs, self.keys, self._buf,
            self._buf_allocated, self._fmt, int(n_outer), plan, self._scratch)

    def kernel_arrays(self) -> tuple:
        """The arrays the compiled kernel works on, for compiled callers (the env steps):
        ``(regs, state, params, inputs, keys, buf, rec, fmt, input_plan, scratch)``, the first
        nine in the order of the first arguments of :func:`jvl_gym.lanes.advance_block`, with
        the held-input plan, and the blocks' working memory (:func:`jvl_gym.lanes.lane_scratch`).

        A caller that advances motors itself bypasses the :attr:`world` schedule (inputs are
        held): it sets ``inputs`` between samples instead.
        """
        compile_first(self.regs, self.state, self.params, self.inputs, self.keys, self._buf,
                      self._fmt, self._scratch)
        return (self.regs, self.state, self.params, self.inputs, self.keys, self._buf,
                self._buf_allocated, self._fmt, self._no_schedule, self._scratch)

    def run(self, seconds: float) -> None:
        """Advance by ``seconds`` (rounded to whole outer samples of 1.92 ms)."""
        real = (int, float, np.integer, np.floating)
        if (isinstance(seconds, (bool, np.bool_)) or not isinstance(seconds, real)
                or not math.isfinite(seconds) or seconds < 0):
            raise ValueError(f"seconds must be a finite number >= 0, got {seconds!r}")
        self.step(int(round(seconds * c.OUTER_HZ)))

    def trace(self, keys: list[str | int], n_outer: int) -> dict[str, np.ndarray]:
        """Step ``n_outer`` outer samples and record registers and physical quantities.

        ``keys`` are register names/numbers or the properties ``speed_rpm``, ``position_rad``,
        ``torque``, ``bus_voltage``. Returns ``{"t": (T,), key: (T, N)}`` (user units), like a
        scope attached to every motor at the outer rate.
        """
        n_outer = _outer_count(n_outer, "trace")
        physical = {"speed_rpm", "speed_rad_s", "position_rad", "torque", "bus_voltage"}
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

    @property
    def time(self) -> np.ndarray:
        """Time since power-on of each motor [s], (N,)."""
        return self.state[:, L.S_TICK] * c.INNER_DT

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

        A value is a real number (an int or float, or an integer or float array): a str,
        bytes, bool or complex value is refused. A quantity is rounded half away from zero to
        the register's resolution (``V_SOLL = 1600.7`` stores 1601, ``KVOUT = 3.9`` stores
        998/256); a register that holds a code (MODE_REG, CNTRL_BITS, HOME_MODE, STARTMODE,
        the pointers, SAMPLE1..4, MYADDR …: ``registers.formats.whole_only``) takes whole
        numbers only. ``index`` selects motors (:func:`_as_index`): None, an integer, a slice,
        distinct integers, or a boolean mask of shape (N,).
        """
        plan = self._key_plan((key,))
        self._write_plan(plan, (value,), _as_index(index, self.n))

    def _write_many(self, values: Mapping[str | int, Any], index: Any = None) -> None:
        """Write several registers (key → value in user units, in this order) to the motors
        ``index``; every value is validated before the first is stored, as by :meth:`write`,
        and a store the firmware refuses restores the motors (nothing is changed)."""
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
            plan = _StorePlan.of(tuple(self._lookup(key) for key in keys))
            if all(type(key) is str for key in keys) and len(self._plans) < _PLAN_CACHE_SIZE:
                self._plans[keys] = plan
        return plan

    def _store(self, reg: Register, idx: np.ndarray, raw: np.ndarray) -> None:
        """Check and store the validated stored integers ``raw`` (one per motor of ``idx``) of
        one register; a refused write raises and changes nothing."""
        num = reg.number
        if num == R.MODE_REG and _special_modes(raw):
            self._request_modes(reg, idx, raw)
            return
        if num in W.POINTERS:
            self._check_refusal(reg, idx, raw)
            W.apply_pointer(self.regs, idx, num, raw)
            return
        if num == R.CNTRL_BITS and np.any(raw & c.RECORDBIT):
            self._ensure_buffer()
        plan = self._plans.get(num)
        if plan is None:
            plan = self._plans[num] = _StorePlan.of((reg,))
        self._store_rows(plan, idx, raw.reshape(1, -1))

    def _store_many(self, plan: _StorePlan, idx: np.ndarray, raws: np.ndarray) -> None:
        """Check and store the (K, M) validated stored integers ``raws`` of the registers of
        ``plan`` (in order) in motors ``idx``; if one is refused, the motors are restored."""
        saved = (self.regs[idx], self.state[idx]) if len(plan.regs) > 1 else None
        try:
            if plan.one_by_one or any(_special_modes(raws[k]) for k in plan.mode_rows):
                for reg, raw in zip(plan.regs, raws):
                    self._store(reg, idx, raw)
            else:
                self._store_rows(plan, idx, raws)
        except RegisterError:
            if saved is not None:  # (one register is checked for every motor before it is stored)
                self.regs[idx], self.state[idx] = saved
            raise

    def _store_rows(self, plan: _StorePlan, idx: np.ndarray, raws: np.ndarray) -> None:
        """Compiled check and store (:func:`jvl_gym.store.store_rows`); a refusal raises with
        the registers before the refused one stored."""
        k = store_rows(self.regs, self.state, idx, plan.nums, plan.high, raws)
        if k >= 0:
            self._check_refusal(plan.regs[k], idx, raws[k])
            raise AssertionError(f"{plan.regs[k].name}: compiled store refused a write the "
                                 "rules accept")  # pragma: no cover - the rules are shared

    def _check_refusal(self, reg: Register, idx: np.ndarray, raw: np.ndarray) -> None:
        """Raise the firmware's refusal of storing ``raw`` in register ``reg`` of motors
        ``idx`` (mode-change rules of manual 4.4 and ``jvl_gym.firmware.write_rules``), if any.

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

    # ------------------------------------------------------------------ safe mode, flash
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

    def _load_rw(self, i: int, image: np.ndarray) -> None:
        rw = self._rw_numbers()
        self.regs[i, rw] = image[rw]

    def _rw_numbers(self) -> np.ndarray:
        return np.array([r.number for r in self.table if r.access == Access.RW
                         and r.number != R.MODE_REG and r.format != Format.LONGINT_HIGH])

    def _indices_in(self, idx: np.ndarray, modes: tuple[int, ...], what: str) -> None:
        bad = idx[~M.member(self.regs[idx, R.MODE_REG], modes)]
        if bad.size:
            names = " or ".join(c.MODE_NAMES[m] for m in modes)
            raise ModeError(f"{what} needs {names} (manual 4.4.16); motor {int(bad[0])} is in "
                            f"{c.MODE_NAMES.get(int(self.regs[bad[0], R.MODE_REG]), '?')}")

    def go_safe_mode(self, index: Any = None) -> None:
        """MacTalk 'go safe mode' (5.1): stop if moving, then SAFE_MODE (4.4.16)."""
        M.go_safe(self.regs, self.state, _as_index(index, self.n))

    def go_init_mode(self, index: Any = None) -> None:
        """MacTalk 'go init mode' (5.1): the protective path to INIT_MODE."""
        M.go_init(self.regs, self.state, _as_index(index, self.n))

    def exit_safe_mode(self, index: Any = None) -> None:
        """Leave SAFE_MODE; the motor always goes to INIT_MODE (manual 2.2)."""
        idx = _as_index(index, self.n)
        self._indices_in(idx, (c.SAFE_MODE,), "exit_safe_mode")
        M.go_init(self.regs, self.state, idx)

    def _save_flash(self, idx: np.ndarray) -> None:
        if self._flash is None:
            self._flash = np.zeros((self.n, L.N_REGS), dtype=np.int64)
        rw = self._rw_numbers()
        self._flash[np.ix_(idx, rw)] = self.regs[np.ix_(idx, rw)]
        self._flash[idx, R.PROG_VERSION] = self._rom[self._type_of[idx], R.PROG_VERSION]
        self._has_flash[idx] = True

    def write_flash(self, index: Any = None) -> None:
        """Save the register set to flash and reset; only in SAFE_MODE (manual 2.2, 5.1)."""
        idx = _as_index(index, self.n)
        self._indices_in(idx, (c.SAFE_MODE,), "write_flash")
        self._save_flash(idx)
        self.software_reset(idx)

    def software_reset(self, index: Any = None) -> None:
        """Reset the electronics (registers from flash/ROM, P_IST = 0); INIT or SAFE only.

        The rotor keeps its physical angle and speed: only the firmware restarts.
        """
        idx = _as_index(index, self.n)
        self._indices_in(idx, (c.INIT_MODE, c.SAFE_MODE), "software_reset")
        keep = [L.S_THETA, L.S_OMEGA, L.S_I_RE, L.S_I_IM, L.S_ACC, L.S_UBUS, L.S_DUMP_ON,
                L.S_TICK, L.S_REC_LEN, L.S_E_ELEC, L.S_E_COPPER, L.S_E_FRICTION, L.S_E_LOAD,
                L.S_E_DUMP, L.S_E_SUPPLY, L.S_I2T_Q, L.S_UIT_Q]
        saved = self.state[np.ix_(idx, keep)].copy()
        self.state[idx] = 0.0
        self.state[np.ix_(idx, keep)] = saved
        self._power_on(idx)

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
            self._flash = np.zeros((self.n, L.N_REGS), dtype=np.int64)
        self._flash[i] = staged
        self._has_flash[i] = True

    def _check_setup_keys(self, registers: Mapping[str, Any]) -> None:
        """Refuse a setup that contains MODE_REG (a setup is parameters, not a command)."""
        if any(self._lookup(name).number == R.MODE_REG for name in registers):
            raise RegisterError("a setup must not contain MODE_REG (manual 3.2.2: a mode is "
                                "requested after the parameters are written)")

    def load_setup(self, setup: str | os.PathLike[str] | dict[str, Any], index: Any = None
                   ) -> None:
        """Write a register set (name → value) to the selected motors, validated as a whole."""
        cfg = load_setup(setup)
        self._check_setup_keys(cfg.registers)
        self._write_many(cfg.registers, index)

    # ------------------------------------------------------------------ sample buffer
    def _ensure_buffer(self) -> None:
        if not self._buf_allocated:
            self._buf = np.zeros((self.n, c.REC_CNT_MAX, 4), dtype=np.int64)
            self._buf_allocated = True

    def sample_buffer_raw(self, index: int) -> np.ndarray:
        """Raw samples of one motor, shape (REC_CNT, 4) for SAMPLE1..SAMPLE4."""
        index = _motor_index(index, self.n, "sample_buffer_raw")
        count = int(self.regs[index, R.REC_CNT])
        if not self._buf_allocated:
            return np.zeros((0, 4), dtype=np.int64)
        return self._buf[index, :count].copy()

    def sample_buffer(self) -> dict[str, np.ndarray]:
        """The sample buffer in user units: {register name: (N, max REC_CNT) array}.

        Channels are named after SAMPLE1..SAMPLE4 of motor 0 (a channel whose register differs
        between motors is named ``SAMPLEk``); entries past a motor's REC_CNT are 0.
        """
        count = int(self.regs[:, R.REC_CNT].max()) if self._buf_allocated else 0
        valid = np.arange(count)[None, :] < self.regs[:, R.REC_CNT][:, None]
        out: dict[str, np.ndarray] = {}
        for ch, num in enumerate((R.SAMPLE1, R.SAMPLE2, R.SAMPLE3, R.SAMPLE4)):
            nums = self.regs[:, num]
            raw = np.where(valid, self._buf[:, :count, ch], 0) if count else np.zeros(
                (self.n, 0), dtype=np.int64)
            reg = self.table.lookup(int(nums[0])) if 1 <= nums[0] <= 164 else None
            if reg is None or np.any(nums != nums[0]) or reg.name in out:
                out[f"SAMPLE{ch + 1}"] = raw  # raw values: no single register to name them by
            else:
                out[reg.name] = from_raw(reg, raw)
        return out

    # ------------------------------------------------------------------ world inputs
    def set_input(self, index: Any = None, *, load_torque: Any = None, analog_volts: Any = None,
                  pulse_counts: Any = None, home: Any = None, supply_volts: Any = None) -> None:
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
        idx = _as_index(index, self.n)
        staged = []
        for name, val, col in (("load_torque", load_torque, L.I_LOAD_TORQUE),
                               ("analog_volts", analog_volts, L.I_ANALOG_VOLTS),
                               ("pulse_counts", pulse_counts, L.I_PULSE_COUNTS),
                               ("home", home, L.I_HOME),
                               ("supply_volts", supply_volts, L.I_SUPPLY_VOLTS)):
            if val is None:
                continue
            arr = _real_array(name, val, allow_bool=name == "home")
            if arr.ndim > 1 or (arr.ndim == 1 and arr.shape[0] != idx.size):
                raise ValueError(f"{name}: expected a scalar or shape ({idx.size},), "
                                 f"got {arr.shape}")
            if not np.all(np.isfinite(arr)):
                raise ValueError(f"{name}: values must be finite, got {val!r}")
            if name == "pulse_counts" and np.any(arr != np.round(arr)):
                raise ValueError("pulse_counts must be whole counts per outer sample")
            if name == "supply_volts" and np.any((arr < 0) | (arr > 60)):
                raise ValueError("supply_volts must be within 0..60 V")
            staged.append((col, np.broadcast_to(arr, (idx.size,))))
        for col, arr in staged:
            self.inputs[idx, col] = arr

    # ------------------------------------------------------------------ physical truth
    @property
    def speed_rpm(self) -> np.ndarray:
        """Shaft speed [rpm], (N,)."""
        return self.state[:, L.S_OMEGA] * 60.0 / (2.0 * math.pi)

    @property
    def speed_rad_s(self) -> np.ndarray:
        """Shaft speed [rad/s], (N,)."""
        return self.state[:, L.S_OMEGA].copy()

    @property
    def position_rad(self) -> np.ndarray:
        """Shaft angle [rad] relative to the world zero, (N,)."""
        return self.state[:, L.S_THETA].copy()

    def _current_vector(self) -> np.ndarray:
        """Stator current space vector [A], (N,) complex (``jvl_gym.plant.coil``)."""
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
        """Energy accounts since power-on [J], (N,) each, and the kinetic energy now."""
        s = self.state
        j = self.params[:, L.P_J_MOTOR] + self.params[:, L.P_J_LOAD]
        return {
            "electrical": s[:, L.S_E_ELEC].copy(),
            "copper": s[:, L.S_E_COPPER].copy(),
            "friction": s[:, L.S_E_FRICTION].copy(),
            "load": s[:, L.S_E_LOAD].copy(),
            "dump": s[:, L.S_E_DUMP].copy(),
            "supply": s[:, L.S_E_SUPPLY].copy(),
            "kinetic": 0.5 * j * s[:, L.S_OMEGA] ** 2,
        }

    def mode_name(self, index: int = 0) -> str:
        """Name of the current mode of one motor."""
        index = _motor_index(index, self.n, "mode_name")
        return c.MODE_NAMES.get(int(self.regs[index, R.MODE_REG]), "?")

    def __repr__(self) -> str:
        types = sorted({cfg.name for cfg in self._configs})
        return f"MotorArray({'/'.join(types)}, n={self.n})"
