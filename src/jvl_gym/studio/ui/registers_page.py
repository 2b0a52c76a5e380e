"""The Registers view: every register of the motor's family, grouped as the manual groups
them, with name, number, value in engineering units (or, with the raw toggle, in the
register's own unit) and in raw counts, range and description; mode registers as the list of
the family's modes, bit registers as named check boxes; edits go through the motor's validated
write, a value typed is written on Enter or on leaving the field; the values refresh live;
setups load and save."""

from __future__ import annotations

from typing import Any

from nicegui import background_tasks, events, run, ui

from ...registers import from_raw
from ..line import LineDown
from ..registers import edit, grouped_registers, load_setup_file, setup_text
from ..session import Session
from ..units_view import Kind, UnitsView
from .common import Page, frame, tid
from .notice import compile_notice
from .parameters_panel import ParametersPanel

#: seconds between two refreshes of the values
REFRESH_S = 0.5


class _Rows:
    """The rows of the page: one widget set per register, rebuilt when the units change."""

    def __init__(self, page: Page, view: UnitsView, panel: ParametersPanel | None = None
                 ) -> None:
        self.page = page
        self.panel = panel
        self.motor = page.motor
        self.view = view
        #: number → (register, kind, widget(s), raw label, row)
        self.fields: dict[int, tuple[Any, str, Any, Any, Any]] = {}
        self.editing: set[int] = set()
        self.typed: set[int] = set()  # numbers of the inputs typed in and not yet written
        self.updating = False  # True while the refresh sets widgets (not the user)
        self.busy = False
        self.marked: set[int] = set()  # numbers of the rows highlighted as changed

    async def write(self, reg: Any, text: str) -> None:
        self.typed.discard(reg.number)  # committed: leaving the field does not send it again
        if self.panel is not None:  # recorded for undo
            result = await run.io_bound(self.panel.history.edit, reg.name, text, self.view)
        else:
            result = await run.io_bound(edit, self.motor, reg.name, text, self.view)
        self.page.say(result.message, result.ok)
        self.editing.discard(reg.number)
        await self.refresh()

    async def write_raw(self, reg: Any, raw: int) -> None:
        """Write a mode or a bit pattern (a raw value) to ``reg``."""
        def go() -> Any:
            if self.panel is not None:
                return self.panel.history.edit(reg.name, str(int(raw)))
            return edit(self.motor, reg.name, str(int(raw)))
        result = await run.io_bound(go)
        self.page.say(result.message, result.ok)
        await self.refresh()

    def build(self, regs: list[Any]) -> None:
        for reg in regs:
            with ui.row().classes("items-center gap-2 w-full no-wrap py-0 my-0") as row:
                ui.label(str(reg.number)).classes("w-8 shrink-0 text-right text-gray-500")
                kind = Kind.VALUE if self.view.raw else self.view.kind(reg)
                widget = self._widget(reg, kind)
                raw = ui.label("").classes("w-28 shrink-0 text-gray-600 text-sm").props(
                    tid("raw-" + reg.name))
                ui.label(self.view.unit_text(reg)).classes("w-24 shrink-0 text-sm").props(
                    tid("unit-" + reg.name))
                ui.label(self.view.range_text(reg)).classes("w-48 shrink-0 text-sm")
                ui.label(f"{reg.access.value} · {reg.description}").classes(
                    "text-sm text-gray-700 truncate").tooltip(reg.description)
            self.fields[reg.number] = (reg, kind, widget, raw, row)

    def _widget(self, reg: Any, kind: str) -> Any:
        writable = reg.access.value == "rw"
        page = self.page
        if kind == Kind.MODE:
            async def set_mode(value: int, reg: Any = reg) -> None:
                if await run.io_bound(self.motor.read_raw, reg.number) != value:
                    await self.write_raw(reg, value)

            def on_mode(e: events.ValueChangeEventArguments, reg: Any = reg) -> None:
                # the refresh setting the value is no user's choice (checked now, not later)
                if not self.updating and e.value is not None:
                    background_tasks.create(page.guard(set_mode)(int(e.value), reg))
            sel = ui.select(self.view.modes(reg), label=reg.name, on_change=on_mode).props(
                f'dense outlined hide-bottom-space {tid("reg-" + reg.name)}'
            ).classes("w-56 shrink-0")
            if not writable:
                sel.disable()
            return sel
        if kind == Kind.BITS:
            boxes = {}
            with ui.row().classes("w-[36rem] shrink-0 gap-x-2 gap-y-0 items-center") as box:
                ui.label(reg.name).classes("text-xs font-bold w-full")
                for f in self.view.bits(reg):
                    async def set_bit(on: bool, bit: int = f.first, reg: Any = reg) -> None:
                        raw = await run.io_bound(self.motor.read_raw, reg.number)
                        new = self.view.with_bit(reg, raw, bit, on)
                        if new != raw:
                            await self.write_raw(reg, new)

                    def on_bit(e: events.ValueChangeEventArguments, bit: int = f.first,
                               reg: Any = reg) -> None:
                        if not self.updating:  # a click, not the refresh
                            background_tasks.create(page.guard(set_bit)(bool(e.value), bit, reg))
                    cb = ui.checkbox(f"{f.first} {f.name}", on_change=on_bit
                                     ).props(f'dense {tid(f"bit-{reg.name}-{f.first}")}'
                                             ).classes("text-xs")
                    if not writable:
                        cb.disable()
                    boxes[f.first] = cb
            box.props(tid("reg-" + reg.name))
            return boxes
        field = ui.input(label=reg.name).props(
            f'dense outlined hide-bottom-space {tid("reg-" + reg.name)}'
            + ("" if writable else " readonly")
        ).classes("w-44 shrink-0")
        field.on("focus", lambda _e, n=reg.number: self.editing.add(n))
        # typed by the user (the refresh setting the value is not): what leaving sends
        field.on_value_change(lambda _e, n=reg.number: None if self.updating
                              else self.typed.add(n))

        async def on_enter(e: events.GenericEventArguments, reg: Any = reg) -> None:
            await self.write(reg, str(e.args))

        async def on_blur(e: events.GenericEventArguments, reg: Any = reg) -> None:
            # a value typed without Enter is written on leaving the field, never dropped
            text = str(e.args)
            if writable and text.strip() and reg.number in self.typed:
                await self.write(reg, text)
            else:
                self.editing.discard(reg.number)
        # the text typed travels with the event: what is written is what is shown
        field.on("keydown.enter", page.guard(on_enter), js_handler="(e) => emit(e.target.value)")
        field.on("blur", page.guard(on_blur), js_handler="(e) => emit(e.target.value)")
        return field

    def show(self, text: str | None) -> None:
        t = (text or "").upper()
        for reg, _k, _w, _r, row in self.fields.values():
            row.set_visibility(not t or t in reg.name.upper() or t in reg.description.upper())

    async def refresh(self) -> None:
        if self.busy or not self.fields:
            return
        self.busy = True
        try:
            raws = await run.io_bound(self.motor.read_raws, list(self.fields))
        except LineDown as exc:
            self.page.say(f"{self.motor.label} not reachable: {exc}", ok=False)
            return
        finally:
            self.busy = False
        values = {reg.name: float(from_raw(reg, raws[n]))
                  for n, (reg, *_rest) in self.fields.items()}
        differ = self.panel.changed_names(values) if self.panel is not None else set()
        if self.panel is not None:
            self.panel.show_count(differ)
        self.updating = True
        try:
            for n, (reg, kind, widget, raw_label, row) in self.fields.items():
                # a setting that differs from the baseline is highlighted (sent on a change)
                mark = reg.name in differ
                if mark != (n in self.marked):
                    row.classes(add="bg-amber-100" if mark else "",
                                remove="" if mark else "bg-amber-100")
                    row.props(f'data-changed="{int(mark)}"')
                    (self.marked.add if mark else self.marked.discard)(n)
                raw_label.set_text(f"raw {raws[n]}")
                if kind == Kind.MODE:
                    if raws[n] not in widget.options:
                        widget.set_options({**widget.options,
                                            raws[n]: self.motor.facts.mode_name(raws[n])})
                    if widget.value != raws[n]:
                        widget.set_value(raws[n])
                elif kind == Kind.BITS:
                    for bit, on in self.view.bits_set(reg, raws[n]).items():
                        if widget[bit].value != on:
                            widget[bit].set_value(on)
                elif n not in self.editing:
                    text = self.view.text(reg, raws[n])
                    if widget.value != text:  # unchanged values are not sent again
                        widget.value = text
        finally:
            self.updating = False


