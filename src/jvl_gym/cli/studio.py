"""``jvl-gym studio``: the motor workbench in the browser (docs/studio.md).

Examples
--------
``jvl-gym studio``  (no motor yet: connect lines and add motors on the Connections view)
``jvl-gym studio --motor MAC140 --motor MIS232``  (two simulated motors, two families)
``jvl-gym studio --connect socket://127.0.0.1:5000 --address 19``  (a ``jvl-gym serve`` twin)
``jvl-gym studio --connect /dev/ttyUSB0 --scan 1-32 --motor MAC140``  (motors on a line)

It prints the URL to open with the token of this start; every request needs that token
(docs/studio.md, "Who may open the studio").
"""

from __future__ import annotations

import errno
import ipaddress
import socket
from typing import Annotated

import typer

from .app import CliError

__all__ = ["studio", "parse_range", "STUDIO_EXTRA_HINT"]

#: what to do when the studio extra (NiceGUI) is missing
STUDIO_EXTRA_HINT = ("needs the studio extra (NiceGUI): run `make setup-rl` or "
                     "`.venv/bin/pip install -e '.[studio]'`")


def parse_range(text: str) -> range:
    """``--scan``'s ``"1-32"`` → range(1, 33) (:func:`~..studio.connections.address_range`);
    a malformed range is a usage error naming ``--scan``."""
    from ..studio.connections import address_range

    try:
        return address_range(text)
    except ValueError as exc:
        raise typer.BadParameter(f"--scan: {exc}") from None


def check_host(host: str) -> None:
    """Refuse a ``--host`` that is neither an IP address nor a name this machine resolves
    (one line naming the option)."""
    bare = host.strip("[]")
    try:
        ipaddress.ip_address(bare)
        return
    except ValueError:
        pass
    if not bare or all(ch.isdigit() or ch == "." for ch in bare):
        raise CliError(f"--host {host!r} is not an IP address (four numbers 0..255, e.g. "
                       "127.0.0.1) nor a host name")
    try:
        socket.getaddrinfo(bare, None, type=socket.SOCK_STREAM)
    except (socket.gaierror, UnicodeError) as exc:
        raise CliError(f"--host {host!r} does not resolve ({exc}); give an address of this "
                       "machine, e.g. 127.0.0.1") from None


def _port_free(host: str, port: int) -> None:
    """Refuse a ``host``:``port`` the studio cannot listen on: taken (another ``--port``) or
    not an address of this machine (another ``--host``)."""
    bare = host.strip("[]")
    try:
        family = socket.getaddrinfo(bare, port, type=socket.SOCK_STREAM)[0][0]
    except (socket.gaierror, UnicodeError) as exc:
        raise CliError(f"--host {host!r} does not resolve ({exc})") from None
    with socket.socket(family) as s:
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)  # as uvicorn binds
        try:
            s.bind((bare, port))
        except OSError as exc:
            if exc.errno in (errno.EADDRINUSE, errno.EACCES):
                raise CliError(f"cannot listen on port {port} ({exc.strerror}); give another "
                               "--port") from None
            raise CliError(f"cannot listen on --host {host} ({exc.strerror}): not an address "
                           "of this machine; give e.g. 127.0.0.1") from None


def allowed_hosts(host: str) -> list[str]:
    """The names the studio answers to beyond the loopback names: ``host``, and for a
    wildcard host (0.0.0.0, ::) this machine's name and addresses."""
    names = [host]
    if host.strip("[]") in ("0.0.0.0", "::"):
        try:
            hostname = socket.gethostname()
            names += [hostname, socket.getfqdn(), *socket.gethostbyname_ex(hostname)[2]]
        except OSError:
            pass
    return names


#: the warning for a studio that listens beyond this machine
NETWORK_WARNING = ("warning: --host {host} lets the whole network reach this studio, which "
                   "writes registers and moves motors; the token in the URL is required, keep "
                   "it secret")


