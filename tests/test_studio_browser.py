"""The studio in Chromium (pytest-playwright): a simulated MAC140 and MIS232 driven from the
registers view and seen running on the scope, a refused value with its reason, a setup saved
and loaded, a sample buffer captured, the tuning page run to the written result, the episodes
page, and twins served as ``jvl-gym serve`` serves them (in this process, on a free port) whose
value written by another client appears (and whose line comes back after the twin restarts);
the lock (a foreign Host name or Origin refused, nothing served without the token, the twin
unchanged) and STOP (the header's button on every view and the Escape key, on simulated motors
and on twins).
Each view is saved as a screenshot in the artefacts folder (``$JVL_ARTEFACTS``, default the
test run's temporary folder), and in ``docs/img/studio`` with ``JVL_STUDIO_DOCS=1``."""

from __future__ import annotations

import os
import re
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from conftest import CHROMIUM, FOREIGN_HOST
from test_studio_lock import Studio, start_twin, twin_registers

ROOT = Path(__file__).resolve().parents[1]

pytestmark = pytest.mark.skipif(not Path(CHROMIUM).exists(),
                                reason=f"Debian's Chromium ({CHROMIUM}) is not installed")
expect = pytest.importorskip("playwright.sync_api").expect
#: how long a page's answer may take: the studio answers in well under a second on an idle
#: machine, but the suite runs beside other work (load averages of 20 on two cores seen), so the
#: tests wait as long as a user would before calling the studio broken
PAGE_TIMEOUT_MS = 60_000
expect.set_options(timeout=PAGE_TIMEOUT_MS)


@pytest.fixture(autouse=True)
def _patient_page(page) -> None:
    """Every action on the page (click, fill, goto) waits up to :data:`PAGE_TIMEOUT_MS`."""
    page.set_default_timeout(PAGE_TIMEOUT_MS)
    page.set_default_navigation_timeout(PAGE_TIMEOUT_MS)


@pytest.fixture(scope="session")
def browser_context_args(browser_context_args: dict) -> dict:
    return {**browser_context_args, "viewport": {"width": 1400, "height": 900},
            "accept_downloads": True}


