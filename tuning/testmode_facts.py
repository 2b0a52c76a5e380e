"""The rates and scales of TESTU/TESTA records of the family they are asked about
(``Capability.TEST_MODES`` and ``Family.tuning`` of the family contract; MAC050–141 manual
4.4.9, 4.4.10).

A TESTU record is taken at the current-loop rate, a TESTA record at the servo rate (manual
4.4.9, 4.4.10); the CSV format (:mod:`tuning.records`), the TESTU/TESTA fits
(:mod:`tuning.identify_coil`, :mod:`tuning.identify_mechanics`) and the resonance tools use
these numbers of the motor they work on: :func:`record_facts` of its family, or
:func:`record_facts_of` the motor itself. A family without test modes is refused by name.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from jvl_gym.families import Capability, Family
from jvl_gym.registers import RegisterTable

from .family import tuned_family
from .models import MotorData

__all__ = ["RecordFacts", "record_facts", "record_facts_of"]


@dataclass(frozen=True)
class RecordFacts:
    """A family's TESTU/TESTA facts.

    Attributes
    ----------
    family : Family
        The family (its contract record).
    ts_i, ts_o : float
        TESTU (current loop) and TESTA (servo loop) sample times [s].
    inner_per_outer : int
        Current-loop samples per servo sample.
    pwm_full : int
        UA_VAL full scale ↔ U_supply/2 [PWM counts].
    adc_full : int
        IA_IST … measurement range [ADC counts].
    counts_per_rev : int
        Encoder counts per revolution.
    test_record_samples : int
        Samples of a test-mode record the firmware keeps (MAC050–141 manual 4.4.9).
    recordbit : int
        The CNTRL_BITS bit that starts a record.
    """

    family: Family = field(repr=False)
    ts_i: float
    ts_o: float
    inner_per_outer: int
    pwm_full: int
    adc_full: int
    counts_per_rev: int
    test_record_samples: int
    recordbit: int

    @property
    def counts_per_rad(self) -> float:
        """Encoder counts per radian."""
        return self.counts_per_rev / (2.0 * math.pi)

    @property
    def table(self) -> RegisterTable:
        """The family's register table."""
        return self.family.table

    @property
    def constants(self) -> Any:
        """The family's constants (modes, the sample buffer's control bits)."""
        return self.family.constants

    @property
    def rates(self) -> dict[str, float]:
        """Sample rate [Hz] of a record by kind: ``"TESTU"``, ``"TESTA"``."""
        return {"TESTU": 1.0 / self.ts_i, "TESTA": 1.0 / self.ts_o}


def record_facts(fam: Family) -> RecordFacts:
    """The TESTU/TESTA facts of family ``fam``.

    Raises
    ------
    UnsupportedOperation
        The family does not declare ``Capability.TEST_MODES``.
    ValueError
        It has no tuning facts (``Family.tuning`` is None).
    """
    fam.require(Capability.TEST_MODES)
    spec = fam.tuning
    if spec is None:
        raise ValueError(f"{fam.title} have test modes but no tuning facts (Family.tuning)")
    c = fam.constants
    return RecordFacts(family=fam, ts_i=spec.inner_dt, ts_o=spec.outer_dt,
                       inner_per_outer=spec.inner_per_outer, pwm_full=spec.pwm_full,
                       adc_full=c.ADC_FULL, counts_per_rev=spec.counts_per_rev,
                       test_record_samples=c.TEST_RECORD_SAMPLES, recordbit=c.RECORDBIT)


def record_facts_of(motor: Any) -> RecordFacts:
    """The TESTU/TESTA facts of ``motor``'s family: a motor type name, config path or config,
    a :class:`tuning.models.MotorData` (its type name), or a motor array or serial motor (its
    ``family``).

    Raises
    ------
    UnsupportedOperation, ValueError
        As :func:`record_facts`; ValueError also for a motor of no tuned family.
    """
    fam = getattr(motor, "family", None)
    if not isinstance(fam, Family):
        fam = tuned_family(motor.name if isinstance(motor, MotorData) else motor)
    return record_facts(fam)
