"""The register view's logic: rows of values, edits with the API's validation, setup files.

A row shows a register's name, number, value in its unit and in raw counts, range, unit and
description (the family's register table). An edit goes through the motor's own write
(:meth:`~jvl_gym.MotorArray.write` or the protocol client's validated write): a refused value
comes back as its reason and nothing changes. A setup file is the project's setup format
(``motor:`` and ``registers:`` name → value, as ``configs/setups``), written from the motor's
writable registers and loaded through the motor's validated ``load_setup``.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path

import yaml

from ..families.config import ConfigError
from ..registers import Access, Register, RegisterError, from_raw
from ..registers.table import FORMAT_SCALE
from .groups import family_ranges, register_groups, visible
from .line import LineDown
from .motor import StudioMotor
from .units_view import UnitsView

__all__ = ["Row", "rows", "value_text", "range_text", "parse_value", "edit", "EditResult",
           "setup_of", "setup_text", "save_setup", "read_setup", "load_setup_file",
           "grouped_registers"]


def value_text(reg: Register, raw: int) -> str:
    """``raw`` of ``reg`` in its unit, as the register view shows it."""
    value = float(from_raw(reg, raw))
    if reg.format in FORMAT_SCALE:
        return f"{value:.10g}"
    return str(int(value))


def range_text(reg: Register) -> str:
    """``"<min> … <max>"`` in the register's unit."""
    if reg.format in FORMAT_SCALE:
        return f"{reg.minimum:.10g} … {reg.maximum:.10g}"
    return f"{int(reg.minimum)} … {int(reg.maximum)}"


@dataclass(frozen=True)
class Row:
    """One register as the view shows it."""

    name: str
    number: int
    value: str
    raw: int
    unit: str
    range: str
    access: str
    description: str
    section: str


def grouped_registers(motor: StudioMotor) -> list[tuple[str, list[Register]]]:
    """The registers of ``motor``'s family grouped as the manual groups them."""
    return register_groups(motor.table, family_ranges(motor.facts.constants))


def rows(motor: StudioMotor, regs: list[Register] | None = None) -> list[Row]:
    """Rows of ``regs`` (default: every register the view shows) read from ``motor`` now."""
    regs = regs if regs is not None else [r for r in motor.table if visible(r)]
    raws = motor.read_raws([r.number for r in regs])
    return [Row(r.name, r.number, value_text(r, raws[r.number]), raws[r.number], r.unit,
                range_text(r), r.access.value, r.description, r.section) for r in regs]


def parse_value(text: str) -> float:
    """A value typed in the register view: a decimal or ``0x`` hexadecimal number.

    Raises
    ------
    ValueError
        Text that is no finite number.
    """
    t = text.strip().replace("_", "")
    try:
        value = float(int(t, 16)) if t.lower().startswith(("0x", "-0x")) else float(t)
    except ValueError:
        raise ValueError(f"{text!r} is not a number") from None
    if not math.isfinite(value):
        raise ValueError(f"{text!r} is not a finite number")
    return value


@dataclass(frozen=True)
class EditResult:
    """The outcome of an edit: ``ok`` and the message to show."""

    ok: bool
    message: str


def edit(motor: StudioMotor, name: str, text: str, view: UnitsView | None = None
         ) -> EditResult:
    """Write ``text`` to register ``name`` of ``motor`` through the motor's validated write.

    ``text`` is in the unit ``view`` shows the register in (its engineering unit; default:
    the register's own unit). A value that is no number, out of range, read-only or not
    allowed in the present mode is refused with the reason of the motor's API and changes
    nothing.
    """
    try:
        reg = motor.register(name)
        value = parse_value(text)
        if view is not None:
            value = view.to_register(reg, value)
        motor.write(reg.number, value)
    except (RegisterError, ValueError, LineDown) as exc:
        text = str(exc)
        return EditResult(False, text if text.startswith(name) else f"{name}: {text}")
    raw = motor.read_raw(reg.number)
    if view is not None and view.unit_of(reg) is not None:
        return EditResult(True, f"{reg.name} = {view.text(reg, raw)} {view.unit_text(reg)}"
                          .rstrip())
    return EditResult(True, f"{reg.name} = {value_text(reg, raw)}")


def setup_of(motor: StudioMotor) -> dict[str, object]:
    """The setup of ``motor`` now: its type and every writable register but the mode
    register, name → value in the register's unit."""
    regs = [r for r in motor.table if r.access == Access.RW and visible(r)
            and r.name != motor.facts.mode_register]
    raws = motor.read_raws([r.number for r in regs])
    values: dict[str, float | int] = {}
    for r in regs:
        v = float(from_raw(r, raws[r.number]))
        values[r.name] = v if r.format in FORMAT_SCALE else int(v)
    return {"motor": motor.motor_type, "registers": values}


def setup_text(motor: StudioMotor) -> str:
    """The setup of ``motor`` as the text of a setup file (YAML)."""
    return (f"# setup of {motor.label}, saved by jvl-gym studio\n"
            + yaml.safe_dump(setup_of(motor), sort_keys=False))


def save_setup(motor: StudioMotor, path: str | os.PathLike[str]) -> Path:
    """Write the setup of ``motor`` to ``path`` (YAML) and return the path."""
    path = Path(path)
    path.write_text(setup_text(motor), encoding="utf-8")
    return path


def read_setup(text: str, where: str = "setup") -> dict[str, float]:
    """The ``registers`` of a setup file's text, name → value.

    Raises
    ------
    ConfigError
        Text that is no setup (one line naming ``where`` and the problem).
    """
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise ConfigError(f"{where}: not YAML ({str(exc).splitlines()[0]})") from None
    regs = data.get("registers") if isinstance(data, dict) else None
    if not isinstance(regs, dict) or not regs:
        raise ConfigError(f"{where}: a setup is a mapping with 'registers: {{NAME: value}}'")
    out = {}
    for k, v in regs.items():
        try:
            if isinstance(v, bool) or not isinstance(v, (int, float, str)):
                raise ValueError(f"{v!r} is not a number")
            out[str(k)] = parse_value(v) if isinstance(v, str) else float(v)
        except ValueError as exc:
            raise ConfigError(f"{where}: register {k}: {exc}") from None
    return out


def load_setup_file(motor: StudioMotor, text: str, where: str = "setup") -> EditResult:
    """Load a setup file's text into ``motor``, validated as a whole by the motor's API:
    a refused setup changes nothing and comes back with its reason."""
    try:
        regs = read_setup(text, where)
        registers = {}
        for name in regs:
            registers[motor.register(name).name] = regs[name]
        motor.load_setup(registers)
    except (ConfigError, RegisterError, ValueError, LineDown) as exc:
        return EditResult(False, str(exc))
    return EditResult(True, f"loaded {len(regs)} registers from {where}")
