"""What the digital twin needs of a family beyond its register table (:class:`TwinSpec`): part
of the family contract (:mod:`.contract`), stated in the family's ``family.yaml``."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

__all__ = ["TwinSpec"]


@dataclass(frozen=True)
class TwinSpec:
    """What the digital twin needs of a family beyond its register table.

    Attributes
    ----------
    dialects : tuple of str
        The MacTalk dialects the motors speak (``jvl_gym.protocol.mactalk.dialect``), the default
        first.
    safe_mode : int or None
        MODE_REG value of safe mode, None where the family has none.
    init_mode : int or None
        MODE_REG value of the mode "go init mode" and "exit safe mode" lead to, or None.
    passive_mode : int or None
        MODE_REG value of the passive mode (the power stage off), which a bus time-out may
        command; None where the family has none.
    stop_mode : int or None
        MODE_REG value of the family's stop: the mode that brings a running motor to rest on
        its stop ramp and then goes to :attr:`passive_mode` by itself (what a STOP button
        writes); None where the family has no such mode and the stop is the passive mode.
    status_register : str
        The register whose bits :attr:`status_bits` names (the status a FastMAC status byte
        or a CANopen status word is built from).
    status_bits : Mapping[int, str]
        Bit mask → name of the status register's bits.
    error_bits : tuple of str
        Names (in :attr:`status_bits`) of the bits that report an error.
    clearable_bits : tuple of str
        Names of the bits a "reset errors" command clears.
    commands : Mapping[str, int]
        User command numbers by meaning (``"reset"``, ``"save_reset"``, ``"save"``, …) for
        families with a command register; empty otherwise.
    """

    dialects: tuple[str, ...]
    safe_mode: int | None = None
    init_mode: int | None = None
    passive_mode: int | None = None
    stop_mode: int | None = None
    status_register: str = "ERR_STAT"
    status_bits: Mapping[int, str] = field(default_factory=dict)
    error_bits: tuple[str, ...] = ()
    clearable_bits: tuple[str, ...] = ()
    commands: Mapping[str, int] = field(default_factory=dict)

    @property
    def dialect(self) -> str:
        """The default MacTalk dialect."""
        return self.dialects[0]

    def bit(self, name: str) -> int:
        """The mask of status bit ``name``; KeyError naming the known bits if there is none."""
        for mask, known in self.status_bits.items():
            if known == name:
                return mask
        raise KeyError(f"no status bit {name!r} in {self.status_register}; known: "
                       f"{', '.join(self.status_bits.values())}")

    @staticmethod
    def named_bits(constants: Any, names: tuple[str, ...]) -> dict[int, str]:
        """Bit mask → name of the bits ``names``, each a constant of ``constants``."""
        return {int(getattr(constants, name)): name for name in names}

    def has_bit(self, name: str) -> bool:
        """Whether the status register has a bit ``name``."""
        return name in self.status_bits.values()

    def mask(self, names: tuple[str, ...]) -> int:
        """The OR of the masks of the status bits ``names``."""
        out = 0
        for name in names:
            out |= self.bit(name)
        return out
