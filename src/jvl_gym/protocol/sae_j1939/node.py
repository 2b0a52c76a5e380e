"""The J1939 nodes of a twin's motors on a python-can bus: received frames go to each motor's
:class:`.device.J1939Device` under the twin's lock, their answers are sent on the bus.

One address per node: the motors' addresses must differ (a node refuses to start otherwise,
as two units answering at one address would both carry out every request), and every frame
one motor sends is also heard by the twin's other motors, as on a real bus, so that they know
each other's claims (SAE J1939/81).
"""

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
        self.check_addresses(addresses, twin.m.n)
        self.twin = twin
        self.bus = bus
        self.devices = [J1939Device(twin.m, i, a) for i, a in enumerate(addresses)]
        self._lock = threading.Lock()
        self.notifier: can.Notifier | None = None

    @staticmethod
    def check_addresses(addresses: Sequence[int], n: int) -> None:
        """Nothing if ``addresses`` are ``n`` different addresses; a one-line ValueError
        naming the two motors of one address otherwise (both would answer its requests)."""
        if len(addresses) != n:
            raise ValueError(f"give one J1939 address per motor ({n}), got {len(addresses)}")
        seen: dict[int, int] = {}
        for k, a in enumerate(addresses):
            if a in seen:
                raise ValueError(f"motor {seen[a]} and motor {k} have J1939 address {a}: two "
                                 "nodes at one address would both answer; give each motor "
                                 "its own address")
            seen[a] = k

    def start(self) -> J1939Node:
        """Send the address claims and listen."""
        with self.twin.lock:
            out = []
            for d in self.devices:
                out += self._among(d, d.claim(), time.monotonic())
        self._send(out)
        self.notifier = can.Notifier(self.bus, [self])
        return self

    def _among(self, sender: J1939Device, frames: list[Any], now: float) -> list[Any]:
        """``frames`` sent by ``sender`` and what the twin's other motors answer on hearing
        them (under the twin's lock), to a depth that ends: each answer is heard in turn."""
        out: list[Any] = []
        queue = [(sender, f) for f in frames]
        for _ in range(16 * len(self.devices) + len(queue)):  # claims settle in a few rounds
            if not queue:
                break
            source, frame = queue.pop(0)
            out.append(frame)
            for d in self.devices:
                if d is not source:
                    queue += [(d, f) for f in d.handle(frame.arbitration_id, frame.data, now)]
        return out + [f for _, f in queue]

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
                out += self._among(d, d.handle(msg.arbitration_id, bytes(msg.data), now), now)
        self._send(out)

    def _send(self, frames: list[Any]) -> None:
        with self._lock:
            for f in frames:
                self.bus.send(can.Message(arbitration_id=f.arbitration_id, data=f.data,
                                          is_extended_id=True))
