"""A CANopen bus for the tests: simulated MIS motors served by
:class:`jvl_gym.protocol.canopen.server.CanopenServer` and the ``canopen`` package as master,
on a python-can ``virtual`` bus of its own.

Time is the server's: it moves only when a test calls ``rig.advance(seconds)`` (which first
carries out every frame the master has sent), or, with ``step_per_frame``, by that much after
each frame the master sends. What the motors and slaves do is then a function of the frames and
of simulated time, whatever the wall clock does.
"""

from __future__ import annotations

import itertools
import threading
import time
from typing import Any

import can
import canopen

from jvl_gym import MotorArray
from jvl_gym.protocol.canopen.eds import shipped_path
from jvl_gym.protocol.canopen.server import CanopenServer, open_bus
from jvl_gym.protocol.mactalk.twin16 import Twin

_channels = itertools.count()
#: the master's SDO response time-out [s] (the canopen package's is 0.3 s). The rig's time is
#: simulated, so this wall-clock time-out only stops a master waiting for a server that never
#: answers: answers took 0.7 ms (median) and 34 ms at most at a load average of 24 on two
#: cores, but one request of a test run beside others (load 13) waited more than 0.3 s
SDO_TIMEOUT = 5.0


class Rig:
    """``n`` motors of ``motor`` with node ids ``node_ids`` (default: their register, 5),
    a ``canopen`` network, and a raw bus to send any frame."""

    def __init__(self, motor: str = "MIS232", n: int = 1, node_ids: list[int] | None = None,
                 step_per_frame: float = 0.0, node_class: type = canopen.RemoteNode,
                 flash_dir: Any = None, motors: Any = None, **array_kw: Any) -> None:
        self.channel = f"canopen-test-{next(_channels)}-{time.monotonic_ns()}"
        self.m = motors if motors is not None else MotorArray(motor, n=n, **array_kw)
        self.twin = Twin(self.m, flash_dir=flash_dir)
        self.server = CanopenServer([self.twin], open_bus("virtual", self.channel),
                                    node_ids=node_ids, run_clock=False,
                                    step_per_frame=step_per_frame)
        self.net = canopen.Network()
        self.net.connect(interface="virtual", channel=self.channel)
        self.raw = can.Bus(interface="virtual", channel=self.channel)
        self.frames: list[can.Message] = []
        self.raw_sent = 0
        self.seen = 0
        self.net.notifier.add_listener(self._on_frame)
        self.node_class = node_class
        self.nodes: dict[int, Any] = {}
        self.server.start()
        self.settle()

    def _on_frame(self, msg: can.Message) -> None:
        self.frames.append(msg)
        self.seen += 1

    def node(self, node_id: int = 5) -> Any:
        """The master's view of node ``node_id`` (from the shipped EDS)."""
        if node_id not in self.nodes:
            node = self.node_class(node_id, str(shipped_path()))
            node.sdo.RESPONSE_TIMEOUT = SDO_TIMEOUT
            self.net.add_node(node)
            self.nodes[node_id] = node
        return self.nodes[node_id]

    @property
    def slave(self) -> Any:
        return self.server.slaves[0]

    def advance(self, seconds: float) -> None:
        self.server.advance(seconds)
        self.settle()

    def settle(self) -> None:
        """Carry out the frames sent so far and wait until the master's notifier thread has
        taken every frame the slaves sent."""
        self.server.advance(0)
        deadline = time.monotonic() + 5.0
        while (self.seen < self.raw_sent + self.server.frames_sent
               and time.monotonic() < deadline):
            time.sleep(0.001)

    def clear(self) -> None:
        self.settle()
        self.frames.clear()

    def sent(self, cob: int) -> list[bytes]:
        """Data of the frames on COB-ID ``cob`` since the last :meth:`clear`."""
        self.settle()
        return [bytes(f.data) for f in self.frames
                if f.arbitration_id == cob and not f.is_remote_frame]

    def send(self, cob: int, data: bytes = b"", remote: bool = False) -> None:
        """A raw frame from the master's side, carried out before this returns."""
        self.raw.send(can.Message(arbitration_id=cob, data=data, is_extended_id=False,
                                  is_remote_frame=remote, dlc=len(data)))
        self.raw_sent += 1
        self.server.advance(0)

    def request(self, cob: int, data: bytes, reply: int) -> bytes | None:
        """Send a raw frame and return the data of the first answer on ``reply``."""
        self.clear()
        self.send(cob, data)
        got = self.sent(reply)
        return got[0] if got else None

    def close(self) -> None:
        self.server.stop()
        self.twin.close()  # the flash directory is free for the next twin (a power cycle)
        # wake the master's notifier (it waits up to 1 s for a frame) so it stops at once
        wake = threading.Timer(0.01, lambda: self.raw.send(can.Message(arbitration_id=0x7FF)))
        wake.start()
        self.net.disconnect()
        wake.join()
        self.raw.shutdown()
