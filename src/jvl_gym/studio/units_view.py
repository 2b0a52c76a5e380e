"""Register values in engineering units, mode registers as mode names, bit registers as bits.

A register's engineering unit comes from its family's ``units`` module
(``ENGINEERING_UNITS``: register unit, or register name, → the units it is shown in, the first
the default; each a factor per register unit, times a field of the motor's data where the
factor is the motor's own, as the peak torque behind ``1/1023 peak torque``). A register in no
entry is shown in its own unit. The raw toggle shows every register in its own unit.

The mode register and the registers the family's constants list in ``MODE_VALUED_REGISTERS``
take a mode: they are shown as the family's ``MODE_NAMES``. A register whose description names
its bits (:mod:`.bits`) is shown as named check boxes.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

from ..families import family_of_motor
from ..registers import Access, Register, from_raw
from ..registers.table import FORMAT_SCALE
from .bits import BitField, bit_fields
from .facts import FamilyFacts, facts_of

__all__ = ["EngineeringUnit", "UnitsView", "Kind"]


@dataclass(frozen=True)
class EngineeringUnit:
    """An engineering unit of a register.

    Attributes
    ----------
    unit : str
        The unit shown (``"rpm"``).
    factor : float
        Engineering units per register unit (the register's value as ``from_raw`` gives it).
    """

    unit: str
    factor: float

    def to_engineering(self, value: float) -> float:
        """A value in the register's unit → this unit."""
        return value * self.factor

    def to_register(self, value: float) -> float:
        """A value in this unit → the register's unit."""
        return value / self.factor


class Kind:
    """How a register is shown: a value, a mode (a list of modes) or bits (check boxes)."""

    VALUE = "value"
    MODE = "mode"
    BITS = "bits"


class UnitsView:
    """The engineering units of one motor type's registers.

    Parameters
    ----------
    motor_type : str
        The motor type (any family).
    prefer : iterable of str
        Units to show where a register offers them (``{"°"}``: positions in degrees rather
        than the default turns).

    Attributes
    ----------
    raw : bool
        True: every register in its own unit (the raw toggle).
    """

    def __init__(self, motor_type: str, prefer: Iterable[str] = ()) -> None:
        family = family_of_motor(motor_type)
        self.facts: FamilyFacts = facts_of(motor_type)
        self._table: dict[str, tuple[tuple[Any, ...], ...]] = dict(
            getattr(family.units, "ENGINEERING_UNITS", {}))
        self._motor = family.load_motor(motor_type)
        self._mode_valued = {self.facts.mode_register,
                             *getattr(family.constants, "MODE_VALUED_REGISTERS", ())}
        self.prefer = set(prefer)
        self.raw = False

    # ------------------------------------------------------------------ units
    def options(self, reg: Register) -> list[EngineeringUnit]:
        """The engineering units ``reg`` can be shown in, the default first (empty: its own
        unit only)."""
        entry = self._table.get(reg.name, self._table.get(reg.unit, ()))
        out = []
        for option in entry:
            unit, factor, *field = option
            if field:
                value = getattr(self._motor, field[0], None)
                if value is None:
                    continue  # the motor's data does not give the factor: its own unit
                factor = factor * float(value)
            out.append(EngineeringUnit(str(unit), float(factor)))
        return out

    def unit_of(self, reg: Register) -> EngineeringUnit | None:
        """The engineering unit ``reg`` is shown in now; None: its own unit (the raw toggle,
        or no engineering unit)."""
        if self.raw or self.kind(reg) != Kind.VALUE:
            return None
        options = self.options(reg)
        for o in options:
            if o.unit in self.prefer:
                return o
        return options[0] if options else None

    def unit_text(self, reg: Register) -> str:
        """The unit ``reg`` is shown in now."""
        eu = self.unit_of(reg)
        return eu.unit if eu else reg.unit

    def value(self, reg: Register, raw: int) -> float:
        """``raw`` of ``reg`` in the unit it is shown in now."""
        value = float(from_raw(reg, raw))
        eu = self.unit_of(reg)
        return eu.to_engineering(value) if eu else value

    def text(self, reg: Register, raw: int) -> str:
        """``raw`` of ``reg`` as shown now: an engineering value to 6 significant digits, a
        value in the register's own unit exactly."""
        eu = self.unit_of(reg)
        if eu is None:
            value = float(from_raw(reg, raw))
            return f"{value:.10g}" if reg.format in FORMAT_SCALE else str(int(value))
        return f"{eu.to_engineering(float(from_raw(reg, raw))):.6g}"

    def to_register(self, reg: Register, value: float) -> float:
        """A value typed in the unit ``reg`` is shown in → the register's unit, rounded to
        the register's resolution (what the motor stores)."""
        if not math.isfinite(value):
            raise ValueError(f"{reg.name}: {value!r} is not a finite number")
        eu = self.unit_of(reg)
        if eu is None:
            return value
        scale = FORMAT_SCALE.get(reg.format, 1)
        return round(eu.to_register(value) * scale) / scale

    def range_text(self, reg: Register) -> str:
        """``"<min> … <max> <unit>"`` as shown now."""
        eu = self.unit_of(reg)
        if eu is None:
            return f"{reg.minimum:.10g} … {reg.maximum:.10g}"
        lo, hi = sorted((eu.to_engineering(reg.minimum), eu.to_engineering(reg.maximum)))
        return f"{lo:.6g} … {hi:.6g}"

    # ------------------------------------------------------------------ modes and bits
    def kind(self, reg: Register) -> str:
        """:attr:`Kind.MODE`, :attr:`Kind.BITS` or :attr:`Kind.VALUE`."""
        if reg.name in self._mode_valued:
            return Kind.MODE
        if bit_fields(reg):
            return Kind.BITS
        return Kind.VALUE

    def modes(self, reg: Register) -> dict[int, str]:
        """The values a mode register offers: value → ``"<name> (<value>)"``, those within the
        register's range."""
        return {v: f"{n} ({v})" for v, n in sorted(self.facts.mode_names.items())
                if reg.minimum <= v <= reg.maximum}

    @staticmethod
    def bits(reg: Register) -> list[BitField]:
        """The named single bits of a bit register (its check boxes), in bit order."""
        return [f for f in bit_fields(reg) if f.first == f.last]

    @staticmethod
    def bits_set(reg: Register, raw: int) -> dict[int, bool]:
        """Bit number → set, for each check box of ``reg``."""
        return {f.first: bool(int(raw) >> f.first & 1) for f in UnitsView.bits(reg)}

    @staticmethod
    def with_bit(reg: Register, raw: int, bit: int, on: bool) -> int:
        """``raw`` with ``bit`` set or cleared (a check box clicked); the other bits as they
        are.

        Raises
        ------
        ValueError
            A bit the register does not name, or a register that is not writable.
        """
        if reg.access != Access.RW:
            raise ValueError(f"{reg.name} is read-only")
        if bit not in {f.first for f in UnitsView.bits(reg)}:
            raise ValueError(f"{reg.name} names no bit {bit}")
        return (int(raw) | 1 << bit) if on else (int(raw) & ~(1 << bit))