@pytest.fixture(scope="session")
def artefacts(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = Path(os.environ.get("JVL_ARTEFACTS") or tmp_path_factory.getbasetemp() / "artefacts")
    path = path / "studio"
    path.mkdir(parents=True, exist_ok=True)
    return path


def shoot(page, artefacts: Path, name: str, full: bool = False) -> None:
    """Save a screenshot of the page (``full``: the whole page, else the window) as an
    artefact, and for the docs if asked."""
    page.screenshot(path=str(artefacts / f"{name}.png"), full_page=full)
    if os.environ.get("JVL_STUDIO_DOCS") == "1":
        docs = ROOT / "docs" / "img" / "studio"
        docs.mkdir(parents=True, exist_ok=True)
        page.screenshot(path=str(docs / f"{name}.png"), full_page=full)


@pytest.fixture(scope="module")
def studio() -> Iterator[Studio]:
    studio = Studio("--motor", "MAC140", "--motor", "MIS232", "--motor", "MAC140")
    yield studio
    studio.stop()


def open_raw_registers(page, url: str) -> None:
    """The Registers view at ``url`` with the raw toggle on: values in the registers' own
    units, every register a field."""
    page.goto(url)
    expect(page.get_by_test_id("raw-V_SOLL")).to_contain_text("raw")  # the page is live
    page.get_by_test_id("units-raw").click()
    expect(page.get_by_test_id("unit-V_SOLL")).to_have_text(
        re.compile(r"count|0\.01 RPM"))  # the register's own unit


def write(page, name: str, value: str) -> None:
    expect(page.get_by_test_id(f"raw-{name}")).to_contain_text("raw")  # the page is live
    field = page.get_by_label(name, exact=True)
    field.fill(value)
    field.press("Enter")


def last_value(page, name: str) -> float:
    text = page.get_by_test_id("scope-last").inner_text()
    m = re.search(rf"{re.escape(name)}(?: \[[^\]]*\])? = (\S+?)(?:;|$)", text)
    return float(m.group(1)) if m else float("nan")


def wait_value(page, name: str, target: float, tol: float, seconds: float = 60.0) -> float:
    end = time.monotonic() + seconds
    v = float("nan")
    while time.monotonic() < end:
        v = last_value(page, name)
        if abs(v - target) <= tol:
            return v
        time.sleep(0.2)
    raise AssertionError(f"{name} = {v} on the scope, expected {target} ± {tol}")


def test_motors_view(page, studio, artefacts):
    page.goto(studio.with_token("/?m=0"))
    expect(page.get_by_test_id("mode-0")).to_contain_text("INIT_MODE")
    expect(page.get_by_test_id("mode-1")).to_contain_text("passive")
    expect(page.get_by_test_id("bits-1-ERR_BITS")).to_contain_text("ERR_BITS")
    card = page.get_by_test_id("motor-1")
    card.get_by_role("button", name="safe mode", exact=True).click()
    expect(page.get_by_test_id("mode-1")).to_contain_text("safe")
    card.get_by_role("button", name="leave safe mode").click()
    expect(page.get_by_test_id("mode-1")).to_contain_text("passive")
    shoot(page, artefacts, "motors")


@pytest.mark.parametrize("m, v_soll, v_ist, name", [(0, "320", 20.0, "MAC140"),
                                                    (1, "5000", 5000.0, "MIS232")])
def test_write_from_registers_and_see_it_run_on_the_scope(page, studio, artefacts, m, v_soll,
                                                          v_ist, name):
    """V_SOLL then MODE_REG = 1 (velocity mode): the MAC050–141 runs at V_SOLL/16
    counts/sample (manual 3.2.5, 3.2.12), the MIS at V_SOLL in 0.01 rpm (§8.2.6, §8.2.13)."""
    open_raw_registers(page, studio.with_token(f"/registers?m={m}"))
    message = page.get_by_test_id("message")
    write(page, "V_SOLL", v_soll)
    expect(message).to_have_text(f"V_SOLL = {v_soll}")
    write(page, "MODE_REG", "1")
    expect(message).to_have_text("MODE_REG = 1")
    write(page, "V_SOLL", "9999999999")
    expect(message).to_contain_text("outside the range")
    expect(page.get_by_label("V_SOLL", exact=True)).to_have_value(v_soll)
    shoot(page, artefacts, f"registers_{name}")
    page.goto(studio.with_token(f"/scope?m={m}"))
    wait_value(page, "V_IST", v_ist, 0.15 * v_ist)
    assert last_value(page, "V_SOLL") == float(v_soll)
    if m == 0:
        page.get_by_test_id("capture").click()
        expect(page.get_by_test_id("message")).to_contain_text(
            "sample buffer: 200 samples of V_IST [counts/sample], P_IST [counts]")
        shoot(page, artefacts, "scope", full=True)


def test_save_and_load_a_setup(page, studio, tmp_path):
    open_raw_registers(page, studio.with_token("/registers?m=0"))
    field = page.get_by_label("A_SOLL", exact=True)
    expect(field).not_to_have_value("")
    saved = field.input_value()
    with page.expect_download() as download:
        page.get_by_test_id("save-setup").click()
    path = tmp_path / "setup.yaml"
    download.value.save_as(path)
    assert f"A_SOLL: {saved}" in path.read_text()
    write(page, "A_SOLL", "99")
    expect(page.get_by_test_id("message")).to_have_text("A_SOLL = 99")
    page.get_by_test_id("load-setup").locator("input[type=file]").set_input_files(path)
    expect(page.get_by_test_id("message")).to_contain_text("loaded")
    expect(field).to_have_value(saved)
    bad = tmp_path / "bad.yaml"
    bad.write_text("registers: {A_SOLL: 5, V_SOLL: 1e9}\n")
    page.get_by_test_id("load-setup").locator("input[type=file]").set_input_files(bad)
    expect(page.get_by_test_id("message")).to_contain_text("outside the range")
    expect(field).to_have_value(saved)


def test_stop_in_every_view_stops_every_motor(page, studio):
    """The header's STOP is on every view; pressed on the registers view it stops every motor
    by its family's stop (MAC050–141 STOP_MODE, manual 4.1.8; MIS mode 11, §8.2.3), which
    ramps down and goes passive."""
    from jvl_gym.studio.ui.common import VIEWS

    for path in VIEWS:
        page.goto(studio.with_token(f"{path}?m=0"))
        expect(page.get_by_test_id("stop")).to_be_visible()
    open_raw_registers(page, studio.with_token("/registers?m=1"))
    write(page, "V_SOLL", "5000")
    write(page, "MODE_REG", "1")
    expect(page.get_by_test_id("message")).to_have_text("MODE_REG = 1")
    page.get_by_test_id("stop").click()
    message = page.get_by_test_id("message")
    expect(message).to_contain_text("STOP: MAC140 @ 1")
    expect(message).to_contain_text("MIS232 @ 2: stop (11), ramp, then passive")
    page.goto(studio.with_token("/?m=0"))
    expect(page.get_by_test_id("mode-1")).to_contain_text("passive")
    expect(page.get_by_test_id("mode-0")).to_contain_text("INIT_MODE")


def test_tuning_page_to_the_written_result(page, studio, artefacts):
    page.goto(studio.with_token("/tuning?m=2"))
    page.get_by_test_id("tuning-run").click()
    expect(page.get_by_test_id("tuning-write")).to_be_visible(timeout=240000)
    table = page.get_by_test_id("tuning-registers")
    row = table.locator("tr", has_text="KVOUT")
    new = row.locator("td").nth(2).inner_text()
    shoot(page, artefacts, "tuning", full=True)
    page.get_by_test_id("tuning-write").click()
    page.get_by_test_id("tuning-confirm").click()
    expect(page.get_by_test_id("message")).to_contain_text("wrote")
    open_raw_registers(page, studio.with_token("/registers?m=2"))
    expect(page.get_by_label("KVOUT", exact=True)).to_have_value(new)


def test_episodes_page(page, studio, artefacts):
    page.goto(studio.with_token("/episodes"))
    page.get_by_test_id("episode-run").click()
    expect(page.get_by_test_id("episode-total")).to_contain_text("return", timeout=120000)
    shoot(page, artefacts, "episodes")


def test_a_twin_shows_what_another_client_writes(page, artefacts):
    from jvl_gym.protocol.mactalk.client16 import MacTalkClient

    twin = start_twin(["MAC140"], [19])
    tcp = twin.endpoint("mactalk", "tcp").port
    studio = None
    try:
        studio = Studio("--connect", f"socket://127.0.0.1:{tcp}", "--scan", "18-20")
        open_raw_registers(page, studio.with_token("/registers?m=0"))
        field = page.get_by_label("V_SOLL", exact=True)
        with MacTalkClient(f"socket://127.0.0.1:{tcp}", 19) as other:
            other.write("V_SOLL", 321)
        expect(field).to_have_value("321")
        shoot(page, artefacts, "registers_twin")
        twin.stop()
        expect(page.get_by_test_id("line-state")).to_contain_text("127.0.0.1")
        twin = start_twin(["MAC140"], [19], tcp)
        with MacTalkClient(f"socket://127.0.0.1:{tcp}", 19) as other:
            other.write("V_SOLL", 123)
        expect(field).to_have_value("123")
        expect(page.get_by_test_id("line-state")).to_have_text("")
    finally:
        if studio is not None:
            studio.stop()
        twin.stop()


def test_a_line_of_mis_and_mac800_twins(page, artefacts):
    """`jvl-gym serve` twins of an MIS232 and a MAC800 (32-bit MacTalk, MIS manual §18.2,
    MAC800 quick guide §1.3): a value written from the registers view is read back by another
    client, one the other client writes appears on the page, and a value the motor refuses
    (safe mode by MODE_REG: only by its command, MIS manual §8.2.3, §18.2.5) shows why."""
    from jvl_gym.families import family_of_motor
    from jvl_gym.protocol.mactalk.client32 import MacTalk32Client

    twin = start_twin(["MIS232", "MAC800"], [7, 8])
    line = f"socket://127.0.0.1:{twin.endpoint('mactalk', 'tcp').port}"
    studio = None
    try:
        studio = Studio("--connect", line, "--motor", "MIS232", "--address", "7",
                                 "--motor", "MAC800", "--address", "8")
        open_raw_registers(page, studio.with_token("/registers?m=0"))
        message = page.get_by_test_id("message")
        write(page, "V_SOLL", "4321")
        expect(message).to_have_text("V_SOLL = 4321")
        with MacTalk32Client(line, 7, table=family_of_motor("MIS232").table) as other:
            assert other.read("V_SOLL") == 4321
        write(page, "MODE_REG", "15")
        expect(message).to_contain_text("did not accept")
        expect(page.get_by_label("MODE_REG", exact=True)).to_have_value("0")
        shoot(page, artefacts, "registers_line32")
        open_raw_registers(page, studio.with_token("/registers?m=1"))
        field = page.get_by_label("V_SOLL", exact=True)
        with MacTalk32Client(line, 8, table=family_of_motor("MAC800").table) as other:
            other.write("V_SOLL", 277)
        expect(field).to_have_value("277")
    finally:
        if studio is not None:
            studio.stop()
        twin.stop()


# ---------------------------------------------------------------------- the lock
@pytest.fixture(scope="module")
def on_twin() -> Iterator[tuple[Studio, object]]:
    """A studio on the twin of an MAC140 at address 19 (``jvl-gym serve``)."""
    twin = start_twin(["MAC140"], [19])
    studio = None
    try:
        studio = Studio("--connect", f"socket://127.0.0.1:{twin.endpoint('mactalk', 'tcp').port}",
                        "--address", "19")
        yield studio, twin
    finally:
        if studio is not None:
            studio.stop()
        twin.stop()


def test_a_foreign_host_name_is_refused_and_changes_nothing(page, on_twin):
    """A page fetched under a foreign name that leads here (DNS rebinding) is refused with
    the reason, even with the token in the URL; what its scripts send is refused too, and the
    twin's registers are unchanged."""
    studio, twin = on_twin
    before = twin_registers(twin)
    response = page.goto(f"http://{FOREIGN_HOST}:{studio.port}/?token={studio.token}")
    assert response is not None and response.status == 403
    expect(page.locator("body")).to_contain_text(f"refused: Host '{FOREIGN_HOST}:{studio.port}'")
    status = page.evaluate("""async () => (await fetch('/_nicegui/client/x/upload/1',
        {method: 'POST', body: 'registers: {A_SOLL: 5}'})).status""")
    assert status == 403
    assert twin_registers(twin) == before


OPEN_WS = """url => new Promise(resolve => {
    const ws = new WebSocket(url);
    ws.onopen = () => { ws.close(); resolve('open'); };
    ws.onerror = () => resolve('refused');
})"""


def test_a_websocket_from_a_foreign_origin_is_refused(page, on_twin):
    """A page of another origin on this machine (which gets the studio's cookie: same site)
    cannot open the studio's live connection, with the cookie or even with the token; the
    studio's own page can."""
    import http.server
    import threading

    studio, twin = on_twin
    before = twin_registers(twin)
    page.goto(studio.with_token("/"))  # the cookie is set
    live = f"ws://127.0.0.1:{studio.port}/_nicegui_ws/socket.io/?EIO=4&transport=websocket"
    assert page.evaluate(OPEN_WS, live) == "open"

    class Quiet(http.server.SimpleHTTPRequestHandler):
        def log_message(self, *args) -> None:
            pass

    other = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Quiet)
    threading.Thread(target=other.serve_forever, daemon=True).start()
    try:
        page.goto(f"http://127.0.0.1:{other.server_address[1]}/")
        assert page.evaluate(OPEN_WS, live) == "refused"
        assert page.evaluate(OPEN_WS, f"{live}&token={studio.token}") == "refused"
    finally:
        other.shutdown()
        other.server_close()
    assert twin_registers(twin) == before


