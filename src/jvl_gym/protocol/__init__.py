"""The motors' buses: one folder per bus, each holding its codec, its client where there is
one, and its serving side; the serving side they share stands apart.

=====================  ====================================================================
:mod:`.mactalk`        MacTalk in both dialects, FastMAC and FlexMAC: codecs, the serial
                       master and clients (:class:`MacTalkClient`, :class:`MacTalk32Client`;
                       a device path or any pyserial URL such as ``socket://127.0.0.1:5000``),
                       the dialect probe, and the twin's MacTalk units and line
:mod:`.modbus`         Modbus RTU of the MIS/SMC motors (MIS manual §12): codec, server, twin
:mod:`.canopen`        CANopen with DSP-402 (MIS manual §11): dictionary, slave, server, EDS
:mod:`.sae_j1939`      SAE J1939: frames, device, node
:mod:`.dmx512`         DMX512: frames, receiver, server
:mod:`.serving`        what every bus's serving side shares: the twin it wraps and the
                       transport (pseudo-terminals, TCP on loopback, the real-time clock)
:mod:`.errors`         the errors every bus raises
=====================  ====================================================================

``mactalk``, ``mactalk32``, ``fastmac``, ``flexmac`` and ``modbus`` stay names of this package
(the codecs), as before the buses became folders. See ``docs/protocol.md`` for the frame formats
and the decisions taken where the manual is ambiguous.
"""

from __future__ import annotations

from typing import Any

from . import mactalk, modbus
from .errors import FrameError, NoAnswerError, ProtocolError, RefusedError, UnexpectedReplyError
from .mactalk import codec32 as mactalk32
from .mactalk import fastmac, flexmac

__all__ = [
    "FrameError",
    "MacTalk32Client",
    "MacTalkClient",
    "NoAnswerError",
    "ProtocolError",
    "RefusedError",
    "UnexpectedReplyError",
    "fastmac",
    "flexmac",
    "mactalk",
    "mactalk32",
    "modbus",
]


def __getattr__(name: str) -> Any:  # the clients need pyserial: import them on first use
    if name == "MacTalkClient":
        from .mactalk.client16 import MacTalkClient

        return MacTalkClient
    if name == "MacTalk32Client":
        from .mactalk.client32 import MacTalk32Client

        return MacTalk32Client
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
