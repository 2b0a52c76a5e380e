"""The scope in Chromium at 1280×720, an engineer's laptop screen: the chart in view without
scrolling with its legend outside the plot, an error that never covers the register table, and
a capture saved and overlaid on the live chart (a malformed file refused with one line,
nothing changed)."""

from __future__ import annotations

import re
from collections.abc import Iterator
from pathlib import Path

import pytest

from conftest import CHROMIUM
from test_studio_lock import Studio

WIDTH, HEIGHT = 1280, 720
#: generous: the machine may be busy with other work
SLOW = 60000

pytestmark = pytest.mark.skipif(not Path(CHROMIUM).exists(),
                                reason=f"Debian's Chromium ({CHROMIUM}) is not installed")
expect = pytest.importorskip("playwright.sync_api").expect

#: the ECharts instance of the element of a test id, in the page
CHART = "(id) => getElement(document.querySelector(`[data-testid='${id}']`)).chart"


@pytest.fixture(scope="session")
def browser_context_args(browser_context_args: dict) -> dict:
    return {**browser_context_args, "viewport": {"width": WIDTH, "height": HEIGHT}}


@pytest.fixture(scope="module")
def studio() -> Iterator[Studio]:
    studio = Studio("--motor", "MAC140")
    yield studio
    studio.stop()


def _inside(box: dict, width: float = WIDTH, height: float = HEIGHT) -> bool:
    return (box["x"] >= 0 and box["y"] >= 0 and box["x"] + box["width"] <= width
            and box["y"] + box["height"] <= height)


def _overlap(a: dict, b: dict) -> bool:
    return not (a["x"] + a["width"] <= b["x"] or b["x"] + b["width"] <= a["x"]
                or a["y"] + a["height"] <= b["y"] or b["y"] + b["height"] <= a["y"])


def open_scope(page, studio: Studio) -> None:
    page.goto(studio.with_token("/scope?m=0"), timeout=SLOW)
    expect(page.get_by_test_id("scope-count")).to_contain_text("update", timeout=SLOW)


def chart_rects(page, test_id: str) -> dict:
    """The plot's rectangle and the legend's, in the chart's pixels."""
    return page.evaluate(f"""(id) => {{
        const chart = ({CHART})(id);
        const grid = chart.getModel().getComponent('grid').coordinateSystem.getRect();
        const legend = chart._componentsViews.find((v) => v.type.startsWith('legend'))
            .group.getBoundingRect();
        const at = chart._componentsViews.find((v) => v.type.startsWith('legend')).group;
        return {{grid: {{x: grid.x, y: grid.y, width: grid.width, height: grid.height}},
                 legend: {{x: legend.x + at.x, y: legend.y + at.y, width: legend.width,
                          height: legend.height}},
                 names: chart.getOption().series.map((s) => s.name)}};
    }}""", test_id)


def test_the_chart_is_in_view_at_1280x720_and_its_legend_covers_no_data(page, studio):
    open_scope(page, studio)
    chart = page.get_by_test_id("scope-chart")
    expect(chart).to_be_visible(timeout=SLOW)
    assert page.evaluate("() => [window.scrollX, window.scrollY]") == [0, 0]
    box = chart.bounding_box()
    assert box is not None and box["height"] > 250, box
    assert _inside(box), f"the chart at {box} is not inside the {WIDTH}×{HEIGHT} window"
    rects = chart_rects(page, "scope-chart")
    assert len(rects["names"]) == 4  # V_SOLL, V_IST, shaft speed, MODE_REG
    assert rects["legend"]["height"] > 0
    assert not _overlap(rects["legend"], rects["grid"]), rects


def test_an_error_is_in_view_and_covers_no_register(page, studio):
    page.goto(studio.with_token("/registers?m=0"), timeout=SLOW)
    expect(page.get_by_test_id("raw-V_SOLL")).to_contain_text("raw", timeout=SLOW)
    field = page.get_by_label("V_SOLL", exact=True)
    field.fill("9999999999")
    field.press("Enter")
    message = page.get_by_test_id("message")
    expect(message).to_contain_text("outside the range", timeout=SLOW)
    assert _inside(message.bounding_box())
    page.wait_for_timeout(500)  # a pop-up would be on its way in by now
    rows = [b for b in (r.bounding_box() for r in
                        page.locator("[data-testid^='reg-']").all()[:40]) if b]
    pops = [b for b in (n.bounding_box() for n in page.locator(".q-notification").all()) if b]
    covered = [(p, r) for p in pops for r in rows if _overlap(p, r)]
    assert not covered, f"a pop-up covers the registers: {covered[:1]}"


