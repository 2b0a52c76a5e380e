"""Serial protocols of the JVL motors: codecs, a client and a digital twin.

* :mod:`.mactalk` — MacTalk (MAC050–141 manual 5.1), :mod:`.fastmac` — FastMAC (5.2.1),
  :mod:`.flexmac` — FlexMAC (5.2.2), :mod:`.mactalk32` — the MacTalk of the 32-bit register
  families (MAC800 serial quick guide §1.3, MIS manual §18.2): pure functions, bytes in / bytes
  out, streaming decoders that resynchronise; :mod:`.dialect` — which MacTalk a family speaks.
* :class:`MacTalkClient` — pyserial client (device path or any pyserial URL such as
  ``socket://127.0.0.1:5000``), typed read/write by register name; :class:`MacTalk32Client`
  the same in the 32-bit MacTalk; both on :mod:`.master` (the port, timeout, retries);
  :mod:`.probe` — which dialect a unit on a line speaks.
* :mod:`.twin` (:mod:`.twin32` for the 32-bit families) and :mod:`.transport` — a simulated
  motor (or several on one bus; :mod:`.bus`: motors of several families on one line) served over
  a pseudo-terminal or TCP on localhost (``jvl-gym serve``).
* :mod:`.modbus` — Modbus RTU of the MIS/SMC motors (MIS manual §12): codec, addressing, PDO
  remapping, RTU framing; :mod:`.modbus_server` — a Modbus RTU slave for any device of 32-bit
  registers over the same transports, with the Modbus timeout and the MacTalk → Modbus switch;
  :mod:`.modbus_twin` — a twin's motors as Modbus slaves (``jvl-gym serve --modbus``).

See ``docs/protocol.md`` for the frame formats and the decisions taken where the manual is
ambiguous.
"""

from __future__ import annotations

from typing import Any

from . import fastmac, flexmac, mactalk, mactalk32, modbus
from .errors import FrameError, NoAnswerError, ProtocolError, RefusedError, UnexpectedReplyError

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
        from .client import MacTalkClient

        return MacTalkClient
    if name == "MacTalk32Client":
        from .client32 import MacTalk32Client

        return MacTalk32Client
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
