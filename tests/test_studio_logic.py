"""The studio's logic without a browser: family facts, bit words, register groups, edits with
the API's validation, setup files, the scope, the sample buffer, a line through the protocol
client (with a twin that goes away and comes back), tuning through the toolkit it is given
(refusals, the entry point, a run written as a setup file), episodes refusals."""

from __future__ import annotations

import threading
import time

import numpy as np
import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from jvl_gym.families import family
from jvl_gym.registers import to_raw
from jvl_gym.studio import bits, capture, groups
from jvl_gym.studio import registers as R
from jvl_gym.studio.facts import facts_of
from jvl_gym.studio.motor import SimMotor
from jvl_gym.studio.scope import Scope, channel_choices
from jvl_gym.studio.session import Session, plan_motors


@pytest.fixture(scope="module")
def mac() -> SimMotor:
    return SimMotor("MAC140", 1)


@pytest.fixture(scope="module")
def mis() -> SimMotor:
    return SimMotor("MIS232", 2)


# ---------------------------------------------------------------------- facts, bits, groups
def test_facts_come_from_the_family():
    f = facts_of("MAC140")
    assert f.title == family("mac050_141").title
    assert f.mode_name(1) == "V_MODE" and f.mode_register == "MODE_REG"
    # TESTU and TESTA are modes 8 and 9 (MAC050–141 manual 4.4.9, 4.4.10); the MIS has none
    assert f.test_modes() == {"TESTU": 8, "TESTA": 9}
    assert facts_of("MIS232").test_modes() == {}
    assert facts_of("MIS232").mode_name(1) == "velocity"  # MIS manual §8.2.3


def test_err_stat_bits_in_words():
    """ERR_STAT bits of MAC050–141 manual 3.2.35: 1 FLW, 4 IN_POS; a bit the table does not
    name is shown by number."""
    table = facts_of("MAC140").table
    reg = table.lookup("ERR_STAT")
    assert reg in bits.status_registers(table)
    assert bits.words(reg, (1 << 1) | (1 << 4)) == ["FLW", "IN_POS"]
    assert bits.words(reg, 0) == []
    assert bits.words(reg, 1 << 15) == ["bit 15"]


def test_mis_bit_registers_and_fields():
    """MIS ERR_BITS (§8.2.31): bit 1 follow error; bits 8-10 one field (H3 encoder)."""
    table = facts_of("MIS232").table
    names = [r.name for r in bits.status_registers(table)]
    assert {"ERR_BITS", "STATUSBITS"} <= set(names)
    err = table.lookup("ERR_BITS")
    assert bits.words(err, 1 << 1) == ["follow error"]
    field = next(f for f in bits.bit_fields(err) if f.first == 8)
    assert field.last == 10 and bits.words(err, 1 << 9) == [field.name]


def test_record_and_rewind_bits_from_the_table():
    """CNTRL_BITS: RECORD bit 6, REWIND bit 7 (MAC050–141 manual 3.2.36); MAC800 bits 0, 1."""
    assert capture.control_register(facts_of("MAC140").table) == ("CNTRL_BITS", 6, 7)
    assert capture.control_register(facts_of("MAC800").table) == ("CNTRL_BITS", 0, 1)
    assert capture.control_register(facts_of("MIS232").table) is None


def test_mac050_141_groups_are_the_manuals():
    """MAC050–141 manual 3.2: Main Control 1..15, Error handling 16..35, …, Diverse 153..163."""
    f = facts_of("MAC140")
    got = groups.register_groups(f.table, groups.family_ranges(f.constants))
    titles = [t for t, _ in got]
    assert titles[:9] == ["Main Control", "Error handling", "Power on", "Register mode",
                          "Filters", "Data acquisition", "Position / velocity-loop",
                          "Current-loops", "Diverse"]
    main = dict(got)["Main Control"]
    assert min(r.number for r in main) == 1 and max(r.number for r in main) <= 15
    shown = [r.number for _, regs in got for r in regs]
    assert len(shown) == len(set(shown)) == sum(groups.visible(r) for r in f.table)


def test_groups_from_the_section_column():
    """The MAC800 overview names each row's group (§1.2 Main Control, …)."""
    f = facts_of("MAC800")
    titles = [t for t, _ in groups.register_groups(f.table, groups.family_ranges(f.constants))]
    assert "1.2 Main Control" in titles and "1.2 Filters (main 6th order servo filter)" in titles


# ---------------------------------------------------------------------- edits and setups
def test_a_refused_value_changes_nothing_and_says_why(mac):
    numbers = [r.number for r in mac.table if groups.visible(r)]
    before = mac.read_raws(numbers)
    for name, text, reason in (("V_SOLL", "99999", "outside the range"),
                               ("V_IST", "3", "ro"), ("V_SOLL", "fast", "not a number")):
        res = R.edit(mac, name, text)
        assert not res.ok and res.message.startswith(name) and reason in res.message
    assert mac.read_raws(numbers) == before


def test_an_edit_writes_in_the_registers_unit(mac):
    res = R.edit(mac, "KVOUT", "1.5")  # Fixed8 (MAC050–141 manual 3.1, 3.2.13): raw = 1.5 · 256
    assert res.ok and mac.read_raw("KVOUT") == 384
    assert R.edit(mac, "A_SOLL", "0x20").ok and mac.read_raw("A_SOLL") == 32


@settings(max_examples=60, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.one_of(st.integers(-10**6, 10**6).map(str), st.floats(allow_nan=True).map(str),
                 st.text(max_size=8)))
