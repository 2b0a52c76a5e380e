"""The rates and scales of TESTU/TESTA records: those of the family whose firmware has the test
modes (``Capability.TEST_MODES`` of the family contract; MAC050–141 manual 4.4.9, 4.4.10).

A TESTU record is taken at the current-loop rate, a TESTA record at the servo rate (manual
4.4.9, 4.4.10); both the CSV format (:mod:`tuning.records`) and the TESTU/TESTA fits
(:mod:`tuning.identify_coil`, :mod:`tuning.identify_mechanics`) use these numbers. The family
is found by its capability, never by its key.
"""

from __future__ import annotations

from typing import Any

from jvl_gym.families import Capability, Family, families, family

__all__ = ["TEST_FAMILY", "TS_I", "TS_O", "INNER_PER_OUTER", "PWM_FULL", "ADC_FULL",
           "COUNTS_PER_REV", "COUNTS_PER_RAD", "TABLE", "TEST_RECORD_SAMPLES", "RECORDBIT"]


def _test_family() -> Family:
    for key in families():
        fam = family(key)
        if fam.supports(Capability.TEST_MODES) and fam.tuning is not None:
            return fam
    raise ImportError("no registered family declares Capability.TEST_MODES with a TuningSpec")


#: the family whose firmware has TESTU/TESTA
TEST_FAMILY: Family = _test_family()
_SPEC: Any = TEST_FAMILY.tuning
TS_I: float = _SPEC.inner_dt  #: TESTU sample time (current loop) [s]
TS_O: float = _SPEC.outer_dt  #: TESTA sample time (servo loop) [s]
INNER_PER_OUTER: int = _SPEC.inner_per_outer  #: current-loop samples per servo sample
PWM_FULL: int = _SPEC.pwm_full  #: UA_VAL full scale ↔ U_supply/2 [PWM counts]
ADC_FULL: int = TEST_FAMILY.constants.ADC_FULL  #: IA_IST … measurement range [ADC counts]
COUNTS_PER_REV: int = _SPEC.counts_per_rev  #: encoder counts per revolution
COUNTS_PER_RAD: float = _SPEC.counts_per_rad  #: encoder counts per radian
TABLE = TEST_FAMILY.table  #: the family's register table
#: samples of a test-mode record the firmware keeps (MAC050–141 manual 4.4.9)
TEST_RECORD_SAMPLES: int = TEST_FAMILY.constants.TEST_RECORD_SAMPLES
RECORDBIT: int = TEST_FAMILY.constants.RECORDBIT  #: CNTRL_BITS bit that starts a record
