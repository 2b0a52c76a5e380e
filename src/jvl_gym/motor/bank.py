"""Register access of a motor array: read and write by name or number, validated, in batches.

Values are checked against the family's register table (format, range, access; manual 3.1,
3.2 for the MACs) before anything is stored; several registers written together are checked
and stored as one transaction (:meth:`RegisterBank.write_many`); the family's firmware rules
decide in its hooks (:meth:`RegisterBank._store_rows`, :meth:`RegisterBank._store_special`).
"""

from __future__ import annotations

import logging
import os
import warnings
from abc import ABC, abstractmethod
from collections.abc import Callable, Mapping
from typing import Any, ClassVar, NamedTuple

import numpy as np

from ..families.config import load_setup
from ..registers import (
    Access,
    Conformance,
    Format,
    NotModelledWarning,
    ReadOnlyRegisterError,
    Register,
    RegisterError,
    RegisterRangeError,
    RegisterShapeError,
    RegisterTable,
)
from ..registers.formats import (
    from_raw,
    raw_bounds,
    raws_of_floats,
    raws_of_rows,
    real_values,
    to_raw,
)
from .arguments import MotorIndex, RegisterKey, RegisterValue, as_index

__all__ = ["RegisterBank", "StorePlan"]

#: register-key tuples whose store plan an array keeps (``RegisterBank._key_plan``)
_PLAN_CACHE_SIZE = 256
#: where a write of a register the simulator does not model is logged (the twin's log too)
log = logging.getLogger("jvl_gym.conformance")


class StorePlan(NamedTuple):
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
           one_by_one: frozenset[int]) -> StorePlan:
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