def test_without_the_token_nothing_is_served_and_with_it_a_write_works(page, on_twin):
    """Without the token: the page, an upload and the live connection (over which every write
    goes) are refused and the twin is unchanged; the URL with the token opens the studio and a
    write reaches the motor."""
    studio, twin = on_twin
    before = twin_registers(twin)
    for path in ("/", "/registers?m=0", "/registers?m=0&token=wrong"):
        response = page.goto(studio.url + path)
        assert response is not None and response.status == 401
        expect(page.locator("body")).to_contain_text("refused: the studio's token")
    upload = page.request.post(studio.url + "/_nicegui/client/x/upload/1",
                               multipart={"file": {"name": "setup.yaml", "mimeType": "text/yaml",
                                                   "buffer": b"registers: {A_SOLL: 5}\n"}})
    assert upload.status == 401
    live = f"ws://127.0.0.1:{studio.port}/_nicegui_ws/socket.io/?EIO=4&transport=websocket"
    assert page.evaluate(OPEN_WS, live) == "refused"
    assert twin_registers(twin) == before
    open_raw_registers(page, studio.with_token("/registers?m=0"))
    value = str(before["V_SOLL"] + 111)
    write(page, "V_SOLL", value)
    expect(page.get_by_test_id("message")).to_have_text(f"V_SOLL = {value}")
    assert twin_registers(twin)["V_SOLL"] == int(value)


