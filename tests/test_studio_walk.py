"""The acceptance walk of the studio (docs/studio.md "A first session, step by step"): what a
new user does with the docs alone, in Chromium at 1280×720.

A ``jvl-gym serve`` line of two MAC140 twins runs in real time on a free TCP port; the studio
starts with no motor and opens on the Connections view. The user connects the line, scans it,
adds the two motors, jogs one, records a triggered step response and reads its rise time with
the cursors, changes KVOUT and sees it against the flash, undoes it, makes it again and saves it
in flash, and stops every motor with STOP. After each step the twin's registers are read
through a MacTalk client of its own, and the page is saved as a screenshot (the artefacts
folder, and ``docs/img/studio/walk_*.png`` with ``JVL_STUDIO_DOCS=1``)."""

from __future__ import annotations

import csv
import io
import re
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np
import pytest

from conftest import CHROMIUM
from test_studio_browser import artefacts, shoot  # noqa: F401 - the shared fixture
from test_studio_lock import ROOT, Studio, _env, free_port, stop_process

pytestmark = pytest.mark.skipif(not Path(CHROMIUM).exists(),
                                reason=f"Debian's Chromium ({CHROMIUM}) is not installed")
expect = pytest.importorskip("playwright.sync_api").expect

#: generous [ms]: a loaded machine may hold a page, the twin or the studio up for seconds
LONG = 90_000


@pytest.fixture(scope="session")
def browser_context_args(browser_context_args: dict) -> dict:
    return {**browser_context_args, "viewport": {"width": 1280, "height": 720},
            "accept_downloads": True}


class Twins:
    """``jvl-gym serve -m MAC140 -a 1 -m MAC140 -a 2 --tcp 127.0.0.1:PORT`` in a process of
    its own, real time, with its flash in ``flash_dir``."""

    def __init__(self, flash_dir: Path) -> None:
        self.port = free_port()
        self.url = f"socket://127.0.0.1:{self.port}"
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "jvl_gym.cli", "serve", "-m", "MAC140", "-a", "1", "-m",
             "MAC140", "-a", "2", "--tcp", f"127.0.0.1:{self.port}", "--flash-dir",
             str(flash_dir)], env=_env(), cwd=ROOT, stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL)
        end = time.monotonic() + 300
        while True:  # until both answer (the first answers may wait for numba)
            try:
                if self.read(1, "MODE_REG") == 0 and self.read(2, "MODE_REG") == 0:
                    return
            except Exception:  # noqa: BLE001 - not up yet
                if self.proc.poll() is not None or time.monotonic() > end:
                    self.stop()
                    raise RuntimeError("jvl-gym serve did not answer") from None
                time.sleep(0.5)

    def client(self, address: int):
        """A MacTalk client of its own (MAC050–141 manual 5.1) on the twin at ``address``."""
        from jvl_gym.protocol.mactalk.client16 import MacTalkClient

        return MacTalkClient(self.url, address, timeout=2.0, retries=3)

    def read(self, address: int, name: str) -> float:
        with self.client(address) as c:
            return float(c.read(name))

    def write(self, address: int, name: str, value: float) -> None:
        with self.client(address) as c:
            c.write(name, value)

    def until(self, what: str, ok: Callable[[], bool], seconds: float = 60.0) -> None:
        """Poll ``ok`` through the client until it holds (a twin in real time needs a moment
        to ramp); fail saying ``what`` otherwise."""
        end = time.monotonic() + seconds
        while not ok():
            assert time.monotonic() < end, f"the twin never showed: {what}"
            time.sleep(0.2)

    def stop(self) -> None:
        stop_process(self.proc)


@pytest.fixture(scope="module")
def twins(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Twins]:
    t = Twins(tmp_path_factory.mktemp("flash"))
    yield t
    t.stop()


@pytest.fixture(scope="module")
def studio() -> Iterator[Studio]:
    # no motor: the studio opens on the Connections view; the twins share the two cores with
    # the rest of the suite, so the line waits for their answers as docs/studio.md advises
    s = Studio("--answer-timeout", "3")
    yield s
    s.stop()


def rise_time(text: str, channel: str, level: float) -> tuple[float, float]:
    """The times [s] at which ``channel`` of a scope CSV reaches 10 % and 90 % of its final
    value, interpolated between samples, on the triggered window's time axis: 0 where the
    trace last rises through ``level`` (the trigger's crossing, docs/studio.md "Scope"); the
    final value is the mean over 1 to 1.5 s after it."""
    rows = [r for r in csv.reader(io.StringIO(text))]
    head, rows = rows[0], [r for r in rows[1:] if r and r[0]]
    t = np.array([float(r[0]) for r in rows])
    v = np.array([float(r[head.index(channel)]) for r in rows])

    def crossing(k: int, at: float) -> float:
        return float(t[k - 1] + (at - v[k - 1]) / (v[k] - v[k - 1]) * (t[k] - t[k - 1]))

    ups = np.flatnonzero((v[:-1] < level) & (v[1:] >= level)) + 1
    assert len(ups), f"no rising edge through {level} in the scope's CSV"
    k0 = int(ups[-1])
    t0 = crossing(k0, level)
    final = float(np.mean(v[(t >= t0 + 1.0) & (t <= t0 + 1.5)]))
    rest = np.flatnonzero(v[:k0] < 0.05 * final)  # at rest before the step
    start = int(rest[-1]) if len(rest) else 0
    out = []
    for share in (0.1, 0.9):
        k = start + int(np.argmax(v[start:] >= share * final))
        out.append(crossing(k, share * final) - t0)
    return out[0], out[1]


