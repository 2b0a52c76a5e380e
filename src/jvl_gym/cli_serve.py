"""``jvl-gym serve``: the digital twin on a pseudo-terminal and/or TCP on localhost.

Examples
--------
``jvl-gym serve --motor MAC140 --address 19 --tcp 127.0.0.1:5000``
``jvl-gym serve --motor MAC140 --address 19 --address 20 --pty --speed 4``
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

__all__ = ["app", "serve", "parse_tcp", "banner"]

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


@app.command()
def serve(
    motor: Annotated[list[str] | None, typer.Option(
        "--motor", "-m", help="Motor type (repeat: one per --address; default MAC140).")] = None,
    address: Annotated[list[int] | None, typer.Option(
        "--address", "-a", help="MYADDR 1..254 of each motor (repeat: multi-drop; default 1).")
    ] = None,
    tcp: Annotated[str | None, typer.Option(
        help="MacTalk over TCP, HOST:PORT on localhost (port 0: any free port).")] = None,
    pty: Annotated[bool, typer.Option("--pty", help="MacTalk over a pseudo-terminal.")] = False,
    user_tcp: Annotated[int | None, typer.Option(
        help="FastMAC/FlexMAC user interface of motor i on TCP port BASE+i.")] = None,
    user_pty: Annotated[bool, typer.Option(
        "--user-pty", help="FastMAC/FlexMAC user interfaces on pseudo-terminals.")] = False,
    speed: Annotated[float, typer.Option(help="Simulated seconds per wall-clock second.")] = 1.0,
    seed: Annotated[int, typer.Option(help="Noise seed.")] = 0,
    flash_dir: Annotated[Path | None, typer.Option(
        help="Directory of the flash files (persist 'write to flash' across runs).")] = None,
    record_length: Annotated[int, typer.Option(
        help="TESTU/TESTA record length (manual: 11).")] = 11,
    fastmac_code: Annotated[str, typer.Option(
        help="FastMAC register code: 'example' (manual 5.2.1.5) or 'table' (5.2.1.4).")
    ] = "example",
    verbose: Annotated[bool, typer.Option("--verbose", "-v", help="Log every refusal.")] = False,
) -> None:
    """Serve one or many simulated motors (multi-drop by MYADDR) until Ctrl-C."""
    from .protocol import fastmac as fm
    from .protocol.transport import TwinServer
    from .protocol.twin import Twin
    from .sim import MotorArray

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
    m = MotorArray(types, n=len(address), seed=seed, record_length=record_length)
    twin = Twin(m, list(address), flash_dir=flash_dir, fastmac_code=code)
    server = TwinServer(twin, speed=speed, tcp=parse_tcp(tcp) if tcp else None, pty=pty,
                        user_tcp=user_tcp, user_pty=user_pty)
    server.start()
    for line in banner(types, twin, list(address)):
        typer.echo(line)
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
        typer.echo(f"stopped; {dict(twin.stats)}")


if __name__ == "__main__":
    app()