def build(session: Session, m: int) -> None:
    """The Registers page of motor ``m``."""
    page = frame(session, "/registers", m)
    compile_notice(page)
    motor = page.motor
    view = UnitsView(motor.motor_type)
    state: dict[str, Any] = {"rows": _Rows(page, view), "filter": ""}

    async def refresh_rows() -> None:
        await state["rows"].refresh()

    with ui.row().classes("items-center gap-4"):
        ui.label(f"{motor.label} · {motor.facts.title}").classes("text-lg")
        raw = ui.switch("raw (register units)", value=False).props(tid("units-raw"))
        degrees = ui.switch("positions in °", value=False).props(tid("units-degrees"))
        ui.input("filter", on_change=lambda e: (state.update(filter=e.value),
                                                state["rows"].show(e.value))
                 ).props("dense clearable")

        async def save() -> None:
            text = await run.io_bound(setup_text, motor)
            ui.download.content(text, f"{motor.motor_type}_{motor.address}_setup.yaml")
            page.say(f"setup of {motor.label} saved")

        ui.button("save setup", on_click=page.guard(save)).props(
            "dense outline " + tid("save-setup"))

        async def load(e: events.UploadEventArguments) -> None:
            text = await e.file.text()
            result = await run.io_bound(load_setup_file, motor, text, e.file.name)
            page.say(result.message, result.ok)
            await state["rows"].refresh()

        # a compact upload (a button, no list): the table keeps the screen
        ui.upload(label="load setup", auto_upload=True, on_upload=page.guard(load)
                  ).props('accept=".yaml,.yml" flat dense hide-upload-btn '
                          + tid("load-setup")).classes("w-40 max-h-12 overflow-hidden")

    panel = ParametersPanel(page, view, refresh_rows)
    groups = grouped_registers(motor)

    @ui.refreshable
    def table() -> None:
        rows = _Rows(page, view, panel)
        state["rows"] = rows
        for title, regs in groups:
            with ui.expansion(f"{title} ({len(regs)})", value=True).classes("w-full").props(
                    "dense"), ui.column().classes("gap-1 w-full"):  # rows close together
                rows.build(regs)
        rows.show(state["filter"])

    def set_units() -> None:
        view.raw = bool(raw.value)
        view.prefer = {"°"} if degrees.value else set()
        table.refresh()

    raw.on_value_change(page.guard(set_units))
    degrees.on_value_change(page.guard(set_units))
    table()

    async def tick() -> None:
        await state["rows"].refresh()

    page.every(REFRESH_S, page.guard(tick))
