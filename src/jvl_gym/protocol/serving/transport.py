"""The transport every bus's serving side shares: pseudo-terminals and TCP on localhost, with
the simulation paced in real time.

A server that runs the clock steps the twin once before it listens
(:meth:`TwinServer.warm_up`), so the motors' compiled step is ready when the first request
comes: a client's first request is answered within its time-out.

A :class:`TwinServer` serves anything :class:`Served` (the MacTalk twin, a line of several
twins; the Modbus and DMX512 servers are TwinServers of their own sessions) and runs, in daemon
threads,

* a clock that advances the simulation in real time (``speed`` × wall-clock time, whole outer
  samples of each twin's motors, catching up at most ``max_lag`` seconds at once);
* the line's endpoint per pseudo-terminal (``os.openpty``, raw mode; the slave's device path is
  usable by any serial program) and/or a TCP listener on 127.0.0.1 (one session per connection —
  pyserial reaches it as ``socket://127.0.0.1:PORT``); it is named ``mactalk``, the motors'
  main serial channel;
* optionally the user interface of every motor (FastMAC/FlexMAC) on its own pty or TCP port.

An inter-character pause of ``frame_timeout`` seconds ends a partial frame (reported as
truncated). :meth:`TwinServer.stop` shuts everything down and joins the threads.

Limits of a TCP endpoint: at most ``max_connections`` connections at once (a connection beyond
is closed at once, the first of a run of them logged); a connection that sends nothing for
``idle_timeout`` seconds is closed (0: never); an accept that fails for want of resources (no
file descriptors, buffers or memory, or a connection aborted before it was accepted) is retried
after ``accept_backoff`` seconds, so the endpoint accepts again as soon as resources are free.
"""

from __future__ import annotations

import contextlib
import errno
import logging
import os
import select
import socket
import threading
import time
import tty
from collections import Counter, deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol

from ...registers.errors import echo

__all__ = ["TwinServer", "Endpoint", "LOCALHOSTS", "Session", "ByteSession", "Served",
           "MAX_CONNECTIONS", "IDLE_TIMEOUT", "TRANSIENT_ACCEPT_ERRORS", "KEPT_SESSIONS",
           "kept_sessions"]

log = logging.getLogger(__name__)

LOCALHOSTS = ("127.0.0.1", "localhost", "::1")
#: connections a TCP endpoint serves at once by default
MAX_CONNECTIONS = 32
#: seconds without a received byte after which a TCP connection is closed by default
IDLE_TIMEOUT = 300.0
#: sessions a server keeps for inspection (``sessions``), the latest ones
KEPT_SESSIONS = 64


def kept_sessions() -> deque[Any]:
    """The latest sessions of a server, at most :data:`KEPT_SESSIONS` (older ones are let go:
    a server that runs for long holds no more)."""
    return deque(maxlen=KEPT_SESSIONS)
#: errors of ``accept`` that pass: the process or system is out of descriptors, buffers or
#: memory, or the peer gave up before the connection was accepted
TRANSIENT_ACCEPT_ERRORS = frozenset({errno.EMFILE, errno.ENFILE, errno.ECONNABORTED,
                                     errno.ENOBUFS, errno.ENOMEM, errno.EPROTO, errno.EPERM,
                                     errno.EAGAIN, errno.EINTR})


@dataclass
class Endpoint:
    """Where a session is served: a pty path or a TCP (host, port)."""

    kind: str  # "pty" or "tcp"
    what: str  # "mactalk" or "user<i>"
    path: str = ""
    host: str = ""
    port: int = 0

    @property
    def url(self) -> str:
        """A pyserial URL or device path for this endpoint."""
        return self.path if self.kind == "pty" else f"socket://{self.host}:{self.port}"


class ByteSession(Protocol):
    """One byte stream of a bus: received bytes in, the reply bytes out."""

    def feed(self, chunk: bytes) -> bytes: ...
    def flush(self) -> bytes: ...


