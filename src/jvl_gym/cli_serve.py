"""``jvl-gym serve``: the digital twin on a pseudo-terminal and/or TCP on localhost.

Motors of several families may share the line, each answering in its family's MacTalk dialect
(``protocol.bus``); ``--modbus`` serves motors of one 32-bit family (MIS) over Modbus RTU instead
(MIS manual §12).

Examples
--------
``jvl-gym serve --motor MAC140 --address 19 --tcp 127.0.0.1:5000``
``jvl-gym serve --motor MAC140 --address 19 --address 20 --pty --speed 4``
``jvl-gym serve -m MAC140 -a 19 -m MIS231 -a 7 --pty``  (two families, one line)
``jvl-gym serve --motor MIS231 --address 42 --modbus --tcp 127.0.0.1:5020``
``python -m jvl_gym.cli_serve --motor MAC050 --pty --user-pty``  (FastMAC/FlexMAC too)
"""

from __future__ import annotations

import logging
import signal
import threading
from pathlib import Path
from typing import Annotated, Any

import typer

from .cli_app import App

__all__ = ["app", "serve", "parse_tcp", "banner", "build_line"]

app = App(prog="jvl-gym serve", add_completion=False,
          help="Serve simulated MAC motors over serial protocols.")


def banner(types: list[str], twin: Any, given: list[int] | None = None) -> list[str]:
    """One line per motor: its type and the address it answers at (MYADDR now, which a flash
    file may have set; ``given`` are the ``--address`` values, named when they differ)."""
    lines = []
    for i, (t, a) in enumerate(zip(types, twin.addresses())):
        note = ""
        if given is not None and given[i] != a:
            note = f" (from the flash file; --address said {given[i]})"
        lines.append(f"motor {i}: {t} at address {a}{note}")
    return lines


def parse_tcp(text: str) -> tuple[str, int]:
    """``"127.0.0.1:5000"`` or ``"5000"`` → (host, port); only local hosts are allowed."""
    from .protocol.transport import LOCALHOSTS

    host, _, port = text.rpartition(":")
    host = host.strip("[]") or "127.0.0.1"
    if host not in LOCALHOSTS:
        raise typer.BadParameter(f"TCP is served on localhost only, not {host!r}")
    if not port.isdigit() or not 0 <= int(port) <= 65535:
        raise typer.BadParameter(f"bad TCP port in {text!r}")
    return host, int(port)


def build_line(types: list[str], addresses: list[int], seed: int = 0,
               flash_dir: Path | None = None,
               fastmac_code: dict[str, tuple[int, int]] | None = None,
               **array_kw: Any) -> tuple[Any, list[int]]:
    """The twins of ``types`` at ``addresses``: one :class:`~.protocol.twin.Twin` per motor
    family (a :class:`~.protocol.bus.Bus` of them when there are several), and the motor
    indices in the order the line lists them (family by family). With several families each
    keeps its flash files in ``flash_dir/<family key>``; ``array_kw`` go to every
    ``MotorArray``."""
    from .families import family_of_motor
    from .protocol import fastmac as fm
    from .protocol.bus import Bus
    from .protocol.twin import Twin
    from .sim import MotorArray

    groups: dict[str, list[int]] = {}
    for k, t in enumerate(types):
        groups.setdefault(family_of_motor(t).key, []).append(k)
    twins = []
    for key, members in groups.items():
        m = MotorArray([types[k] for k in members], n=len(members), seed=seed, **array_kw)
        where = flash_dir / key if flash_dir is not None and len(groups) > 1 else flash_dir
        twins.append(Twin(m, [addresses[k] for k in members], flash_dir=where,
                          fastmac_code=fastmac_code or fm.DEFAULT_CODE))
    order = [k for members in groups.values() for k in members]
    return (twins[0] if len(twins) == 1 else Bus(twins)), order