def test_escape_stops_the_motors_on_a_line(page):
    """The Escape key stops every motor on a line of twins (MIS232 and MAC140 over the
    MacTalk line) as STOP does: each goes through its stop mode to passive."""
    from jvl_gym.families import family_of_motor
    from jvl_gym.protocol.mactalk.client16 import MacTalkClient
    from jvl_gym.protocol.mactalk.client32 import MacTalk32Client

    twin = start_twin(["MIS232", "MAC140"], [7, 8])
    line = f"socket://127.0.0.1:{twin.endpoint('mactalk', 'tcp').port}"
    studio = None
    try:
        studio = Studio("--connect", line, "--motor", "MIS232", "--address", "7", "--motor",
                        "MAC140", "--address", "8")

        def clients() -> list:
            return [MacTalk32Client(line, 7, table=family_of_motor("MIS232").table),
                    MacTalkClient(line, 8)]

        for client, speed in zip(clients(), (5000, 320)):
            with client:
                client.write("V_SOLL", speed)
                client.write("MODE_REG", 1)
        page.goto(studio.with_token("/scope?m=0"))
        expect(page.get_by_test_id("stop")).to_be_visible()
        page.keyboard.press("Escape")
        message = page.get_by_test_id("message")
        expect(message).to_contain_text("MIS232 @ 7: stop (11)")
        expect(message).to_contain_text("MAC140 @ 8: STOP_MODE (11)")
        for client in clients():
            end = time.monotonic() + 60
            with client:
                while client.read_raw(2) != 0 and time.monotonic() < end:  # MODE_REG
                    time.sleep(0.1)
                assert client.read_raw(2) == 0
    finally:
        if studio is not None:
            studio.stop()
        twin.stop()


