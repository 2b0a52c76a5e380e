"""The parameter workflow: the motor's settings compared with a baseline, undo and redo of
edits, and a write to flash after a confirmation that lists the changes.

The settings are the registers a setup holds (:func:`.registers.setup_of`: the writable ones
but the mode register). A baseline is one of

* the motor's **flash** (a simulated motor's flash image, MAC050–141 manual 5.1 'write flash',
  MIS manual §18.2.7; a motor whose flash was never written powers on with its defaults);
* its **defaults**: the register table's ROM defaults with the motor type's default setup
  over them (what a motor without flash powers on with);
* a **setup file** (the project's setup format).

Every edit through :class:`History` is recorded with the value before it, so it can be undone
and redone; an undo goes through the motor's validated write like any edit.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from ..families.config import ConfigError
from ..registers import RegisterError, from_raw
from ..registers.table import FORMAT_SCALE
from .motor import SimMotor, StudioMotor
from .registers import EditResult, edit, read_setup, setup_of
from .units_view import UnitsView

__all__ = ["Difference", "settings_of", "flash_values", "default_values", "file_values",
           "compare", "History", "flash_changes", "write_flash"]


def settings_of(motor: StudioMotor) -> dict[str, float]:
    """The motor's settings now (:func:`.registers.setup_of`): register name → value."""
    regs = setup_of(motor)["registers"]
    assert isinstance(regs, dict)
    return {str(k): float(v) for k, v in regs.items()}


def _stored(motor: StudioMotor, name: str, value: float) -> float:
    """``value`` of register ``name`` as the motor stores it (its resolution)."""
    reg = motor.register(name)
    scale = FORMAT_SCALE.get(reg.format, 1)
    return float(from_raw(reg, int(math.copysign(math.floor(abs(value) * scale + 0.5), value))))


def default_values(motor: StudioMotor) -> dict[str, float]:
    """The register table's ROM defaults of the settings, with the motor type's default setup
    over them, as the motor stores them."""
    values = {r.name: _stored(motor, r.name, r.default) for r in motor.table
              if r.name in _names(motor)}
    try:
        fam = motor.family
        setup_name = getattr(fam.load_motor(motor.motor_type), "setup", None)
        if setup_name:
            for k, v in fam.config.load_setup(setup_name).registers.items():
                if k in values:
                    values[k] = _stored(motor, k, float(v))
    except (ValueError, OSError):  # no default setup: the table's defaults alone
        pass
    return values


def _names(motor: StudioMotor) -> set[str]:
    from ..registers import Access
    from .groups import visible

    return {r.name for r in motor.table if r.access == Access.RW and visible(r)
            and r.name != motor.facts.mode_register}


def flash_values(motor: StudioMotor) -> dict[str, float] | None:
    """The settings in the motor's flash (its defaults if the flash was never written). A
    motor on a line cannot be read from flash: its flash record instead (the settings as
    read when the studio took it up and at each flash write from the studio,
    :attr:`~.line.LineMotor.flash_record`); None where it has none."""
    if not isinstance(motor, SimMotor):
        record = getattr(motor, "flash_record", None)
        return None if record is None else {k: v for k, v in record.items()
                                            if k in _names(motor)}
    with motor.lock:
        image = motor.array.flash_image(0)
    if not image:
        return default_values(motor)
    names = _names(motor)
    out = {}
    for n, raw in image.items():
        reg = motor.register(n)
        if reg.name in names:
            out[reg.name] = float(from_raw(reg, raw))
    return out


def file_values(motor: StudioMotor, text: str, where: str = "setup") -> dict[str, float]:
    """The settings of a setup file's text (:func:`.registers.read_setup`) as ``motor``
    stores them; a register the motor does not have is refused (one line)."""
    out = {}
    for k, v in read_setup(text, where).items():
        try:
            reg = motor.register(k)
        except RegisterError:
            raise ConfigError(f"{where}: the {motor.facts.title} have no register {k}") from None
        out[reg.name] = _stored(motor, reg.name, v)
    return out