@app.command()
def serve(
    motor: Annotated[list[str] | None, typer.Option(
        "--motor", "-m", help="Motor type (repeat: one per --address; default MAC140).")] = None,
    address: Annotated[list[int] | None, typer.Option(
        "--address", "-a", help="MYADDR 1..254 of each motor (repeat: multi-drop; default 1).")
    ] = None,
    tcp: Annotated[str | None, typer.Option(
        help="MacTalk (or Modbus RTU) over TCP, HOST:PORT on localhost (port 0: any free port)."
    )] = None,
    pty: Annotated[bool, typer.Option(
        "--pty", help="MacTalk (or Modbus RTU) over a pseudo-terminal.")] = False,
    modbus: Annotated[bool, typer.Option(
        "--modbus", help="Serve Modbus RTU (MIS manual §12) instead of MacTalk: motors of one "
        "32-bit family (MIS) at addresses 1..247.")] = False,
    modbus_switch: Annotated[bool, typer.Option(
        "--modbus-switch", help="Serve the MIS main channel as the motor does: MacTalk after "
        "power-on, Modbus RTU after 1 s of silence if bit 0 of register 121 is set (MIS manual "
        "§12.2.1).")] = False,
    user_tcp: Annotated[int | None, typer.Option(
        help="FastMAC/FlexMAC user interface of motor i on TCP port BASE+i.")] = None,
    user_pty: Annotated[bool, typer.Option(
        "--user-pty", help="FastMAC/FlexMAC user interfaces on pseudo-terminals.")] = False,
    speed: Annotated[float, typer.Option(help="Simulated seconds per wall-clock second.")] = 1.0,
    seed: Annotated[int, typer.Option(help="Noise seed.")] = 0,
    flash_dir: Annotated[Path | None, typer.Option(
        help="Directory of the flash files (persist 'write to flash' across runs).")] = None,
    record_length: Annotated[int | None, typer.Option(
        help="TESTU/TESTA record length of the MAC050–141 (manual: 11).")] = None,
    fastmac_code: Annotated[str, typer.Option(
        help="FastMAC register code: 'example' (manual 5.2.1.5) or 'table' (5.2.1.4).")
    ] = "example",
    verbose: Annotated[bool, typer.Option("--verbose", "-v", help="Log every refusal.")] = False,
) -> None:
    """Serve one or many simulated motors (multi-drop by MYADDR) until Ctrl-C."""
    from .protocol import fastmac as fm
    from .protocol.transport import TwinServer

    logging.basicConfig(level=logging.INFO if verbose else logging.WARNING)
    motor = motor or ["MAC140"]
    address = address or [1]
    if tcp is None and not pty:
        raise typer.BadParameter("give --tcp HOST:PORT and/or --pty")
    types = motor if len(motor) == len(address) else [motor[0]] * len(address)
    if len(motor) not in (1, len(address)):
        raise typer.BadParameter("give one --motor, or one per --address")
    code = {"example": fm.EXAMPLE_CODE, "table": fm.TABLE_CODE}.get(fastmac_code)
    if code is None:
        raise typer.BadParameter("--fastmac-code is 'example' or 'table'")
    modbus = modbus or modbus_switch
    if modbus and (user_tcp is not None or user_pty):
        raise typer.BadParameter("--modbus serves the main channel only (no --user-tcp/-pty)")
    array_kw = {} if record_length is None else {"record_length": record_length}
    line, order = build_line(types, list(address), seed=seed, flash_dir=flash_dir,
                             fastmac_code=code, **array_kw)
    endpoint = parse_tcp(tcp) if tcp else None
    if modbus:
        server = _modbus_server(line, endpoint, pty, speed, switch=modbus_switch)
    else:
        server = TwinServer(line, speed=speed, tcp=endpoint, pty=pty, user_tcp=user_tcp,
                            user_pty=user_pty)
    server.start()
    for text in banner([types[k] for k in order], line, [address[k] for k in order]):
        typer.echo(text)
    for e in server.endpoints:
        typer.echo(f"{e.what} {e.kind}: {e.url}", err=False)
    typer.echo(f"running at speed {speed}; Ctrl-C to stop")
    done = threading.Event()
    signal.signal(signal.SIGINT, lambda *_: done.set())
    signal.signal(signal.SIGTERM, lambda *_: done.set())
    try:
        done.wait()
    finally:
        server.stop()
        stats = server.bus.stats if modbus else line.stats
        typer.echo(f"stopped; {dict(stats)}")


def _modbus_server(line: Any, tcp: tuple[str, int] | None, pty: bool, speed: float,
                   switch: bool = False) -> Any:
    """A Modbus RTU server of the motors of ``line`` (one twin of a 32-bit family); with
    ``switch``, every stream starts in MacTalk and goes to Modbus as the first motor's register
    121 says (MIS manual §12.2.1), the silence counted from now (power-on)."""
    import time

    from .protocol.modbus_server import (
        ModbusServer,
        ModbusSession,
        ProtocolSwitch,
        SwitchingSession,
    )
    from .protocol.modbus_twin import modbus_bus
    from .protocol.twin import Twin

    if not isinstance(line, Twin):
        raise typer.BadParameter("--modbus serves motors of one family")
    try:
        bus = modbus_bus(line)
    except ValueError as exc:
        raise typer.BadParameter(f"--modbus: {exc}") from None
    for a in line.addresses():
        if not 1 <= a <= 247:
            raise typer.BadParameter(f"--modbus: address {a} is no Modbus slave address "
                                     "(1..247; MIS manual §12.1)")
    if not switch:
        return ModbusServer(line, speed=speed, tcp=tcp, pty=pty, bus=bus, run_clock=True)
    setup = bus.slaves[0].registers.setup
    if setup is None:
        raise typer.BadParameter("--modbus-switch: the family has no Modbus set-up register")
    line_switch = ProtocolSwitch.for_device(bus.slaves[0].device, setup, time.monotonic())

    def switching() -> SwitchingSession:
        return SwitchingSession(line.session(), ModbusSession(bus), line_switch)

    return ModbusServer(line, speed=speed, tcp=tcp, pty=pty, bus=bus, run_clock=True,
                        make_session=switching)


if __name__ == "__main__":
    app()
