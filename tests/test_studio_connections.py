"""The studio's Connections logic (jvl_gym.studio.connections, docs/studio.md "Connections"):
address ranges, the firmware version of each family, a scan of a twin line that names the
motors with their type, firmware and serial number, motors added to and removed from a running
session (thread-safe, STOP reaching every motor held at that moment), the flash record of a
motor on a line, bad input refused with one line and nothing changed, and the command line's
empty start."""

from __future__ import annotations

import threading
import time
from collections.abc import Iterator

import pytest

from jvl_gym.families import family
from jvl_gym.studio import parameters as P
from jvl_gym.studio.connections import (
    NONE,
    Connections,
    address_range,
    identify,
    version_text,
)
from jvl_gym.studio.line import ANSWER_TIMEOUT_S, LineDown, LineMotor
from jvl_gym.studio.motor import SimMotor
from jvl_gym.studio.session import Session

TYPES, ADDRESSES = ["MAC140", "MIS232"], [1, 2]


@pytest.fixture(scope="module")
def twin() -> Iterator[tuple[object, str]]:
    """A ``jvl-gym serve`` line of an MAC140 at 1 and an MIS232 at 2, answering."""
    from jvl_gym.cli.serve import build_line
    from jvl_gym.protocol.mactalk.client16 import MacTalkClient
    from jvl_gym.protocol.serving.transport import TwinServer

    line, _ = build_line(TYPES, ADDRESSES)
    server = TwinServer(line, tcp=("127.0.0.1", 0)).start()
    url = server.endpoint("mactalk", "tcp").url
    with MacTalkClient(url, 1, timeout=60) as c:  # the twin's first answer may compile
        c.read_raw(2)
    yield line, url
    server.stop()


def twin_raw(url: str, address: int, name: str) -> int:
    """Register ``name`` of the twin at ``address`` through a MacTalk client of its own."""
    from jvl_gym.families import family_of_motor
    from jvl_gym.protocol.mactalk.dialect import client_class

    fam = family_of_motor(TYPES[ADDRESSES.index(address)])
    with client_class(fam.twin.dialect)(url, address, table=fam.table) as client:
        return int(client.read_raw(fam.table.lookup(name).number))


@pytest.fixture()
def session() -> Iterator[Session]:
    s = Session()
    s.start()
    yield s
    s.stop()


def test_address_ranges():
    assert address_range("1-32") == range(1, 33) and address_range(" 19 ") == range(19, 20)
    for bad in ("", "a-b", "0-3", "5-2", "1-255", "1-2-3"):
        with pytest.raises(ValueError, match="FIRST-LAST|1..254"):
            address_range(bad)


@pytest.mark.parametrize("key, raw, text", [
    ("mac050_141", 78, "4.14"),        # manual 3.2.1: 78 = 4Eh = version 4.14
    ("mac800", 32832, "1.0"),          # register overview §1.2: bits 6-12 major, 0-5 minor
    ("mis", 540720, "3.0"),            # MIS manual §8.2.2: bits 4-12 major, 0-3 minor
    ("mis", 33 * 2**14 + (3 << 4) + 2 + 2**13, "3.2 beta")])
def test_firmware_version_as_each_manual_reads_it(key, raw, text):
    assert version_text(family(key), raw) == text


class _Registers:
    """A line stand-in whose units answer every register from ``values`` (number → raw)."""

    def __init__(self, values: dict[int, int]) -> None:
        self.values = values

    def call(self, address, fn, *, dialect, table=None):
        class Client:
            def read_raw(_, number: int) -> int:
                return self.values.get(number, 0)
        return fn(Client())