def test_engineering_units_modes_bits_and_a_jog(page, studio, artefacts):
    """The Registers view in engineering units (MAC050–141 manual 3.2.5: V_SOLL in rpm), the
    mode register as the modes, CNTRL_BITS as named boxes, a value written on leaving its field;
    the motion panel jogs while its button is held and stops on release."""
    page.goto(studio.with_token("/registers?m=0"))
    message = page.get_by_test_id("message")
    expect(page.get_by_test_id("unit-V_SOLL")).to_have_text("rpm")
    expect(page.get_by_test_id("unit-P_IST")).to_have_text("turns")
    expect(page.get_by_test_id("reg-MODE_REG")).to_contain_text(re.compile(r"[A-Z]+_MODE \(\d+\)"))
    expect(page.get_by_test_id("bit-CNTRL_BITS-6")).to_contain_text("RECORD")
    write(page, "V_SOLL", "100")
    expect(message).to_have_text(re.compile(r"V_SOLL = (99|100)\.\d+ rpm"))
    field = page.get_by_label("A_SOLL", exact=True)
    field.fill("20000")
    page.get_by_label("KVOUT", exact=True).click()  # leave the field without Enter
    expect(message).to_have_text(re.compile(r"A_SOLL = (19|20)\d{3}(\.\d+)? rpm/s"))
    shoot(page, artefacts, "registers_engineering")
    page.goto(studio.with_token("/?m=0"))
    state = page.get_by_test_id("motion-state-0")
    expect(state).to_contain_text("position")
    page.get_by_test_id("speed-0").fill("200")
    page.get_by_test_id("jog-plus-0").hover()
    page.mouse.down()
    expect(state).to_contain_text("jogging")
    shoot(page, artefacts, "motion_jog")
    page.mouse.up()
    expect(message).to_contain_text("jog stopped")
    expect(state).not_to_contain_text("jogging")
    page.get_by_test_id("passive-0").click()
    expect(state).to_contain_text("INIT_MODE")


