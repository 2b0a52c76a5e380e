"""Which motor family a ``jvl-tune`` command works on, and the facts the toolkit takes from it.

The toolkit reaches a family through its public modules only (``constants``, ``table``,
``config``; docs/architecture.md): the sample times of the current and servo loops, the
encoder's counts per revolution, the register table (formats and ranges for the quantisation),
the main filter's order and whether the firmware has the TESTU/TESTA test modes.

* ``mac050_141`` (MAC050–141 manual 1.2, 3.2.89–3.2.111, 4.4.9, 4.4.10): 7812.5 Hz / 520.8 Hz,
  4096 counts/rev, Fixed4/Fixed8, a fourth-order speed filter, TESTU/TESTA records
  (:mod:`tuning.autotune`);
* ``mac800`` (MAC800 register overview §1.2): 11550 Hz / 770 Hz, 8000 counts/rev,
  Fixed16/Fixed24, the sixth-order main filter, no test modes: sample-buffer records of torque
  steps (:mod:`tuning.autotune800`).

Other families (the MIS/SMC step motors) have no tuning procedure; :func:`tuning_family` says so.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any

from jvl_gym.families import family_of_motor
from jvl_gym.registers import RegisterTable

__all__ = ["TuningFamily", "tuning_family", "SUPPORTED"]


@dataclass(frozen=True)
class TuningFamily:
    """The facts of a motor family the tuning toolkit uses.

    Attributes
    ----------
    key : str
        The family's key (``"mac050_141"``, ``"mac800"``).
    inner_dt, outer_dt : float
        Current-loop and servo sample times [s].
    counts_per_rev : int
        Encoder counts per revolution.
    table : RegisterTable
        The family's register table.
    filter_order : int
        Order of the speed (main) filter VF.
    test_modes : bool
        The firmware has TESTU/TESTA.
    """

    key: str
    inner_dt: float
    outer_dt: float
    counts_per_rev: int
    table: RegisterTable
    filter_order: int
    test_modes: bool


def _facts(key: str, c: Any, table: RegisterTable) -> TuningFamily:
    """A family's tuning facts from its constants ``c`` and register ``table``: the speed
    filter's order is the number of its numerator taps KVFX1 … KVFXn in the table (MAC050–141
    manual 3.2.89–3.2.111; MAC800 overview, registers KVFX6 … KVFX1), the test modes are
    there when the constants name TESTU and TESTA."""
    order = sum(1 for reg in table if re.fullmatch(r"KVFX\d", reg.name))
    tests = hasattr(c, "TESTU_MODE") and hasattr(c, "TESTA_MODE")
    return TuningFamily(key, c.INNER_DT, c.OUTER_DT, c.COUNTS_PER_REV, table, order, tests)


def _mac050_141() -> TuningFamily:
    from jvl_gym.families.mac050_141 import constants as c
    from jvl_gym.families.mac050_141.table import TABLE

    return _facts("mac050_141", c, TABLE)


def _mac800() -> TuningFamily:
    from jvl_gym.families.mac800 import constants as c
    from jvl_gym.families.mac800.table import TABLE

    return _facts("mac800", c, TABLE)


#: the families with a tuning procedure
SUPPORTED = {"mac050_141": _mac050_141, "mac800": _mac800}


def tuning_family(motor: Any) -> TuningFamily:
    """The tuning facts of ``motor``'s family (a motor type name, config path or config).

    Raises
    ------
    ValueError
        The family has no tuning procedure.
    """
    key = family_of_motor(motor).key
    if key not in SUPPORTED:
        raise ValueError(f"jvl-tune has no tuning procedure for the {key} family of {motor!r}; "
                         f"it tunes the {' and '.join(sorted(SUPPORTED))} families")
    return SUPPORTED[key]()