class Served(Protocol):
    """What a :class:`TwinServer` serves: a session per connection of the line, the user
    interface of each motor, and the simulated time."""

    user: Sequence[ByteSession]

    def session(self) -> ByteSession: ...
    def advance(self, seconds: float) -> None: ...
    def warm_up(self) -> None: ...


@dataclass
class Session:
    """A served stream's two calls: ``feed`` (bytes in → reply) and ``flush`` (the
    inter-character timeout)."""

    feed: Callable[[bytes], bytes]
    flush: Callable[[], bytes]


@dataclass
class TwinServer:
    """Serve a twin over ptys and TCP, with the simulation running in real time.

    Parameters
    ----------
    twin : Served
        The motors served: a MacTalk twin (:class:`~jvl_gym.protocol.mactalk.twin16.Twin`) or a
        line of several (:class:`~jvl_gym.protocol.mactalk.line.Bus`).
    speed : float
        Simulated seconds per wall-clock second (> 0); 1 is real time.
    tcp : tuple (host, port) or None
        MacTalk over TCP; host must be local (127.0.0.1 / localhost); port 0 picks a free one.
    pty : bool
        MacTalk over a pseudo-terminal.
    user_tcp : int or None
        Base port of the FastMAC/FlexMAC user interfaces (motor i on base + i; 0: free ports).
    user_pty : bool
        FastMAC/FlexMAC user interfaces on pseudo-terminals.
    frame_timeout : float
        Inter-character timeout [s] after which a partial frame is dropped as truncated.
    run_clock : bool
        Advance the simulation in real time (False: the caller steps it).
    max_connections : int
        Connections each TCP endpoint serves at once (>= 1); one more is closed at once.
    idle_timeout : float
        Seconds without a received byte after which a TCP connection is closed (0: never).
    accept_backoff : float
        Seconds to wait before accepting again after an accept failed for want of resources.

    Attributes
    ----------
    counts : collections.Counter
        ``accept_errors`` (accepts that failed and were retried), ``refused_connections``
        (beyond ``max_connections``), ``idle_closed`` (closed after ``idle_timeout``).
    """

    twin: Served
    speed: float = 1.0
    tcp: tuple[str, int] | None = None
    pty: bool = False
    user_tcp: int | None = None
    user_pty: bool = False
    frame_timeout: float = 0.5
    run_clock: bool = True
    max_lag: float = 0.25
    endpoints: list[Endpoint] = field(default_factory=list)
    max_connections: int = MAX_CONNECTIONS
    idle_timeout: float = IDLE_TIMEOUT
    accept_backoff: float = 0.05

    def __post_init__(self) -> None:
        if not 0 < self.speed < float("inf"):
            raise ValueError(f"speed must be a finite number > 0, got {self.speed}")
        if isinstance(self.max_connections, bool) or not (
                isinstance(self.max_connections, int) and self.max_connections >= 1):
            raise ValueError(f"max_connections must be an integer >= 1, got "
                             f"{echo(self.max_connections)}")
        if not 0 <= self.idle_timeout < float("inf"):
            raise ValueError(f"idle_timeout must be a finite number of seconds >= 0 (0: never), "
                             f"got {self.idle_timeout}")
        self.counts: Counter[str] = Counter()
        self._open: Counter[str] = Counter()  # open connections per endpoint
        self._refusing: set[str] = set()  # endpoints whose refusals are logged already
        self._stop = threading.Event()
        #: guards _threads and _socks (connection threads remove themselves when they end)
        self._lock = threading.Lock()
        self._threads: list[threading.Thread] = []
        self._fds: list[int] = []
        self._socks: list[socket.socket] = []
        self.lag_events = 0

    # ------------------------------------------------------------------ lifecycle
    def start(self) -> TwinServer:
        """Open the endpoints and start the threads; return self. With ``run_clock`` the
        twin is warmed up first (:meth:`warm_up`): its first request is answered at once."""
        self.warm_up()
        if self.tcp is not None:
            self._listen(self.tcp[0], self.tcp[1], "mactalk", lambda: self._mactalk())
        if self.pty:
            self._open_pty("mactalk", self._mactalk())
        for i in range(len(self.twin.user)):
            if self.user_tcp is not None:
                port = self.user_tcp + i if self.user_tcp else 0
                self._listen("127.0.0.1", port, f"user{i}", lambda i=i: self._user(i))
            if self.user_pty:
                self._open_pty(f"user{i}", self._user(i))
        if self.run_clock:
            self._spawn(self._clock, "twin-clock")
        return self

    def stop(self) -> None:
        """Stop all threads and close all endpoints (idempotent)."""
        self._stop.set()
        with self._lock:
            socks, threads = list(self._socks), list(self._threads)
        for s in socks:
            with contextlib.suppress(OSError):
                s.close()
        for t in threads:
            t.join(timeout=2.0)
        for fd in self._fds:
            with contextlib.suppress(OSError):
                os.close(fd)
        self._fds.clear()
        self._socks.clear()

    def __enter__(self) -> TwinServer:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def endpoint(self, what: str = "mactalk", kind: str | None = None) -> Endpoint:
        """The first endpoint serving ``what`` (of ``kind`` if given)."""
        for e in self.endpoints:
            if e.what == what and (kind is None or e.kind == kind):
                return e
        raise KeyError(f"no {kind or ''} endpoint for {what}")

    def warm_up(self) -> None:
        """With ``run_clock``, step the twin once before anything listens
        (:meth:`~jvl_gym.protocol.serving.twin.MotorTwin.warm_up`: the compile of the
        motors' step, or its load from the cache, is done before a client connects, not under
        the lock while a request waits). Without, the caller steps the twin: nothing here."""
        if self.run_clock and self.twin is not None:
            self.twin.warm_up()

    # ------------------------------------------------------------------ internals
    def _spawn(self, target: Callable[..., None], name: str, *args: object) -> None:
        t = threading.Thread(target=target, args=args, name=name, daemon=True)
        with self._lock:
            self._threads.append(t)
        t.start()

    def _mactalk(self) -> Session:
        s = self.twin.session()
        return Session(s.feed, s.flush)

    def _user(self, i: int) -> Session:
        u = self.twin.user[i]
        return Session(u.feed, u.flush)

    def _clock(self) -> None:
        last = time.monotonic()
        cap = self.max_lag * self.speed  # simulated seconds caught up at most at once
        while not self._stop.wait(0.004):
            now = time.monotonic()
            seconds = (now - last) * self.speed
            last = now
            if seconds > cap:  # the host cannot keep up: drop the backlog rather than spiral
                self.lag_events += 1
                seconds = cap
            self.twin.advance(seconds)

    def _listen(self, host: str, port: int, what: str, make: Callable[[], Session]) -> None:
        if host not in LOCALHOSTS:
            raise ValueError(f"the twin serves TCP on localhost only, not {echo(host)}")
        family = socket.AF_INET6 if host == "::1" else socket.AF_INET
        srv = socket.socket(family, socket.SOCK_STREAM)
        srv.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            srv.bind((host, port))
        except OSError as exc:
            srv.close()
            raise OSError(exc.errno, f"cannot serve {what} on {host}:{port}: "
                                     f"{exc.strerror or exc}; choose another port (0: any free "
                                     "port)") from None
        srv.listen(16)
        srv.settimeout(0.2)
        self._socks.append(srv)
        self.endpoints.append(Endpoint("tcp", what, host=host, port=srv.getsockname()[1]))
        self._spawn(self._accept_loop, f"twin-tcp-{what}", srv, make, what)

    def _accept_loop(self, srv: socket.socket, make: Callable[[], Session],
                     what: str = "mactalk") -> None:
        """Accept connections until the server stops: an accept that fails for want of
        resources is retried after ``accept_backoff`` seconds (logged once per run of
        failures), a connection beyond ``max_connections`` is closed at once."""
        failing = False
        while not self._stop.is_set():
            try:
                conn, _ = srv.accept()
            except TimeoutError:
                continue
            except OSError as exc:
                if self._stop.is_set() or srv.fileno() < 0:
                    return  # the server stopped: its socket is closed
                self.counts["accept_errors"] += 1
                if not failing:
                    failing = True
                    log.warning("%s endpoint cannot accept (%s); retrying every %g s",
                                what, exc.strerror or exc, self.accept_backoff)
                if exc.errno not in TRANSIENT_ACCEPT_ERRORS:
                    log.debug("accept error %r", exc)
                self._stop.wait(self.accept_backoff)
                continue
            if failing:
                failing = False
                log.warning("%s endpoint accepts again", what)
            with self._lock:
                full = self._open[what] >= self.max_connections
                if not full:
                    self._open[what] += 1
                    self._socks.append(conn)
            if full:
                self._refuse(conn, what)
                continue
            conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            self._spawn(self._serve_conn, "twin-conn", conn, make(), what)

    def _refuse(self, conn: socket.socket, what: str) -> None:
        """Close a connection beyond ``max_connections`` (logged once until one closes)."""
        # counted and logged before the close: whoever sees the connection closed sees it
        # counted too
        self.counts["refused_connections"] += 1
        if what not in self._refusing:
            self._refusing.add(what)
            log.warning("%s endpoint serves %d connections at most: a new connection is "
                        "refused until one closes", what, self.max_connections)
        with contextlib.suppress(OSError):
            conn.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, b"\x01\x00\x00\x00"
                            b"\x00\x00\x00\x00")  # a reset: the client knows at once
        conn.close()

    def _serve_conn(self, conn: socket.socket, session: Session,
                    what: str = "mactalk") -> None:
        """Serve one TCP connection until it closes; then release its socket and thread."""
        try:
            self._serve_open_conn(conn, session)
        finally:
            with self._lock:
                self._open[what] -= 1
                self._refusing.discard(what)
                with contextlib.suppress(ValueError):
                    self._socks.remove(conn)
                with contextlib.suppress(ValueError):
                    self._threads.remove(threading.current_thread())

    def _serve_open_conn(self, conn: socket.socket, session: Session) -> None:
        conn.settimeout(self.frame_timeout)
        last = time.monotonic()
        with conn:
            while not self._stop.is_set():
                try:
                    data = conn.recv(4096)
                except TimeoutError:
                    session.flush()
                    if self.idle_timeout and time.monotonic() - last >= self.idle_timeout:
                        self.counts["idle_closed"] += 1
                        log.info("closed a connection idle for %g s", self.idle_timeout)
                        return
                    continue
                except OSError:
                    return
                if not data:
                    return
                last = time.monotonic()
                reply = session.feed(data)
                if reply:
                    try:
                        conn.sendall(reply)
                    except OSError:
                        return

    def _open_pty(self, what: str, session: Session) -> None:
        master, slave = os.openpty()
        tty.setraw(slave)  # bytes pass unchanged: no echo, no CR/LF translation
        path = os.ttyname(slave)
        self._fds += [master, slave]  # keep the slave open: the device stays valid
        self.endpoints.append(Endpoint("pty", what, path=path))
        self._spawn(self._serve_pty, f"twin-pty-{what}", master, session)

    def _serve_pty(self, fd: int, session: Session) -> None:
        while not self._stop.is_set():
            try:
                ready, _, _ = select.select([fd], [], [], self.frame_timeout)
            except (OSError, ValueError):
                return
            if not ready:
                session.flush()
                continue
            try:
                data = os.read(fd, 4096)
            except OSError:
                return
            if not data:
                return
            reply = session.feed(data)
            if reply:
                try:
                    os.write(fd, reply)
                except OSError:
                    return