def test_parameters_against_flash_undo_and_write_to_flash(page, studio, artefacts):
    """KVOUT changed on the Registers view shows against the flash, an undo takes it back, a
    redo makes it again, and the flash write lists it before it writes (MAC050–141 manual
    5.1)."""
    page.goto(studio.with_token("/registers?m=0"))
    message = page.get_by_test_id("message")
    field = page.get_by_label("KVOUT", exact=True)
    expect(field).not_to_have_value("")
    old = field.input_value()
    new = f"{float(old) + 0.5:g}"
    changed_row = page.locator('[data-changed="1"]', has=field)
    write(page, "KVOUT", new)
    expect(message).to_have_text(f"KVOUT = {new}")
    expect(changed_row).to_have_count(1)
    expect(page.get_by_test_id("changes")).to_contain_text("changed against flash")
    shoot(page, artefacts, "parameters_changed")
    page.get_by_test_id("undo").click()
    expect(message).to_contain_text("undone: KVOUT")
    expect(field).to_have_value(old)
    expect(changed_row).to_have_count(0)
    page.get_by_test_id("redo").click()
    expect(field).to_have_value(new)
    page.get_by_test_id("write-flash").click()
    expect(page.get_by_test_id("flash-dialog")).to_contain_text(f"KVOUT: {old} → {new}")
    shoot(page, artefacts, "parameters_flash_dialog")
    page.get_by_test_id("flash-confirm").click()
    expect(message).to_contain_text("saved in flash")
    expect(changed_row).to_have_count(0)
    expect(field).to_have_value(new)


def test_a_triggered_step_response_read_with_cursors(page, studio, artefacts):
    """The scope armed in single mode on V_IST rising through 10 counts/sample (76 rpm,
    MAC050–141 manual 3.2.12), a run at 300 rpm from the motion panel beside it: the scope
    stops on the edge with time 0 at the crossing, and the cursors read Δt, Δvalue and
    1/Δt."""
    page.goto(studio.with_token("/scope?m=0"))
    page.get_by_test_id("passive-0").click()
    expect(page.get_by_test_id("motion-state-0")).to_contain_text("INIT_MODE")
    page.get_by_test_id("trigger").click()
    page.get_by_test_id("trigger-channel").click()
    page.get_by_role("option", name="V_IST [counts/sample]").click()
    page.get_by_test_id("trigger-level").fill("10")
    page.get_by_test_id("time-base").fill("2")
    page.get_by_test_id("trigger-mode").get_by_text("single").click()
    expect(page.get_by_test_id("scope-count")).to_contain_text("waiting for the trigger")
    page.get_by_test_id("speed-0").fill("300")
    page.get_by_test_id("run-0").click()
    expect(page.get_by_test_id("message")).to_contain_text("single: triggered on V_IST")
    expect(page.get_by_test_id("live")).to_have_attribute("aria-checked", "false")
    page.get_by_test_id("cursors").click()
    page.get_by_test_id("cursor-channel").click()
    page.get_by_role("option", name="V_IST [counts/sample]").last.click()
    page.get_by_test_id("t1").fill("0")
    page.get_by_test_id("t2").fill("0.1")
    readout = page.get_by_test_id("cursor-readout")
    expect(readout).to_contain_text("Δt = 0.1 s")
    expect(readout).to_contain_text("1/Δt = 10 Hz")
    shoot(page, artefacts, "scope_triggered_step")
    page.get_by_test_id("passive-0").click()
