"""The Motors view: every motor with its type, family, address, mode, error and status bits in
words, and the actions its family has."""

from __future__ import annotations

from nicegui import run, ui

from ..bits import status_registers, words
from ..line import LineDown
from ..session import Session
from .common import Page, tid
from .motion_panel import motion_panel
from .notice import compile_notice


def _card(page: Page, motor, k: int) -> None:
    facts = motor.facts
    bit_regs = status_registers(motor.table)
    with ui.card().classes("w-full").props(tid(f"motor-{k}")):
        with ui.row().classes("items-baseline gap-6"):
            ui.label(motor.motor_type).classes("text-xl font-bold")
            ui.label(facts.title)
            ui.label(f"address {motor.address}")
            ui.label("simulated in-process" if motor.simulated else f"on {motor.line.port}")
        mode = ui.label("").props(tid(f"mode-{k}"))
        bit_labels = {r.name: ui.label("").props(tid(f"bits-{k}-{r.name}"))
                      for r in bit_regs}

        busy = [False]

        async def refresh() -> None:
            if busy[0] or motor.paused:
                return
            busy[0] = True
            try:
                raws = await run.io_bound(motor.read_raws,
                                          [motor.register(facts.mode_register).number]
                                          + [r.number for r in bit_regs])
            except LineDown as exc:
                mode.set_text(f"not reachable: {exc}")
                return
            finally:
                busy[0] = False
            value = raws[motor.register(facts.mode_register).number]
            mode.set_text(f"mode: {facts.mode_name(value)} ({value})")
            for r in bit_regs:
                set_bits = words(r, raws[r.number])
                bit_labels[r.name].set_text(f"{r.name}: {', '.join(set_bits) or 'none set'}")

        with ui.expansion("motion", value=k == page.session.motors.index(page.motor)
                          ).classes("w-full").props("dense " + tid(f"motion-open-{k}")):
            motion_panel(page, motor, k)
        with ui.row():
            for name, action in motor.actions().items():
                async def do(action=action, name=name) -> None:
                    await run.io_bound(action)
                    page.say(f"{motor.label}: {name} done")
                ui.button(name, on_click=page.guard(do)).props("outline dense")
        page.every(0.25, page.guard(refresh))


def build(session: Session, m: int) -> None:
    """The Motors page."""
    from .common import frame

    page = frame(session, "/", m)
    compile_notice(page)
    for k, motor in enumerate(session.motors):
        _card(page, motor, k)