def test_identify_names_the_family_by_its_type_code_and_leaves_an_unknown_one_open():
    """Two families speak the 32-bit MacTalk: the type code tells an MIS (MOTORTYPE,
    register 151, MIS manual §8.2.89) from a MAC800 (MOTOR_TYPE, register 203, §1.2); a code
    neither knows leaves the type "—" with the reason."""
    mis = identify(_Registers({151: 153, 1: 540720, 152: 4711}), 5, "mactalk32")
    assert (mis.motor_type, mis.firmware, mis.serial) == ("MIS232", "3.0", "4711")
    mac800 = identify(_Registers({203: 800, 1: 32832, 204: 99}), 5, "mactalk32")
    assert (mac800.motor_type, mac800.firmware, mac800.serial) == ("MAC800", "1.0", "99")
    unknown = identify(_Registers({151: 7, 203: 7}), 5, "mactalk32")
    assert unknown.motor_type is None and unknown.type_text == NONE
    assert unknown.firmware == NONE and "pick the type" in unknown.note


def test_scan_names_the_motors_and_adds_them_to_a_running_studio(twin, session):
    line, url = twin
    conn = Connections(session)
    conn.connect(url)
    found = conn.scan(url, "1-3")
    assert [(f.address, f.motor_type, f.firmware, f.serial) for f in found] == [
        (1, "MAC140", "4.14", "0"), (2, "MIS232", "3.0", "0")]
    added = conn.add_found(url)
    assert session.labels() == ["MAC140 @ 1", "MIS232 @ 2"] and len(added) == 2
    assert conn.add_found(url) == []  # held already
    with pytest.raises(ValueError, match="already"):
        conn.add(url, 1)
    mac = session.motor("MAC140 @ 1")
    mac.write("A_SOLL", 41)
    assert twin_raw(url, 1, "A_SOLL") == 41
    said = conn.disconnect(url)
    assert len(said) == 2 and session.motors == [] and session.lines == {}


def test_a_line_waits_the_studios_answer_timeout(twin, session):
    """A line the Connections view opens waits the session's answer timeout for each reply
    (``jvl-gym studio --answer-timeout``); a timeout that is not a positive number of seconds
    is refused."""
    _, url = twin
    assert Connections(session).connect(url).timeout == ANSWER_TIMEOUT_S
    session.drop_line(url)
    patient = Session(answer_timeout=2.5)
    assert Connections(patient).connect(url).timeout == 2.5
    patient.drop_line(url)
    for bad in (0.0, -1.0, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="answer timeout"):
            Session(answer_timeout=bad)


def test_bad_input_is_one_line_and_changes_nothing(twin, session):
    _, url = twin
    conn = Connections(session)
    conn.connect(url)
    conn.add_simulated("MAC140")
    before = (session.labels(), dict(session.lines), dict(conn.found))
    for port in ("socket://127.0.0.1:9", "/dev/ttyNOPE", ""):
        with pytest.raises((LineDown, ValueError)) as info:
            conn.connect(port)
        assert "\n" not in str(info.value)
    with pytest.raises(ValueError, match="FIRST-LAST"):
        conn.scan(url, "1..3")
    with pytest.raises(ValueError, match="no motor answered"):
        conn.scan(url, "40-41")
    with pytest.raises(ValueError, match="not connected"):
        conn.scan("socket://127.0.0.1:9", "1-2")
    with pytest.raises(ValueError, match="not known"):
        conn.add(url, 1)  # not scanned: the type is not known
    with pytest.raises(ValueError, match="1..254"):
        conn.add_simulated("MAC140", 0)
    assert (session.labels(), dict(session.lines), dict(conn.found)) == before


def test_two_lines_with_the_same_motor_are_told_apart_by_the_port(twin, session):
    _, url = twin
    conn = Connections(session)
    conn.connect(url)
    conn.scan(url, "1-1")
    conn.add(url, 1)
    other = Connections(session, line_factory=lambda port: _second_line(port))
    alias = url.replace("127.0.0.1", "localhost")
    other.connect(alias)
    motor = other.add(alias, 1, "MAC140")
    assert motor.label == f"MAC140 @ 1 on {alias}"
    assert session.labels() == ["MAC140 @ 1", f"MAC140 @ 1 on {alias}"]
    assert sorted(session.lines) == sorted([url, alias])


