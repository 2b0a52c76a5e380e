"""The Scope view: registers and physical signals of the motor as channels on one live chart
with one shared axis (each trace with its scale and offset), a trigger on any channel (level,
edge, pre-trigger share; auto, normal, single), a time base, cursors reading Δt, Δvalue and
1/Δt, zoom and pan, recording to a file; the motor's sample buffer and TESTU/TESTA records on
the same trigger and cursors; a capture saved to a file and a stored trace overlaid, aligned
at the trigger; CSV and PNG export (the logic: :mod:`jvl_gym.studio.scope`,
:mod:`jvl_gym.studio.trigger`, :mod:`jvl_gym.studio.capture`, :mod:`jvl_gym.studio.stored`).
The chart comes right below the channels, so at 1280×720 it is in view without scrolling."""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Callable
from pathlib import Path
from typing import Any

from nicegui import run, ui

from .. import stored
from ..capture import capture as capture_buffer
from ..capture import run_test, triggered
from ..scope import Scope, channel_choices, series_csv, series_png
from ..session import Session
from ..stored import StoredTraceError, stored_label
from ..trigger import TIME, Recorder, Trigger, TriggerMode, cursors, scaled, window
from .common import Page, frame, multiple_picker, redrawn_alone, tid
from .motion_panel import motion_panel
from .notice import compile_notice

#: seconds between two scope updates
PERIOD_S = 0.03
#: seconds after which a chart update the browser has not reported drawn counts as lost (the
#: next one is sent anyway)
DRAWN_WITHIN_S = 2.0
#: chart updates on their way to the browser or being drawn at one time: when the browser has
#: drawn one, the next is already there, so a frame does not wait for the report's trip to the
#: server and the update's trip back (on a loaded machine that trip takes longer than two
#: frames); a busy browser still has at most this many queued (0.1 s at 30 frames a second)
IN_FLIGHT = 3
#: seconds between two updates of the scope's text lines (with a chart update, or without one
#: while a trigger is awaited): a person reads no faster, and every change of the page's text
#: costs the browser time the chart's frames need
LABELS_S = 0.1
#: points the live scope keeps per channel (about 10 s at the page's rate; the time base
#: shows up to that)
DEPTH = 300
#: the channels a scope opens with: those of these names the motor has
DEFAULT_CHANNELS = ("V_SOLL", "V_IST", "shaft speed", "MODE_REG")


def _short(v: float) -> float:
    """``v`` to 7 significant digits (what a chart can show; a smaller message)."""
    return float(f"{float(v):.7g}")


#: the chart's layout [px]: the legend in a line of its own below the zoom slider, which sits
#: below the x axis's labels and name, so neither covers a trace
LEGEND_BOTTOM, LEGEND_HEIGHT = 0, 22
SLIDER_BOTTOM, SLIDER_HEIGHT = 30, 18
GRID_TOP, GRID_BOTTOM = 30, 88


