"""A server is ready when it says so: every server that runs the twin's clock steps the motors
once before it listens (their compiled step is then loaded or compiled, not while a client's
first request waits on the twin's lock for it), and ``jvl-gym serve`` does so before its ready
line and takes Ctrl-C from the moment it prints it."""

from __future__ import annotations

import os
import signal
from typing import Any

import pytest
import typer

from jvl_gym import MotorArray
from jvl_gym.protocol.mactalk.twin16 import Twin
from jvl_gym.protocol.serving.transport import TwinServer


def _recorded(twin: Twin, server: Any) -> list[tuple[int, int]]:
    """Each step of the twin's motors as (outer samples, endpoints the server had open then)."""
    steps: list[tuple[int, int]] = []
    real = twin.m.step

    def step(n_outer: int = 1) -> None:
        steps.append((n_outer, len(server().endpoints)))
        real(n_outer)

    twin.m.step = step  # type: ignore[method-assign]
    return steps


def _modbus(twin: Twin, **kw: Any) -> Any:
    from jvl_gym.protocol.modbus.server import ModbusServer
    from jvl_gym.protocol.modbus.twin import modbus_bus

    return ModbusServer(twin, bus=modbus_bus(twin), **kw)


def _dmx(twin: Twin, **kw: Any) -> Any:
    from jvl_gym.protocol.dmx512.receiver import DmxSettings
    from jvl_gym.protocol.dmx512.server import DmxLine, DmxServer

    return DmxServer(twin, line=DmxLine(twin, [DmxSettings(start_address1=1)]), **kw)


SERVERS = {"mactalk": ("MAC140", TwinServer), "modbus": ("MIS232", _modbus),
           "dmx": ("MIS232", _dmx)}


@pytest.mark.parametrize("kind", SERVERS)
def test_a_server_with_a_clock_steps_the_motors_before_it_listens(kind: str) -> None:
    motor, make = SERVERS[kind]
    twin = Twin(MotorArray(motor, n=1, seed=0), [7])
    holder: list[Any] = []
    steps = _recorded(twin, lambda: holder[0])
    server = make(twin, tcp=("127.0.0.1", 0), run_clock=True, speed=1e-3)
    holder.append(server)
    server.start()
    try:
        assert steps and steps[0] == (1, 0)  # one outer sample, before any endpoint opened
        assert server.endpoints and twin.m.time[0] > 0
    finally:
        server.stop()
        twin.close()


def test_a_server_without_a_clock_leaves_the_stepping_to_its_caller() -> None:
    twin = Twin(MotorArray("MAC140", n=1, seed=0), [7])
    holder: list[Any] = []
    steps = _recorded(twin, lambda: holder[0])
    with TwinServer(twin, tcp=("127.0.0.1", 0), run_clock=False) as server:
        holder.append(server)
        assert steps == [] and twin.m.time[0] == 0  # a simulated clock stays the caller's


def test_the_warm_up_is_one_outer_sample_of_the_twins_time_once() -> None:
    twin = Twin(MotorArray("MAC140", n=1, seed=0), [7])
    twin.warm_up()
    twin.warm_up()
    assert twin.m.time[0] == pytest.approx(twin.outer_dt)
    twin.advance(9.5 * twin.outer_dt)  # the twin's time goes on from there, in whole samples
    assert twin.m.time[0] == pytest.approx(10 * twin.outer_dt)


def test_a_canopen_server_with_a_clock_steps_the_motors_before_it_boots() -> None:
    from jvl_gym.protocol.canopen.server import CanopenServer, open_bus

    twin = Twin(MotorArray("MIS232", n=1, seed=0), [1])
    holder: list[Any] = []
    sent: list[int] = []
    real = twin.m.step

    def step(n_outer: int = 1) -> None:
        sent.append(holder[0].frames_sent)
        real(n_outer)

    twin.m.step = step  # type: ignore[method-assign]
    server = CanopenServer([twin], open_bus("virtual", f"ready-{os.getpid()}"), speed=1e-3)
    holder.append(server)
    server.start()
    try:
        assert sent and sent[0] == 0  # stepped before the boot-up message went out
    finally:
        server.stop()
        twin.close()


