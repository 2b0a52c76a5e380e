"""A family's plain facts in ``family.yaml`` beside its ``__init__.py``: the fields of its
:class:`~.contract.Family` record that are data (key, title, capabilities, the twin's facts,
the J1939 NAME), read by :meth:`~.contract.Family.of_package`.

Every number or string the firmware also uses stays in the family's ``constants`` module and is
written in the file as that constant's name, so it is stated once::

    key: mac800
    title: MAC800 integrated servo motors
    capabilities: [TORQUE, ENERGY]          # Capability members by name
    twin:
      dialects: [MACTALK_DIALECT]           # constants, the default first
      passive_mode: PASSIVE_MODE            # a constant (safe_mode, init_mode, stop_mode
                                            # likewise)
      status_register: ERR_STAT             # a register name, as written
      status_bits: ERR_STAT_BITS            # a constant name → mask, or a list of constants
      error_bits: BLOCKING_ERRORS           # a constant mask (its status bits), or a list of
      clearable_bits: [I2T_ERR, FLW_ERR]    # status-bit names
      commands: {reset: CMD_RESET}          # meaning → constant
    j1939_name: J1939_NAME                  # a constant

A file that is missing, not a mapping, names an unknown field, capability or constant raises
:class:`ValueError` naming the file and the entry.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from types import ModuleType
from typing import Any

import yaml

from .capability import Capability
from .twin_spec import TwinSpec

__all__ = ["FAMILY_FILE", "record_fields"]

FAMILY_FILE = "family.yaml"  #: the file's name in a family's folder
_TOP = ("key", "title", "capabilities", "twin", "j1939_name")
_TWIN = ("dialects", "safe_mode", "init_mode", "passive_mode", "stop_mode", "status_register",
         "status_bits", "error_bits", "clearable_bits", "commands")
_BIT_LISTS = ("error_bits", "clearable_bits")


def record_fields(folder: Path, constants: ModuleType) -> dict[str, Any]:
    """The :class:`~.contract.Family` fields stated in ``folder/family.yaml``.

    Parameters
    ----------
    folder : pathlib.Path
        The family's package folder.
    constants : module
        The family's ``constants``, whose names the file uses.

    Returns
    -------
    dict
        ``key``, ``title``, ``capabilities`` (frozenset of :class:`~.capability.Capability`),
        ``twin`` (:class:`~.twin_spec.TwinSpec`) and ``j1939_name`` where the file has them.

    Raises
    ------
    ValueError
        The file is missing or malformed (the message names the file and the entry).
    """
    path = folder / FAMILY_FILE
    where = str(path)
    try:
        data = yaml.safe_load(path.read_text(encoding="utf-8"))
    except (OSError, yaml.YAMLError) as exc:
        raise ValueError(f"{where}: cannot read the family's facts: {exc}") from exc
    _check_keys(data, _TOP, where)
    out: dict[str, Any] = {k: str(data[k]) for k in ("key", "title") if k in data}
    if "capabilities" in data:
        out["capabilities"] = frozenset(_capability(n, where) for n in data["capabilities"])
    if "twin" in data:
        out["twin"] = _twin(data["twin"], constants, f"{where}: twin")
    if "j1939_name" in data:
        out["j1939_name"] = int(_constant(constants, data["j1939_name"], where))
    return out


def _check_keys(data: Any, known: tuple[str, ...], where: str) -> None:
    if not isinstance(data, Mapping):
        raise ValueError(f"{where}: expected a mapping, got {type(data).__name__}")
    unknown = sorted(set(data) - set(known))
    if unknown:
        raise ValueError(f"{where}: unknown entries {unknown}; known: {', '.join(known)}")


def _capability(name: Any, where: str) -> Capability:
    try:
        return Capability[str(name)]
    except KeyError:
        raise ValueError(f"{where}: no capability {name!r}; known: "
                         f"{', '.join(c.name for c in Capability)}") from None


def _constant(constants: ModuleType, name: Any, where: str) -> Any:
    if not isinstance(name, str) or not hasattr(constants, name):
        raise ValueError(f"{where}: {name!r} is not a constant of {constants.__name__}")
    return getattr(constants, name)


def _twin(data: Any, constants: ModuleType, where: str) -> TwinSpec:
    """The twin's facts (module docstring)."""
    _check_keys(data, _TWIN, where)
    fields: dict[str, Any] = {}
    fields["dialects"] = tuple(_constant(constants, n, where) for n in data.get("dialects", ()))
    for key in ("safe_mode", "init_mode", "passive_mode", "stop_mode"):
        if key in data:
            fields[key] = int(_constant(constants, data[key], where))
    if "status_register" in data:
        fields["status_register"] = str(data["status_register"])
    bits = data.get("status_bits", ())
    names = tuple(_constant(constants, bits, where)) if isinstance(bits, str) else tuple(bits)
    fields["status_bits"] = {int(_constant(constants, n, where)): n for n in names}
    for key in _BIT_LISTS:
        fields[key] = _bit_names(data.get(key, ()), constants, fields["status_bits"], where)
    if "commands" in data:
        fields["commands"] = {str(k): int(_constant(constants, v, where))
                              for k, v in dict(data["commands"]).items()}
    return TwinSpec(**fields)


def _bit_names(given: Any, constants: ModuleType, status_bits: Mapping[int, str],
               where: str) -> tuple[str, ...]:
    """A list of status-bit names, or a constant mask: the names of the bits it covers."""
    if isinstance(given, str):
        mask = int(_constant(constants, given, where))
        return tuple(name for bit, name in status_bits.items() if bit & mask)
    names = tuple(str(n) for n in given)
    for n in names:
        if n not in status_bits.values():
            raise ValueError(f"{where}: {n!r} is not one of the status bits")
    return names
