"""The MAC050, MAC095, MAC140 and MAC141 integrated servo motors (technical manual)."""

from __future__ import annotations

from .. import Family
from . import compiled

FAMILY = Family(key="mac050_141", title="MAC050–141 integrated servo motors", compiled=compiled)