def test_the_first_session_walk(page, studio, twins, artefacts):  # noqa: F811
    page.set_default_timeout(LONG * 2)  # a loaded machine holds Chromium up for seconds
    message = page.get_by_test_id("message")

    # 1. the studio without motors opens on the Connections view
    page.goto(studio.with_token("/"))
    expect(page).to_have_url(re.compile(r"/connections"), timeout=LONG)
    expect(page.get_by_test_id("studio-motors")).to_contain_text("none yet")
    page.get_by_test_id("connect-port").fill(twins.url)
    page.get_by_test_id("connect").click()
    expect(message).to_contain_text(f"connected {twins.url}", timeout=LONG)

    # 2. scan the line: two MAC140 with their firmware version (manual 3.2.1: 4.14)
    page.get_by_test_id("scan-range-0").fill("1-4")
    page.get_by_test_id("scan-0").click()
    expect(message).to_contain_text("found 2 on", timeout=LONG)
    for a in (1, 2):
        expect(page.get_by_test_id(f"found-0-{a}")).to_contain_text("MAC140")
        expect(page.get_by_test_id(f"found-firmware-0-{a}")).to_have_text("4.14")
    shoot(page, artefacts, "walk_scan")
    page.get_by_test_id("add-all-0").click()
    expect(message).to_contain_text("added MAC140 @ 1, MAC140 @ 2", timeout=LONG)
    expect(page.get_by_test_id("line-motors-0")).to_contain_text("MAC140 @ 1, MAC140 @ 2")
    shoot(page, artefacts, "walk_connections")
    assert twins.read(1, "MODE_REG") == 0 and twins.read(2, "MODE_REG") == 0  # untouched

    # 3. jog motor 1 from the Motors view: velocity mode while the button is held
    page.get_by_test_id("held-0").click()
    state = page.get_by_test_id("motion-state-0")
    expect(page.get_by_test_id("mode-0")).to_contain_text("INIT_MODE", timeout=LONG)
    expect(state).to_contain_text("INIT_MODE", timeout=LONG)  # the page is laid out
    expect(page.get_by_test_id("bits-1-ERR_STAT")).to_contain_text("ERR_STAT", timeout=LONG)
    page.get_by_test_id("speed-0").fill("200")
    page.get_by_test_id("jog-plus-0").hover()
    page.mouse.down()
    expect(message).to_contain_text("jogging +200 rpm", timeout=LONG)
    expect(state).to_contain_text("jogging", timeout=LONG)
    twins.until("motor 1 jogging forwards (MODE_REG 1, V_IST > 0)",
                lambda: twins.read(1, "MODE_REG") == 1 and twins.read(1, "V_IST") > 0)
    assert twins.read(2, "MODE_REG") == 0
    shoot(page, artefacts, "walk_jog")
    page.mouse.up()
    expect(message).to_contain_text("jog stopped", timeout=LONG)
    twins.until("the jog's speed back to 0", lambda: twins.read(1, "V_SOLL") == 0)
    page.get_by_test_id("passive-0").click()
    twins.until("motor 1 passive", lambda: twins.read(1, "MODE_REG") == 0)

    # 4. a step response triggered in normal mode and held, its rise time read with the cursors
    page.goto(studio.url + "/scope?m=0")
    expect(page.get_by_test_id("motion-state-0")).to_contain_text("INIT_MODE", timeout=LONG)
    for name in ("V_SOLL", "MODE_REG"):  # V_IST alone: a lighter chart for a busy browser
        page.locator(".q-chip", has_text=name).locator(".q-chip__icon--remove").click()
        expect(page.locator(".q-chip", has_text=name)).to_have_count(0, timeout=LONG)
    page.get_by_test_id("trigger").click()
    expect(page.get_by_test_id("trigger")).to_have_attribute("aria-checked", "true",
                                                                     timeout=LONG)
    page.get_by_test_id("trigger-channel").click()
    page.get_by_role("option", name="V_IST [counts/sample]").click()
    expect(page.get_by_test_id("trigger-channel")).to_contain_text("V_IST", timeout=LONG)
    page.get_by_test_id("trigger-level").fill("10")
    page.get_by_test_id("time-base").fill("2")
    page.get_by_test_id("trigger-mode").get_by_text("normal").click()
    count = page.get_by_test_id("scope-count")
    expect(count).to_contain_text("waiting for the trigger", timeout=LONG)
    page.get_by_test_id("speed-0").fill("300")
    page.get_by_test_id("run-0").click()
    expect(message).to_contain_text("running at 300 rpm", timeout=LONG)
    expect(count).not_to_contain_text("waiting for the trigger", timeout=LONG)
    twins.until("motor 1 running (MODE_REG 1, V_IST above the level 10)",
                lambda: twins.read(1, "MODE_REG") == 1 and twins.read(1, "V_IST") > 10)
    page.wait_for_timeout(2500)  # the window's 1.6 s after the edge fill up
    page.get_by_test_id("live").click()  # hold the triggered window
    expect(page.get_by_test_id("live")).to_have_attribute("aria-checked", "false",
                                                          timeout=LONG)
    with page.expect_download() as download:
        page.get_by_test_id("scope-csv").click()
    (artefacts / "walk_step.csv").write_text(Path(download.value.path()).read_text())
    t10, t90 = rise_time(Path(download.value.path()).read_text(), "V_IST [counts/sample]", 10)
    assert 0 < t90 - t10 < 2.0
    page.get_by_test_id("cursors").click()
    page.get_by_test_id("cursor-channel").click()
    page.get_by_role("option", name="V_IST [counts/sample]").last.click()
    page.get_by_test_id("t1").fill(f"{t10:.4f}")
    page.get_by_test_id("t2").fill(f"{t90:.4f}")
    readout = page.get_by_test_id("cursor-readout")
    expect(readout).to_contain_text(f"Δt = {float(f'{t90:.4f}') - float(f'{t10:.4f}'):.6g} s",
                                    timeout=LONG)
    shoot(page, artefacts, "walk_step")
    page.get_by_test_id("passive-0").click()
    twins.until("motor 1 passive after the step", lambda: twins.read(1, "MODE_REG") == 0)

    # 5. KVOUT changed against the flash, undone, made again and saved in flash
    page.goto(studio.url + "/registers?m=0")
    field = page.get_by_label("KVOUT", exact=True)
    expect(field).not_to_have_value("", timeout=LONG)
    old = field.input_value()
    new = f"{float(old) + 0.5:g}"
    assert twins.read(1, "KVOUT") == float(old)
    changed_row = page.locator('[data-changed="1"]', has=field)
    field.fill(new)
    field.press("Enter")
    expect(message).to_have_text(f"KVOUT = {new}", timeout=LONG)
    expect(changed_row).to_have_count(1, timeout=LONG)
    expect(page.get_by_test_id("changes")).to_contain_text("changed against flash")
    assert twins.read(1, "KVOUT") == float(new)
    shoot(page, artefacts, "walk_kvout")
    page.get_by_test_id("undo").click()
    expect(message).to_contain_text("undone: KVOUT", timeout=LONG)
    expect(changed_row).to_have_count(0, timeout=LONG)
    assert twins.read(1, "KVOUT") == float(old)
    page.get_by_test_id("redo").click()
    expect(field).to_have_value(new, timeout=LONG)
    assert twins.read(1, "KVOUT") == float(new)
    page.get_by_test_id("write-flash").click()
    expect(page.get_by_test_id("flash-dialog")).to_contain_text(f"KVOUT: {old} → {new}",
                                                                timeout=LONG)
    shoot(page, artefacts, "walk_flash")
    page.get_by_test_id("flash-confirm").click()
    expect(message).to_contain_text("saved in flash", timeout=LONG)
    expect(changed_row).to_have_count(0, timeout=LONG)
    twins.until("KVOUT kept through the flash write's reset",
                lambda: twins.read(1, "KVOUT") == float(new)
                and twins.read(1, "MODE_REG") == 0)

    # 6. STOP stops every motor of the studio: both run, both ramp down to passive
    twins.write(2, "V_SOLL", 320)
    twins.write(2, "MODE_REG", 1)
    page.goto(studio.url + "/?m=0")
    page.get_by_test_id("speed-0").fill("300")
    page.get_by_test_id("run-0").click()
    twins.until("both motors running", lambda: twins.read(1, "MODE_REG") == 1
                and twins.read(2, "V_IST") > 10)
    page.get_by_test_id("stop").click()
    expect(message).to_contain_text("MAC140 @ 1: STOP_MODE (11)", timeout=LONG)
    expect(message).to_contain_text("MAC140 @ 2: STOP_MODE (11)")
    shoot(page, artefacts, "walk_stop")
    for a in (1, 2):  # STOP_MODE ramps down, then INIT_MODE (manual 4.1.8, 4.4.12)
        twins.until(f"motor {a} passive after STOP", lambda a=a: twins.read(a, "MODE_REG") == 0)
