"""DMX512 served to the twin's motors over TCP on localhost and/or a pseudo-terminal (the byte
stream of :mod:`.frames`), with the simulation running in real time.

Every stream is one DMX line: its packets go to every motor's :class:`.receiver.DmxReceiver`
(each picks its own slots by its start addresses); a DMX receiver never answers. A poll thread
watches the jogging inputs and the end of a homing every ``poll_interval`` seconds.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass, field

from ..serving.transport import Session, TwinServer, kept_sessions
from ..serving.twin import MotorTwin
from .frames import DmxDecoder, DmxPacket
from .receiver import DmxReceiver, DmxSettings

__all__ = ["DmxLine", "DmxSession", "DmxServer"]


class DmxLine:
    """The DMX receivers of the motors of ``twin`` (one :class:`DmxSettings` each, default
    the MacTalk tab's with Start Address 1 = 1 + 3·i)."""

    def __init__(self, twin: MotorTwin, settings: Sequence[DmxSettings] | None = None) -> None:
        n = twin.m.n
        settings = list(settings) if settings is not None else [
            DmxSettings(start_address1=1 + 3 * i) for i in range(n)]
        if len(settings) != n:
            raise ValueError(f"give one DMX512 setting per motor ({n}), got {len(settings)}")
        self.twin = twin
        self.receivers = [DmxReceiver(twin.m, i, s) for i, s in enumerate(settings)]
        self.packets = 0

    def packet(self, packet: DmxPacket) -> None:
        """One packet to every motor (under the twin's lock)."""
        with self.twin.lock:
            self.packets += 1
            for r in self.receivers:
                r.packet(packet)

    def poll(self) -> None:
        with self.twin.lock:
            for r in self.receivers:
                r.poll()


class DmxSession:
    """One byte stream of a DMX line: bytes in, nothing out."""

    def __init__(self, line: DmxLine) -> None:
        self.line = line
        self.decoder = DmxDecoder()

    def feed(self, chunk: bytes) -> bytes:
        for p in self.decoder.feed(chunk):
            self.line.packet(p)
        return b""

    def flush(self) -> bytes:
        return b""  # a pause in the stream is no end of packet: the next break is


@dataclass
class DmxServer(TwinServer):
    """Serve a :class:`DmxLine` over TCP (``endpoint("dmx", "tcp")``) and/or a pty, and run the
    twin's clock; ``line`` is required."""

    line: DmxLine | None = None
    poll_interval: float = 0.005
    frame_timeout: float = 1.0
    sessions: deque[DmxSession] = field(default_factory=kept_sessions)

    def start(self) -> DmxServer:
        """Open the endpoints and start the threads; return self."""
        if self.line is None:
            raise ValueError("DmxServer needs a line")
        self.warm_up()
        if self.tcp is not None:
            self._listen(self.tcp[0], self.tcp[1], "dmx", self._session)
        if self.pty:
            self._open_pty("dmx", self._session())
        if self.run_clock:
            self._spawn(self._clock, "twin-clock")
        self._spawn(self._poll, "dmx-poll")
        return self

    def _session(self) -> Session:
        assert self.line is not None
        s = DmxSession(self.line)
        self.sessions.append(s)
        return Session(s.feed, s.flush)

    def _poll(self) -> None:
        assert self.line is not None
        while not self._stop.wait(self.poll_interval):
            self.line.poll()