def chart_options(series: dict[str, Any], title: str = "",
                  traces: dict[str, tuple[float, float]] | None = None,
                  marks: tuple[float, float] | None = None,
                  level: float | None = None,
                  overlay: dict[str, Any] | None = None,
                  overlay_name: str = "") -> dict[str, Any]:
    """ECharts options of ``series`` (first entry: x axis; labels ``"name [unit]"``): one
    line per channel on one shared y axis, each trace times its scale plus its offset
    (``traces``: label → (scale, offset)); ``marks``: the two cursors' times; ``level``: the
    trigger level (of the trigger's trace as drawn); ``overlay``: a stored trace (its own
    ``"t [s]"`` and channels, :mod:`jvl_gym.studio.stored`) drawn dashed over it on the same
    axes, each channel with the scale and offset of the live channel of its label and its own
    legend entry (:func:`~jvl_gym.studio.stored.stored_label` with ``overlay_name``). The
    legend sits below the chart and the zoom slider, outside the plot; zoom and pan with the
    mouse wheel and the slider."""
    keys = list(series)
    x = series[keys[0]] if keys else []
    traces = traces or {}
    lines = []

    def line_of(name: str, xs: Any, ys: Any, scale: float, offset: float) -> dict[str, Any]:
        return {"name": name, "type": "line", "showSymbol": False, "animation": False,
                "sampling": "lttb",
                "data": [[_short(a), _short(b)] for a, b in zip(xs, scaled(ys, scale, offset))]}

    def legend_name(k: str, scale: float, offset: float) -> str:
        return k if (scale, offset) == (1.0, 0.0) else f"{k} ×{scale:g}{offset:+g}"

    for n, k in enumerate(keys[1:]):
        scale, offset = traces.get(k, (1.0, 0.0))
        line = line_of(legend_name(k, scale, offset), x, series[k], scale, offset)
        if n == 0 and (marks or level is not None):
            data: list[Any] = [{"xAxis": _short(t)} for t in (marks or ())]
            if level is not None:
                data.append({"yAxis": _short(level)})
            line["markLine"] = {"silent": True, "symbol": "none", "animation": False,
                                "lineStyle": {"type": "dashed"}, "data": data}
        lines.append(line)
    if overlay:
        xs = overlay[TIME]
        for k in (k for k in overlay if k != TIME):
            scale, offset = traces.get(k, (1.0, 0.0))
            line = line_of(legend_name(stored_label(overlay_name, k), scale, offset), xs,
                           overlay[k], scale, offset)
            line["lineStyle"] = {"type": "dashed", "width": 1.5}
            lines.append(line)
    return {"title": {"text": title, "textStyle": {"fontSize": 12}, "left": "center",
                      "top": 0},
            "animation": False, "tooltip": {"trigger": "axis", "animation": False},
            "legend": {"type": "scroll", "bottom": LEGEND_BOTTOM, "height": LEGEND_HEIGHT},
            "grid": {"top": GRID_TOP, "left": 60, "right": 30, "bottom": GRID_BOTTOM},
            "dataZoom": [{"type": "inside"}, {"type": "slider", "bottom": SLIDER_BOTTOM,
                                              "height": SLIDER_HEIGHT}],
            "xAxis": {"type": "value", "name": keys[0] if keys else "", "scale": True,
                      "nameLocation": "middle", "nameGap": 22},
            "yAxis": {"type": "value", "scale": True}, "series": lines}


