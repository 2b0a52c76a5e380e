"""The Connections view: the serial ports of this machine, the lines the studio holds (connect,
scan an address range, add what the scan found, disconnect), simulated motors, and the motors
of the studio with their remove buttons (the logic: :mod:`jvl_gym.studio.connections`)."""

from __future__ import annotations

from typing import Any

from nicegui import run, ui

from ..connections import Connections, Found, lines_of, motor_types, serial_ports
from ..session import DEFAULT_MOTOR
from .common import Page, frame, tid

__all__ = ["build", "DEFAULT_RANGE"]

#: the address range a scan proposes
DEFAULT_RANGE = "1-32"
#: the columns of a scan's table
COLUMNS = ("address", "MacTalk", "type", "firmware", "serial", "")


def _found_row(page: Page, conn: Connections, k: int, port: str, f: Found,
               redraw: Any) -> None:
    """One motor a scan found, with its add button (and a type choice where the scan could
    not name the type)."""
    from ...families import families, family

    with ui.row().classes("items-center gap-4 w-full no-wrap").props(
            tid(f"found-{k}-{f.address}")):
        ui.label(str(f.address)).classes("w-16")
        ui.label(f.dialect).classes("w-24")
        types = [t for key in families() if family(key).twin.dialect == f.dialect
                 for t in family(key).motor_types()]
        choice = None
        if f.motor_type is None:
            choice = ui.select(types, value=types[0] if types else None, label="type").props(
                "dense " + tid(f"found-type-{k}-{f.address}")).classes("w-28")
        else:
            ui.label(f.type_text).classes("w-28 font-bold")
        ui.label(f.firmware).classes("w-20").props(tid(f"found-firmware-{k}-{f.address}"))
        ui.label(f.serial).classes("w-24").props(tid(f"found-serial-{k}-{f.address}"))

        async def add() -> None:
            motor = await run.io_bound(conn.add, port, f.address,
                                       None if choice is None else choice.value)
            page.say(f"added {motor.label}")
            redraw()
        ui.button("add", on_click=page.guard(add)).props(
            "dense outline " + tid(f"add-{k}-{f.address}"))
        if f.note:
            ui.label(f.note).classes("text-xs text-gray-600")


def _line_card(page: Page, conn: Connections, k: int, port: str, motors: list,
               redraw: Any) -> None:
    """One line: its port and state, its motors, scan and disconnect."""
    line = conn.session.lines[port]
    with ui.card().classes("w-full").props(tid(f"line-{k}")):
        with ui.row().classes("items-center gap-4"):
            ui.label(port).classes("font-mono font-bold")
            ui.label(line.problem or "open").classes(
                "text-negative" if line.problem else "text-positive")
            ui.label("motors: " + (", ".join(m.label for m in motors) or "none")).props(
                tid(f"line-motors-{k}"))
        with ui.row().classes("items-center gap-2"):
            addresses = ui.input("addresses", value=DEFAULT_RANGE).props(
                "dense " + tid(f"scan-range-{k}")).classes("w-28")

            async def scan() -> None:
                page.say(f"scanning {port} at {addresses.value} …")
                found = await run.io_bound(conn.scan, port, addresses.value or "")
                page.say(f"found {len(found)} on {port}: "
                         + ", ".join(f"{f.type_text} @ {f.address}" for f in found))
                redraw()

            async def add_all() -> None:
                added = await run.io_bound(conn.add_found, port)
                page.say("added " + (", ".join(m.label for m in added) or "nothing new"))
                redraw()

            async def disconnect() -> None:
                said = await run.io_bound(conn.disconnect, port)
                page.say(f"disconnected {port}" + (": " + "; ".join(said) if said else ""))
                redraw()
            ui.button("scan", on_click=page.guard(scan)).props(
                "dense unelevated " + tid(f"scan-{k}"))
            ui.button("add all found", on_click=page.guard(add_all)).props(
                "dense outline " + tid(f"add-all-{k}"))
            ui.button("disconnect", on_click=page.guard(disconnect)).props(
                "dense flat color=negative " + tid(f"disconnect-{k}"))
        found = conn.found.get(port, [])
        if found:
            with ui.row().classes("gap-4 text-xs text-gray-600 no-wrap"):
                for title, width in zip(COLUMNS, ("w-16", "w-24", "w-28", "w-20", "w-24", "")):
                    ui.label(title).classes(width)
            for f in found:
                _found_row(page, conn, k, port, f, redraw)


