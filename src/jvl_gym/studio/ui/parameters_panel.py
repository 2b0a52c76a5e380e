"""The parameter panel of the Registers view: the baseline the settings are compared with
(flash, defaults or a setup file), the changes listed, undo and redo, and the write to flash
after a confirmation that lists the changes (the logic: :mod:`jvl_gym.studio.parameters`)."""

from __future__ import annotations

from collections.abc import Awaitable, Callable
from typing import Any

from nicegui import events, run, ui

from .. import parameters as P
from ..units_view import UnitsView
from .common import Page, tid

__all__ = ["ParametersPanel"]


class ParametersPanel:
    """The panel; :attr:`baseline` is what the rows highlight against (None: nothing).

    Parameters
    ----------
    page : Page
        The page.
    view : UnitsView
        The units the changes are listed in.
    refresh : callable
        Refreshes the register rows (after an undo, a redo or a flash write).
    """

    def __init__(self, page: Page, view: UnitsView,
                 refresh: Callable[[], Awaitable[None]]) -> None:
        self.page = page
        self.motor = page.motor
        self.view = view
        self.history = P.History(self.motor)
        self.baseline: dict[str, float] | None = None
        self.source = "flash"
        self._refresh = refresh
        with ui.row().classes("items-center gap-2"):
            ui.label("compare with").classes("text-sm")
            self.choice = ui.toggle(["flash", "defaults", "file", "none"], value="flash",
                                    on_change=page.guard(self._choose)).props(
                "dense " + tid("baseline"))
            self.upload = ui.upload(label="setup file", auto_upload=True,
                                    on_upload=page.guard(self._file)).props(
                'accept=".yaml,.yml" flat dense hide-upload-btn ' + tid("baseline-file")
            ).classes("w-40 max-h-12 overflow-hidden")
            self.upload.set_visibility(False)
            ui.button("undo", on_click=page.guard(self._undo)).props(
                "dense outline " + tid("undo"))
            ui.button("redo", on_click=page.guard(self._redo)).props(
                "dense outline " + tid("redo"))
            ui.button("write to flash…", on_click=page.guard(self._confirm)).props(
                "dense color=warning " + tid("write-flash"))
            self.summary = ui.label("").classes("text-sm").props(tid("changes"))
        self.dialog = ui.dialog()
        self._load_baseline()

    def _load_baseline(self) -> None:
        if self.source == "flash":
            self.baseline = P.flash_values(self.motor)
            if self.baseline is None:
                self.page.say(f"{self.motor.label}: the flash cannot be read over the line; "
                              "compare with a setup file saved after the last flash write",
                              ok=False)
        elif self.source == "defaults":
            self.baseline = P.default_values(self.motor)
        elif self.source == "none":
            self.baseline = None

    async def _choose(self, e: events.ValueChangeEventArguments) -> None:
        self.source = str(e.value)
        self.upload.set_visibility(self.source == "file")
        if self.source != "file":
            await run.io_bound(self._load_baseline)
        await self._refresh()

    async def _file(self, e: events.UploadEventArguments) -> None:
        text = await e.file.text()
        self.baseline = P.file_values(self.motor, text, e.file.name)
        self.page.say(f"comparing with {e.file.name}")
        await self._refresh()

    def changed_names(self, values: dict[str, float]) -> set[str]:
        """Names of the settings in ``values`` (name → value now) the baseline differs in."""
        if self.baseline is None:
            return set()
        return {k for k, v in values.items() if k in self.baseline and self.baseline[k] != v}

    def show_count(self, names: set[str]) -> None:
        """Show how many settings differ from the baseline."""
        self.summary.set_text("" if self.baseline is None else
                              f"{len(names)} changed against {self.source}")

    async def _undo(self) -> None:
        result = await run.io_bound(self.history.undo)
        self.page.say(result.message, result.ok)
        await self._refresh()

    async def _redo(self) -> None:
        result = await run.io_bound(self.history.redo)
        self.page.say(result.message, result.ok)
        await self._refresh()

    async def _confirm(self) -> None:
        changes = await run.io_bound(P.flash_changes, self.motor)
        self.dialog.clear()
        with self.dialog, ui.card().props(tid("flash-dialog")):
            ui.label(f"Write the settings of {self.motor.label} to flash?").classes(
                "text-lg")
            if changes is None:
                ui.label("The flash cannot be read over the line: every setting is written.")
            elif not changes:
                ui.label("The flash holds these settings already.")
            for d in changes or []:
                ui.label(P.describe(d, self.view, self.motor)).classes("font-mono text-sm")
            ui.label("The motor goes to safe mode and resets from the flash.").classes(
                "text-sm text-gray-600")
            with ui.row():
                ui.button("write", on_click=self.page.guard(self._write)).props(
                    "color=warning " + tid("flash-confirm"))
                ui.button("cancel", on_click=self.dialog.close).props("flat")
        self.dialog.open()

    async def _write(self) -> None:
        self.dialog.close()
        result: Any = await run.io_bound(P.write_flash, self.motor)
        self.page.say(result.message, result.ok)
        if self.source == "flash":
            await run.io_bound(self._load_baseline)
        await self._refresh()
