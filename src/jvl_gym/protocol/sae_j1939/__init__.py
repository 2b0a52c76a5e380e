"""SAE J1939 of the MIS motors (MIS manual §11.8): the NAME field and address claim, and MAC
register access by the memory access messages DM14/DM15/DM16 (:mod:`.frames`, pure), the
motor's J1939 node (:mod:`.device`) and its service on a python-can bus (:mod:`.node`)."""

from __future__ import annotations

from .device import J1939Device
from .frames import Dm14, Dm15, Dm16, Name

__all__ = ["J1939Device", "Name", "Dm14", "Dm15", "Dm16"]