def test_an_edit_is_written_exactly_or_refused_unchanged(mac, text):
    reg = mac.register("V_SOLL")
    before = mac.read_raw("V_SOLL")
    res = R.edit(mac, "V_SOLL", text)
    if res.ok:
        assert mac.read_raw("V_SOLL") == int(to_raw(reg, float(text)))  # the table's rounding
        assert reg.minimum <= mac.read("V_SOLL") <= reg.maximum
    else:
        assert mac.read_raw("V_SOLL") == before


def test_setup_round_trip_between_two_motors(mac, tmp_path):
    mac.write("A_SOLL", 77)
    mac.write("KVOUT", 2.0)
    path = R.save_setup(mac, tmp_path / "setup.yaml")
    other = SimMotor("MAC140", 3)
    res = R.load_setup_file(other, path.read_text(), path.name)
    assert res.ok, res.message
    assert R.setup_of(other) == R.setup_of(mac)
    assert yaml.safe_load(path.read_text())["motor"] == "MAC140"


def test_a_refused_setup_changes_nothing(mac):
    before = R.setup_of(mac)
    for text, reason in (("registers: {A_SOLL: 5, V_SOLL: 1e9}", "outside the range"),
                         ("registers: {A_SOLL: 5, NOPE: 1}", "NOPE"),
                         ("registers: {A_SOLL: 5, MODE_REG: 1}", "MODE_REG"),
                         ("[1, 2", "not YAML"), ("motor: MAC140", "registers")):
        res = R.load_setup_file(mac, text, "bad.yaml")
        assert not res.ok and reason in res.message
    assert R.setup_of(mac) == before


def test_mis_setup_round_trip(mis):
    mis.write("V_SOLL", 4321)
    text = yaml.safe_dump(R.setup_of(mis))
    other = SimMotor("MIS232", 4)
    assert R.load_setup_file(other, text).ok
    assert other.read("V_SOLL") == 4321


def test_plan_motors():
    assert plan_motors(["MAC140", "MIS232"], [], "MAC140") == [("MAC140", 1), ("MIS232", 2)]
    assert plan_motors(["MAC140"], [5, 6], "X") == [("MAC140", 5), ("MAC140", 6)]
    assert plan_motors([], [], "MAC140") == [("MAC140", 1)]
    for motors, addresses, what in ((["A", "B"], [1, 2, 3], "one per --address"),
                                    (["A"], [0], "1..254"), (["A", "B"], [3, 3], "once")):
        with pytest.raises(ValueError, match=what):
            plan_motors(motors, addresses, "A")


# ---------------------------------------------------------------------- scope and buffer
def test_scope_reads_registers_and_physical_signals():
    m = SimMotor("MAC140", 1, seed=1)
    m.write("V_SOLL", 400)  # 400/16 counts/sample (MAC050–141 manual 3.2.5)
    m.write("MODE_REG", 1)
    assert "shaft speed" in channel_choices(m) and "phase currents A" in channel_choices(m)
    sc = Scope(m, ["V_IST", "V_SOLL", "shaft speed", "phase currents A"])
    for _ in range(20):
        m.step(50)
        sc.sample()
    s = sc.series()
    assert list(s) == ["t [s]", "V_IST [counts/sample]", "V_SOLL [1/16 count/sample]",
                       "shaft speed [rpm]", "phase currents A [A]"]
    assert np.all(np.diff(s["t [s]"]) > 0)
    # at speed: V_IST = V_SOLL / 16 counts/sample, shaft speed = that in rpm (4096 counts/rev)
    assert s["V_IST [counts/sample]"][-1] == pytest.approx(25, abs=2)
    rpm = 25 * m.facts.outer_hz * 60 / 4096
    assert s["shaft speed [rpm]"][-1] == pytest.approx(rpm, rel=0.1)
    csv = sc.csv().splitlines()
    assert csv[0].startswith('"t [s]","V_IST [counts/sample]"') and len(csv) == 21
    assert sc.png().startswith(b"\x89PNG")
    with pytest.raises(KeyError):
        Scope(m, ["NO_SUCH_SIGNAL"])


def test_a_scope_read_at_an_unchanged_motor_time_replaces_its_last_point():
    """A clock that did not advance between two reads (a busy machine): the scope keeps one
    point per motor time, so a saved window's times increase and it loads back as a stored
    trace."""
    m = SimMotor("MAC140", 1, seed=1)
    sc = Scope(m, ["V_SOLL"])
    sc.sample()
    m.write("V_SOLL", 400)
    sc.sample()  # the motor's time did not move
    m.step(5)
    sc.sample()
    s = sc.series()
    assert len(s["t [s]"]) == 2 and np.all(np.diff(s["t [s]"]) > 0)
    assert s["V_SOLL [1/16 count/sample]"].tolist() == [400.0, 400.0]


@pytest.fixture(scope="module")
def running() -> Session:
    s = Session.simulated(["MAC140", "MIS232"], seed=3)
    s.start()
    yield s
    s.stop()