class _Tools:
    """The trigger, time base, cursors and trace settings of one chart."""

    def __init__(self, page: Page, prefix: str, labels: list[str], live: bool) -> None:
        self.prefix = prefix
        self.traces: dict[str, tuple[float, float]] = {}
        with ui.row().classes("items-center gap-2"):
            self.on = ui.switch("trigger", value=False).props(tid(f"{prefix}trigger"))
            self.channel = ui.select(labels, value=labels[0] if labels else None,
                                     label="on").props(
                "dense outlined " + tid(f"{prefix}trigger-channel")).classes("w-56")
            self.level = ui.number("level", value=0.0, format="%.6g").props(
                "dense outlined " + tid(f"{prefix}trigger-level")).classes("w-28")
            self.edge = ui.toggle(["rising", "falling"], value="rising").props(
                "dense " + tid(f"{prefix}trigger-edge"))
            self.pre = ui.number("pre-trigger %", value=20, min=0, max=100).props(
                "dense outlined " + tid(f"{prefix}trigger-pre")).classes("w-28")
            if live:
                self.mode = ui.toggle([m.value for m in TriggerMode], value="auto").props(
                    "dense " + tid(f"{prefix}trigger-mode"))
                self.span = ui.number("time base [s]", value=5.0, min=0.05).props(
                    "dense outlined " + tid(f"{prefix}time-base")).classes("w-28")
        with ui.row().classes("items-center gap-2"):
            self.cursor_on = ui.switch("cursors", value=False).props(tid(f"{prefix}cursors"))
            self.cursor_channel = ui.select(labels, value=labels[0] if labels else None,
                                            label="on").props(
                "dense outlined " + tid(f"{prefix}cursor-channel")).classes("w-56")
            self.t1 = ui.number("t1 [s]", value=0.0, format="%.6g").props(
                "dense outlined " + tid(f"{prefix}t1")).classes("w-28")
            self.t2 = ui.number("t2 [s]", value=0.1, format="%.6g").props(
                "dense outlined " + tid(f"{prefix}t2")).classes("w-28")
            self.readout = ui.label("").classes("text-sm font-mono").props(
                tid(f"{prefix}cursor-readout"))
        self.trace_row = ui.row().classes("items-center gap-2")
        self.set_labels(labels)

    def set_labels(self, labels: list[str]) -> None:
        """The traces the tools offer (after a change of channels)."""
        for sel in (self.channel, self.cursor_channel):
            sel.set_options(labels, value=sel.value if sel.value in labels else
                            (labels[0] if labels else None))
        self.traces = {k: self.traces.get(k, (1.0, 0.0)) for k in labels}
        self.trace_row.clear()
        with self.trace_row:
            ui.label("scale · offset:").classes("text-xs")
            scales: dict[str, tuple[Any, Any]] = {}
            for k in labels:
                def set_trace(_e: Any = None, k: str = k) -> None:
                    s, o = scales[k]
                    self.traces[k] = (float(s.value or 1.0), float(o.value or 0.0))
                s = ui.number(f"{k} ×", value=self.traces[k][0], format="%.6g",
                              on_change=set_trace).props("dense").classes("w-36")
                o = ui.number("+", value=self.traces[k][1], format="%.6g",
                              on_change=set_trace).props("dense").classes("w-20")
                scales[k] = (s, o)

    def trigger(self) -> Trigger | None:
        """The trigger set, None while it is off."""
        if not self.on.value or not self.channel.value:
            return None
        return Trigger(str(self.channel.value), float(self.level.value or 0.0),
                       str(self.edge.value), float(self.pre.value or 0.0) / 100.0)

    def show_cursors(self, series: dict[str, Any], stored: dict[str, Any] | None = None,
                     name: str = "") -> tuple[float, float] | None:
        """Read the cursors on ``series``, and on the same channel of a ``stored`` trace
        overlaid (``name``: its legend name); their times to mark, None while they are
        off."""
        if not self.cursor_on.value or not self.cursor_channel.value \
                or self.cursor_channel.value not in series or len(series[TIME]) == 0:
            self.readout.set_text("")
            return None
        t1, t2 = float(self.t1.value or 0.0), float(self.t2.value or 0.0)
        label = str(self.cursor_channel.value)
        unit = label.rpartition("[")[2].rstrip("]") if label.endswith("]") else ""
        c = cursors(series, label, t1, t2)
        text = f"v1 = {c.v1:.6g}, v2 = {c.v2:.6g}; " + c.text(unit)
        if stored is not None and label in stored:
            s = cursors(stored, label, t1, t2)
            text += (f" | {stored_label(name, 'stored')}: v1 = {s.v1:.6g}, v2 = {s.v2:.6g}; "
                     + s.text(unit))
        self.readout.set_text(text)
        return t1, t2

    def level_drawn(self) -> float | None:
        """The trigger level as drawn (on its trace's scale), None without a trigger."""
        trig = self.trigger()
        if trig is None:
            return None
        scale, offset = self.traces.get(trig.channel, (1.0, 0.0))
        return trig.level * scale + offset


