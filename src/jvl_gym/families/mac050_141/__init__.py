"""The MAC050, MAC095, MAC140 and MAC141 integrated servo motors (technical manual).

``FAMILY`` is the family's record (:class:`jvl_gym.families.Family`); its plain facts (key,
title, capabilities, the twin's modes and bits) are in ``family.yaml``.
"""

from __future__ import annotations

from ..contract import Family, TuningSpec
from . import units
from .motors import MacMotorArray
from .table import TABLE

__all__ = ["FAMILY"]

FAMILY = Family.of_package(__name__, array_class=MacMotorArray,
                           tuning=TuningSpec.of("testu_pi", units, TABLE))