def _second_line(port: str):
    from jvl_gym.studio.line import Line

    return Line(port)


def test_motors_added_and_removed_while_the_clock_runs(session):
    """The clock runs the simulated motors added after it started; adds and removes from
    several threads while it runs leave a consistent studio."""
    conn = Connections(session)
    first = conn.add_simulated("MAC140")
    assert isinstance(first, SimMotor)
    end = time.monotonic() + 120
    while first.now() <= 0.05:
        assert time.monotonic() < end, "the clock does not run a motor added after its start"
        time.sleep(0.05)
    errors: list[BaseException] = []

    def churn(k: int) -> None:
        try:
            for j in range(5):
                m = conn.add_simulated("MAC050", 100 + 10 * k + j)
                session.stop_motors(wait=5)
                conn.remove(m.label)
        except BaseException as exc:  # reported in the test's thread
            errors.append(exc)

    threads = [threading.Thread(target=churn, args=(k,)) for k in range(3)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(300)
    assert not errors and session.labels() == ["MAC140 @ 1"]
    assert session.clock_problem is None
    t0 = first.now()
    while first.now() <= t0:
        assert time.monotonic() < end + 120
        time.sleep(0.05)


def test_stop_reaches_a_motor_added_to_a_running_studio(twin, session):
    """STOP stops every motor held at that moment, the one added last included (MAC050–141
    STOP_MODE, manual 4.1.8; MIS mode 11, §8.2.3), each on its way to passive."""
    line, url = twin
    conn = Connections(session)
    conn.connect(url)
    conn.scan(url, "2-2")
    mis = conn.add(url, 2)
    mis.write("V_SOLL", 5000)
    mis.write("MODE_REG", 1)
    said = session.stop_motors()
    assert said == ["MIS232 @ 2: stop (11), ramp, then passive"]
    assert twin_raw(url, 2, "MODE_REG") in (11, 0)
    assert conn.remove("MIS232 @ 2").startswith("removed MIS232 @ 2")
    assert session.stop_motors() == []


def test_the_flash_record_of_a_motor_on_a_line(twin, session):
    """A motor on a line cannot be read from flash (MacTalk has no such command): the
    settings read when it was added stand for its flash, a change shows against them, and a
    flash write from the studio makes its settings the record (MAC050–141 manual 5.1)."""
    line, url = twin
    conn = Connections(session)
    conn.connect(url)
    conn.scan(url, "1-1")
    mac = conn.add(url, 1)
    assert isinstance(mac, LineMotor) and P.flash_changes(mac) == []
    kvout = mac.read("KVOUT")
    mac.write("KVOUT", kvout + 0.5)
    assert [d.name for d in P.flash_changes(mac)] == ["KVOUT"]
    assert P.write_flash(mac).ok
    assert P.flash_changes(mac) == [] and mac.flash_record["KVOUT"] == kvout + 0.5
    mac.write("KVOUT", kvout)
    assert P.write_flash(mac).ok


def test_an_empty_studio_starts_and_stops():
    s = Session()
    s.start()
    try:
        assert s.motors == [] and s.line is None and s.stop_motors() == []
    finally:
        s.stop()


def test_cli_without_motors_starts_an_empty_studio(monkeypatch, capsys):
    import socket

    import jvl_gym.studio.ui.app as app_module
    from jvl_gym.cli.main import app

    started = []
    monkeypatch.setattr(app_module, "serve", lambda session, *a, **k: started.append(session))
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        port = str(sock.getsockname()[1])
    with pytest.raises(SystemExit) as info:
        app(["studio", "--no-browser", "--port", port])
    assert info.value.code in (0, None) and started[0].motors == []
    assert "no motor yet" in capsys.readouterr().out