class _Stored:
    """Save the chart's capture to a file; load a stored trace to overlay the chart, aligned
    at the trigger (:mod:`jvl_gym.studio.stored`)."""

    def __init__(self, page: Page, prefix: str, default: str, tools: _Tools,
                 current: Callable[[], dict[str, Any] | None],
                 redraw: Callable[[], None]) -> None:
        self.page = page
        self.tools = tools
        self.current = current
        self.redraw = redraw
        self.series: dict[str, Any] | None = None
        self.name = ""
        with ui.row().classes("items-center gap-2"):
            self.path = ui.input("stored trace (.csv, .parquet)", value=default).props(
                "dense outlined " + tid(f"{prefix}stored-path")).classes("w-72")
            ui.button("save", on_click=page.guard(self.save)).props(
                "dense outline " + tid(f"{prefix}save"))
            ui.button("overlay", on_click=page.guard(self.load)).props(
                "dense " + tid(f"{prefix}overlay"))
            ui.button("clear overlay", on_click=page.guard(self.clear)).props(
                "dense flat " + tid(f"{prefix}clear-overlay"))
            self.state = ui.label("").classes("text-sm").props(tid(f"{prefix}overlay-state"))

    def save(self) -> None:
        """The chart's capture to the file named."""
        series = self.current()
        if not series:
            raise StoredTraceError("nothing captured to save yet")
        path = stored.save(series, str(self.path.value or "").strip())
        n = len(series[TIME])
        self.page.say(f"saved {n} samples of {', '.join(k for k in series if k != TIME)} "
                      f"to {path}")

    def load(self) -> None:
        """The file named as the overlay (a bad file: its message, the overlay unchanged)."""
        path = Path(str(self.path.value or "").strip())
        series = stored.load(path)
        _, how = stored.aligned(series, self.tools.trigger())
        self.series, self.name = series, path.stem
        self.state.set_text(f"overlay: {path.name}")
        self.redraw()
        self.page.say(f"overlaid {path.name} ({len(series[TIME])} samples of "
                      f"{', '.join(k for k in series if k != TIME)}), {how}")

    def clear(self) -> None:
        """No overlay."""
        self.series, self.name = None, ""
        self.state.set_text("")
        self.redraw()

    def drawn(self) -> dict[str, Any] | None:
        """The overlay on the trigger as it is set now (times as stored where the trace
        does not cross the level), None without one."""
        if self.series is None:
            return None
        try:
            return stored.aligned(self.series, self.tools.trigger())[0]
        except StoredTraceError:
            return self.series


