"""A MotorArray-like backend on any register table, for protocol tests without physics:
registers with the table's validation, safe mode, flash and reset. It offers what the twin and
the Modbus adapter use, under the names of the family contract (``enter_safe_mode``,
``exit_safe_mode``, ``write_flash``, the power-on ``reset``), and declares what it supports
as a family does (:class:`FakeFamily`: safe mode and flash, no software reset).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from jvl_gym.families import Capability, TwinSpec
from jvl_gym.protocol.mactalk.dialect import MACTALK16
from jvl_gym.registers import Access, ReadOnlyRegisterError, RegisterError
from jvl_gym.registers.formats import to_raw

SAFE_MODE = 15


@dataclass(frozen=True)
class FakeFamily:
    """The twin's view of the fake's family (:class:`jvl_gym.protocol.twin.TwinFamily`)."""

    twin: TwinSpec
    title: str = "register fake"
    capabilities: frozenset[Capability] = frozenset({Capability.SAFE_MODE, Capability.FLASH})

    def supports(self, capability: Capability) -> bool:
        return capability in self.capabilities


class ModeError(RegisterError):
    """A command the mode forbids."""


class RegisterArray:
    """``n`` motors of ``table``: ROM defaults from the table, writes validated by it.

    ``dialect`` is the MacTalk dialect its family declares.
    """

    OUTER_HZ = 1000.0

    def __init__(self, table: Any, n: int = 1, mode_register: str = "MODE_REG",
                 dialect: str = MACTALK16) -> None:
        self.family = FakeFamily(TwinSpec(dialects=(dialect,), safe_mode=SAFE_MODE, init_mode=0,
                                          passive_mode=0))
        self.table = table
        self.n = n
        self.mode_number = table.lookup(mode_register).number
        rom = np.zeros(table.last + 1, dtype=np.int64)
        for reg in table:
            if reg.access != Access.RESERVED:
                rom[reg.number] = int(to_raw(reg, reg.default))
        self.rom = rom
        self.regs = np.tile(rom, (n, 1))
        self.flash: list[dict[int, int]] = [{} for _ in range(n)]
        self.steps = 0
        self.resets = [0] * n

    # ------------------------------------------------------------------ registers
    def read_raw(self, key: str | int) -> np.ndarray:
        return self.regs[:, self.table.lookup(key).number].copy()

    def _check(self, number: int, raw: int) -> None:
        reg = self.table.lookup(number)
        if reg.access != Access.RW:
            raise ReadOnlyRegisterError(f"{reg.name} (register {reg.number}) is "
                                        f"{reg.access.value}")
        to_raw(reg, raw / reg.scale)
        if number == self.mode_number and raw == SAFE_MODE:
            raise ModeError("SAFE_MODE is entered by the safe-mode command only")

    def write_raw(self, key: str | int, raw: Any, index: Any = None) -> None:
        self.write_raw_many({key: raw}, index)

    def write_raw_many(self, values: dict[str | int, Any], index: Any = None) -> None:
        numbers = {self.table.lookup(key).number: int(raw) for key, raw in values.items()}
        for number, raw in numbers.items():
            self._check(number, raw)
        rows = slice(None) if index is None else index
        for number, raw in numbers.items():
            self.regs[rows, number] = raw

    # ------------------------------------------------------------------ modes, flash, reset
    def step(self, n_outer: int = 1) -> None:
        self.steps += n_outer

    def enter_safe_mode(self, index: int) -> None:
        self.regs[index, self.mode_number] = SAFE_MODE

    def exit_safe_mode(self, index: int) -> None:
        self.regs[index, self.mode_number] = 0

    def write_flash(self, index: int) -> None:
        if self.regs[index, self.mode_number] != SAFE_MODE:
            raise ModeError("write flash in SAFE_MODE only")
        self.flash[index] = self.flash_image(index)
        self.reset(index)

    def reset(self, index: int) -> None:
        self.regs[index] = self.rom
        for number, raw in self.flash[index].items():
            self.regs[index, number] = raw
        self.resets[index] += 1

    def flash_image(self, index: int) -> dict[int, int]:
        return {reg.number: int(self.regs[index, reg.number]) for reg in self.table
                if reg.access == Access.RW and reg.number != self.mode_number}

    def check_flash_image(self, index: int, image: dict[int, int]) -> None:
        for number, raw in image.items():
            self._check(number, raw)

    def load_flash_image(self, index: int, image: dict[int, int]) -> None:
        self.check_flash_image(index, image)
        self.flash[index] = {**self.flash[index], **image}