def test_a_capture_saved_and_overlaid_at_the_trigger(page, studio, tmp_path):
    open_scope(page, studio)
    message = page.get_by_test_id("message")
    path = page.get_by_test_id("stored-path")
    saved = tmp_path / "run1.csv"
    expect(page.get_by_test_id("scope-count")).to_contain_text(
        re.compile(r"update ([5-9]|\d\d+):"), timeout=SLOW)  # a window of a few points
    path.fill(str(saved))
    page.get_by_test_id("save").click()
    expect(message).to_contain_text(f"to {saved}", timeout=SLOW)
    assert saved.read_text().startswith('"t [s]"')
    page.get_by_test_id("overlay").click()
    expect(message).to_contain_text("overlaid run1.csv", timeout=SLOW)
    expect(page.get_by_test_id("overlay-state")).to_have_text("overlay: run1.csv")
    page.wait_for_function(f"""() => ({CHART})('scope-chart').getOption().series
        .some((s) => s.name === 'V_IST [counts/sample] · run1')""", timeout=SLOW)
    names = chart_rects(page, "scope-chart")["names"]
    assert len(names) == 8 and "V_SOLL [1/16 count/sample] · run1" in names
    # the cursors read the live trace and the stored one
    page.get_by_test_id("live").click()  # stop the scope: a still chart
    page.get_by_test_id("cursors").click()
    expect(page.get_by_test_id("cursor-readout")).to_contain_text("run1", timeout=SLOW)
    expect(page.get_by_test_id("cursor-readout")).to_contain_text("Δt = 0.1 s")
    # a malformed file: one line, the overlay unchanged
    bad = tmp_path / "bad.csv"
    bad.write_text("t [s],x\n0,1\n1,high\n", encoding="utf-8")
    path.fill(str(bad))
    page.get_by_test_id("overlay").click()
    expect(message).to_contain_text("bad.csv: column 'x' holds a value that is not a number",
                                    timeout=SLOW)
    assert "\n" not in message.inner_text()
    expect(page.get_by_test_id("overlay-state")).to_have_text("overlay: run1.csv")
    assert "V_IST [counts/sample] · run1" in chart_rects(page, "scope-chart")["names"]


def test_a_chart_update_waits_until_the_browser_has_drawn_the_one_before(page, studio):
    """Once the page stops reporting frames drawn (ECharts' ``finished``), the studio sends
    at most ``IN_FLIGHT`` (3) updates not reported drawn, and more only after
    ``DRAWN_WITHIN_S`` (2 s), instead of an update every tick (about 45 in 1.5 s) that a busy
    browser would queue ever further behind the motor.

    The updates are counted from ``DRAWN_WITHIN_S`` after the reports stop: by then the ones
    in flight when they stopped (on a loaded machine up to ``IN_FLIGHT``, sent up to 2 s
    before) have been given up, and each of the ``IN_FLIGHT`` sent since is sent again no
    sooner than ``DRAWN_WITHIN_S`` later, so a window of 1.5 s sees each at most once."""
    from jvl_gym.studio.ui.scope_page import DRAWN_WITHIN_S, IN_FLIGHT, PERIOD_S

    open_scope(page, studio)
    # past the first DRAWN_WITHIN_S of ticks: an update sent before the chart was there to
    # draw it is no longer counted in flight
    ticks = int(DRAWN_WITHIN_S / PERIOD_S) + 5
    page.wait_for_function("""(n) => +document.querySelector('[data-testid="scope-count"]')
        .innerText.match(/update (\\d+)/)[1] >= n""", arg=ticks, timeout=SLOW)
    page.evaluate(f"""() => {{ const chart = ({CHART})('scope-chart');
        window.__updates = 0;
        chart.off('finished');  // the page's report of a frame drawn
        const set = chart.setOption.bind(chart);
        chart.setOption = (...args) => {{ window.__updates++; return set(...args); }}; }}""")
    page.wait_for_timeout(1000 * DRAWN_WITHIN_S + 200)
    page.evaluate("() => { window.__updates = 0; }")
    page.wait_for_timeout(1500)
    assert page.evaluate("() => window.__updates") <= IN_FLIGHT
    # the text lines still follow the motor meanwhile
    expect(page.get_by_test_id("scope-count")).to_contain_text("update", timeout=SLOW)


def test_channels_picked_one_after_another_leave_the_trigger_in_reach(page, studio):
    """Four channels added to the scope's four, one after another as an engineer adds them
    (a click in the picker, the name typed, the option clicked; or the next name typed
    straight away): each choice closes the picker's list and clears the typed name, so the
    list covers neither the chart nor the trigger, and the trigger is then set on a new
    channel."""
    open_scope(page, studio)
    field = page.get_by_test_id("channels")
    menu = page.locator(".q-menu")
    for n, name in enumerate(("P_IST", "FLWERR", "torque", "phase currents A")):
        if n != 1:  # the second typed straight after the first choice: the field has the focus
            field.click()
        page.keyboard.type(name)
        page.get_by_role("option", name=name, exact=True).click()
        expect(menu).to_have_count(0, timeout=SLOW)
        expect(field).to_have_value("")
    page.wait_for_function(f"""() => ({CHART})('scope-chart').getOption().series.length === 8
        """, timeout=SLOW)
    assert "FLWERR [1/16 count]" in chart_rects(page, "scope-chart")["names"]
    page.get_by_test_id("trigger").click()
    expect(page.get_by_test_id("trigger")).to_have_attribute("aria-checked", "true",
                                                             timeout=SLOW)
    page.get_by_test_id("trigger-channel").click()
    page.get_by_role("option", name="FLWERR [1/16 count]", exact=True).click()
    expect(page.get_by_test_id("trigger-channel")).to_contain_text("FLWERR", timeout=SLOW)
    page.get_by_test_id("trigger-level").fill("1e9")  # a following error never reaches
    page.get_by_test_id("trigger-mode").get_by_text("normal").click()
    expect(page.get_by_test_id("scope-count")).to_contain_text("waiting for the trigger",
                                                                timeout=SLOW)
