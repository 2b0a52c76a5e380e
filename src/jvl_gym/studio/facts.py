"""What the studio knows of a motor family, taken from its public objects only.

A family is reached through :func:`jvl_gym.families.family_of_motor` (its :class:`Family`
record: title, array class, motor types, capabilities), the array class's register table and
mode register, and the record's ``constants`` module (``MODE_NAMES``; docs/architecture.md). Bit
registers and the sample-buffer registers are found in the register table by their
descriptions and names (:mod:`.bits`, :mod:`.capture`), never by a family key.
"""

from __future__ import annotations

from dataclasses import dataclass
from types import ModuleType
from typing import Any

from ..families import Capability, family_of_motor
from ..registers import RegisterTable

__all__ = ["FamilyFacts", "facts_of"]


@dataclass(frozen=True)
class FamilyFacts:
    """The facts of one motor family the studio shows and uses.

    Attributes
    ----------
    title : str
        The family's human name.
    table : RegisterTable
        Its register table.
    mode_register : str
        Name of the operating-mode register (``MODE_REG``).
    mode_names : dict
        MODE_REG value → mode name.
    outer_hz : float
        Firmware (servo or profile) sample rate [Hz].
    motor_types : tuple of str
        The family's motor types.
    constants : module or None
        The family's public ``constants`` module.
    capabilities : frozenset of Capability
        What the family declares (``Family.capabilities``).
    """

    title: str
    table: RegisterTable
    mode_register: str
    mode_names: dict[int, str]
    outer_hz: float
    motor_types: tuple[str, ...]
    constants: ModuleType | None
    capabilities: frozenset[Capability] = frozenset()

    def mode_name(self, value: int) -> str:
        """The name of mode ``value`` (``"mode 7"`` for one the family does not name)."""
        return self.mode_names.get(int(value), f"mode {int(value)}")

    def test_modes(self) -> dict[str, int]:
        """The family's TESTU and TESTA modes, name → MODE_REG value (empty where the family
        has none; MAC050–141 manual 4.4.9, 4.4.10)."""
        out: dict[str, int] = {}
        if Capability.TEST_MODES not in self.capabilities:
            return out
        for value, name in self.mode_names.items():
            for test in ("TESTU", "TESTA"):
                if name.upper().startswith(test + "_") or name.upper() == test:
                    out[test] = value
        return out


def facts_of(motor_type: Any) -> FamilyFacts:
    """The :class:`FamilyFacts` of the family of ``motor_type`` (a motor type name)."""
    fam = family_of_motor(motor_type)
    cls = fam.array_class
    const = fam.constants
    names = dict(const.MODE_NAMES)
    return FamilyFacts(title=fam.title, table=cls.TABLE, mode_register=cls.MODE_REGISTER,
                       mode_names={int(k): str(v) for k, v in names.items()},
                       outer_hz=float(cls.OUTER_HZ), motor_types=tuple(fam.motor_types()),
                       constants=const, capabilities=fam.capabilities)
