"""Linear register units: the two conversions of a register whose unit is a fixed multiple of
a physical quantity, made from the one factor a family's ``units`` module states.

A family's manual gives a unit either as the quantity per register unit ("1 unit = 0.888798 V")
or as register units per quantity ("1 RPM = 2.77056 units"); :func:`linear_unit` takes the
factor as the manual gives it, so that each conversion multiplies or divides by the printed
figure itself.

A family lists its linear units in ``units.csv`` beside its ``units`` module (one row a
register unit, :data:`UNIT_COLUMNS`) and makes them names of that module with
:func:`linear_units`; the factors themselves stay constants of the module, with their source.
"""

from __future__ import annotations

import csv
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from .errors import echo

__all__ = ["linear_unit", "linear_units", "UNIT_COLUMNS"]

Conversion = Callable[[float], float]


def linear_unit(register: str, quantity: str, source: str, *,
                quantity_per_unit: float | None = None,
                units_per_quantity: float | None = None) -> tuple[Conversion, Conversion]:
    """The conversions register units → quantity and quantity → register units.

    Parameters
    ----------
    register : str
        The register(s) in this unit, for the docstrings (``"U_BUS"``).
    quantity : str
        The physical quantity with its unit (``"DC bus voltage [V]"``).
    source : str
        The manual's section and worked example (``"register 198: 366 → 325.3 V"``).
    quantity_per_unit, units_per_quantity : float
        The factor as the manual prints it; exactly one is given.

    Returns
    -------
    (callable, callable)
        ``to_quantity(units) -> float`` and its inverse ``to_units(value) -> float``.

    Raises
    ------
    ValueError
        Not exactly one factor given, or a factor that is not a finite positive number.
    """
    if (quantity_per_unit is None) == (units_per_quantity is None):
        raise ValueError("give exactly one of quantity_per_unit and units_per_quantity")
    factor = quantity_per_unit if quantity_per_unit is not None else units_per_quantity
    if not 0.0 < factor < float("inf"):
        raise ValueError(f"a unit factor is a finite positive number, got {echo(factor)}")

    if quantity_per_unit is not None:
        def to_quantity(units: float) -> float:
            return units * factor

        def to_units(value: float) -> float:
            return value / factor
    else:
        def to_quantity(units: float) -> float:
            return units / factor

        def to_units(value: float) -> float:
            return value * factor

    to_quantity.__doc__ = f"{register} units → {quantity} ({source})."
    to_units.__doc__ = f"{quantity} → {register} units (the inverse; {source})."
    return to_quantity, to_units


#: the columns of a family's ``units.csv``: the two conversions' names (``to_units`` empty
#: where only the register → quantity direction is offered), the register(s), the quantity
#: with its unit and the source for the docstrings, the name of the module constant holding the
#: factor and how the manual gives it (``quantity_per_unit`` or ``units_per_quantity``)
UNIT_COLUMNS = ("to_quantity", "to_units", "register", "quantity", "source", "factor",
                "given_as")


def linear_units(path: Path, constants: Mapping[str, Any]) -> dict[str, Conversion]:
    """The conversions of the linear units listed in a family's ``units.csv``.

    Parameters
    ----------
    path : pathlib.Path
        The CSV file, with the header :data:`UNIT_COLUMNS`.
    constants : Mapping
        The names the ``factor`` column refers to (the ``units`` module's globals).

    Returns
    -------
    dict of str to callable
        Conversion name → conversion (:func:`linear_unit`), in the file's order.

    Raises
    ------
    ValueError
        The file is missing, has other columns, or a row names no number or an unknown way of
        giving it (the message names the file and the row).
    """
    try:
        with path.open(encoding="utf-8", newline="") as f:
            rows = list(csv.DictReader(f))
    except OSError as exc:
        raise ValueError(f"{path}: cannot read the unit table: {exc}") from exc
    if not rows or tuple(rows[0]) != UNIT_COLUMNS:
        raise ValueError(f"{path}: expected the columns {', '.join(UNIT_COLUMNS)}")
    out: dict[str, Conversion] = {}
    for line, row in enumerate(rows, start=2):
        factor = constants.get(row["factor"])
        given = row["given_as"]
        if (not isinstance(factor, (int, float)) or isinstance(factor, bool)
                or given not in ("quantity_per_unit", "units_per_quantity")):
            raise ValueError(f"{path}:{line}: factor {echo(row['factor'])} must name a number "
                             "of the "
                             f"units module, given_as quantity_per_unit or units_per_quantity "
                             f"(got {echo(given)})")
        to_quantity, to_units = linear_unit(row["register"], row["quantity"], row["source"],
                                            **{given: float(factor)})
        out[row["to_quantity"]] = to_quantity
        if row["to_units"]:
            out[row["to_units"]] = to_units
    return out
