"""A slow or breaking serial link for tests: a TCP proxy in front of a twin's endpoint.

Every reply of the twin is held ``delay`` seconds before it is passed on (a slow line: the round
trip of a request grows by ``delay``); :meth:`DelayingLink.drop_after` closes the connection
that is open after a number of replies (a broken line; new connections are served again);
:meth:`DelayingLink.hold_reply` holds the reply to one chosen request longer (a line or a motor
that answers one request late, after its master has given up waiting and sent it again).
"""

from __future__ import annotations

import contextlib
import socket
import threading
import time

__all__ = ["DelayingLink", "loopback_round_trip"]


class DelayingLink:
    """A TCP proxy on 127.0.0.1 to ``upstream`` (host, port) that delays every reply.

    Parameters
    ----------
    upstream : tuple (host, port)
        The twin's MacTalk TCP endpoint.
    delay : float
        Seconds each reply chunk is held before it is sent on.
    """

    def __init__(self, upstream: tuple[str, int], delay: float = 0.0) -> None:
        self.upstream = upstream
        self.delay = float(delay)
        self.replies = 0
        self.dropped = 0
        self._drop_at: int | None = None
        self._hold: tuple[bytes, int, float] | None = None  # request, how many more, seconds
        self._held = 0.0  # extra seconds the next reply is held
        self.held = 0
        self._stop = threading.Event()
        self._lock = threading.Lock()
        self._conns: list[socket.socket] = []
        self._srv = socket.create_server(("127.0.0.1", 0))
        self._srv.settimeout(0.1)
        self.url = f"socket://127.0.0.1:{self._srv.getsockname()[1]}"
        self._threads = [threading.Thread(target=self._accept, daemon=True)]
        self._threads[0].start()

    def drop_after(self, replies: int) -> None:
        """Close the open connection once ``replies`` more replies have been passed on."""
        with self._lock:
            self._drop_at = self.replies + int(replies)

    def hold_reply(self, request: bytes, seconds: float, nth: int = 1) -> None:
        """Hold the reply to the ``nth`` request (counted from now) whose bytes are
        ``request`` ``seconds`` longer than the others."""
        with self._lock:
            self._hold = (bytes(request), int(nth), float(seconds))

    def close(self) -> None:
        self._stop.set()
        with self._lock:
            conns = list(self._conns)
        for s in [self._srv, *conns]:
            with contextlib.suppress(OSError):
                s.close()
        for t in self._threads:
            t.join(timeout=2.0)

    def __enter__(self) -> DelayingLink:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _accept(self) -> None:
        while not self._stop.is_set():
            try:
                client, _ = self._srv.accept()
            except TimeoutError:
                continue
            except OSError:
                return
            up = socket.create_connection(self.upstream)
            for s in (client, up):
                s.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            with self._lock:
                self._conns += [client, up]
            for src, dst, slow in ((client, up, False), (up, client, True)):
                t = threading.Thread(target=self._pipe, args=(src, dst, slow, client, up),
                                     daemon=True)
                self._threads.append(t)
                t.start()

    def _pipe(self, src: socket.socket, dst: socket.socket, slow: bool, client: socket.socket,
              up: socket.socket) -> None:
        try:
            while not self._stop.is_set():
                data = src.recv(4096)
                if not data:
                    break
                if not slow:
                    self._count_request(data)
                else:
                    with self._lock:
                        extra, self._held = self._held, 0.0
                    time.sleep(self.delay + extra)
                dst.sendall(data)
                if slow:
                    with self._lock:
                        self.replies += 1
                        drop = self._drop_at is not None and self.replies >= self._drop_at
                        if drop:
                            self._drop_at = None
                            self.dropped += 1
                    if drop:
                        break
        except OSError:
            pass
        for s in (client, up):
            with contextlib.suppress(OSError):
                s.shutdown(socket.SHUT_RDWR)
            with contextlib.suppress(OSError):
                s.close()


    def _count_request(self, data: bytes) -> None:
        """Arm the hold of :meth:`hold_reply` when its request passes (before it is sent on,
        so that its reply finds it armed)."""
        with self._lock:
            if self._hold is None or data != self._hold[0]:
                return
            request, left, seconds = self._hold
            if left > 1:
                self._hold = (request, left - 1, seconds)
                return
            self._hold = None
            self._held = seconds
            self.held += 1


def loopback_round_trip(url: str, address: int, reads: int = 20) -> float:
    """Median round trip [s] of a MacTalk register read to ``url`` (the twin over loopback TCP
    without the proxy)."""
    from jvl_gym.protocol import MacTalkClient

    times = []
    with MacTalkClient(url, address=address) as client:
        for _ in range(reads):
            t0 = time.perf_counter()
            client.read("MODE_REG")
            times.append(time.perf_counter() - t0)
    times.sort()
    return times[len(times) // 2]