def test_capture_the_sample_buffer_of_both_families(running):
    mac, mis = running.motors
    mac.write("V_SOLL", 320)
    mac.write("MODE_REG", 1)
    mis.write("V_SOLL", 5000)  # 50 rpm (0.01 rpm units, MIS manual §8.2.6)
    mis.write("MODE_REG", 1)
    end = time.monotonic() + 20.0  # the clock brings both to speed
    while not (abs(mac.read("V_IST") - 20) <= 2 and mis.read("V_IST") == 5000):
        assert time.monotonic() < end, (mac.read("V_IST"), mis.read("V_IST"))
        time.sleep(0.02)
    a = capture.capture(mac, ["V_IST", "P_IST"], 100)
    assert list(a) == ["t [s]", "V_IST [counts/sample]", "P_IST [counts]"]
    assert len(a["P_IST [counts]"]) == 100
    assert np.all(np.diff(a["P_IST [counts]"]) > 0)  # running forwards, one sample apart
    assert np.median(a["V_IST [counts/sample]"]) == pytest.approx(20, abs=2)
    b = capture.capture(mis, ["V_IST"], 30)
    v_ist = b[f"V_IST [{mis.register('V_IST').unit}]"]
    assert len(v_ist) == 30 and np.all(v_ist == 5000)
    with pytest.raises(capture.CaptureError, match="samples"):
        capture.capture(mac, ["V_IST"], 10**6)


def test_testu_where_the_family_has_it(running):
    m = SimMotor("MAC140", 9)
    m.write("UMEAS", 50)
    sess = Session([m])
    sess.start()
    try:
        rec = capture.run_test(m, "TESTU", {"UMEAS": 60})
    finally:
        sess.stop()
    assert len(rec["sample"]) >= 11  # TESTU records 11 samples (manual 4.4.9)
    assert m.read("MODE_REG") == 0
    with pytest.raises(capture.CaptureError, match="no TESTA"):
        capture.run_test(running.motors[1], "TESTA", {})


# ---------------------------------------------------------------------- a line
@pytest.fixture()
def twin_server():
    from jvl_gym.cli.serve import build_line
    from jvl_gym.protocol.serving.transport import TwinServer

    line, _ = build_line(["MAC140"], [19])
    server = TwinServer(line, tcp=("127.0.0.1", 0)).start()
    yield line, server
    server.stop()


def test_a_line_motor_reads_what_another_client_writes(twin_server):
    from jvl_gym.protocol.mactalk.client16 import MacTalkClient

    twin, server = twin_server
    port = server.endpoint("mactalk", "tcp").port
    s = Session.on_line(f"socket://127.0.0.1:{port}", [], [], range(18, 21))
    try:
        assert s.labels() == ["MAC140 @ 19"]
        m = s.motors[0]
        nums = [r.number for r in m.table if groups.visible(r)]
        raws = m.read_raws(nums)
        assert raws[m.register("KVOUT").number] == int(twin.m.read_raw("KVOUT")[0])
        with MacTalkClient(f"socket://127.0.0.1:{port}", 19) as other:
            other.write("V_SOLL", 321)
        assert m.read("V_SOLL") == 321
        res = R.edit(m, "V_SOLL", "99999")
        assert not res.ok and "outside the range" in res.message and m.read("V_SOLL") == 321
        assert R.edit(m, "A_SOLL", "40").ok and int(twin.m.read_raw("A_SOLL")[0]) == 40
        assert not R.load_setup_file(m, "registers: {A_SOLL: 5, V_SOLL: 1e9}").ok
        assert m.read("A_SOLL") == 40
    finally:
        s.stop()


@pytest.mark.parametrize("motor_type, address", [("MAC140", 19), ("MIS232", 7)])
def test_a_line_survives_a_twin_that_goes_and_comes_back(motor_type, address):
    from jvl_gym.cli.serve import build_line
    from jvl_gym.protocol.serving.transport import TwinServer
    from jvl_gym.studio.line import LineDown

    line, _ = build_line([motor_type], [address])
    server = TwinServer(line, tcp=("127.0.0.1", 0)).start()
    port = server.endpoint("mactalk", "tcp").port
    s = Session.on_line(f"socket://127.0.0.1:{port}", [motor_type], [address])
    m = s.motors[0]
    try:
        assert m.read("MODE_REG") == 0
        server.stop()
        with pytest.raises(LineDown):
            m.read("MODE_REG")
        assert s.line.problem
        server = TwinServer(line, tcp=("127.0.0.1", port)).start()
        assert m.read("MODE_REG") == 0 and s.line.problem is None
    finally:
        server.stop()
        s.stop()


# ---------------------------------------------------------------------- a line of 32-bit motors
@pytest.fixture(scope="module")
def mixed_line():
    """`jvl-gym serve -m MIS232 -a 7 -m MAC140 -a 8 -m MAC800 -a 9` in-process on a free
    port: the twins of three families on one line, two dialects."""
    from jvl_gym.cli.serve import build_line
    from jvl_gym.protocol.serving.transport import TwinServer

    line, _ = build_line(["MIS232", "MAC140", "MAC800"], [7, 8, 9])
    server = TwinServer(line, tcp=("127.0.0.1", 0)).start()
    twins = {t.addresses()[0]: t for t in line.twins}
    yield f"socket://127.0.0.1:{server.endpoint('mactalk', 'tcp').port}", twins
    server.stop()


def test_pair_scanned_by_dialect():
    from jvl_gym.studio.session import pair_scanned

    found = {7: "mactalk32", 8: "mactalk16"}
    assert pair_scanned(found, ["MIS232", "MAC140"]) == [("MIS232", 7), ("MAC140", 8)]
    with pytest.raises(ValueError, match="none of MAC140"):
        pair_scanned(found, [])
    with pytest.raises(ValueError, match="cannot tell them apart"):
        pair_scanned(found, ["MIS232", "MAC800", "MAC140"])


