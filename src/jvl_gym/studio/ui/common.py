"""What every page shares: the header with the views and the motor choice, the message line,
the guard that turns an error into a message on the page (in the header: always in view, never
over the page's content), and the page's timers, which run only
while its tab is connected."""

from __future__ import annotations

import functools
import inspect
import logging
from collections.abc import Callable
from typing import Any

from nicegui import run, ui

from ...cli.app import one_line
from ..motor import StudioMotor
from ..session import Session

__all__ = ["VIEWS", "WITHOUT_MOTOR", "Page", "frame", "tid", "stop_button", "STOP_KEY",
           "multiple_picker", "redrawn_alone"]

#: the views: path → title
VIEWS = {"/connections": "Connections", "/": "Motors", "/registers": "Registers",
         "/scope": "Scope", "/tuning": "Tuning", "/episodes": "Episodes"}
#: the views that work without a motor (the others send an empty studio to Connections)
WITHOUT_MOTOR = ("/connections", "/episodes")

#: the key that stops every motor, as the STOP button does (also inside an input field)
STOP_KEY = "Escape"

log = logging.getLogger("jvl_gym.studio")

#: the colours of the header's message line (on its dark background): an outcome, an error
OK_CLASS, ERROR_CLASS = "text-green-300", "text-red-300 font-bold"


def tid(name: str) -> str:
    """The props that name an element for the browser tests (``data-testid``)."""
    return f'data-testid="{name}"'


def redrawn_alone() -> Any:
    """A container whose content the browser redraws alone when it changes.

    The browser draws a NiceGUI page as one tree of Vue components; a change of a plain
    element (a label's text) redraws the nearest component around it with everything inside
    that, up to the whole page with its selects and chart. Quasar's ``q-no-ssr`` (in a browser
    no more than a ``div`` around its content) is such a component: a label that changes many
    times a second inside one redraws only itself.
    """
    return ui.element("q-no-ssr")


def multiple_picker(options: list[str], value: list[str], label: str, test_id: str) -> Any:
    """A select of several of ``options`` with a search field, shown as chips, whose list
    closes on each choice with the typed search cleared.

    Quasar's multiple select keeps its list open after a choice, over what lies below it (the
    scope's chart and trigger), with the typed text still in the field, so the next name
    typed after a click in the field is appended to the last; and the key that closes a list,
    Escape, is the studio's STOP (:data:`STOP_KEY`). Here a choice adds its chip and closes
    the list in the browser at once; the field keeps the focus, so typing the next name opens
    the list again, filtered.
    """
    pick = ui.select(options, value=value, multiple=True, label=label, with_input=True).props(
        "use-chips dense " + tid(test_id))
    # in the browser, without the trip to the server: no filtering (it would open the list
    # again), then the list closed
    pick.on("update:model-value", js_handler=f"""() => {{
        const q = getElement({pick.id})?.$refs.qRef;
        if (q) {{ q.updateInputValue('', true); q.hidePopup(); }} }}""")
    return pick


