"""The Scope view: registers and physical signals of the motor as channels on one live chart
(one y axis per unit), the motor's sample buffer and TESTU/TESTA records, CSV and PNG export."""

from __future__ import annotations

from typing import Any

from nicegui import run, ui

from ..capture import capture as capture_buffer
from ..capture import run_test
from ..scope import Scope, channel_choices, series_csv, series_png
from ..session import Session
from .common import Page, frame, tid
from .motion_panel import motion_panel

#: seconds between two scope updates
PERIOD_S = 0.03
#: points a live chart keeps per channel (10 s at the page's rate)
DEPTH = 250
#: the channels a scope opens with: those of these names the motor has
DEFAULT_CHANNELS = ("V_SOLL", "V_IST", "shaft speed", "MODE_REG")


def _short(v: float) -> float:
    """``v`` to 7 significant digits (what a chart can show; a smaller message)."""
    return float(f"{float(v):.7g}")


def chart_options(series: dict[str, Any], title: str = "") -> dict[str, Any]:
    """ECharts options of ``series`` (first entry: x axis; labels ``"name [unit]"``): one
    line per channel, one y axis per unit."""
    keys = list(series)
    x = series[keys[0]]
    units: list[str] = []
    lines = []
    for k in keys[1:]:
        unit = k.rpartition("[")[2].rstrip("]") if k.endswith("]") else ""
        if unit not in units:
            units.append(unit)
        lines.append({"name": k, "type": "line", "showSymbol": False, "animation": False,
                      "sampling": "lttb",
                      "yAxisIndex": units.index(unit),
                      "data": [[_short(a), _short(b)] for a, b in zip(x, series[k])]})
    axes = [{"type": "value", "name": u or "value", "scale": True, "nameLocation": "end",
             "nameGap": 8 + 14 * (i // 2), "position": "left" if i % 2 == 0 else "right",
             "offset": 70 * (i // 2), "axisLine": {"show": True}}
            for i, u in enumerate(units or [""])]
    side = 70 * ((len(axes) + 1) // 2)
    return {"title": {"text": title, "textStyle": {"fontSize": 12}},
            "animation": False, "tooltip": {"trigger": "axis", "animation": False},
            "legend": {"top": 20}, "grid": {"top": 80, "left": side, "right": side},
            "xAxis": {"type": "value", "name": keys[0], "scale": True}, "yAxis": axes,
            "series": lines}


def _scope_block(page: Page) -> None:
    motor = page.motor
    choices = channel_choices(motor)
    start = [c for c in DEFAULT_CHANNELS if c in choices]
    state: dict[str, Any] = {"scope": Scope(motor, start, DEPTH), "live": True, "updates": 0}
    with ui.row().classes("items-center gap-4 w-full"):
        pick = ui.select(choices, value=start, multiple=True, label="channels",
                         with_input=True).props("use-chips " + tid("channels")
                                                ).classes("min-w-[28rem]")

        def set_channels() -> None:
            state["scope"] = Scope(motor, list(pick.value), DEPTH)
        pick.on_value_change(page.guard(set_channels))
        live = ui.switch("live", value=True).props(tid("live"))
        live.on_value_change(lambda e: state.update(live=e.value))

        def export_csv() -> None:
            ui.download.content(state["scope"].csv(), "scope.csv")
        ui.button("CSV", on_click=page.guard(export_csv)).props(tid("scope-csv"))

        def export_png() -> None:
            ui.download.content(state["scope"].png(), "scope.png", "image/png")
        ui.button("PNG", on_click=page.guard(export_png)).props(tid("scope-png"))
        counter = ui.label("").props(tid("scope-count"))
    chart = ui.echart(chart_options(state["scope"].series(), motor.label)).classes(
        "w-full h-96").props(tid("scope-chart"))
    last = ui.label("").classes("text-sm").props(tid("scope-last"))

    async def tick() -> None:
        if not state["live"] or state.get("busy") or motor.paused:
            return
        sc = state["scope"]
        state["busy"] = True
        try:
            await run.io_bound(sc.sample)  # a line motor answers over the wire
        finally:
            state["busy"] = False
        state["updates"] += 1
        chart.options.clear()
        chart.options.update(chart_options(sc.series(), motor.label))
        chart.update()
        counter.set_text(f"update {state['updates']}: {len(sc.t)} points, t = {sc.t[-1]:.2f} s")
        last.set_text("; ".join(f"{sc.label(c)} = {b[-1]:.6g}"
                                for c, b in zip(sc.channels, sc.values)))
    page.every(PERIOD_S, page.guard(tick))


def _buffer_block(page: Page) -> None:
    motor = page.motor
    regs = [c for c in channel_choices(motor) if c not in motor.physical()]
    ui.label("Sample buffer").classes("text-lg mt-4")
    with ui.row().classes("items-center gap-4"):
        pick = ui.select(regs, value=[r for r in ("V_IST", "P_IST") if r in regs],
                         multiple=True, label="registers (up to 4)", with_input=True
                         ).props("use-chips " + tid("buffer-registers")).classes("min-w-[24rem]")
        samples = ui.number("samples", value=200, min=1, precision=0).props(
            tid("buffer-samples")).classes("w-28")
        result: dict[str, Any] = {}

        def show(series: dict[str, Any], what: str) -> None:
            result.clear()
            result.update(series)
            chart.options.clear()
            chart.options.update(chart_options(series, f"{motor.label}: {what}"))
            chart.update()
            n = len(next(iter(series.values())))
            page.say(f"{what}: {n} samples of {', '.join(list(series)[1:])}")

        async def trigger() -> None:
            series = await run.io_bound(capture_buffer, motor, list(pick.value)[:4],
                                        int(samples.value or 1))
            show(series, "sample buffer")
        ui.button("capture", on_click=page.guard(trigger)).props(tid("capture"))
        for test, setup in (("TESTU", {}), ("TESTA", {})):
            if test in motor.facts.test_modes():
                async def do(test: str = test, setup: dict = setup) -> None:
                    series = await run.io_bound(run_test, motor, test, setup)
                    show(series, test)
                ui.button(test, on_click=page.guard(do)).props(tid(test.lower()))

        def export_csv() -> None:
            ui.download.content(series_csv(result), "buffer.csv")

        def export_png() -> None:
            ui.download.content(series_png(result, motor.label), "buffer.png", "image/png")
        ui.button("CSV", on_click=page.guard(export_csv)).props(tid("buffer-csv"))
        ui.button("PNG", on_click=page.guard(export_png)).props(tid("buffer-png"))
    chart = ui.echart(chart_options({"t [s]": []})).classes("w-full h-72").props(
        tid("buffer-chart"))


def build(session: Session, m: int) -> None:
    """The Scope page of motor ``m``."""
    page = frame(session, "/scope", m)
    with ui.expansion("motion", value=True).classes("w-full").props("dense"):
        motion_panel(page, page.motor, m)
    _scope_block(page)
    _buffer_block(page)
