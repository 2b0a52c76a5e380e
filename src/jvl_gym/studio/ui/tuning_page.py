"""The Tuning view: the ``jvl-tune autotune`` pipeline on the selected motor as a guided page
(:class:`~jvl_gym.studio.tuning_run.TuningRun`): progress, the identified values with their
intervals, the plots, the quantised registers beside the present ones, the acceptance step, and
writing the result after a confirmation; without the tuning toolkit it says so in one line."""

from __future__ import annotations

import base64
from typing import Any

from nicegui import run, ui

from ..tuning_run import TuningRun, tuning_problem
from .common import frame, tid

#: the run of each motor (a page reopened shows the run that is going on)
RUNS: dict[str, TuningRun] = {}


def build(session: Any, m: int) -> None:
    """The Tuning page of motor ``m``."""
    page = frame(session, "/tuning", m)
    motor = page.motor
    ui.label(f"Autotune {motor.label} ({motor.facts.title})").classes("text-lg")
    ui.markdown("Steps: **records** (TESTU, TESTA or buffer records) → **fits** with 95 % "
                "intervals → **design** (Bode, margins, step) → **quantised registers** → "
                "**acceptance step** against the default setup → **write** (after you confirm). "
                "The motor must be at rest in mode 0.")
    problem = tuning_problem(motor, session.toolkit)
    if problem:
        page.say(problem, ok=False)
        return
    shown = {"lines": 0, "result": False}
    button = ui.button("run autotune").props(tid("tuning-run"))
    out = ui.column().classes("w-full")
    log = ui.log(max_lines=200).classes("w-full h-40").props(tid("tuning-log"))

    def start() -> None:
        if motor.label in RUNS and RUNS[motor.label].running:
            page.say("a run is going on")
            return
        tr = TuningRun(motor, session.toolkit, time_scale=session.speed)
        RUNS[motor.label] = tr
        shown.update(lines=0, result=False)
        out.clear()
        log.clear()
        tr.start()
        page.say(f"autotune of {motor.label} started")
    button.on_click(page.guard(start))


    def poll() -> None:
        tr = RUNS.get(motor.label)
        if tr is None:
            return
        for line in tr.progress[shown["lines"]:]:
            log.push(line)
        shown["lines"] = len(tr.progress)
        if tr.error and not shown["result"]:
            shown["result"] = True
            page.say(f"autotune failed: {tr.error}", ok=False)
        if tr.result is not None and not shown["result"]:
            shown["result"] = True
            _show(out, tr, page)
    page.every(0.3, page.guard(poll))


def _show(out: Any, tr: TuningRun, page: Any) -> None:
    assert tr.result is not None
    res, present = tr.result.outcome, tr.result.present
    with out:
        ui.label("Identified values, loop verification, acceptance step").classes("text-lg")
        ui.code(res.report, language="text").classes("w-full").props(tid("tuning-table"))
        with ui.row().classes("w-full"):
            for title, png in res.plots.items():
                with ui.column():
                    ui.label(title)
                    ui.image("data:image/png;base64," + base64.b64encode(png).decode()
                             ).classes("w-[36rem]")
        ui.label("Acceptance step").classes("text-lg")
        for line in res.acceptance:
            ui.label(line)
        ui.label("Quantised registers").classes("text-lg")
        rows = [{"name": k, "present": f"{present.get(k, float('nan')):.10g}",
                 "new": f"{v:.10g}"} for k, v in res.registers.items()]
        ui.table(columns=[{"name": c, "label": c, "field": c} for c in ("name", "present",
                                                                          "new")],
                 rows=rows).props("dense " + tid("tuning-registers"))
        with ui.dialog() as dialog, ui.card():
            ui.label(f"Write {len(res.registers)} registers to {tr.motor.label}?")
            with ui.row():
                async def confirm() -> None:
                    dialog.close()
                    text = await run.io_bound(tr.write)
                    page.say(text)
                ui.button("write", on_click=page.guard(confirm)).props(tid("tuning-confirm"))
                ui.button("cancel", on_click=dialog.close)
        ui.button("write to motor", on_click=dialog.open).props(tid("tuning-write"))
