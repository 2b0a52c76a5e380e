"""DMX512 of the MIS motors (MIS manual chapter 13): the byte stream with its break and start
code (:mod:`.frames`), the motor's receiver — start addresses, scaling, control channel,
jogging by inputs — (:mod:`.receiver`) and its server on a pty or TCP (:mod:`.server`)."""

from __future__ import annotations

from .frames import BREAK, DmxDecoder, DmxPacket, encode_packet
from .receiver import DmxReceiver, DmxSettings

__all__ = ["BREAK", "DmxDecoder", "DmxPacket", "encode_packet", "DmxReceiver", "DmxSettings"]