def test_a_scan_finds_motors_of_both_dialects(mixed_line):
    url, _ = mixed_line
    s = Session.on_line(url, ["MAC140", "MIS232"], [], range(6, 9))
    try:
        assert s.labels() == ["MIS232 @ 7", "MAC140 @ 8"]
        assert [m.dialect for m in s.motors] == ["mactalk32", "mactalk16"]
        assert s.motors[0].read("MODE_REG") == 0 and s.motors[1].read("MODE_REG") == 0
    finally:
        s.stop()


@pytest.mark.parametrize("motor_type, address, register, value, bad, refused", [
    # 0.01 RPM (MIS manual §8.2.6); safe mode is entered by its command, not by MODE_REG
    # (MIS manual §8.2.3, §18.2.5)
    ("MIS232", 7, "V_SOLL", 5000, 10**9, ("MODE_REG", 15)),
    ("MAC800", 9, "V_SOLL", 277, 2**40, None),  # 100 RPM (quick guide 1.2)
])
def test_a_32_bit_line_motor_reads_writes_and_refuses(mixed_line, motor_type, address,
                                                      register, value, bad, refused):
    from jvl_gym.protocol.mactalk.client32 import MacTalk32Client

    url, twins = mixed_line
    twin = twins[address]
    s = Session.on_line(url, [motor_type], [address])
    m = s.motors[0]
    try:
        nums = [r.number for r in m.table if groups.visible(r)]
        with twin.lock:
            before = {n: int(twin.m.read_raw(n)[0]) for n in nums}
        raws = m.read_raws(nums)
        with twin.lock:
            after = {n: int(twin.m.read_raw(n)[0]) for n in nums}
        stable = [n for n in nums if before[n] == after[n]]  # not a clock or a measurement
        assert len(stable) > 0.9 * len(nums) and set(raws) == set(nums)
        assert {n: raws[n] for n in stable} == {n: before[n] for n in stable}
        with MacTalk32Client(url, address, table=m.table) as other:
            other.write(register, value)
        assert m.read(register) == value
        res = R.edit(m, register, str(bad))
        assert not res.ok and "outside the range" in res.message and m.read(register) == value
        # a value within the table's range that the motor refuses: no accept, the motor
        # still answers, the page says so and nothing changed
        if refused is not None:
            before = twin.m.read_raw(refused[0])[0]
            res = R.edit(m, *map(str, refused))
            assert not res.ok and "did not accept" in res.message and s.line.problem is None
            assert twin.m.read_raw(refused[0])[0] == before
        assert not R.load_setup_file(m, f"registers: {{{register}: 1, P_SOLL: 1e12}}").ok
        assert m.read(register) == value
    finally:
        s.stop()


def test_mis_on_a_line_safe_mode_flash_and_reset(mixed_line):
    """MIS manual §18.2.5 – §18.2.8 through the studio's actions: flash outside safe mode is
    refused with the reason and the line kept; in safe mode the value is saved and a reset
    brings it back from flash."""
    from jvl_gym.studio.line import RefusedByMotor

    url, twins = mixed_line
    s = Session.on_line(url, ["MIS232"], [7])
    m = s.motors[0]
    acts = m.actions()
    try:
        m.write("A_SOLL", 4711)
        with pytest.raises(RefusedByMotor, match="safe mode"):
            acts["save in flash"]()
        assert s.line.problem is None
        acts["safe mode"]()
        assert m.facts.mode_name(m.read_raw("MODE_REG")) == "safe"
        acts["save in flash"]()
        m.write("A_SOLL", 1)
        acts["reset"]()
        assert m.read("A_SOLL") == 4711
        acts["leave safe mode"]()
        assert m.read_raw("MODE_REG") != twins[7].spec.safe_mode
    finally:
        s.stop()


@pytest.mark.parametrize("motor_type, address, mode_register_value", [
    ("MIS232", 7, 1), ("MAC800", 9, 1)])
def test_capture_the_sample_buffer_over_the_line(mixed_line, motor_type, address,
                                                 mode_register_value):
    """The recipe of the family (MIS manual §8.2.60–8.2.63; MAC800 CNTRL_BITS record bits),
    read back with 53h: the samples equal the twin's own buffer."""
    url, twins = mixed_line
    twin = twins[address]
    s = Session.on_line(url, [motor_type], [address])
    m = s.motors[0]
    try:
        m.write("V_SOLL", 2000 if motor_type == "MIS232" else 277)
        m.write("MODE_REG", mode_register_value)
        got = capture.capture(m, ["V_IST", "P_IST"], 20)
        m.write("MODE_REG", 0)
        p = got[f"P_IST [{m.register('P_IST').unit}]"]
        assert len(p) == 20 and np.all(np.diff(p) >= 0) and p[-1] > p[0]
        with twin.lock:
            own = twin.m.sample_buffer(0)
        assert np.array_equal(p, np.asarray(own["P_IST"], dtype=float)[:20])
    finally:
        s.stop()


# ---------------------------------------------------------------------- tuning, episodes
def test_tuning_refuses_what_it_cannot_tune():
    from types import SimpleNamespace

    from tuning.studio_adapter import TOOLKIT

    from jvl_gym.studio.toolkit import MISSING
    from jvl_gym.studio.tuning_run import TuningRun, tuning_problem

    assert "no tuning procedure" in tuning_problem(SimMotor("MIS232", 1), TOOLKIT)
    m = SimMotor("MAC140", 1)
    assert tuning_problem(m, None) == MISSING
    with pytest.raises(ValueError, match="not installed"):
        TuningRun(m, None)
    assert tuning_problem(m, TOOLKIT) is None
    # over a line only with the TESTU/TESTA modes (the contract's Capability.TEST_MODES)
    on_line = SimpleNamespace(motor_type="MAC800", simulated=False, label="MAC800 @ 3")
    assert "TESTU/TESTA" in tuning_problem(on_line, TOOLKIT)
    m.write("MODE_REG", 1)
    before = {k: m.read(k) for k in ("KVOUT", "KVFX1", "KVB0")}
    tr = TuningRun(m, TOOLKIT)
    tr.start()
    tr.join(60)
    assert tr.result is None and "mode 0" in tr.error
    assert {k: m.read(k) for k in before} == before
    with pytest.raises(RuntimeError):
        tr.write()


