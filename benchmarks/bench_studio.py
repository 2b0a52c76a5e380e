"""Speed of ``jvl-gym studio``: the scope's frame rate with eight channels, its trigger
latency, and the register view's refresh of a twin.

``python benchmarks/bench_studio.py`` measures

* **scope updates per second, 8 channels, simulated motor in real time (server side)**: a
  MAC140 simulated in real time by the studio's clock (:class:`jvl_gym.studio.session.Session`)
  runs in velocity mode; one scope update is what the Scope page does per tick: read the 8
  channels (:data:`CHANNELS`: registers and physical signals), build the chart's options and
  encode them as the JSON the browser receives. The rate is the best of equal windows
  (``best_rate.py``);
* **the same in the browser**: with Debian's Chromium present, the studio is started on a free
  port, a headless Chromium opens the Scope page, picks the 8 channels as an engineer does and
  counts for 5 s the samples the page's timer takes (``studio.ui.scope_page.PERIOD_S`` bounds
  them), the chart updates with new data the page receives, and the frames the chart draws
  with new data (ECharts' ``finished`` event after an update whose trace ends later than the
  one before: an update received, laid out and painted, what a person sees move);
* **trigger latency**: on the same page the scope is armed in single mode on V_SOLL rising
  through the value of 150 rpm; a click on the motion panel's ``run`` at 300 rpm (from 10 rpm)
  writes V_SOLL across the level in the motor, and the time from the click to the page showing
  ``single: triggered`` is taken in the browser (``performance.now()``), less the sweep a
  single window holds after its crossing (:data:`SWEEP_S`: single mode shows a whole window,
  :func:`jvl_gym.studio.trigger.window`): the write's trip to the motor, the scope's next
  sample, the trigger found, the message shown (within a sample of the scope). The median and
  the largest of :data:`TRIGGERS` runs;
* **refresh of all registers of a twin motor over TCP**: a ``jvl-gym serve`` twin of one MAC140
  (16-bit MacTalk) and one of an MIS232 (32-bit MacTalk) on a free TCP port, the register
  view's read of every register it shows (:meth:`jvl_gym.studio.line.LineMotor.read_raws`),
  the median of 20 refreshes.

Targets: ≥ 30 frames per second with 8 channels, a trigger shown within 0.1 s, a refresh under
1 s. Figures go to the generated page ``docs/benchmarks.md`` (section "Studio",
:mod:`bench_page`).
"""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_page import table, update_section  # noqa: E402
from best_rate import best_rate  # noqa: E402

CHROMIUM = "/usr/bin/chromium"
#: the scope's channels: the four it opens with and four more
CHANNELS = ["V_SOLL", "V_IST", "shaft speed", "MODE_REG", "P_IST", "FLWERR", "torque",
            "phase currents A"]
#: runs of the trigger latency
TRIGGERS = 7
#: the trigger's time base [s] and the page's pre-trigger share of it (its default, 20 %)
TIME_BASE_S, PRE = 1.0, 0.2
#: what a single window records after its crossing before it is shown [s]
SWEEP_S = (1.0 - PRE) * TIME_BASE_S
#: the ECharts instance of the element of a test id, in the page
CHART = "getElement(document.querySelector('[data-testid=\"scope-chart\"]')).chart"


def scope_rate(seconds: float = 3.0) -> float:
    """Scope updates per second of the server side (read 8 channels, options, JSON)."""
    from jvl_gym.studio.scope import Scope
    from jvl_gym.studio.session import Session
    from jvl_gym.studio.ui.scope_page import chart_options

    session = Session.simulated(["MAC140"])
    m = session.motors[0]
    m.write("V_SOLL", 400)
    m.write("MODE_REG", 1)
    session.start()
    sc = Scope(m, CHANNELS)
    try:
        def update() -> None:
            sc.sample()
            json.dumps(chart_options(sc.series(), m.label))
        return best_rate(lambda batch: [update() for _ in range(batch)], 1, seconds)
    finally:
        session.stop()


def _update_number(text: str) -> int:
    return int(text.split(":")[0].split()[-1])


def _pick_channels(page) -> None:
    """Add the channels of :data:`CHANNELS` the chart does not show yet as an engineer does
    (a click in the channel picker, the name typed, the option clicked: the picker's list
    closes on the choice) and wait for the chart to draw them."""
    field = page.get_by_test_id("channels")
    drawn = f"""(name) => {CHART}.getOption().series.some(
        (s) => s.name === name || s.name.startsWith(name + ' ['))"""
    for name in CHANNELS:
        if page.evaluate(drawn, name):
            continue
        field.click()
        page.keyboard.type(name)
        page.get_by_role("option", name=name, exact=True).click()
        page.locator(".q-menu").wait_for(state="detached", timeout=60000)
        page.wait_for_function(drawn, arg=name, timeout=60000)