class RegisterBank(ABC):
    """The register access of :class:`~jvl_gym.MotorArray` (a mixin over its ``regs``,
    ``state``, ``table`` and ``n``)."""

    n: int
    table: RegisterTable
    regs: np.ndarray
    state: np.ndarray
    params: np.ndarray
    inputs: np.ndarray
    _flash: np.ndarray | None
    _has_flash: np.ndarray
    _plans: dict[Any, StorePlan]
    _read_columns: dict[str, tuple[int, bool]]
    _mode_number: int
    #: registers stored one at a time through :meth:`_store_special` (numbers)
    ONE_BY_ONE: ClassVar[frozenset[int]] = frozenset()
    #: the family's conformance matrix (``registers.conformance``): a write of a value other
    #: than the default to a register or bit it calls not modelled warns once per register
    CONFORMANCE: ClassVar[Conformance | None] = None
    #: per-motor arrays (first axis: the motors) a refused transaction restores, besides the
    #: flash (:meth:`_snapshot`); a family whose writes change further arrays names them
    TRANSACTION_ARRAYS: ClassVar[tuple[str, ...]] = ("regs", "state", "params", "inputs",
                                                     "_has_flash")
    #: the arrays :meth:`_store_rows` may change, when a family knows they are fewer than a
    #: whole transaction's (:meth:`_snapshot`): a refused store puts back their rows alone
    ROWS_STORE_ARRAYS: ClassVar[tuple[str, ...] | None] = None

    def _lookup(self, key: RegisterKey) -> Register:
        if isinstance(key, (bool, np.bool_)) or not isinstance(key, (str, int, np.integer)):
            raise RegisterError(f"register key must be a name or number, got {key!r}")
        return self.table.lookup(int(key) if isinstance(key, np.integer) else key)

    def read_raw(self, key: RegisterKey, index: MotorIndex = None) -> np.ndarray:
        """Stored integers of a register, (M,) int64 (a LongInt's full 32-bit value), of the
        motors ``index`` (as :meth:`write` selects them; default all, M = N)."""
        where = self._read_columns.get(key) if type(key) is str else None
        if where is None:  # the column and whether it is a LongInt's high word
            reg = self._lookup(key)
            high = reg.format == Format.LONGINT_HIGH
            where = (reg.number - 1 if high else reg.number, high)
            if type(key) is str and len(self._read_columns) < _PLAN_CACHE_SIZE:
                self._read_columns[key] = where
        number, high = where
        if index is None:
            column = self.regs[:, number].copy()
        else:
            column = self.regs[as_index(index, self.n), number]
        return (column >> 16) & 0xFFFF if high else column

    def read(self, key: RegisterKey, index: MotorIndex = None) -> np.ndarray:
        """Register value in user units, (M,), of the motors ``index`` (default all): Fixed
        formats as float, others as int64."""
        reg = self._lookup(key)
        return from_raw(reg, self.read_raw(reg.number, index))

    def write(self, key: RegisterKey, value: RegisterValue, index: MotorIndex = None) -> None:
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
        numbers only. ``index`` selects motors (:func:`jvl_gym.motor.arguments.as_index`): None, an
        integer, a slice, distinct integers, or a boolean mask of shape (N,).
        """
        plan = self._key_plan((key,))
        self._write_plan(plan, (value,), as_index(index, self.n))

    def write_many(self, values: Mapping[RegisterKey, RegisterValue],
                   index: MotorIndex = None) -> None:
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
        idx = as_index(index, self.n)
        self._write_plan(self._key_plan(tuple(values)), tuple(values.values()), idx)

    def _write_plan(self, plan: StorePlan, values: tuple[Any, ...], idx: np.ndarray) -> None:
        """Validate ``values`` (user units, one per register of ``plan``) for motors ``idx``,
        then store them (:meth:`_store_many`)."""
        raws = self._batch_raws(plan, values, idx.size)
        if raws is None:  # not plain numbers, or a bad one: validated one by one
            raws = np.empty((len(plan.regs), idx.size), dtype=np.int64)
            for k, (reg, value) in enumerate(zip(plan.regs, values)):
                raws[k] = self._validated_raw(reg, value, idx.size)
        self._store_many(plan, idx, raws)
        self._note_not_modelled(plan.regs, raws, 4)

    def _note_not_modelled(self, regs: tuple[Register, ...], raws: np.ndarray,
                           stacklevel: int) -> None:
        """Warn once per register (:class:`NotModelledWarning`) and log when a write stored a
        value other than the default in a register, or a bit, the family's conformance matrix
        calls not modelled; the value stays stored."""
        conf = self.CONFORMANCE
        if conf is None or not conf.warn_rules:
            return
        rules, warned = conf.warn_rules, self._not_modelled_warned
        for k, reg in enumerate(regs):
            num = reg.number
            if num in rules and num not in warned and conf.not_modelled_change(
                    num, reg.default_raw, raws[k]):
                warned.add(num)
                entry = conf.entries[num]
                what = (f"{reg.name} (register {num})" if entry.status == "not modelled" else
                        f"{reg.name} (register {num}) bits {conf.warn_rules[num][0]:#x}")
                msg = (f"{what} is not modelled by the simulator (manual {entry.section}): "
                       f"{conf.cell(reg)}; the value is stored and read back but has no effect")
                log.warning("%s", msg)
                warnings.warn(msg, NotModelledWarning, stacklevel=stacklevel)

    def _batch_raws(self, plan: StorePlan, values: tuple[Any, ...], size: int
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

    def write_raw(self, key: RegisterKey, raw: int | np.integer | np.ndarray,
                  index: MotorIndex = None) -> None:
        """Write stored integers (Fixed4 = value·4096, …) with the same validation as write."""
        reg = self._lookup(key)
        idx = as_index(index, self.n)
        raws = self._checked_raw(reg, raw, idx.size)
        self._store(reg, idx, raws)
        self._note_not_modelled((reg,), raws[None], 3)

    def write_raw_many(self, values: Mapping[RegisterKey, int | np.integer | np.ndarray],
                       index: MotorIndex = None) -> None:
        """Write stored integers of several registers (key → raw, in this order) to the motors
        ``index`` as one transaction, validated as by :meth:`write_raw` and stored as by
        :meth:`write_many`: every register is checked before the first is stored, and a store
        the firmware refuses restores the motors (registers, state and flash) as they were.

        Examples
        --------
        >>> m.write_raw_many({"V_SOLL": 1234, "COMMAND": 268}, index=0)
        """
        idx = as_index(index, self.n)
        plan = self._key_plan(tuple(values))
        raws = np.empty((len(plan.regs), idx.size), dtype=np.int64)
        for k, (reg, raw) in enumerate(zip(plan.regs, values.values())):
            raws[k] = self._checked_raw(reg, raw, idx.size)
        self._store_many(plan, idx, raws)
        self._note_not_modelled(plan.regs, raws, 3)

    def _checked_raw(self, reg: Register, raw: Any, size: int) -> np.ndarray:
        """The stored integers ``raw`` of ``reg``, (size,) int64, validated as a write in user
        units; a :class:`RegisterError` names what is wrong."""
        arr = None if isinstance(raw, (bool, np.bool_, str, bytes)) else np.asarray(raw)
        if arr is None or arr.dtype.kind not in "iu":
            raise RegisterRangeError(
                f"{reg.name} (register {reg.number}): raw values must be integers (the stored "
                f"integer: Fixed4 = value·4096, Fixed8 = value·256), got {raw!r}")
        self._validated_raw(reg, arr / reg.scale, size)
        return np.broadcast_to(arr.astype(np.int64), (size,)).copy()

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

    def _key_plan(self, keys: tuple[Any, ...]) -> StorePlan:
        """The store plan of the registers ``keys`` (names are cached, other keys looked up)."""
        try:
            plan = self._plans.get(keys)
        except TypeError:  # an unhashable key: _lookup words the error
            plan = None
        if plan is None:
            plan = StorePlan.of(tuple(self._lookup(key) for key in keys), self._mode_number,
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
            plan = self._plans[num] = StorePlan.of((reg,), self._mode_number, self.ONE_BY_ONE)
        self._store_rows(plan, idx, raw.reshape(1, -1))

    def _store_many(self, plan: StorePlan, idx: np.ndarray, raws: np.ndarray) -> None:
        """Check and store the (K, M) validated stored integers ``raws`` of the registers of
        ``plan`` (in order) in motors ``idx``; if one is refused, the motors are restored."""
        one_by_one = plan.one_by_one or any(self._special_request(raws[k])
                                            for k in plan.mode_rows)
        # what a refusal puts back: the rows _store_rows may change, or the whole transaction's
        rows = None if one_by_one else self.ROWS_STORE_ARRAYS
        saved = (None if len(plan.regs) == 1 else self._snapshot(idx) if rows is None
                 else [getattr(self, name)[idx] for name in rows])
        try:
            if one_by_one:
                for reg, raw in zip(plan.regs, raws):
                    self._store(reg, idx, raw)
            else:
                self._store_rows(plan, idx, raws)
        except RegisterError:
            if saved is not None:  # (one register is checked for every motor before it is stored)
                if rows is None:
                    self._restore(idx, saved)
                else:
                    for name, row in zip(rows, saved):
                        getattr(self, name)[idx] = row
            raise

    def _snapshot(self, idx: np.ndarray) -> tuple[Any, ...]:
        """Copies of what a transaction on motors ``idx`` may change: the rows of
        :attr:`TRANSACTION_ARRAYS` and the motors' flash (a user command or a SAFE_MODE
        request saves to flash and resets)."""
        flash = self._flash
        return ([getattr(self, name)[idx] for name in self.TRANSACTION_ARRAYS],
                flash is None, None if flash is None else flash[idx])

    def _restore(self, idx: np.ndarray, saved: tuple[Any, ...]) -> None:
        """Put back the rows :meth:`_snapshot` copied."""
        rows, no_flash, flash = saved
        for name, row in zip(self.TRANSACTION_ARRAYS, rows):
            getattr(self, name)[idx] = row
        if no_flash:
            self._flash = None
        elif flash is not None:
            assert self._flash is not None
            self._flash[idx] = flash

    @abstractmethod
    def _store_rows(self, plan: StorePlan, idx: np.ndarray, raws: np.ndarray) -> None:
        """Check the firmware's write rules and store the (K, M) stored integers ``raws`` of
        ``plan``'s registers in motors ``idx``; a refusal raises with the registers before
        the refused one stored (the caller restores the motors)."""

    def _store_special(self, reg: Register, idx: np.ndarray, raw: np.ndarray) -> bool:
        """Store a write the family handles itself (a mode command, a register-set pointer);
        True when it did. By default, nothing is special."""
        return False

    def _special_request(self, raw: np.ndarray) -> bool:
        """The mode-register values ``raw`` need :meth:`_store_special` (default: never)."""
        return False

    def _check_setup_keys(self, registers: Mapping[str, Any]) -> None:
        """Refuse a setup that contains MODE_REG (a setup is parameters, not a command)."""
        if any(self._lookup(name).number == self._mode_number for name in registers):
            raise RegisterError("a setup must not contain MODE_REG (manual 3.2.2: a mode is "
                                "requested after the parameters are written)")

    def _setup_rom_image(self, setup: str | os.PathLike[str] | dict[str, Any],
                         store: Callable[[np.ndarray, Register, Any, np.ndarray], None]
                         ) -> np.ndarray:
        """The table's defaults with the register set ``setup`` written over them: a ROM image
        (number of registers,) int64.

        Every register is validated as :meth:`load_setup` validates it (no MODE_REG, a value in
        range) and handed to ``store(image, register, value, raw)`` (the value as given and its
        stored integers), which applies the family's write rules and stores it. A refusal raises
        the :class:`RegisterError` naming the setup.
        """
        image = self.table.default_raw_array.astype(np.int64).copy()
        try:
            cfg = load_setup(setup, self.SETUPS_DIR)
            self._check_setup_keys(cfg.registers)
            for name, value in cfg.registers.items():
                reg = self._lookup(name)
                store(image, reg, value, self._validated_raw(reg, value, 1))
        except RegisterError as exc:
            where = "setup mapping" if isinstance(setup, Mapping) else f"setup {setup}"
            raise type(exc)(f"{where}: {exc}") from exc
        return image

    def load_setup(self, setup: str | os.PathLike[str] | dict[str, Any],
                   index: MotorIndex = None) -> None:
        """Write a register set (name → value) to the selected motors, validated as a whole."""
        cfg = load_setup(setup, self.SETUPS_DIR)
        self._check_setup_keys(cfg.registers)
        self.write_many(cfg.registers, index)