def studio(
    motor: Annotated[list[str] | None, typer.Option(
        "--motor", "-m", help="Motor type (repeat: several motors, any families). Simulated "
        "in-process unless --connect. None: the studio opens on the Connections view with no "
        "motor.")] = None,
    address: Annotated[list[int] | None, typer.Option(
        "--address", "-a", help="Unit address (MYADDR) of each motor (repeat; default 1, 2, …).")
    ] = None,
    connect: Annotated[str | None, typer.Option(
        help="A twin or a real line: pyserial URL (socket://127.0.0.1:5000) or serial device."
    )] = None,
    scan: Annotated[str | None, typer.Option(
        help="With --connect: the addresses FIRST-LAST to scan for motors (instead of "
        "--address).")] = None,
    host: Annotated[str, typer.Option(
        help="Address the studio listens on (default this machine only; another address lets "
        "the network in, behind the token).")] = "127.0.0.1",
    port: Annotated[int, typer.Option(help="Port the studio listens on.", min=1, max=65535)]
    = 8080,
    no_browser: Annotated[bool, typer.Option("--no-browser", help="Do not open a browser.")]
    = False,
    speed: Annotated[float, typer.Option(
        help="Simulated seconds per wall-clock second: of the simulated motors, or with "
        "--connect of the twin at the other end (its own --speed; 1 for real motors).")]
    = 1.0,
    seed: Annotated[int, typer.Option(help="Noise seed of the simulated motors.")] = 0,
    toolkit: Annotated[str | None, typer.Option(
        help="The tuning toolkit, MODULE[:OBJECT] (default: the one installed as the entry "
        "point jvl_gym.toolkits).")] = None,
    answer_timeout: Annotated[float | None, typer.Option(
        help="Seconds to wait for each reply on a line (--connect and the Connections view; "
        "default: the line's own, a few hundred ms); raise it for a twin on a busy computer or "
        "a slow gateway.")] = None,
) -> None:
    """Open the motor workbench in the browser: motors, registers, scope, tuning, episodes.

    It prints the URL to open, with this start's token, which every page and write needs.

    STOP in every view, or the Escape key, stops every motor.
    """
    try:
        import nicegui  # noqa: F401
    except ImportError as exc:
        raise CliError(STUDIO_EXTRA_HINT) from exc
    from ..studio.lock import Access, is_loopback, new_token
    from ..studio.session import Session
    from ..studio.toolkit import load_toolkit
    from ..studio.ui.app import serve

    if scan is not None and connect is None:
        raise typer.BadParameter("--scan needs --connect (a line to scan)")
    if not 0 < speed < float("inf"):
        raise typer.BadParameter(f"--speed must be a finite number > 0, got {speed}")
    if answer_timeout is not None and not 0 < answer_timeout < float("inf"):
        raise typer.BadParameter(
            f"--answer-timeout must be a finite number of seconds > 0, got {answer_timeout}")
    check_host(host)
    _port_free(host, port)
    try:
        kit = load_toolkit(toolkit) if toolkit is not None else None
    except (ValueError, TypeError) as exc:
        raise CliError(str(exc)) from None
    access = Access(new_token(), port, allowed_hosts(host))
    timeout = {} if answer_timeout is None else {"answer_timeout": answer_timeout}
    try:
        if connect is None and not motor and not address:
            session = Session(speed=speed, toolkit=kit, **timeout)
        elif connect is None:
            session = Session.simulated(motor or [], address or [], seed=seed, speed=speed,
                                        toolkit=kit, **timeout)
        else:
            session = Session.on_line(connect, motor or [], address or [],
                                      parse_range(scan) if scan else None, toolkit=kit,
                                      speed=speed, **timeout)
    except (ValueError, ConnectionError) as exc:
        raise CliError(str(exc)) from None
    if not is_loopback(host):
        typer.echo(NETWORK_WARNING.format(host=host), err=True)
    typer.echo(f"jvl-gym studio with {', '.join(session.labels()) or 'no motor yet'}; open "
               f"{access.url(host)} (Ctrl-C to stop)")
    serve(session, access, host, show=not no_browser)