def _frames(page, seconds: float) -> tuple[float, float, float]:
    """Per second over ``seconds``: frames the chart draws with new data (what a person
    sees move), chart updates with new data the page receives, and samples the page's timer
    takes (its updates)."""
    counter = page.get_by_test_id("scope-count")
    first = _update_number(counter.inner_text())
    # an update is new when its first trace ends at a later time than the one before; a frame
    # is drawn when ECharts reports it finished (laid out and painted) after a new update
    page.evaluate(f"""() => {{ const chart = {CHART};
        window.__frames = 0; window.__received = 0;
        let last = null, fresh = false;
        const set = chart.setOption.bind(chart);
        chart.setOption = (option, ...rest) => {{
            const data = option?.series?.[0]?.data;
            const t = data && data.length ? data[data.length - 1][0] : null;
            if (t !== null && t !== last) {{ last = t; fresh = true; window.__received++; }}
            return set(option, ...rest); }};
        chart.on('finished', () => {{ if (fresh) {{ fresh = false; window.__frames++; }} }});
        }}""")
    time.sleep(seconds)
    frames, received = page.evaluate("() => [window.__frames, window.__received]")
    ticks = _update_number(counter.inner_text()) - first
    return frames / seconds, received / seconds, ticks / seconds


def _trigger_latency(page, repeats: int) -> list[float]:
    """Seconds from the click that writes V_SOLL across the trigger's level to the page
    showing the trigger, less :data:`SWEEP_S`, ``repeats`` times."""
    from jvl_gym.families import family_of_motor

    level = 150.0 / family_of_motor("MAC140").units.v_soll_to_rpm(1.0)
    page.get_by_test_id("trigger").click()
    page.get_by_test_id("trigger-channel").click()
    page.get_by_role("option", name="V_SOLL [1/16 count/sample]", exact=True).click()
    page.get_by_test_id("trigger-level").fill(f"{level:.6g}")
    page.get_by_test_id("trigger-pre").fill(f"{PRE * 100:g}")
    page.get_by_test_id("time-base").fill(f"{TIME_BASE_S:g}")
    page.get_by_test_id("trigger-mode").get_by_text("single").click()
    out = []
    for _ in range(repeats):
        page.get_by_test_id("speed-0").fill("10")
        page.get_by_test_id("run-0").click()
        page.wait_for_function("""() => document.querySelector('[data-testid="message"]')
            .innerText.includes('running at 10 rpm')""", timeout=60000)
        if page.get_by_test_id("live").get_attribute("aria-checked") == "false":
            page.get_by_test_id("live").click()  # armed again: a fresh record
        # waiting, with the pre-trigger share of the window recorded (0.2 s: 15 points)
        page.wait_for_function("""() => { const text = document.querySelector(
            '[data-testid="scope-count"]').innerText; const m = text.match(/: (\\d+) points/);
            return text.includes('waiting for the trigger') && m && +m[1] >= 15; }""",
                               timeout=60000)
        page.get_by_test_id("speed-0").fill("300")
        page.evaluate("""() => {
            window.__shown = null;
            const msg = document.querySelector('[data-testid="message"]');
            const seen = new MutationObserver(() => {
                if (window.__shown === null && msg.innerText.includes('single: triggered')) {
                    window.__shown = performance.now(); seen.disconnect(); } });
            seen.observe(msg, {subtree: true, childList: true, characterData: true});
            window.__click = performance.now();
            document.querySelector('[data-testid="run-0"]').click(); }""")
        page.wait_for_function("() => window.__shown !== null", timeout=60000)
        out.append(page.evaluate("() => (window.__shown - window.__click) / 1000") - SWEEP_S)
    page.get_by_test_id("passive-0").click()
    return out


