"""Speed of ``jvl-gym studio``: the scope's update rate and the register view's refresh time.

``python benchmarks/bench_studio.py`` measures

* **scope updates per second, 4 channels, simulated motor in real time**: a MAC140 simulated in
  real time by the studio's clock (:class:`jvl_gym.studio.session.Session`) runs in velocity
  mode; one scope update is what the Scope page does per tick: read the 4 channels (V_IST,
  V_SOLL, the shaft speed, phase current A), build the chart's options and encode them as the
  JSON the browser receives. The rate is the best of equal windows (``best_rate.py``). With
  Debian's Chromium present, the rate the browser shows is measured too: the studio is started
  on a free port and a headless Chromium counts the scope's updates on the page for 5 s (the
  page's timer bounds it, ``studio.ui.scope_page.PERIOD_S``);
* **refresh of all registers of a twin motor over TCP**: a ``jvl-gym serve`` twin of one MAC140
  (16-bit MacTalk) and one of an MIS232 (32-bit MacTalk) on a free TCP port, the register
  view's read of every register it shows (:meth:`jvl_gym.studio.line.LineMotor.read_raws`),
  the median of 20 refreshes.

Targets: ≥ 20 scope updates per second, a refresh under 1 s. Figures go to the generated page
``docs/benchmarks.md`` (section "Studio", :mod:`bench_page`).
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
CHANNELS = ["V_IST", "V_SOLL", "shaft speed", "phase currents A"]


def scope_rate(seconds: float = 3.0) -> float:
    """Scope updates per second of the server side (read 4 channels, options, JSON)."""
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


def browser_rate(seconds: float = 5.0) -> tuple[float, float] | None:
    """Scope updates per second shown in headless Chromium and sent by the page's timer, or
    None without Chromium."""
    if not Path(CHROMIUM).exists():
        return None
    from playwright.sync_api import sync_playwright

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT / "src"), str(ROOT)]))
    proc = subprocess.Popen([sys.executable, "-m", "jvl_gym.cli", "studio", "--no-browser",
                             "--port", str(port), "--motor", "MAC140"], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
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
            ctx = p.chromium.launch_persistent_context(tempfile.mkdtemp(), headless=True,
                                                       executable_path=CHROMIUM, args=args)
            page = ctx.new_page()
            page.goto(f"{url}/scope?m=0&token={token}", timeout=300000)
            counter = page.get_by_test_id("scope-count")
            counter.wait_for(timeout=60000)
            first = _update_number(counter.inner_text())
            page.evaluate("""() => { window.__n = 0; const el = document.querySelector(
                '[data-testid="scope-count"]'); new MutationObserver(() => window.__n++)
                .observe(el, {subtree: true, childList: true, characterData: true}); }""")
            time.sleep(seconds)
            n = page.evaluate("() => window.__n")
            sent = _update_number(counter.inner_text()) - first
            ctx.close()
        return n / seconds, sent / seconds
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
    rates = browser_rate()
    shown, sent = rates if rates is not None else (None, None)
    seconds, count = refresh_seconds("MAC140")
    seconds32, count32 = refresh_seconds("MIS232")
    rows = [["scope updates/s, 4 channels, MAC140 in real time (server side)",
             f"{rate:.0f}", "≥ 20"],
            ["scope updates/s sent by the Scope page's timer",
             "no Chromium" if sent is None else f"{sent:.1f}", "≥ 20"],
            ["scope updates/s shown in headless Chromium",
             "no Chromium" if shown is None else f"{shown:.1f}", "≥ 20"],
            [f"refresh of all {count} registers of a twin MAC140 over TCP",
             f"{seconds * 1e3:.0f} ms", "< 1 s"],
            [f"refresh of all {count32} registers of a twin MIS232 over TCP (32-bit MacTalk)",
             f"{seconds32 * 1e3:.0f} ms", "< 1 s"]]
    text = table(["measure", "result", "target"], rows, ["l", "r", "r"])
    print(text)
    page = update_section("studio", text)
    if page is not None:
        print(f"wrote {page}")
    ok = rate >= 20 and (shown is None or shown >= 20) and max(seconds, seconds32) < 1.0
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
