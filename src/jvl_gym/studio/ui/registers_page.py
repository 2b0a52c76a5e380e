"""The Registers view: every register of the motor's family, grouped as the manual groups
them, with name, number, value in its unit and in raw counts, range and description; edits go
through the motor's validated write; the values refresh live; setups load and save."""

from __future__ import annotations

from typing import Any

from nicegui import events, run, ui

from ..line import LineDown
from ..registers import (
    edit,
    grouped_registers,
    load_setup_file,
    range_text,
    setup_text,
    value_text,
)
from ..session import Session
from .common import frame, tid

#: seconds between two refreshes of the values
REFRESH_S = 0.5


def build(session: Session, m: int) -> None:
    """The Registers page of motor ``m``."""
    page = frame(session, "/registers", m)
    motor = page.motor
    fields: dict[int, tuple[Any, Any, Any, Any]] = {}  # number → (register, input, raw, row)
    editing: set[int] = set()

    async def write(reg: Any, text: str) -> None:
        result = await run.io_bound(edit, motor, reg.name, text)
        page.say(result.message, result.ok)
        editing.discard(reg.number)
        await refresh()

    def writer(reg: Any) -> Any:
        async def on_enter(e: events.GenericEventArguments) -> None:
            await write(reg, str(e.args))
        return page.guard(on_enter)

    with ui.row().classes("items-center gap-4"):
        ui.label(f"{motor.label} · {motor.facts.title}").classes("text-lg")

        async def save() -> None:
            text = await run.io_bound(setup_text, motor)
            ui.download.content(text, f"{motor.motor_type}_{motor.address}_setup.yaml")
            page.say(f"setup of {motor.label} saved")

        ui.button("save setup", on_click=page.guard(save)).props(tid("save-setup"))

        async def load(e: events.UploadEventArguments) -> None:
            text = await e.file.text()
            result = await run.io_bound(load_setup_file, motor, text, e.file.name)
            page.say(result.message, result.ok)
            await refresh()

        ui.upload(label="load setup", auto_upload=True, on_upload=page.guard(load)
                  ).props('accept=".yaml,.yml" flat bordered' + " " + tid("load-setup")
                          ).classes("w-64")
        ui.input("filter", on_change=lambda e: show(e.value)).props("dense clearable")

    groups = grouped_registers(motor)
    for title, regs in groups:
        with ui.expansion(f"{title} ({len(regs)})", value=True).classes("w-full"):
            for reg in regs:
                with ui.row().classes("items-center gap-3 w-full no-wrap") as row:
                    ui.label(str(reg.number)).classes("w-10 shrink-0 text-right text-gray-500")
                    field = ui.input(label=reg.name).props(
                        f'dense outlined {tid("reg-" + reg.name)}'
                        + (" readonly" if reg.access.value != "rw" else "")
                    ).classes("w-48 shrink-0")
                    field.on("focus", lambda _e, n=reg.number: editing.add(n))
                    field.on("blur", lambda _e, n=reg.number: editing.discard(n))
                    # the text typed travels with the event: what Enter writes is what is shown
                    field.on("keydown.enter", writer(reg),
                             js_handler="(e) => emit(e.target.value)")
                    raw = ui.label("").classes("w-32 shrink-0 text-gray-600").props(
                        tid("raw-" + reg.name))
                    ui.label(reg.unit).classes("w-40 shrink-0 text-sm")
                    ui.label(range_text(reg)).classes("w-56 shrink-0 text-sm")
                    ui.label(f"{reg.access.value} · {reg.description}").classes(
                        "text-sm text-gray-700")
                fields[reg.number] = (reg, field, raw, row)

    def show(text: str | None) -> None:
        t = (text or "").upper()
        for _n, (reg, _f, _r, row) in fields.items():
            row.set_visibility(not t or t in reg.name.upper() or t in reg.description.upper())

    busy = [False]

    async def refresh() -> None:
        if busy[0]:
            return
        busy[0] = True
        try:
            raws = await run.io_bound(motor.read_raws, list(fields))
        except LineDown as exc:
            page.say(f"{motor.label} not reachable: {exc}", ok=False)
            return
        finally:
            busy[0] = False
        for n, (reg, field, raw_label, _row) in fields.items():
            raw_label.set_text(f"raw {raws[n]}")
            if n not in editing:
                field.value = value_text(reg, raws[n])

    page.every(REFRESH_S, page.guard(refresh))
