"""The accessors of a family's task interface that every family writes alike, written once.

A compiled task reaches the motors through its family's task interface (``families/<key>/
task.py``, docs/architecture.md): register values by number, data-register stores saturated to
the register's range, the shaft angle and the world inputs. Their code is the same for every
family but for the family's facts: the register table's write limits and the columns of the
family's layout (``S_THETA``, ``I_ANALOG_VOLTS``, ``I_LOAD_TORQUE``, ``I_PULSE_COUNTS``).
:func:`task_accessors` binds these facts into the functions below with
:func:`~jvl_gym.engine.specialize.specialise` and compiles them as a family's own accessors are
compiled (``cache=True, inline="always"``), so that they inline into the task's hooks.
"""

from __future__ import annotations

from collections.abc import Sequence
from types import ModuleType
from typing import Any

from ..registers.table import RegisterTable
from .specialize import specialise
from .view import EngineView

__all__ = ["task_accessors"]

# the family's facts, bound per family by ``task_accessors``; defined here only for linters
RAW_MIN: Any = None
RAW_MAX: Any = None
S_THETA: int = 0
I_ANALOG_VOLTS: int = 0
I_LOAD_TORQUE: int = 0
I_PULSE_COUNTS: int = 0

#: the layout columns the accessors use
_COLUMNS = ("S_THETA", "I_ANALOG_VOLTS", "I_LOAD_TORQUE", "I_PULSE_COUNTS")
_OPTIONS = {"cache": True, "inline": "always"}


def reg(view: EngineView, i: int, number: int) -> int:  # pragma: no cover - compiled
    """Stored integer of register ``number`` of motor ``i`` (a 32-bit register's, or a
    LongInt's 32-bit, value)."""
    return view.regs[i, number]


def set_reg(view: EngineView, i: int, number: int, raw: int) -> None:  # pragma: no cover
    """Store ``raw`` in the read-write data register ``number`` of motor ``i``, saturated to
    the register's range (register table); the firmware uses it from the next outer sample.
    Mode requests and registers with write rules go through ``MotorArray.write``."""
    view.regs[i, number] = min(max(raw, RAW_MIN[number]), RAW_MAX[number])


def shaft_angle(view: EngineView, i: int) -> float:  # pragma: no cover - compiled
    """Shaft (rotor) angle of motor ``i`` relative to the world zero [rad]."""
    return view.state[i, S_THETA]


def set_analog_volts(view: EngineView, i: int, volts: float) -> None:  # pragma: no cover
    """Analogue input of motor ``i`` [V] from the next outer sample on."""
    view.inputs[i, I_ANALOG_VOLTS] = volts


def set_load_torque(view: EngineView, i: int, torque: float) -> None:  # pragma: no cover
    """External load torque on the shaft of motor ``i``, opposing positive rotation [N·m]."""
    view.inputs[i, I_LOAD_TORQUE] = torque


def set_pulse_counts(view: EngineView, i: int, counts: float) -> None:  # pragma: no cover
    """Pulse (gear) input counts of motor ``i`` during the next outer sample."""
    view.inputs[i, I_PULSE_COUNTS] = counts


_TEMPLATES = {fn.__name__: fn for fn in (reg, set_reg, shaft_angle, set_analog_volts,
                                         set_load_torque, set_pulse_counts)}


def task_accessors(family_key: str, source: str, table: RegisterTable, mode_register: int,
                   layout: ModuleType, names: Sequence[str]) -> tuple[Any, ...]:
    """The compiled accessors ``names`` of a family's task interface.

    Parameters
    ----------
    family_key : str
        The family's key (in the accessors' cache names, ``<accessor>__<key>``).
    source : str
        The family's task module (its edits recompile the accessors).
    table : RegisterTable
        The family's register table: ``set_reg`` saturates to its read-write registers'
        ranges.
    mode_register : int
        The mode register's number, which ``set_reg`` does not store (a mode request goes
        through ``MotorArray.write``).
    layout : module
        The family's layout, with the columns the requested accessors use.
    names : sequence of str
        Accessors among ``reg``, ``set_reg``, ``shaft_angle``, ``set_analog_volts``,
        ``set_load_torque``, ``set_pulse_counts``.

    Returns
    -------
    tuple of numba dispatchers
        The accessors in the order of ``names``.
    """
    raw_min, raw_max = table.data_write_limits(mode_register)
    bindings: dict[str, Any] = {"RAW_MIN": raw_min, "RAW_MAX": raw_max}
    bindings.update({name: getattr(layout, name) for name in _COLUMNS if hasattr(layout, name)})
    fns = specialise({name: _TEMPLATES[name] for name in names}, bindings, family_key, source,
                     {name: _OPTIONS for name in names})
    return tuple(fns[name] for name in names)
