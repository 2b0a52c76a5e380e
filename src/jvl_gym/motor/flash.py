"""Flash of a motor array: the register images a power-on loads instead of the ROM defaults.

Flash holds the read-write registers but the mode register and a LongInt's high word; an image
is checked as a whole before the flash is touched.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from ..registers import (
    Access,
    Format,
    ReadOnlyRegisterError,
    RegisterError,
    RegisterRangeError,
    RegisterTable,
)
from ..registers.formats import to_raw
from .arguments import motor_index

__all__ = ["FlashStorage"]


class FlashStorage:
    """Flash images of :class:`~jvl_gym.MotorArray` (a mixin over its ``regs``, ``table``,
    ROM images and type pool)."""

    n: int
    table: RegisterTable
    regs: np.ndarray
    _rom: np.ndarray
    _type_of: np.ndarray
    _flash: np.ndarray | None
    _has_flash: np.ndarray
    _mode_number: int

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

    def _save_flash(self, idx: np.ndarray) -> None:
        """Save the registers flash holds (:meth:`_rw_numbers`) of motors ``idx`` (M,)."""
        if self._flash is None:
            self._flash = np.zeros_like(self.regs)
        rw = self._rw_numbers()
        self._flash[np.ix_(idx, rw)] = self.regs[np.ix_(idx, rw)]
        self._has_flash[idx] = True

    def flash_image(self, index: int) -> dict[int, int]:
        """The flash contents of one motor (register number → raw), or {} if never written.

        Raises
        ------
        RegisterShapeError
            ``index`` is not an integer in ``-N..N-1``.
        """
        i = motor_index(index, self.n, "flash_image")
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
        i = motor_index(index, self.n, "load_flash_image")
        staged = self._staged_flash_image(i, image)
        if self._flash is None:
            self._flash = np.zeros_like(self.regs)
        self._flash[i] = staged
        self._has_flash[i] = True

    def check_flash_image(self, index: int, image: Mapping[int, int]) -> None:
        """Check ``image`` as :meth:`load_flash_image` does, storing nothing (to check the
        images of several motors before any is loaded).

        Raises
        ------
        RegisterShapeError, RegisterError
            As :meth:`load_flash_image`.
        """
        self._staged_flash_image(motor_index(index, self.n, "load_flash_image"), image)

    def _staged_flash_image(self, i: int, image: Mapping[int, int]) -> np.ndarray:
        """The flash row of motor ``i`` that ``image`` gives (ROM defaults where it gives
        nothing), every entry checked (:meth:`load_flash_image`)."""
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
        return staged