def browser_rate(seconds: float = 5.0) -> tuple[float, float, float, list[float]] | None:
    """Per second in headless Chromium with 8 channels: frames the chart draws with new
    data, chart updates with new data the page receives, samples the page's timer takes; and
    the trigger latencies [s]; None without Chromium."""
    if not Path(CHROMIUM).exists():
        return None
    from playwright.sync_api import sync_playwright

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT / "src"), str(ROOT)]))
    proc = subprocess.Popen([sys.executable, "-m", "jvl_gym.cli", "studio", "--no-browser",
                             "--port", str(port), "--motor", "MAC140"], env=env,
                            cwd=tempfile.mkdtemp(), stdout=subprocess.PIPE,
                            stderr=subprocess.DEVNULL, text=True)
    try:
        url = f"http://127.0.0.1:{port}"
        token = ""
        for line in proc.stdout:  # the URL with this start's token (docs/studio.md)
            if "?token=" in line:
                token = line.split("?token=", 1)[1].split()[0]
                break
        threading.Thread(target=proc.stdout.read, daemon=True).start()
        for _ in range(600):
            try:
                with socket.create_connection(("127.0.0.1", port), timeout=1):
                    break
            except OSError:
                time.sleep(0.5)
        args = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
                "--no-first-run", "--disable-background-networking",
                "--disable-component-update", "--disable-sync"]
        with sync_playwright() as p:
            ctx = p.chromium.launch_persistent_context(
                tempfile.mkdtemp(), headless=True, executable_path=CHROMIUM, args=args,
                viewport={"width": 1280, "height": 720})
            page = ctx.new_page()
            page.set_default_timeout(60000)
            page.goto(f"{url}/scope?m=0&token={token}", timeout=300000)
            page.get_by_test_id("scope-count").wait_for(timeout=60000)
            page.wait_for_function("""() => document.querySelector(
                '[data-testid="scope-count"]').innerText.includes('update')""", timeout=300000)
            _pick_channels(page)
            time.sleep(1.0)  # the new channels' first points
            frames, received, ticks = _frames(page, seconds)
            latencies = _trigger_latency(page, TRIGGERS)
            ctx.close()
        return frames, received, ticks, latencies
    finally:
        proc.terminate()
        proc.wait(10)


def refresh_seconds(motor: str = "MAC140", repeats: int = 20) -> tuple[float, int]:
    """Median seconds to read every register the view shows of a twin ``motor`` over TCP,
    and the number of registers."""
    from jvl_gym.cli.serve import build_line
    from jvl_gym.protocol.serving.transport import TwinServer
    from jvl_gym.studio.groups import visible
    from jvl_gym.studio.session import Session

    line, _ = build_line([motor], [19])
    server = TwinServer(line, tcp=("127.0.0.1", 0)).start()
    try:
        port = server.endpoint("mactalk", "tcp").port
        session = Session.on_line(f"socket://127.0.0.1:{port}", [motor], [19])
        m = session.motors[0]
        numbers = [r.number for r in m.table if visible(r)]
        times = []
        for _ in range(repeats):
            t = time.perf_counter()
            m.read_raws(numbers)
            times.append(time.perf_counter() - t)
        session.stop()
    finally:
        server.stop()
    times.sort()
    return times[len(times) // 2], len(numbers)


def main() -> int:
    rate = scope_rate()
    browser = browser_rate()
    seconds, count = refresh_seconds("MAC140")
    seconds32, count32 = refresh_seconds("MIS232")
    none = "no Chromium"
    frames, received, ticks, latencies = (browser if browser is not None
                                          else (None, None, None, []))
    latencies = sorted(latencies)
    median = latencies[len(latencies) // 2] if latencies else None
    rows = [["scope updates/s, 8 channels, MAC140 in real time (server side)",
             f"{rate:.0f}", "≥ 30"],
            ["scope samples/s taken by the Scope page's timer, 8 channels",
             none if ticks is None else f"{ticks:.1f}", "≥ 30"],
            ["chart updates/s with new data received by headless Chromium, 8 channels",
             none if received is None else f"{received:.1f}", "≥ 30"],
            ["scope frames/s drawn with new data in headless Chromium, 8 channels",
             none if frames is None else f"{frames:.1f}", "≥ 30"],
            ["frames drawn per sample taken",
             none if frames is None else f"{frames / max(ticks, 1e-9):.2f}", "1"],
            [f"trigger latency, level crossing in the motor → trigger shown, less the "
             f"{SWEEP_S:g} s sweep of the window (median of {len(latencies) or TRIGGERS})",
             none if median is None else f"{median * 1e3:.0f} ms", "< 100 ms"],
            ["trigger latency, largest",
             none if median is None else f"{latencies[-1] * 1e3:.0f} ms", "< 100 ms"],
            [f"refresh of all {count} registers of a twin MAC140 over TCP",
             f"{seconds * 1e3:.0f} ms", "< 1 s"],
            [f"refresh of all {count32} registers of a twin MIS232 over TCP (32-bit MacTalk)",
             f"{seconds32 * 1e3:.0f} ms", "< 1 s"]]
    text = table(["measure", "result", "target"], rows, ["l", "r", "r"])
    print(text)
    page = update_section("studio", text)
    if page is not None:
        print(f"wrote {page}")
    ok = (rate >= 30 and (frames is None or frames >= 30)
          and (median is None or latencies[-1] < 0.1) and max(seconds, seconds32) < 1.0)
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
