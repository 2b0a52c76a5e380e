"""The motion panel: enable and passive, jog ± while a button is held, run at speed, moves to
and by a position, home, the motor's position, speed and mode, and its limits (the logic:
:mod:`jvl_gym.studio.motion`)."""

from __future__ import annotations

from typing import Any

from nicegui import run, ui

from ..line import LineDown
from ..motion import Motion, has_motion
from ..motor import StudioMotor
from .common import Page, log, tid

__all__ = ["motion_panel"]

#: seconds between two updates of the panel's position and speed
REFRESH_S = 0.25


def motion_panel(page: Page, motor: StudioMotor, k: int = 0) -> Motion | None:
    """Lay out the motion panel of ``motor`` (test ids end in ``-<k>``); None (and nothing
    laid out) if its family states no motion."""
    if not has_motion(motor):
        return None
    motion = Motion(motor)
    unit = motion.position_unit

    async def do(what: str, fn: Any, *args: Any) -> None:
        await run.io_bound(fn, *args)
        page.say(f"{motor.label}: {what}")

    def act(describe: Any, fn: Any, *values: Any) -> Any:
        """A button's handler: ``fn`` with the values read when it is clicked (``values``:
        callables), its errors on the message line."""
        async def handler() -> None:
            args = [v() for v in values]
            await do(describe(*args), fn, *args)
        return page.guard(handler)

    def rpm() -> float:
        return float(speed.value or 0)

    def position() -> float:
        return float(target.value or 0)

    with ui.column().classes("gap-1 w-full").props(tid(f"motion-{k}")):
        with ui.row().classes("items-center gap-2"):
            ui.button("enable", on_click=act(lambda: "enabled (holding its position)",
                                             motion.enable)).props(
                f'dense color=positive {tid(f"enable-{k}")}')
            ui.button("passive", on_click=act(lambda: "passive", motion.passive)).props(
                f'dense outline {tid(f"passive-{k}")}')
            speed = ui.number("speed [rpm]", value=100, format="%.6g").props(
                f'dense outlined {tid(f"speed-{k}")}').classes("w-32")
            jog_minus = ui.button("◀ jog").props(f'dense {tid(f"jog-minus-{k}")}')
            jog_plus = ui.button("jog ▶").props(f'dense {tid(f"jog-plus-{k}")}')
            ui.button("run", on_click=act(lambda v: f"running at {v:g} rpm", motion.run, rpm)
                      ).props(f'dense {tid(f"run-{k}")}')
        with ui.row().classes("items-center gap-2"):
            target = ui.number(f"position [{unit}]", value=0, format="%.6g").props(
                f'dense outlined {tid(f"target-{k}")}').classes("w-36")
            ui.button("move to", on_click=act(lambda p, v: f"moving to {p:g} {unit}",
                                              motion.move_absolute, position, rpm)).props(
                f'dense {tid(f"move-to-{k}")}')
            ui.button("move by", on_click=act(lambda p, v: f"moving by {p:g} {unit}",
                                              motion.move_relative, position, rpm)).props(
                f'dense {tid(f"move-by-{k}")}')
            homes = motion.home_modes()
            home = ui.select({v: f"{n} ({v})" for v, n in homes.items()},
                             value=next(iter(homes), None), label="home mode").props(
                f'dense outlined {tid(f"home-mode-{k}")}').classes("w-52")
            ui.button("home", on_click=act(
                lambda h: f"homing ({motor.facts.mode_name(h)})", motion.home,
                lambda: home.value)).props(f'dense {tid(f"home-{k}")}')
        state = ui.label("").classes("text-sm").props(tid(f"motion-state-{k}"))
        limits = ui.label("").classes("text-xs text-gray-600").props(tid(f"limits-{k}"))

    # press and hold: start on press, stop on release, on leaving the button, and when the
    # page loses its connection
    def jog(direction: int) -> Any:
        async def start() -> None:
            await run.io_bound(motion.jog_start, direction, float(speed.value or 0))
            page.say(f"{motor.label}: jogging {'+' if direction > 0 else '-'}"
                     f"{abs(float(speed.value or 0)):g} rpm")
        return page.guard(start)

    async def stop_jog() -> None:
        if motion.jogging:
            await run.io_bound(motion.jog_stop)
            page.say(f"{motor.label}: jog stopped")
    for button, direction in ((jog_minus, -1), (jog_plus, 1)):
        button.on("pointerdown", jog(direction))
        for end in ("pointerup", "pointerleave", "pointercancel"):
            button.on(end, page.guard(stop_jog))

    def lost() -> None:
        if motion.jogging:
            try:
                motion.jog_stop()
            except Exception:  # noqa: BLE001 - the page is gone: nothing to show it on
                log.debug("jog stop after the page left failed", exc_info=True)
    ui.context.client.on_disconnect(lost)

    busy = [False]

    async def refresh() -> None:
        if busy[0] or motor.paused:
            return
        busy[0] = True
        try:
            pos, spd, mode, lim = await run.io_bound(
                lambda: (motion.position(), motion.speed(), motion.mode(), motion.limits()))
        except LineDown as exc:
            state.set_text(f"not reachable: {exc}")
            return
        finally:
            busy[0] = False
        state.set_text(f"position {pos:.6g} {unit} · speed {spd:.6g} rpm · "
                       f"{motor.facts.mode_name(mode)} ({mode})"
                       + (" · jogging" if motion.jogging else ""))
        limits.set_text("limits: " + lim.text())
    page.every(REFRESH_S, page.guard(refresh))
    return motion
