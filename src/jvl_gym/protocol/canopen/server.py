"""The CANopen slaves of a twin's motors on a python-can bus, with the simulation's clock.

A :class:`CanopenServer` opens one python-can bus (any interface: ``virtual`` in tests,
``socketcan`` on a ``vcan``/``can`` device, …), makes a :class:`~.slave.CanopenSlave` of every
motor of the twins it is given, sends their boot-up messages and then

* hands every received frame to every slave (a receive thread: a frame is taken off the bus and
  carried out in one step, under the server's lock and the twin's);
* advances simulated time in whole milliseconds: the motors by the outer samples of that
  millisecond (``twin.step``, exact in integers of the motors' rate), then every slave's
  :meth:`~.slave.CanopenSlave.tick` (heartbeat, event timers, EMCY, the DSP-402 drive).

**Clocks.** With ``run_clock`` a clock thread advances time at ``speed`` simulated seconds per
wall-clock second, as the twins' :class:`~jvl_gym.protocol.serving.transport.TwinServer` does
(give that server ``run_clock=False`` when both serve the same twin: one clock). Without it the
caller advances time: :meth:`CanopenServer.advance` first carries out every frame already
received, then runs the milliseconds, so a test that sends frames and then advances is
deterministic: what the slaves do depends on the frames and on simulated time only.
``step_per_frame`` adds that many simulated seconds after each received frame, for a master
that polls until something happens (``canopen``'s ``BaseNode402.homing``): time then moves
with the master's requests.
"""

from __future__ import annotations

import contextlib
import logging
import threading
import time
from fractions import Fraction
from typing import Any

import can

from ..serving.canbus import open_bus as serving_open_bus
from .facts import facts_of
from .objects import build_dictionary
from .slave import CanopenSlave

__all__ = ["CanopenServer", "open_bus"]

log = logging.getLogger(__name__)


def open_bus(interface: str, channel: str, bitrate: int | None = None) -> can.BusABC:
    """A python-can bus (:func:`~jvl_gym.protocol.serving.canbus.open_bus`: ``udp_multicast``
    on loopback only); ValueError (one line) if it cannot be opened."""
    try:
        return serving_open_bus(interface, channel, bitrate)
    except ValueError as exc:
        raise ValueError(f"{exc}; check --can-interface and --can-channel") from None


