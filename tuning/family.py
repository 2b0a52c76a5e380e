"""Which motor family a ``jvl-tune`` command works on, and the facts the toolkit takes from it.

The toolkit reaches a family through its public modules only (``constants``, ``table``,
``config``; docs/architecture.md): the sample times of the current and servo loops, the
encoder's counts per revolution, the PWM full scale, the register table (formats and ranges for
the quantisation), the speed filter's taps and order, how AMPLITUDE scales VF_OUT to the phase
current, the speed feedback's gain, the motor configs and default setups, and whether the
firmware has the TESTU/TESTA test modes.

* ``mac050_141`` (MAC050–141 manual 1.2, 3.2.89–3.2.111, 4.4.9, 4.4.10): 7812.5 Hz / 520.8 Hz,
  4096 counts/rev, Fixed4/Fixed8, a fourth-order speed filter, TESTU/TESTA records
  (:mod:`tuning.autotune`);
* ``mac800`` (MAC800 register overview §1.2): 11550 Hz / 770 Hz, 8000 counts/rev,
  Fixed16/Fixed24, the sixth-order main filter, no test modes: sample-buffer records of torque
  steps (:mod:`tuning.autotune_sixth_order`).

Other families (the MIS/SMC step motors) have no tuning procedure; :func:`tuning_family` says so.
"""

from __future__ import annotations

import functools
import math
import re
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import yaml

from jvl_gym.families import family_of_motor
from jvl_gym.registers import Format, RegisterTable

__all__ = ["TuningFamily", "tuning_family", "family_facts", "SUPPORTED", "SPEED_UNITS"]

#: speed registers' unit per count/sample: V_SOLL, FNC_OUT and the speed error are in
#: 1/16 count/sample (MAC050–141 manual 3.2.5, 3.2.101, 3.2.117; MAC800 register overview §1.2
#: register 5)
SPEED_UNITS: float = 16.0


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
    inner_per_outer : int
        Current-loop samples per servo sample.
    pwm_full : int
        UA_VAL … full scale ↔ half the supply (bus) voltage [PWM counts].
    amplitude_vf : int
        VF_OUT at which the phase current amplitude is AMPLITUDE ADC counts: 1 where AMPLITUDE
        is a fixed-point gain per VF_OUT unit (MAC050–141 manual 3.2.127), VF_FULL where it is
        an integer number of ADC counts at peak torque (MAC800 overview register 174).
    ff_keys, vb_keys, vfx_keys, vfy_keys : tuple of str
        The speed filter's taps in the table, highest number first: FF and VB numerator taps
        of delay 0, 1, …; VF numerator taps of delay 0, 1, …; VF denominator taps of delay
        1, 2, … (MAC050–141 manual 3.2.89–3.2.105; MAC800 overview registers 121–143).
    vb_gain_register : str or None
        The register that scales V_IST into the speed error's unit (GEARB, MAC050–141 manual
        3.2.101); None where the firmware scales it by :data:`SPEED_UNITS` (MAC800:
        ``e = FF(FNC_OUT) − VB(16·V_IST)``, ``firmware/main_filter.py`` of the family).
    load_motor : callable
        The family's motor-config loader (type name, config path or config → config).
    setups_dir : Path
        The family's default setups (``configs/setups``).
    """

    key: str
    inner_dt: float
    outer_dt: float
    counts_per_rev: int
    table: RegisterTable = field(repr=False, compare=False)
    filter_order: int
    test_modes: bool
    inner_per_outer: int
    pwm_full: int
    amplitude_vf: int
    ff_keys: tuple[str, ...]
    vb_keys: tuple[str, ...]
    vfx_keys: tuple[str, ...]
    vfy_keys: tuple[str, ...]
    vb_gain_register: str | None
    load_motor: Callable[[Any], Any] = field(repr=False, compare=False)
    setups_dir: Path = field(repr=False, compare=False)

    @property
    def counts_per_rad(self) -> float:
        """Encoder counts per radian."""
        return self.counts_per_rev / (2.0 * math.pi)

    def default_amplitude(self, cfg: Any) -> float:
        """AMPLITUDE of motor config ``cfg``'s default setup (:attr:`setups_dir`), the table's
        ROM default where the setup file is missing or leaves it out."""
        path = self.setups_dir / f"{cfg.setup}.yaml"
        regs = (yaml.safe_load(path.read_text()) or {}).get("registers") if path.is_file() else {}
        return float((regs or {}).get("AMPLITUDE", self.table.lookup("AMPLITUDE").default))


def _taps(table: RegisterTable, prefix: str) -> tuple[str, ...]:
    """Names ``<prefix><digit>`` in ``table``, highest digit first."""
    names = [reg.name for reg in table if re.fullmatch(prefix + r"\d", reg.name)]
    return tuple(sorted(names, key=lambda n: -int(n[len(prefix):])))


def _facts(key: str, c: Any, table: RegisterTable, load_motor: Callable[[Any], Any],
           setups_dir: Path) -> TuningFamily:
    """A family's tuning facts from its constants ``c``, register ``table`` and configs: the
    speed filter's taps are its KFF, KVB, KVFX and KVFY registers in the table and its order
    the number of KVFX taps (MAC050–141 manual 3.2.89–3.2.111; MAC800 overview, registers
    KVFX6 … KVFX1), the test modes are there when the constants name TESTU and TESTA, AMPLITUDE
    is a gain per VF_OUT unit when its format is fixed-point, and V_IST is scaled by GEARB when
    the table has it."""
    vfx = _taps(table, "KVFX")
    tests = hasattr(c, "TESTU_MODE") and hasattr(c, "TESTA_MODE")
    amp_fixed = table.lookup("AMPLITUDE").format in (Format.FIXED4, Format.FIXED8,
                                                     Format.FIXED16, Format.FIXED24)
    return TuningFamily(
        key, c.INNER_DT, c.OUTER_DT, c.COUNTS_PER_REV, table, len(vfx), tests,
        c.INNER_PER_OUTER, c.PWM_FULL, 1 if amp_fixed else c.VF_FULL, _taps(table, "KFF"),
        _taps(table, "KVB"), vfx, _taps(table, "KVFY"),
        "GEARB" if "GEARB" in table else None, load_motor, setups_dir)


def _mac050_141() -> TuningFamily:
    from jvl_gym.families.mac050_141 import constants as c
    from jvl_gym.families.mac050_141.config import SETUPS_DIR, load_motor
    from jvl_gym.families.mac050_141.table import TABLE

    return _facts("mac050_141", c, TABLE, load_motor, SETUPS_DIR)


def _mac800() -> TuningFamily:
    from jvl_gym.families.mac800 import constants as c
    from jvl_gym.families.mac800.config import load_motor, setup_path
    from jvl_gym.families.mac800.table import TABLE

    return _facts("mac800", c, TABLE, load_motor, setup_path("").parent)


#: the families with a tuning procedure
SUPPORTED = {"mac050_141": _mac050_141, "mac800": _mac800}


@functools.cache
def family_facts(key: str) -> TuningFamily:
    """The tuning facts of the family ``key`` (one of :data:`SUPPORTED`), built once.

    Raises
    ------
    ValueError
        ``key`` has no tuning procedure.
    """
    if key not in SUPPORTED:
        raise ValueError(f"jvl-tune has no tuning procedure for the {key} family; "
                         f"it tunes the {' and '.join(sorted(SUPPORTED))} families")
    return SUPPORTED[key]()


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
    return family_facts(key)
