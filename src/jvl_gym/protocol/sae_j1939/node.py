"""The J1939 nodes of a twin's motors on a python-can bus: received frames go to each motor's
:class:`.device.J1939Device` under the twin's lock, their answers are sent on the bus."""

from __future__ import annotations

import threading
import time
from collections.abc import Sequence
from typing import Any

import can

from .device import J1939Device

__all__ = ["J1939Node"]


class J1939Node(can.Listener):
    """Serve the motors of ``twin`` as J1939 nodes on ``bus`` (one address each).

    Parameters
    ----------
    twin : MotorTwin
        Its motors and lock.
    bus : can.BusABC
        The CAN bus (any python-can interface: ``virtual``, ``socketcan`` …).
    addresses : sequence of int
        Node address of each motor (§11.8.3).
    """

    def __init__(self, twin: Any, bus: can.BusABC, addresses: Sequence[int]) -> None:
        if len(addresses) != twin.m.n:
            raise ValueError(f"give one J1939 address per motor ({twin.m.n})")
        self.twin = twin
        self.bus = bus
        self.devices = [J1939Device(twin.m, i, a) for i, a in enumerate(addresses)]
        self._lock = threading.Lock()
        self.notifier: can.Notifier | None = None

    def start(self) -> J1939Node:
        """Send the address claims and listen."""
        for d in self.devices:
            self._send(d.claim())
        self.notifier = can.Notifier(self.bus, [self])
        return self

    def close(self) -> None:
        """Stop listening (the bus stays open)."""
        notifier, self.notifier = self.notifier, None
        if notifier is not None:
            notifier.stop()

    def on_message_received(self, msg: can.Message) -> None:
        if not msg.is_extended_id or msg.is_error_frame or msg.is_remote_frame:
            return
        now = time.monotonic()
        out = []
        with self.twin.lock:
            for d in self.devices:
                out += d.handle(msg.arbitration_id, bytes(msg.data), now)
        self._send(out)

    def _send(self, frames: list[Any]) -> None:
        with self._lock:
            for f in frames:
                self.bus.send(can.Message(arbitration_id=f.arbitration_id, data=f.data,
                                          is_extended_id=True))