class CanopenServer:
    """Serve the motors of ``twins`` as CANopen slaves on ``bus``.

    Parameters
    ----------
    twins : list of MotorTwin
        Twins whose motors' family declares CANopen (:func:`~.facts.facts_of`).
    bus : can.BusABC
        An open python-can bus (:func:`open_bus`); closed by :meth:`stop`.
    node_ids : list of int, optional
        Node id of each motor, twin by twin (default: each motor's node-id register).
    speed : float
        Simulated seconds per wall-clock second of the clock thread.
    run_clock : bool
        Advance time in real time (False: the caller calls :meth:`advance`).
    step_per_frame : float
        Simulated seconds added after each received frame (default 0).

    Raises
    ------
    ValueError
        A family without CANopen, a bad or repeated node id (one line).
    """

    def __init__(self, twins: list[Any], bus: can.BusABC, node_ids: list[int] | None = None,
                 speed: float = 1.0, run_clock: bool = True, step_per_frame: float = 0.0,
                 max_lag: float = 0.25) -> None:
        if not 0 < speed < float("inf"):
            raise ValueError(f"speed must be a finite number > 0, got {speed}")
        self.bus = bus
        self.twins = list(twins)
        self.speed = speed
        self.run_clock = run_clock
        self.step_per_frame = step_per_frame
        self.max_lag = max_lag
        self.lock = threading.RLock()
        self.slaves: list[CanopenSlave] = []
        self._owner: list[Any] = []
        self._ms = 0
        self._stepped: list[int] = [0] * len(self.twins)
        self._rate = [Fraction(float(t.m.OUTER_HZ)).limit_denominator(10**6) for t in twins]
        self._stop = threading.Event()
        self._threads: list[threading.Thread] = []
        self.errors = 0
        #: frames sent so far
        self.frames_sent = 0
        total = sum(t.m.n for t in self.twins)
        if node_ids is not None and len(node_ids) != total:
            raise ValueError(f"{len(node_ids)} node ids for {total} motors")
        self._carry = 0.0
        facts = [facts_of(t.m) for t in self.twins]
        ids = [node_ids[k] for k in range(total)] if node_ids is not None else [
            int(t.m.read_raw(f.node_id)[i]) for t, f in zip(self.twins, facts)
            for i in range(t.m.n)]
        for n in ids:
            if not 1 <= int(n) <= 127:
                raise ValueError(f"a CANopen node id is 1..127 (MIS manual §11.1.5), got {n}")
        dup = sorted({n for n in ids if ids.count(n) > 1})
        if dup:
            raise ValueError(f"node id {dup[0]} is given to {ids.count(dup[0])} motors on one "
                             "bus; give each motor its own --node-id")
        k = 0
        for twin, f in zip(self.twins, facts):
            od = build_dictionary(twin.m.table, f)
            for i in range(twin.m.n):
                nid = None if node_ids is None else node_ids[k]
                k += 1
                with twin.lock:
                    s = CanopenSlave(twin.m, i, od, f, self._send, node_id=nid,
                                     on_store=lambda before, twin=twin, i=i:
                                     twin.save_flash_file(i, before))
                self.slaves.append(s)
                self._owner.append(twin)

    # ------------------------------------------------------------------ lifecycle
    def start(self) -> CanopenServer:
        """Boot every slave (boot-up messages) and start the threads; return self. With
        ``run_clock`` the twins are warmed up first
        (:meth:`~jvl_gym.protocol.serving.twin.MotorTwin.warm_up`): the motors' compiled step
        is ready before the first frame is carried out."""
        if self.run_clock:
            for twin in self.twins:
                twin.warm_up()
        with self.lock:
            for s, twin in zip(self.slaves, self._owner):
                with twin.lock:
                    s.boot()
        self._spawn(self._receive, "canopen-rx")
        if self.run_clock:
            self._spawn(self._clock, "canopen-clock")
        return self

    def stop(self) -> None:
        """Stop the threads and close the bus (idempotent)."""
        self._stop.set()
        for t in self._threads:
            t.join(timeout=2.0)
        self._threads.clear()
        with contextlib.suppress(Exception):
            self.bus.shutdown()

    def __enter__(self) -> CanopenServer:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def _spawn(self, target: Any, name: str) -> None:
        t = threading.Thread(target=target, name=name, daemon=True)
        self._threads.append(t)
        t.start()

    # ------------------------------------------------------------------ frames
    def _send(self, cob: int, data: bytes, remote: bool) -> None:
        msg = can.Message(arbitration_id=cob, data=data, is_extended_id=False,
                          is_remote_frame=remote, dlc=len(data))
        try:
            self.bus.send(msg)
            self.frames_sent += 1
        except can.CanError as exc:
            self.errors += 1
            log.warning("CAN send of 0x%03X failed: %s", cob, exc)

    def _handle(self, msg: can.Message) -> None:
        if msg.is_extended_id or msg.is_error_frame:
            return
        data = bytes(msg.data)
        for s, twin in zip(self.slaves, self._owner):
            with twin.lock:
                s.on_frame(msg.arbitration_id, data, msg.is_remote_frame)
        if self.step_per_frame > 0:
            self._run(self.step_per_frame)

    def _take(self) -> bool:
        """Carry out one received frame if there is one; whether there was."""
        with self.lock:
            msg = self.bus.recv(timeout=0)
            if msg is None:
                return False
            try:
                self._handle(msg)
            except Exception:  # a slave's fault must not stop the bus: logged and counted
                self.errors += 1
                log.exception("CANopen frame 0x%03X %s not carried out", msg.arbitration_id,
                              bytes(msg.data).hex())
            return True

    def _receive(self) -> None:
        while not self._stop.is_set():
            try:
                if not self._take():
                    self._stop.wait(0.0005)
            except can.CanError as exc:
                self.errors += 1
                log.warning("CAN receive failed: %s", exc)
                self._stop.wait(0.05)

    # ------------------------------------------------------------------ time
    @property
    def time_ms(self) -> int:
        """Simulated milliseconds since the server was made."""
        return self._ms

    def advance(self, seconds: float) -> None:
        """Carry out the frames received so far, then advance ``seconds`` of simulated time
        (whole milliseconds; the rest is carried to the next call)."""
        with self.lock:
            while self._take():
                pass
            self._run(seconds)

    def _milliseconds(self, seconds: float) -> int:
        """The whole milliseconds of ``seconds`` more simulated time (the rest is carried)."""
        self._carry += seconds * 1000.0
        n = int(self._carry + 1e-9)
        self._carry -= n
        return n

    def _run(self, seconds: float) -> None:
        for _ in range(self._milliseconds(seconds)):
            self._millisecond()

    def _millisecond(self) -> None:
        """One simulated millisecond: the motors' outer samples of it, then every slave's
        tick."""
        self._ms += 1
        for k, twin in enumerate(self.twins):
            due = int(self._ms * self._rate[k] / 1000) - self._stepped[k]
            if due > 0:
                twin.step(due)
                self._stepped[k] += due
        for s, twin in zip(self.slaves, self._owner):
            with twin.lock:
                s.tick()

    def _catch_up(self, seconds: float) -> None:
        """The clock's advance: ``seconds`` of simulated time one millisecond at a time, each
        after the frames received so far. A frame waits for one simulated millisecond of work,
        not for the whole catch-up of a clock that fell behind (up to ``max_lag``: tens of
        milliseconds of work on a busy machine), so a master's SDO request is answered within
        its time-out."""
        with self.lock:
            n = self._milliseconds(seconds)
        for _ in range(n):
            with self.lock:
                while self._take():
                    pass
                self._millisecond()

    def _clock(self) -> None:
        last = time.monotonic()
        cap = self.max_lag * self.speed
        while not self._stop.wait(0.004):
            now = time.monotonic()
            seconds = min((now - last) * self.speed, cap)
            last = now
            self._catch_up(seconds)