def build(conn: Connections, m: int) -> None:
    """The Connections page."""
    session = conn.session
    page = frame(session, "/connections", m)

    def redraw() -> None:  # the lines' and motors' cards, after a change
        lines.refresh()
        held.refresh()
    with ui.row().classes("w-full gap-4 items-start no-wrap"):
        with ui.column().classes("w-3/5 gap-2"):
            with ui.card().classes("w-full"):
                ui.label("Connect a line").classes("text-lg font-bold")
                ports = serial_ports()
                with ui.row().classes("items-center gap-2 w-full no-wrap"):
                    field = ui.input(
                        "serial port or twin URL", placeholder="socket://127.0.0.1:5000",
                        autocomplete=[p for p, _ in ports]).props(
                        "dense " + tid("connect-port")).classes("grow")

                    async def connect() -> None:
                        line = await run.io_bound(conn.connect, field.value or "")
                        page.say(f"connected {line.port}: scan it for motors")
                        lines.refresh()
                    field.on("keydown.enter", page.guard(connect))
                    ui.button("connect", on_click=page.guard(connect)).props(
                        "unelevated " + tid("connect"))
                with ui.row().classes("gap-2 text-sm").props(tid("serial-ports")):
                    ui.label("serial ports:" if ports else "serial ports: none found")
                    for device, description in ports:
                        ui.button(device, on_click=lambda d=device: field.set_value(d)).props(
                            f'flat dense no-caps title="{description}"')

            @ui.refreshable
            def lines() -> None:
                for k, (port, motors) in enumerate(lines_of(session)):
                    _line_card(page, conn, k, port, motors, redraw)
            lines()
        with ui.column().classes("w-2/5 gap-2"):
            with ui.card().classes("w-full"):
                ui.label("Simulated motor").classes("text-lg font-bold")
                with ui.row().classes("items-center gap-2"):
                    kind = ui.select(motor_types(), value=DEFAULT_MOTOR, label="type",
                                     with_input=True).props(
                        "dense " + tid("sim-type")).classes("w-32")
                    address = ui.number("address", min=1, max=254, precision=0).props(
                        "dense " + tid("sim-address")).classes("w-24")

                    async def add_sim() -> None:
                        a = None if address.value is None else int(address.value)
                        motor = await run.io_bound(conn.add_simulated, kind.value, a)
                        page.say(f"added {motor.label} (simulated)")
                        redraw()
                    ui.button("add simulated", on_click=page.guard(add_sim)).props(
                        "unelevated " + tid("add-sim"))

            @ui.refreshable
            def held() -> None:
                with ui.card().classes("w-full").props(tid("studio-motors")):
                    ui.label("Motors of the studio").classes("text-lg font-bold")
                    if not session.motors:
                        ui.label("none yet: connect a line and scan it, or add a simulated "
                                 "motor")
                    for j, motor in enumerate(session.motors):
                        with ui.row().classes("items-center gap-2"):
                            ui.link(motor.label, f"/?m={j}").props(tid(f"held-{j}"))
                            ui.label("simulated" if motor.simulated else
                                     f"on {motor.line.port}").classes("text-sm text-gray-600")

                            async def remove(label: str = motor.label) -> None:
                                said = await run.io_bound(conn.remove, label)
                                page.say(said)
                                redraw()
                            ui.button("remove", on_click=page.guard(remove)).props(
                                "dense flat color=negative " + tid(f"remove-{j}"))
            held()
