"""The MAC050, MAC095, MAC140 and MAC141 integrated servo motors (technical manual)."""

from __future__ import annotations

from .. import Family
from . import compiled
from .config import canonical_motor_name, motor_types
from .motors import MacMotorArray

FAMILY = Family(key="mac050_141", title="MAC050–141 integrated servo motors", compiled=compiled,
                array_class=MacMotorArray, motor_types=motor_types,
                canonical_name=canonical_motor_name)