class LineToolkit:
    """A toolkit that records what the run gives its ``autotune_line`` (the only method a run
    on a line calls)."""

    def __init__(self):
        self.calls = []

    def autotune_line(self, port, motor, address, progress, time_scale=1.0):
        from jvl_gym.studio.toolkit import TuningOutcome

        self.calls.append((port, motor, address, time_scale))
        return TuningOutcome(motor, "report", {"KVOUT": 1.0}, ["kept"], "note")


def test_a_line_run_passes_the_twins_speed_to_the_toolkit(mixed_line):
    """A motor on a line is tuned with the other end's time scale (``jvl-tune autotune
    --time-scale``), which the session of a twin at ``--speed`` holds as its speed."""
    from jvl_gym.studio.tuning_run import TuningRun

    url, _ = mixed_line
    s = Session.on_line(url, ["MAC140"], [8], speed=25.0)
    kit = LineToolkit()
    try:
        tr = TuningRun(s.motors[0], kit, time_scale=s.speed)
        tr.start()
        tr.join(60)
        assert tr.error is None and tr.result is not None, tr.progress
    finally:
        s.stop()
    assert kit.calls == [(url, "MAC140", 8, 25.0)]


@settings(max_examples=40, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(st.floats(allow_nan=True, allow_infinity=True))
def test_a_tuning_run_takes_a_finite_positive_time_scale(mac, time_scale):
    """A time scale or a line's speed that is not a finite number > 0 is refused before
    anything starts (the line is not opened)."""
    from tuning.studio_adapter import TOOLKIT

    from jvl_gym.studio.tuning_run import TuningRun

    if 0 < time_scale < float("inf"):
        assert TuningRun(mac, TOOLKIT, time_scale=time_scale).time_scale == time_scale
    else:
        with pytest.raises(ValueError, match="time_scale"):
            TuningRun(mac, TOOLKIT, time_scale=time_scale)
    with pytest.raises(ValueError, match="speed must be > 0"):
        Session.on_line("socket://127.0.0.1:9", ["MAC140"], [1], speed=-abs(time_scale))


def test_tuning_toolkit_from_the_entry_point(tmp_path, monkeypatch):
    """The entry point pyproject.toml declares is what the studio finds when none is given."""
    from pathlib import Path

    import tomllib
    from tuning.studio_adapter import TOOLKIT

    from jvl_gym.studio.toolkit import GROUP, NAME, find_toolkit

    project = tomllib.loads((Path(__file__).parents[1] / "pyproject.toml").read_text())
    value = project["project"]["entry-points"][GROUP][NAME]
    dist = tmp_path / "jvl_gym_toolkit_probe-0.dist-info"
    dist.mkdir()
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: jvl-gym-toolkit-probe\n"
                                   "Version: 0\n")
    (dist / "entry_points.txt").write_text(f"[{GROUP}]\n{NAME} = {value}\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    assert find_toolkit() is TOOLKIT
    assert find_toolkit(TOOLKIT) is TOOLKIT
    with pytest.raises(TypeError, match="TuningToolkit"):
        find_toolkit(object())


def test_tuning_run_writes_the_setup_file_it_shows(tmp_path):
    """A run on a simulated MAC140: the report and plots of ``jvl-tune autotune``, the kept
    registers written as the setup file and loaded into the motor as written."""
    from tuning.pipeline import setup_text
    from tuning.studio_adapter import TOOLKIT

    from jvl_gym.studio.tuning_run import TuningRun

    m = SimMotor("MAC140", 1)
    tr = TuningRun(m, TOOLKIT)
    tr.start()
    tr.join(600)
    assert tr.error is None and tr.result is not None, tr.progress
    out = tr.result.outcome
    assert "Identified values" in out.report and "Acceptance step" in out.report
    assert set(out.plots) == {"fits", "Bode (margins)", "speed step"}
    assert all(png.startswith(b"\x89PNG") for png in out.plots.values())
    assert "KVOUT" in out.registers and "KVOUT" in tr.result.present
    assert any(line.startswith("kept") for line in out.acceptance)
    assert "wrote" in tr.write(tmp_path)
    path = tmp_path / "setup.yaml"
    assert tr.written == path
    assert path.read_text() == setup_text(out.motor, out.registers, out.note)
    written = yaml.safe_load(path.read_text())["registers"]
    for k, v in written.items():
        assert m.read(k) == pytest.approx(v, rel=1e-6, abs=1e-9), k


def test_tuning_a_motor_on_a_line_writes_the_result_to_the_twin(tmp_path):
    """The tuning page on a MAC140 behind `jvl-gym serve --speed 25` (in-process, a free
    port) with a studio told that speed: the pipeline of `jvl-tune autotune --port …
    --address … --time-scale 25` through the toolkit, then the kept registers written as
    `--write` writes them (the client's write_registers, read back): the twin's registers hold
    the result's values."""
    from tuning.studio_adapter import TOOLKIT

    from jvl_gym.cli.serve import build_line
    from jvl_gym.protocol.serving.transport import TwinServer
    from jvl_gym.studio.tuning_run import TuningRun

    twin, _ = build_line(["MAC140"], [19])
    server = TwinServer(twin, speed=25.0, tcp=("127.0.0.1", 0)).start()
    s = Session.on_line(server.endpoint("mactalk", "tcp").url, ["MAC140"], [19],
                        toolkit=TOOLKIT, speed=25.0)
    try:
        tr = TuningRun(s.motors[0], s.toolkit, time_scale=s.speed)
        tr.start()
        tr.join(600)
        assert tr.error is None and tr.result is not None, (tr.progress, twin.last_refusal)
        kept = tr.result.outcome.registers
        assert tr.result.present == {k: float(twin.m.read(k)[0]) for k in kept}
        assert any(twin.m.read(k)[0] != pytest.approx(v, abs=1 / 256) for k, v in kept.items())
        assert "wrote" in tr.write(tmp_path)
        for name, value in kept.items():
            assert twin.m.read(name)[0] == pytest.approx(value, abs=1 / 256), name
    finally:
        server.stop()
        s.stop()


def test_episode_is_deterministic_and_refuses_unknown():
    from jvl_gym.studio.episodes import controllers, run_episode

    a = run_episode("jvl_gym/Positioning-v0", "baseline", seed=3)
    b = run_episode("jvl_gym/Positioning-v0", "baseline", seed=3)
    assert a.total == b.total and a.total == pytest.approx(a.signals["reward"].sum())
    assert "action: torque" in a.signals and len(a.signals["reward"]) > 10
    assert controllers("jvl_gym/Positioning-v0")[0] == "baseline"
    with pytest.raises(ValueError, match="unknown env"):
        run_episode("jvl_gym/Nope-v0")
    with pytest.raises(ValueError, match="controller"):
        run_episode("jvl_gym/Positioning-v0", "magic")


# ---------------------------------------------------------------------- the command line
class NamedToolkit:
    """A toolkit other than the installed one, for ``--toolkit test_studio_logic:KIT``."""

    def autotune(self, m, seed, progress):
        raise NotImplementedError

    def autotune_line(self, port, motor, address, progress, time_scale=1.0):
        raise NotImplementedError

    def write_setup(self, path, motor, registers, note):
        raise NotImplementedError


KIT = NamedToolkit()
TOOLKIT = NamedToolkit()


def test_a_toolkit_named_on_the_command_line(monkeypatch, capsys):
    """``jvl-gym studio --toolkit MODULE[:OBJECT]`` gives the tuning page that toolkit instead
    of the entry point's; a name that is no toolkit is a one-line error."""
    import jvl_gym.studio.ui.app as app_module
    from jvl_gym.studio.toolkit import load_toolkit

    assert load_toolkit("test_studio_logic:KIT") is KIT
    assert load_toolkit("test_studio_logic") is TOOLKIT  # the module's TOOLKIT
    with pytest.raises(ValueError, match="cannot import"):
        load_toolkit("no_such_toolkit_module")
    with pytest.raises(ValueError, match="has no 'NOPE'"):
        load_toolkit("test_studio_logic:NOPE")
    with pytest.raises(TypeError, match="TuningToolkit"):
        load_toolkit("jvl_gym.studio.toolkit:GROUP")
    started = []
    monkeypatch.setattr(app_module, "serve", lambda session, *a, **k: started.append(session))
    from jvl_gym.cli.main import app

    with __import__("socket").socket() as sock:
        sock.bind(("127.0.0.1", 0))
        port = str(sock.getsockname()[1])
    with pytest.raises(SystemExit) as info:
        app(["studio", "--toolkit", "test_studio_logic:KIT", "--no-browser", "--port", port])
    assert info.value.code in (0, None) and started[0].toolkit is KIT
    code, line = _cli(["--toolkit", "no_such_toolkit_module", "--no-browser", "--port", port],
                      capsys)
    assert code == 1 and "--toolkit no_such_toolkit_module" in line


def test_cli_speed_reaches_a_line_and_must_be_finite(monkeypatch, capsys):
    """``jvl-gym studio --connect PORT --speed S``: the line's session runs tuning with the
    twin's time scale S; a speed that is not a finite number > 0 is a usage error."""
    import jvl_gym.studio.ui.app as app_module
    from jvl_gym.studio.session import Session

    seen = {}

    def on_line(port, motors, addresses=(), scan_range=None, toolkit=None, speed=1.0):
        seen.update(port=port, speed=speed)
        return Session.simulated(["MAC140"], [1], speed=speed)

    monkeypatch.setattr(Session, "on_line", staticmethod(on_line))
    monkeypatch.setattr(app_module, "serve", lambda session, *a, **k: seen.update(s=session))
    from jvl_gym.cli.main import app

    with __import__("socket").socket() as sock:
        sock.bind(("127.0.0.1", 0))
        port = str(sock.getsockname()[1])
    with pytest.raises(SystemExit) as info:
        app(["studio", "--connect", "socket://127.0.0.1:9", "--speed", "7", "--no-browser",
             "--port", port])
    assert info.value.code in (0, None)
    assert seen["port"] == "socket://127.0.0.1:9" and seen["speed"] == 7.0
    assert seen["s"].speed == 7.0
    for bad in ("inf", "nan", "0", "-2"):
        code, line = _cli(["--speed", bad, "--no-browser", "--port", port], capsys)
        assert code == 2 and "--speed" in line
        code, line = _cli(["--answer-timeout", bad, "--no-browser", "--port", port], capsys)
        assert code == 2 and "--answer-timeout" in line


def _cli(args, capsys):
    from jvl_gym.cli.main import app

    with pytest.raises(SystemExit) as info:
        app(["studio", *args])
    _, err = capsys.readouterr()
    lines = [ln for ln in err.strip().splitlines() if not ln.startswith("jvl_gym: compil")]
    assert info.value.code not in (0, None) and len(lines) == 1 and "Traceback" not in err, err
    return info.value.code, lines[0]


def test_cli_errors_are_one_line(capsys):
    code, line = _cli(["--scan", "1-3"], capsys)
    assert code == 2 and "--scan needs --connect" in line
    code, line = _cli(["--connect", "socket://127.0.0.1:9", "--scan", "0-3"], capsys)
    assert code == 2 and "1..254" in line
    code, line = _cli(["--motor", "MAC999", "--no-browser", "--port", "8", "--host",
                       "127.0.0.1"], capsys)
    assert code == 1 and line.startswith("jvl-gym studio: error:")
    with __import__("socket").socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        code, line = _cli(["--no-browser", "--port", str(s.getsockname()[1])], capsys)
    assert code == 1 and "cannot listen" in line and "--port" in line
    code, line = _cli(["--connect", "socket://127.0.0.1:9", "--scan", "1-2"], capsys)
    assert code == 1 and "cannot open socket://127.0.0.1:9" in line


@pytest.mark.parametrize("motor_type, register, bit", [("MAC140", "ERR_STAT", 1 << 1),
                                                       ("MIS232", "ERR_BITS", 1 << 1)])
def test_actions_of_the_family(motor_type, register, bit):
    """Clear errors writes 0 to the error register (follow-error bit: MAC050–141 manual 3.2.35,
    MIS manual §8.2.31); save in flash needs safe mode and is refused with the reason outside
    it (MAC050–141 manual 2.2, MIS manual §8.2.3)."""
    m = SimMotor(motor_type, 1)
    acts = m.actions()
    assert {"passive", "safe mode", "leave safe mode", "save in flash", "reset",
            "clear errors"} <= set(acts)
    m.write(register, bit)
    assert m.read_raw(register) & bit
    acts["clear errors"]()
    assert not m.read_raw(register) & bit
    with pytest.raises(ValueError, match="(?i)safe"):
        acts["save in flash"]()
    acts["safe mode"]()
    assert "safe" in m.facts.mode_name(m.read_raw("MODE_REG")).lower()
    m.write("A_SOLL", 123)
    acts["save in flash"]()  # saves and resets: the value stays, from flash
    assert m.read("A_SOLL") == 123


def test_actions_follow_the_family_capabilities():
    """The MAC800 declares no safe mode, flash save or software reset: its motor offers only
    passive and clear errors; the MIS, declaring them, offers them all, and no test modes
    (Capability.TEST_MODES is the MAC050–141's)."""
    m = SimMotor("MAC800", 1)
    assert set(m.actions()) == {"passive", "clear errors"}
    assert facts_of("MIS232").test_modes() == {} and set(facts_of("MAC140").test_modes()) == {
        "TESTU", "TESTA"}


# ---------------------------------------------------------------------- page timers
@pytest.mark.parametrize("seconds", [0.0, -1.0, float("nan")])
def test_a_page_timer_needs_a_positive_interval(seconds):
    from jvl_gym.studio.ui.common import Page

    with pytest.raises(ValueError, match="interval > 0"):
        Page(Session([SimMotor("MAC140", 1)]), SimMotor("MAC140", 1)).every(seconds, print)


def test_a_page_timer_runs_only_while_its_tab_is_connected():
    """``Page.every``: the callback runs while the tab's websocket is connected, not after it
    disconnects (a tab closed or navigated away), and again when it reconnects."""
    import asyncio
    import uuid

    from nicegui import Client
    from nicegui.testing.user_simulation import user_simulation

    from jvl_gym.studio.ui.common import Page

    calls: list[float] = []
    timers: list = []

    def root() -> None:
        motor = SimMotor("MAC140", 1)
        timers.append(Page(Session([motor]), motor).every(0.01, lambda: calls.append(1)))

    async def grows(seconds: float = 10.0) -> bool:
        n = len(calls)
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            await asyncio.sleep(0.01)
            if len(calls) > n + 2:
                return True
        return False

    async def scenario() -> None:
        async with user_simulation(root) as user:
            client: Client = await user.open("/")
            assert await grows() and timers[0].active
            (socket,) = list(client._socket_to_document_id)
            client.handle_disconnect(socket)
            assert not timers[0].active
            await asyncio.sleep(0.05)  # a call under way when the tab went may still end
            n = len(calls)
            await asyncio.sleep(0.2)  # twenty intervals
            assert len(calls) == n
            await client.handle_handshake(f"test-{uuid.uuid4()}", user.tab_id, None,
                                          str(uuid.uuid4()), None)
            assert timers[0].active and await grows()

    # in a thread of its own: pytest-playwright's sync API may run an event loop in this one
    failed: list[BaseException] = []
    worker = threading.Thread(target=lambda: _catch(failed, asyncio.run, scenario()))
    worker.start()
    worker.join(120)
    assert not worker.is_alive(), "the simulated page did not finish within 120 s"
    if failed:
        raise failed[0]


def _catch(failed: list[BaseException], fn, *args) -> None:
    """``fn(*args)``, its exception appended to ``failed``."""
    try:
        fn(*args)
    except BaseException as exc:  # noqa: BLE001 - handed to the test's thread
        failed.append(exc)


# ---------------------------------------------------------------------- STOP
def test_each_family_states_its_stop():
    """The family contract says how each family stops: the MAC050–141's STOP_MODE (11,
    manual 4.1.8, 4.4.12) and the MIS's mode 11 "Stop" (§8.2.3) ramp down and go passive; the
    MAC800 has no stop mode (register overview §1.2: modes 7–11 reserved) and goes passive."""
    assert family("mac050_141").twin.stop_mode == 11
    assert family("mis").twin.stop_mode == 11
    assert family("mac800").twin.stop_mode is None
    assert all(family(k).twin.passive_mode == 0 for k in ("mac050_141", "mis", "mac800"))


def _run(m: SimMotor, speed: float) -> None:
    """Velocity mode at ``speed`` (V_SOLL in the family's unit), stepped until it runs."""
    m.write("V_SOLL", speed)
    m.write("MODE_REG", 1)
    m.step(int(m.facts.outer_hz))  # 1 s


@pytest.mark.parametrize("motor_type, speed, ramped", [("MAC140", 320, True),
                                                       ("MIS232", 5000, True),
                                                       ("MAC800", 320, False)])
def test_stop_by_the_family_stop(motor_type, speed, ramped):
    """``stop_motor``: MODE_REG gets the family's stop mode, which decelerates (the speed
    after one sample is still near the running speed) and then goes passive by itself; a
    family without a stop mode goes passive at once; a passive motor is left as it is."""
    m = SimMotor(motor_type, 1)
    assert "already" in m.stop_motor() and m.read_raw("MODE_REG") == 0
    _run(m, speed)
    running = abs(m.read_raw("V_IST"))
    assert running > 0
    line = m.stop_motor()
    assert line.startswith(f"{m.label}: ")
    if ramped:
        assert m.read_raw("MODE_REG") == 11 and "ramp, then passive" in line
        m.step(1)
        assert abs(m.read_raw("V_IST")) > 0.5 * running  # a ramp, not a halt
        for _ in range(50):  # up to 5 s of firmware time
            m.step(int(m.facts.outer_hz) // 10)
            if m.read_raw("MODE_REG") == 0:
                break
    else:
        assert "passive at once" in line
    assert m.read_raw("MODE_REG") == 0
    m.step(int(m.facts.outer_hz) // 10)
    assert m.read_raw("MODE_REG") == 0


def test_stop_leaves_safe_mode_alone():
    m = SimMotor("MIS232", 1)
    m.actions()["safe mode"]()
    safe = m.read_raw("MODE_REG")
    assert "already" in m.stop_motor() and m.read_raw("MODE_REG") == safe


def test_session_stops_every_motor():
    """STOP stops every motor of a studio of three families at once, one line each."""
    s = Session.simulated(["MAC140", "MIS232", "MAC800"])
    for m, speed in zip(s.motors, (320, 5000, 320)):
        _run(m, speed)
    lines = s.stop_motors(wait=600.0)
    assert [ln.split(":")[0] for ln in lines] == s.labels()
    assert [m.read_raw("MODE_REG") for m in s.motors] == [11, 11, 0]


def test_stop_waits_for_a_run_that_holds_the_motor():
    """A motor held by a long run (its lock) does not hold up the others; it is stopped as
    soon as the run lets go."""
    s = Session.simulated(["MAC140", "MIS232"])
    for m, speed in zip(s.motors, (320, 5000)):
        _run(m, speed)
    held = s.motors[0]
    held.lock.acquire()
    try:
        lines = s.stop_motors(wait=0.0)
        assert "STOP pending" in lines[0]
        free = s.motors[1]  # stopped meanwhile, while the other is still held
        for _ in range(60000):
            if free.read_raw("MODE_REG") == 11:
                break
            time.sleep(0.01)
        assert free.read_raw("MODE_REG") == 11
    finally:
        held.lock.release()
    for _ in range(6000):  # the waiting stop goes ahead once the lock is free
        if held.read_raw("MODE_REG") == 11:
            break
        time.sleep(0.01)
    assert held.read_raw("MODE_REG") == 11


@pytest.mark.parametrize("motor_type, address, speed", [("MIS232", 7, 5000),
                                                         ("MAC140", 8, 320),
                                                         ("MAC800", 9, 320)])
def test_stop_a_motor_on_a_line(motor_type, address, speed):
    """STOP over the MacTalk line reaches a twin as it would a real motor: the family's stop
    mode written in its dialect, the twin ramps down and goes passive."""
    from jvl_gym.cli.serve import build_line
    from jvl_gym.protocol.serving.transport import TwinServer

    line, _ = build_line([motor_type], [address])
    server = TwinServer(line, tcp=("127.0.0.1", 0), run_clock=False).start()
    twin = line.twins[0] if hasattr(line, "twins") else line
    s = Session.on_line(f"socket://127.0.0.1:{server.endpoint('mactalk', 'tcp').port}",
                        [motor_type], [address])
    try:
        m = s.motors[0]
        m.write("V_SOLL", speed)
        m.write("MODE_REG", 1)
        with twin.lock:
            twin.step(1000)
            assert twin.m.read_raw("V_IST")[0] != 0
        (out,) = s.stop_motors(wait=600.0)
        stop = family_of(motor_type).twin.stop_mode
        assert m.read_raw("MODE_REG") == (0 if stop is None else stop), out
        with twin.lock:
            twin.step(10000)
        assert m.read_raw("MODE_REG") == 0
    finally:
        s.stop()
        server.stop()


def family_of(motor_type: str):
    from jvl_gym.families import family_of_motor

    return family_of_motor(motor_type)