@dataclass(frozen=True)
class Difference:
    """One setting of the motor against a baseline.

    Attributes
    ----------
    name : str
        Register name.
    now : float
        The motor's value, in the register's unit.
    base : float or None
        The baseline's value; None where the baseline does not hold it.
    """

    name: str
    now: float
    base: float | None

    @property
    def changed(self) -> bool:
        """True where the baseline holds another value."""
        return self.base is not None and self.base != self.now


def compare(motor: StudioMotor, baseline: dict[str, float]) -> list[Difference]:
    """Every setting of ``motor`` now against ``baseline``, in register order."""
    now = settings_of(motor)
    return [Difference(k, v, baseline.get(k)) for k, v in now.items()]


def changed(differences: list[Difference]) -> list[Difference]:
    """The differences that are changes."""
    return [d for d in differences if d.changed]


def describe(d: Difference, view: UnitsView | None = None, motor: StudioMotor | None = None
             ) -> str:
    """``"KVOUT: 1 → 1.5"``: the baseline's value, then the motor's (in the view's units where
    a view and motor are given)."""
    def txt(value: float | None) -> str:
        if value is None:
            return "—"
        if view is not None and motor is not None:
            reg = motor.register(d.name)
            raw = round(value * FORMAT_SCALE.get(reg.format, 1))
            return f"{view.text(reg, raw)} {view.unit_text(reg)}".rstrip()
        return f"{value:.10g}"
    return f"{d.name}: {txt(d.base)} → {txt(d.now)}"


@dataclass
class History:
    """The edits made through the studio, for undo and redo.

    Attributes
    ----------
    done : list
        (register name, value before, value after) of the edits, oldest first.
    undone : list
        The edits undone, the last undone last (what :meth:`redo` does next).
    """

    motor: StudioMotor
    done: list[tuple[str, float, float]] = field(default_factory=list)
    undone: list[tuple[str, float, float]] = field(default_factory=list)

    def edit(self, name: str, text: str, view: UnitsView | None = None) -> EditResult:
        """An edit (:func:`.registers.edit`) recorded for undo when the motor takes it."""
        reg = self.motor.register(name)
        before = self.motor.read(reg.number)
        result = edit(self.motor, reg.name, text, view)
        if result.ok:
            after = self.motor.read(reg.number)
            if after != before:
                self.done.append((reg.name, before, after))
                self.undone.clear()
        return result

    def undo(self) -> EditResult:
        """Write back the value before the last edit."""
        if not self.done:
            return EditResult(False, "nothing to undo")
        name, before, after = self.done[-1]
        result = edit(self.motor, name, repr(before))
        if result.ok:
            self.undone.append(self.done.pop())
            return EditResult(True, f"undone: {name} {after:.10g} → {before:.10g}")
        return result

    def redo(self) -> EditResult:
        """Make the last undone edit again."""
        if not self.undone:
            return EditResult(False, "nothing to redo")
        name, before, after = self.undone[-1]
        result = edit(self.motor, name, repr(after))
        if result.ok:
            self.done.append(self.undone.pop())
            return EditResult(True, f"redone: {name} {before:.10g} → {after:.10g}")
        return result


def flash_changes(motor: StudioMotor) -> list[Difference] | None:
    """The settings a flash write would change (None where the flash cannot be read)."""
    base = flash_values(motor)
    return None if base is None else changed(compare(motor, base))


def write_flash(motor: StudioMotor) -> EditResult:
    """Save the motor's settings in flash with the family's own actions: safe mode, then the
    flash write, which resets the motor from the flash (MAC050–141 manual 5.1, MIS manual
    §18.2.5, §18.2.7); on a motor on a line the settings saved become its flash record."""
    actions = motor.actions()
    if "save in flash" not in actions:
        return EditResult(False, f"{motor.label}: the {motor.facts.title} have no flash write")
    saved = None if isinstance(motor, SimMotor) else settings_of(motor)
    if "safe mode" in actions:
        actions["safe mode"]()
    actions["save in flash"]()
    if saved is not None:  # what the flash of a motor on a line now holds
        motor.flash_record = saved  # type: ignore[attr-defined]
    return EditResult(True, f"{motor.label}: settings saved in flash")