def test_serve_steps_the_motors_before_it_makes_a_server(monkeypatch: pytest.MonkeyPatch
                                                         ) -> None:
    from jvl_gym.cli.main import app
    from jvl_gym.protocol.serving import transport

    seen: list[float] = []

    class Server:
        def __init__(self, line: Any, **_: Any) -> None:
            seen.append(float(line.m.time[0]))

        def start(self) -> None:
            raise typer.Exit(3)

    monkeypatch.setattr(transport, "TwinServer", Server)
    with pytest.raises(SystemExit) as info:
        app(["serve", "--motor", "MAC140", "--tcp", "127.0.0.1:0"])
    assert info.value.code == 3 and seen and seen[0] > 0


def test_ctrl_c_right_after_the_ready_line_stops_serve_cleanly(
        monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]) -> None:
    from jvl_gym.cli.main import app

    echo = typer.echo

    def echo_then_interrupt(message: Any = None, *a: Any, **k: Any) -> None:
        echo(message, *a, **k)
        if str(message).startswith("running at speed"):
            os.kill(os.getpid(), signal.SIGINT)  # the user's Ctrl-C, as the line appears

    monkeypatch.setattr(typer, "echo", echo_then_interrupt)
    before = signal.getsignal(signal.SIGINT)
    with pytest.raises(SystemExit) as info:
        app(["serve", "--motor", "MAC140", "--tcp", "127.0.0.1:0"])
    out = capsys.readouterr().out
    assert info.value.code in (0, None) and "stopped" in out, out
    assert signal.getsignal(signal.SIGINT) is before  # serve gave the handler back


def test_a_canopen_clock_that_catches_up_carries_out_a_frame_within_a_millisecond(
        monkeypatch: pytest.MonkeyPatch) -> None:
    """The clock falls 0.25 s behind (its most); a SDO request that arrives 10 simulated ms
    into the catch-up is answered in the next millisecond, not after the whole catch-up."""
    import types

    import can

    from jvl_gym.protocol.canopen import server as server_module
    from jvl_gym.protocol.canopen.server import CanopenServer, open_bus

    channel = f"catch-up-{os.getpid()}"
    readings = iter([1000.0])  # the clock's start; every later reading is 0.25 s on
    monkeypatch.setattr(server_module, "time", types.SimpleNamespace(
        monotonic=lambda: next(readings, 1000.25)))
    twin = Twin(MotorArray("MIS232", n=1, seed=0), [1])
    twin.warm_up()
    server = CanopenServer([twin], open_bus("virtual", channel), speed=1.0)
    master = can.Bus(interface="virtual", channel=channel)
    answered: list[int] = []  # the simulated millisecond of each SDO answer
    send = server.bus.send

    def recorded(msg: can.Message, *a: Any, **k: Any) -> None:
        if msg.arbitration_id == 0x580 + server.slaves[0].node_id:
            answered.append(server.time_ms)
        send(msg, *a, **k)

    monkeypatch.setattr(server.bus, "send", recorded)
    tick = server.slaves[0].tick

    def tick_then_request() -> None:
        tick()
        if server.time_ms == 10:  # an SDO upload of 1000h sub 0, from the master
            master.send(can.Message(arbitration_id=0x600 + server.slaves[0].node_id,
                                    data=bytes([0x40, 0x00, 0x10, 0, 0, 0, 0, 0]),
                                    is_extended_id=False))

    monkeypatch.setattr(server.slaves[0], "tick", tick_then_request)
    server.start()
    try:
        deadline = 600  # polls of the test's own; the answer's simulated time is what counts
        while not answered and deadline:
            server._stop.wait(0.05)
            deadline -= 1
        assert answered and answered[0] <= 11, answered
    finally:
        server.stop()
        master.shutdown()
        twin.close()
