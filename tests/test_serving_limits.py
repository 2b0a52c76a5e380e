"""Servers that cannot be starved: a TCP endpoint of the twins survives running out of file
descriptors (it accepts again once they are free), serves a bounded number of connections
(one more is refused at once), and closes a connection that stays idle."""

from __future__ import annotations

import os
import socket
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from jvl_gym import MotorArray
from jvl_gym.protocol.mactalk import codec16 as mt
from jvl_gym.protocol.mactalk.twin16 import Twin
from jvl_gym.protocol.serving.transport import IDLE_TIMEOUT, MAX_CONNECTIONS, TwinServer

ROOT = Path(__file__).resolve().parents[1]


def _twin() -> Twin:
    return Twin(MotorArray("MAC140", n=1, seed=0), [19])


def _ask(sock: socket.socket) -> bytes:
    """A read of MODE_REG: the reply's frame bytes."""
    sock.sendall(mt.encode_read(19, 2))
    reply = b""
    while len(reply) < 9:  # the data reply: sync, address, length, 2 words, end
        chunk = sock.recv(64)
        if not chunk:
            break
        reply += chunk
    return reply


def _connect(port: int) -> socket.socket:
    sock = socket.create_connection(("127.0.0.1", port), timeout=30)
    sock.settimeout(30)
    return sock


def test_the_defaults_are_a_cap_and_an_idle_time() -> None:
    server = TwinServer(_twin(), tcp=("127.0.0.1", 0), run_clock=False)
    assert server.max_connections == MAX_CONNECTIONS == 32
    assert server.idle_timeout == IDLE_TIMEOUT == 300.0
    for bad in ({"max_connections": 0}, {"max_connections": 2.5}, {"idle_timeout": -1.0},
                {"idle_timeout": float("inf")}):
        with pytest.raises(ValueError, match=next(iter(bad))):
            TwinServer(_twin(), tcp=("127.0.0.1", 0), run_clock=False, **bad)


def _answered(port: int) -> socket.socket:
    """A connection that is answered, tried again while the server refuses."""
    for _ in range(200):
        sock = None
        try:
            sock = _connect(port)
            if mt.decode(_ask(sock)).data:
                return sock
        except (OSError, ValueError):
            pass
        if sock is not None:
            sock.close()
    raise AssertionError("no connection was answered")


def test_the_connection_beyond_the_cap_is_refused_and_a_freed_place_is_taken() -> None:
    with TwinServer(_twin(), tcp=("127.0.0.1", 0), run_clock=False,
                    max_connections=2) as server:
        port = server.endpoint("mactalk", "tcp").port
        first, second = _connect(port), _connect(port)
        assert mt.decode(_ask(first)).data and mt.decode(_ask(second)).data
        try:  # closed at once (a reset may come before the connect returns)
            third = _connect(port)
            with third:
                assert third.recv(64) == b""
        except ConnectionResetError:
            pass
        assert server.counts["refused_connections"] == 1
        first.close()
        fourth = _answered(port)  # a place is free again (once the server saw the close)
        assert mt.decode(_ask(second)).data
        fourth.close()
        second.close()


def test_an_idle_connection_is_closed_and_a_busy_one_is_not() -> None:
    with TwinServer(_twin(), tcp=("127.0.0.1", 0), run_clock=False, idle_timeout=0.3,
                    frame_timeout=0.05) as server:
        port = server.endpoint("mactalk", "tcp").port
        idle = _connect(port)
        assert mt.decode(_ask(idle)).data
        assert idle.recv(64) == b""  # the server closed it
        assert server.counts["idle_closed"] >= 1
        idle.close()
    with TwinServer(_twin(), tcp=("127.0.0.1", 0), run_clock=False, idle_timeout=0.0,
                    frame_timeout=0.05) as server:  # 0: never
        sock = _connect(port := server.endpoint("mactalk", "tcp").port)
        sock.settimeout(0.5)
        with pytest.raises(TimeoutError):
            sock.recv(64)
        assert mt.decode(_ask(sock)).data and port
        sock.close()


SCRIPT = textwrap.dedent("""
    import os, resource, socket, sys, time
    from jvl_gym import MotorArray
    from jvl_gym.protocol.mactalk import codec16 as mt
    from jvl_gym.protocol.mactalk.twin16 import Twin
    from jvl_gym.protocol.serving.transport import TwinServer

    # no cap here: the descriptors are the limit
    kw = {"max_connections": 10_000} if "max_connections" in TwinServer.__dataclass_fields__ \
        else {}
    server = TwinServer(Twin(MotorArray("MAC140", n=1, seed=0), [19]), tcp=("127.0.0.1", 0),
                        run_clock=False, **kw).start()
    port = server.endpoint("mactalk", "tcp").port
    used = len(os.listdir("/proc/self/fd"))
    resource.setrlimit(resource.RLIMIT_NOFILE, (used + 40, resource.getrlimit(
        resource.RLIMIT_NOFILE)[1]))
    clients = []
    try:
        while True:  # each connection costs a descriptor here and one in the server
            s = socket.socket()
            clients.append(s)
            s.connect(("127.0.0.1", port))
    except OSError as exc:
        print("exhausted", exc.errno, flush=True)
    time.sleep(0.5)  # the server meets the limit on the connections still to accept
    print("accept errors", getattr(server, "counts", {}).get("accept_errors", 0), flush=True)
    for s in clients:
        s.close()
    clients = []
    answered = False
    deadline = time.monotonic() + 60
    while not answered and time.monotonic() < deadline:
        try:
            s = socket.create_connection(("127.0.0.1", port), timeout=2)
            s.sendall(mt.encode_read(19, 2))
            answered = bool(s.recv(64))
            s.close()
        except OSError:
            time.sleep(0.1)
    print("answered" if answered else "silent", flush=True)
    server.stop()
""")


@pytest.mark.skipif(not Path("/proc/self/fd").exists(), reason="counts descriptors in /proc")
def test_the_endpoint_accepts_again_after_the_descriptors_ran_out(tmp_path) -> None:
    """Under a low RLIMIT_NOFILE (a process of its own) the descriptors run out with
    connections pending; once the clients close, the endpoint answers a new connection."""
    script = tmp_path / "starve.py"
    script.write_text(SCRIPT)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT / "src"), str(ROOT)])}
    run = subprocess.run([sys.executable, str(script)], capture_output=True, text=True,
                         timeout=600, env=env)
    lines = run.stdout.splitlines()
    assert run.returncode == 0, run.stderr[-2000:]
    assert lines[0].startswith("exhausted 24")  # EMFILE
    assert lines[-1] == "answered", run.stdout


def test_a_long_running_server_keeps_a_bounded_number_of_sessions() -> None:
    """Connection after connection, a Modbus server keeps the latest sessions only."""
    from jvl_gym.protocol.modbus import codec as mb
    from jvl_gym.protocol.modbus.server import ModbusServer
    from jvl_gym.protocol.modbus.twin import modbus_bus
    from jvl_gym.protocol.serving.transport import KEPT_SESSIONS

    twin = Twin(MotorArray("MIS232", n=1, seed=0), [7])
    with ModbusServer(twin, tcp=("127.0.0.1", 0), bus=modbus_bus(twin)) as server:
        port = server.endpoint("modbus", "tcp").port
        for _ in range(KEPT_SESSIONS + 6):
            with _connect(port) as sock:
                sock.sendall(mb.encode_read_request(7, 2 * 5, 2))
                assert sock.recv(64)[:2] == bytes([7, 3])
        assert len(server.sessions) == KEPT_SESSIONS