def _scope_block(page: Page) -> None:
    """The live scope: its channels, the chart right below them (in view at 1280×720), then
    its tools, the stored trace and the recorder."""
    motor = page.motor
    choices = channel_choices(motor)
    start = [c for c in DEFAULT_CHANNELS if c in choices]
    # "sent": when each chart update the browser has not reported drawn yet was sent
    state: dict[str, Any] = {"scope": Scope(motor, start, DEPTH), "live": True, "updates": 0,
                             "recorder": None, "shown": None, "drawn": None, "sent": deque(),
                             "labelled": 0.0}

    def labels() -> list[str]:
        sc = state["scope"]
        return [sc.label(c) for c in sc.channels]

    with ui.row().classes("items-center gap-4 w-full no-wrap"):
        pick = multiple_picker(choices, start, "channels", "channels").classes(
            "grow min-w-[28rem]")
        live = ui.switch("live", value=True).props(tid("live"))

        def set_live(e: Any) -> None:
            state.update(live=e.value)
            if e.value:  # (re)armed: a fresh record, so a single trigger waits for a new edge
                state["scope"].clear()
                state["shown"] = None
        live.on_value_change(set_live)

        def export_csv() -> None:
            ui.download.content(series_csv(state["shown"] or state["scope"].series()),
                                "scope.csv")
        ui.button("CSV", on_click=page.guard(export_csv)).props("dense " + tid("scope-csv"))

        def export_png() -> None:
            ui.download.content(series_png(state["shown"] or state["scope"].series(),
                                           motor.label), "scope.png", "image/png")
        ui.button("PNG", on_click=page.guard(export_png)).props("dense " + tid("scope-png"))
        with redrawn_alone().classes("w-72 shrink-0"):  # updated with every chart update
            counter = ui.label("").classes("text-sm").props(tid("scope-count"))
    chart = ui.echart(chart_options(state["scope"].series())).classes(
        "w-full h-[52vh] min-h-[16rem]").props(tid("scope-chart"))
    with redrawn_alone():
        last = ui.label("").classes("text-sm").props(tid("scope-last"))
    tools = _Tools(page, "", labels(), live=True)

    def set_channels() -> None:
        state["scope"] = Scope(motor, list(pick.value), DEPTH)
        state["shown"] = None
        tools.set_labels(labels())
    pick.on_value_change(page.guard(set_channels))

    def show_text() -> None:
        """The counter and the channels' last values (as of the last update)."""
        state["labelled"] = time.monotonic()
        if state.get("text"):
            counter.set_text(state["text"][0])
            last.set_text(state["text"][1])

    def draw() -> None:
        shown = state["shown"]
        if shown is None:
            return
        state["drawn"] = shown
        state["sent"].append(time.monotonic())
        if time.monotonic() - state["labelled"] >= LABELS_S:
            show_text()
        over = overlay.drawn()
        marks = tools.show_cursors(shown, over, overlay.name)
        # straight to the chart's setOption: the element's options are reactive in the
        # browser, and ECharts walking the reactive copy of every point takes several times
        # as long as a plain one
        chart.run_chart_method("setOption", chart_options(
            shown, "", tools.traces, marks, tools.level_drawn(), over, overlay.name),
            {"replaceMerge": ["series"]})
    overlay = _Stored(page, "", f"{motor.motor_type}_{motor.address}_scope.csv", tools,
                      lambda: state["shown"], draw)
    for w in (tools.cursor_on, tools.t1, tools.t2, tools.cursor_channel):
        w.on_value_change(page.guard(draw))  # the cursors move on a stopped scope too

    def browser_busy() -> bool:
        """:data:`IN_FLIGHT` updates are on their way or being drawn (those sent more than
        :data:`DRAWN_WITHIN_S` ago count as lost): a new one would queue behind them (on a
        busy machine the chart would fall ever further behind the motor)."""
        sent = state["sent"]
        while sent and time.monotonic() - sent[0] >= DRAWN_WITHIN_S:
            sent.popleft()
        return len(sent) >= IN_FLIGHT

    def drawn(_e: Any = None) -> None:
        if state["sent"]:
            state["sent"].popleft()
        if state["shown"] is not None and state["drawn"] is not state["shown"]:
            draw()  # the newest window, which waited for this one
    chart.on("chart:finished", page.guard(drawn), args=[])

    with ui.row().classes("items-center gap-2"):
        path = ui.input("record to", value=f"{motor.motor_type}_{motor.address}_record.csv"
                        ).props("dense outlined " + tid("record-path")).classes("w-72")
        rec_button = ui.button("record").props("dense color=negative " + tid("record"))
        rec_state = ui.label("").classes("text-sm").props(tid("record-state"))

        def toggle_record() -> None:
            rec = state["recorder"]
            if rec is None:
                state["recorder"] = Recorder(Path(path.value), labels())
                rec_button.set_text("stop recording")
                page.say(f"recording {', '.join(labels())} to {path.value}")
            else:
                state["recorder"] = None
                done = rec.stop()
                rec_button.set_text("record")
                page.say(f"recorded {rec.rows} rows, {rec.elapsed:.1f} s, "
                         f"{done.stat().st_size} bytes to {done}")
        rec_button.on_click(page.guard(toggle_record))

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
        rec = state["recorder"]
        if rec is not None:
            rec.add(sc.t[-1], [b[-1] for b in sc.values])
            rec_state.set_text(f"● {rec.elapsed:.1f} s, {rec.size / 1024:.1f} kB")
        series = sc.series()
        trig = tools.trigger()
        mode = TriggerMode(tools.mode.value)
        span = float(tools.span.value or 5.0)
        shown = window(series, trig, span, mode)
        if shown is not None:
            if trig is not None and mode is TriggerMode.SINGLE:
                live.set_value(False)  # one triggered window, then the scope stops
                page.say(f"single: triggered on {trig.channel}")
            state["shown"] = shown
        waiting = trig is not None and window(series, trig, span, TriggerMode.NORMAL) is None
        # a window is drawn when there is a new one (waiting for a trigger sends nothing) and
        # fewer than IN_FLIGHT are on their way (else when the browser reports one drawn)
        state["text"] = (f"update {state['updates']}: {len(sc.t)} points, t = {sc.t[-1]:.2f} s"
                         + (" · waiting for the trigger" if waiting else ""),
                         "; ".join(f"{sc.label(c)} = {b[-1]:.6g}"
                                   for c, b in zip(sc.channels, sc.values)))
        fresh = state["shown"] is not None and state["drawn"] is not state["shown"]
        if fresh and not browser_busy():
            draw()  # the text lines with it, at most every LABELS_S
        elif not browser_busy() and time.monotonic() - state["labelled"] >= LABELS_S:
            show_text()
    page.every(PERIOD_S, page.guard(tick))


