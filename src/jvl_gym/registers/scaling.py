"""Linear register units: the two conversions of a register whose unit is a fixed multiple of
a physical quantity, made from the one factor a family's ``units`` module states.

A family's manual gives a unit either as the quantity per register unit ("1 unit = 0.888798 V")
or as register units per quantity ("1 RPM = 2.77056 units"); :func:`linear_unit` takes the
factor as the manual gives it, so that each conversion multiplies or divides by the printed
figure itself.
"""

from __future__ import annotations

from collections.abc import Callable

__all__ = ["linear_unit"]

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
        raise ValueError(f"a unit factor is a finite positive number, got {factor!r}")

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