class Page:
    """One open page: its motor and its message line.

    Attributes
    ----------
    motor : StudioMotor or None
        The motor the page works on (None in a studio without motors).
    message : ui.label
        The line that shows the last outcome (``#message``).
    """

    def __init__(self, session: Session, motor: StudioMotor | None) -> None:
        self.session = session
        self.motor = motor
        self.message: Any = None

    def say(self, text: str, ok: bool = True) -> None:
        """Show ``text`` on the message line of the header (an error in red, as a line, never
        a pop-up over the page)."""
        self.message.set_text(text)
        self.message.classes(replace=f"text-sm min-h-6 {OK_CLASS if ok else ERROR_CLASS}")

    def every(self, seconds: float, callback: Callable[[], Any]) -> Any:
        """Call ``callback`` (sync or async) every ``seconds`` s while the page's tab is
        connected.

        The timer starts when the tab's websocket connects, pauses when it disconnects and
        resumes when it reconnects (within the reconnect timeout,
        :data:`~jvl_gym.studio.ui.app.RECONNECT_S`); NiceGUI cancels it when it deletes the
        page. A tab that was closed or navigated away thus polls nothing.

        Parameters
        ----------
        seconds : float
            Interval between two calls [s], > 0.
        callback : callable
            Called without arguments; wrap it in :meth:`guard` to show its errors.

        Returns
        -------
        ui.timer
            The timer (``active`` while the tab is connected).

        Raises
        ------
        ValueError
            ``seconds`` is not > 0.
        """
        if not seconds > 0:
            raise ValueError(f"a page timer needs an interval > 0 s, got {seconds}")
        client = ui.context.client
        timer = ui.timer(seconds, callback)

        def follow() -> None:
            timer.active = client.has_socket_connection
        client.on_connect(follow)
        client.on_disconnect(follow)
        return timer

    def guard(self, fn: Callable[..., Any]) -> Callable[..., Any]:
        """``fn`` (sync or async) with its exceptions shown on the message line."""
        if inspect.iscoroutinefunction(fn):
            @functools.wraps(fn)
            async def run_async(*args: Any, **kw: Any) -> Any:
                try:
                    return await fn(*args, **kw)
                except Exception as exc:  # noqa: BLE001 - an error is a message, never a dead page
                    log.debug("studio action failed", exc_info=True)
                    self.say(one_line(exc), ok=False)
            return run_async

        @functools.wraps(fn)
        def run(*args: Any, **kw: Any) -> Any:
            try:
                return fn(*args, **kw)
            except Exception as exc:  # noqa: BLE001
                log.debug("studio action failed", exc_info=True)
                self.say(one_line(exc), ok=False)
        return run


def stop_button(page: Page) -> None:
    """The STOP button of the header and its key (:data:`STOP_KEY`): both stop every motor
    of the studio, each by its family's stop (:meth:`~..session.Session.stop_motors`), and
    show what each motor did."""
    async def stop() -> None:
        lines = await run.io_bound(page.session.stop_motors)
        failed = any("STOP failed" in line or "STOP pending" in line for line in lines)
        page.say("STOP: " + "; ".join(lines), ok=not failed)

    guarded = page.guard(stop)
    ui.button("STOP", on_click=guarded, color="red").props(
        f'{tid("stop")} unelevated title="Stop every motor ({STOP_KEY})"').classes(
        "font-bold text-white")

    async def key(e: Any) -> None:
        if e.key == STOP_KEY and e.action.keydown and not e.action.repeat:
            await guarded()
    ui.keyboard(on_key=key, ignore=[])


def frame(session: Session, path: str, m: int = 0) -> Page:
    """Lay out the header (views, motor choice, line state) and the message line of the page
    at ``path`` for motor index ``m``; return the page."""
    motors = session.motors  # the motors of this moment
    m = m if 0 <= m < len(motors) else 0
    page = Page(session, motors[m] if motors else None)
    ui.page_title(f"jvl-gym studio · {VIEWS[path]}")
    with ui.header().classes("bg-slate-800 py-1"), ui.column().classes("w-full gap-0"):
        with ui.row().classes("items-center gap-4 w-full"):
            ui.label("jvl-gym studio").classes("text-lg font-bold")
            for p, title in VIEWS.items():
                link = ui.link(title, f"{p}?m={m}").classes("text-white")
                if p == path:
                    link.classes("underline font-bold")
            ui.space()
            stop_button(page)
            options = {k: mm.label for k, mm in enumerate(motors)}
            ui.select(options, value=m if motors else None, label="motor",
                      on_change=lambda e: ui.navigate.to(f"{path}?m={e.value}")
                      ).props("dark dense outlined").classes("w-48").props(tid("motor-select"))
        # the line's state and the message line stay in the header: always in view, and an
        # error never covers what the page shows (no pop-up); the message line is one line high
        # also while empty, so a message does not shift the page under the pointer (a held jog
        # button would see the pointer leave it)
        state = ui.label("").classes(f"{ERROR_CLASS} text-sm").props(tid("line-state"))
        page.message = ui.label("").classes("text-sm min-h-6").props(tid("message"))

    def show_state() -> None:
        problems = [p for p in (session.clock_problem,
                                *(line.problem for line in session.lines.values())) if p]
        state.set_text("; ".join(problems))
        state.set_visibility(bool(problems))

    show_state()
    page.every(1.0, show_state)
    return page