def _buffer_block(page: Page) -> None:
    """The motor's sample buffer and its TESTU/TESTA records on a chart of their own, with
    the same trigger, cursors and stored trace as the live scope."""
    motor = page.motor
    regs = [c for c in channel_choices(motor) if c not in motor.physical()]
    ui.label("Sample buffer").classes("text-lg mt-4")
    result: dict[str, Any] = {}
    with ui.row().classes("items-center gap-4"):
        pick = multiple_picker(regs, [r for r in ("V_IST", "P_IST") if r in regs],
                               "registers (up to 4)", "buffer-registers").classes("min-w-[24rem]")
        samples = ui.number("samples", value=200, min=1, precision=0).props(
            "dense " + tid("buffer-samples")).classes("w-28")

        def show(series: dict[str, Any], what: str) -> None:
            result.clear()
            result.update(series)
            draw()
            n = len(next(iter(series.values())))
            page.say(f"{what}: {n} samples of {', '.join(list(series)[1:])}")

        async def trigger() -> None:
            series = await run.io_bound(capture_buffer, motor, list(pick.value)[:4],
                                        int(samples.value or 1))
            trig = tools.trigger()
            if trig is not None:
                series = triggered(series, trig)
            tools.set_labels(list(series)[1:])
            show(series, "sample buffer" + (f", triggered on {trig.channel}" if trig else ""))
        ui.button("capture", on_click=page.guard(trigger)).props("dense " + tid("capture"))
        for test, setup in (("TESTU", {}), ("TESTA", {})):
            if test in motor.facts.test_modes():
                async def do(test: str = test, setup: dict = setup) -> None:
                    series = await run.io_bound(run_test, motor, test, setup)
                    show(series, test)
                ui.button(test, on_click=page.guard(do)).props("dense " + tid(test.lower()))

        def export_csv() -> None:
            ui.download.content(series_csv(result), "buffer.csv")

        def export_png() -> None:
            ui.download.content(series_png(result, motor.label), "buffer.png", "image/png")
        ui.button("CSV", on_click=page.guard(export_csv)).props("dense " + tid("buffer-csv"))
        ui.button("PNG", on_click=page.guard(export_png)).props("dense " + tid("buffer-png"))
    labels = [f"{r} [{motor.register(r).unit}]" if motor.register(r).unit else r
              for r in pick.value]
    tools = _Tools(page, "buffer-", labels, live=False)

    def draw() -> None:
        if not result:
            return
        over = overlay.drawn() if TIME in result else None  # TESTU/TESTA count samples
        marks = tools.show_cursors(result, over, overlay.name)
        chart.options.clear()
        chart.options.update(chart_options(result, motor.label, tools.traces, marks,
                                           tools.level_drawn(), over, overlay.name))
        chart.update()
    overlay = _Stored(page, "buffer-", f"{motor.motor_type}_{motor.address}_buffer.csv", tools,
                      lambda: dict(result), draw)
    chart = ui.echart(chart_options({TIME: []})).classes("w-full h-72").props(
        tid("buffer-chart"))
    for w in (tools.cursor_on, tools.t1, tools.t2, tools.cursor_channel):
        w.on_value_change(page.guard(draw))


def build(session: Session, m: int) -> None:
    """The Scope page of motor ``m``."""
    page = frame(session, "/scope", m)
    compile_notice(page)
    _scope_block(page)
    with ui.expansion("motion", value=True).classes("w-full").props("dense"):
        motion_panel(page, page.motor, m)
    _buffer_block(page)
