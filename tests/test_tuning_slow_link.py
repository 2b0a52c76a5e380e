"""Tuning over a port that is slow, breaks, or is interrupted: the run stays right or refuses in
one line, and the motor is always left passive (MODE_REG read back)."""

from __future__ import annotations

import numpy as np
import pytest
from tuning.identify_resonance import coupling_of
from tuning.models import MotorData
from tuning.serial_source import autotune_over_serial

from delaying_link import DelayingLink, loopback_round_trip
from jvl_gym import MotorArray
from jvl_gym.families import family_of_motor
from jvl_gym.protocol.mactalk.twin16 import Twin
from jvl_gym.protocol.serving.transport import TwinServer

PASSIVE = family_of_motor("MAC140").twin.passive_mode


def _two_mass(f_res: float) -> MotorArray:
    """A MAC140 with 4·J_m behind a coupling resonating at ``f_res`` [Hz]."""
    md = MotorData.from_config("MAC140")
    j_l, k, d = coupling_of(md.J_m, 4.0, f_res, 0.02)
    return MotorArray("MAC140", n=1, seed=0, load_inertia=j_l, coupling_stiffness=k,
                      coupling_damping=d, record_length=64)


def load_kernels() -> None:
    """Run the modes a port run uses once in this process, so that no compiled kernel is
    loaded while a real-time twin serves (loading holds the twin's lock for about a second,
    longer than a MacTalk request waits for its answer)."""
    from tuning.records import acquire_testa, acquire_testu

    m = _two_mass(90.0)
    acquire_testu(m, 100, 11)
    acquire_testa(m, 20.0, 11)
    _spin(m)
    m.write("MODE_REG", 0)
    m.step(10)


@pytest.fixture(scope="module", autouse=True)
def _kernels_loaded() -> None:
    load_kernels()


def _spin(sm) -> None:
    """Put the motor in AT_MODE with torque on (what the resonance step does)."""
    sm.write("T_SOLL", 200)
    sm.write("ANINP_OFFSET", 1023)
    sm.write("MODE_REG", 4)
    sm.step(40)
    assert int(sm.read("MODE_REG")[0]) == 4 and abs(float(sm.read("V_IST")[0])) > 50


def test_ctrl_c_during_a_port_run_leaves_the_motor_passive():
    m = _two_mass(70.0)
    server = TwinServer(Twin(m, [19]), tcp=("127.0.0.1", 0), run_clock=False).start()
    said: list[str] = []

    def interrupted(sm, _result):
        _spin(sm)
        raise KeyboardInterrupt

    try:
        with pytest.raises(KeyboardInterrupt):
            autotune_over_serial(server.endpoint("mactalk", "tcp").url, "MAC140", address=19,
                                 n_coil=64, n_mech=64, progress=said.append,
                                 two_mass=interrupted, clock=server.twin.advance)
    finally:
        server.stop()
    assert m.read("MODE_REG")[0] == PASSIVE
    assert said[0].startswith("link to socket://") and "round trip" in said[0]
    assert said[-1] == "the motor is passive (MODE_REG read back)"


def test_a_link_that_drops_mid_run_still_stops_the_motor():
    m = _two_mass(70.0)
    server = TwinServer(Twin(m, [19]), tcp=("127.0.0.1", 0), run_clock=False).start()
    ep = server.endpoint("mactalk", "tcp")
    link = DelayingLink((ep.host, ep.port))

    def dropped(sm, _result):
        _spin(sm)
        link.drop_after(1)  # the line breaks after the next reply
        for _ in range(5):
            sm.read("V_IST")

    try:
        with pytest.raises(Exception, match="did not answer|disconnected|onnection"):
            autotune_over_serial(link.url, "MAC140", address=19, n_coil=64, n_mech=64,
                                 two_mass=dropped, clock=server.twin.advance)
    finally:
        link.close()
        server.stop()
    assert link.dropped == 1
    assert m.read("MODE_REG")[0] == PASSIVE  # the stop went through on a new connection


def test_an_unconfirmed_stop_is_reported():
    # a motor that answers but never reports the passive mode: the stop is tried a few times
    # and its failure named
    from tuning.motor_stop import stop_motor
    from tuning.serial_source import SerialMotor

    class Stuck:
        def read(self, key):
            return 4.0

        def write(self, key, value):
            pass

    sm = SerialMotor(Stuck(), "MAC140", clock=lambda _s: None)
    why = stop_motor(sm, within_s=0.2)
    assert why == "MODE_REG still reads 4, not the passive mode 0 (after 4 attempts)"


@pytest.fixture()
def slow_twin():
    """A twin MAC140 (90 Hz two-mass load) on its real-time clock at speed 25, behind a link
    ten times slower than loopback TCP (a proxy adding nine loopback round trips to each
    reply, at least 1 ms)."""
    m = _two_mass(90.0)
    server = TwinServer(Twin(m, [19]), speed=25.0, tcp=("127.0.0.1", 0)).start()
    ep = server.endpoint("mactalk", "tcp")
    rtt = loopback_round_trip(ep.url, 19)
    link = DelayingLink((ep.host, ep.port), delay=max(9 * rtt, 1e-3))
    try:
        yield m, link
    finally:
        link.close()
        server.stop()


def test_identification_over_a_ten_times_slower_link_stays_right(slow_twin):
    m, link = slow_twin
    said: list[str] = []
    ident, _ = autotune_over_serial(link.url, "MAC140", address=19, time_scale=25.0,
                                    n_coil=64, n_mech=64, progress=said.append)
    md = MotorData.from_config("MAC140")
    total = md.J_m + coupling_of(md.J_m, 4.0, 90.0, 0.02)[0]
    assert ident.mechanics.J == pytest.approx(total, rel=0.08)
    assert m.read("MODE_REG")[0] == PASSIVE
    assert any("round trip" in s for s in said)


def test_resonance_over_a_ten_times_slower_link_is_right_or_refused(slow_twin, tmp_path):
    from tuning.cli import app
    from tuning.link import LinkTooSlow
    from typer.testing import CliRunner

    m, link = slow_twin
    res = CliRunner().invoke(app, [
        "autotune", "--motor", "MAC140", "--port", link.url, "--address", "19",
        "--time-scale", "25", "--n-coil", "64", "--n-mech", "64", "--resonance", "--write",
        "--accept", "--out", str(tmp_path)])
    assert m.read("MODE_REG")[0] == PASSIVE, res.output
    if res.exit_code == 0:  # the link kept the long record's timing: the result is right
        report = (tmp_path / "report.txt").read_text()
        f_res = float(report.split("  resonance ")[1].split(" Hz")[0])
        assert f_res == pytest.approx(90.0, rel=0.05)
    else:
        assert isinstance(res.exception, (LinkTooSlow, SystemExit)), res.output
        assert "the resonance step is refused" in res.output or isinstance(
            res.exception, LinkTooSlow), res.output
        assert "round trip" in str(res.exception) or "round trip" in res.output


def test_the_brake_limit_follows_the_link():
    from tuning.identify_resonance import LONG_S, SHORT_S, brake_overshoot, stop_speed
    from tuning.link import LinkTiming

    m = MotorArray("MAC140", n=1)
    limit = 0.5 * stop_speed(m)
    assert stop_speed(m) == pytest.approx(300 / 60 * 2 * np.pi)  # 300 rpm (4.4.5)
    fast, slow = LinkTiming(1e-4, 1e-4, 0.0), LinkTiming(2e-3, 2e-3, 1e-2)
    assert brake_overshoot(fast, SHORT_S, 1.92e-3) <= limit
    assert brake_overshoot(fast, LONG_S, 1.92e-3) <= limit
    assert brake_overshoot(slow, LONG_S, 1.92e-3) > limit


def test_a_motor_still_in_at_mode_after_the_brake_is_refused_not_recorded():
    # a brake that overshot (the link slowed during the record): the motor coasts in AT_MODE
    # above 300 rpm; the step stops with a reason instead of starting the next record
    from tuning.identify_resonance import _brake_and_rest
    from tuning.records import RecordError

    class Coasting:
        n = 1

        def read(self, key):
            return np.array([{"V_IST": -300.0, "MODE_REG": 4.0}[key]])

        def write(self, key, value):
            pass

        def step(self, n=1):
            pass

    with pytest.raises(RecordError, match="did not leave AT_MODE after the brake"):
        _brake_and_rest(Coasting(), np.ones(1), 0.01, 1.92e-3)


@pytest.mark.parametrize("nth", [12, 15, 24])
def test_a_sample_answered_late_is_not_lost_from_the_record(nth):
    # one READ SAMPLE BUFFER reply comes after the client gave up waiting and asked again
    # (MAC050–141 manual 5.1: the motor answers each request with the next sample): the
    # record read out is still the motor's whole record, sample for sample
    from tuning.records import acquire_testu
    from tuning.serial_source import SerialMotor

    from jvl_gym.protocol import MacTalkClient
    from jvl_gym.protocol.mactalk import codec16 as mt

    m = MotorArray("MAC140", n=1, seed=0)  # the firmware's record of 11 samples
    server = TwinServer(Twin(m, [19]), tcp=("127.0.0.1", 0), run_clock=False).start()
    ep = server.endpoint("mactalk", "tcp")
    link = DelayingLink((ep.host, ep.port))
    client = MacTalkClient(link.url, address=19, timeout=0.2)
    sm = SerialMotor(client, "MAC140", clock=server.twin.advance)
    try:
        # the read-out drains to the end of the buffer (12 requests), then reads it (12
        # more): the reply to the end of the drain, to a sample or to the end of the record
        # comes two timeouts late
        link.hold_reply(mt.encode_read_sample_buffer(19), 2 * client.timeout, nth=nth)
        rec = acquire_testu(sm, 100, 11, align=False)[0]
        assert link.held == 1 and client.retried >= 1
        want = m.sample_buffer(0)
        np.testing.assert_array_equal(rec.input, want["UA_VAL"])
        np.testing.assert_array_equal(rec.output, want["IC_IST"])
    finally:
        client.close()
        link.close()
        server.stop()


@pytest.fixture()
def linked_twin():
    """A MAC140 twin at address 19 on a simulated clock behind a :class:`DelayingLink`."""
    m = MotorArray("MAC140", n=1, seed=0)
    server = TwinServer(Twin(m, [19]), tcp=("127.0.0.1", 0), run_clock=False).start()
    ep = server.endpoint("mactalk", "tcp")
    link = DelayingLink((ep.host, ep.port))
    try:
        yield m, server, link
    finally:
        link.close()
        server.stop()


def test_an_answer_that_came_on_a_second_send_leaves_no_answer_behind(linked_twin):
    # the read's first answer comes after the client sent the read again; the answer to the
    # second send must not be taken for the answer to the next request (a MacTalk answer does
    # not say which request it answers, MAC050–141 manual 5.1)
    from jvl_gym.protocol import MacTalkClient
    from jvl_gym.protocol.mactalk import codec16 as mt

    m, _, link = linked_twin
    link.delay = 0.05
    with MacTalkClient(link.url, address=19, timeout=1.0) as client:
        number = client.table.lookup("MODE_REG").number
        link.hold_reply(mt.encode_read(19, number), 1.5 * client.timeout)
        assert client.read("MODE_REG") == 0
        assert link.held == 1 and client.retried == 1
        client.write("T_SOLL", 500)  # answered by its own accept
        assert client.read("T_SOLL") == 500 and m.read("T_SOLL")[0] == 500


def test_a_request_over_a_measured_slow_link_waits_as_the_link_needs(linked_twin):
    # the link answers in 0.25 s; one write's accept comes 2 s later still: longer than the
    # client's own timeout and its retries (3 × 0.5 s), but within the round trips of the
    # measured link the run waits (tuning.link.reply_timeout: 20 round trips, 5 s here)
    from tuning.serial_source import SerialMotor

    from jvl_gym.protocol import MacTalkClient
    from jvl_gym.protocol.mactalk import codec16 as mt

    m, server, link = linked_twin
    link.delay = 0.25
    client = MacTalkClient(link.url, address=19)
    sm = SerialMotor(client, "MAC140", clock=server.twin.advance)
    try:
        timing = sm.measure_link()
        assert timing.wall_s >= link.delay
        late = 2.0
        assert (client.retries + 1) * 0.5 < late + link.delay  # the client's own: 0.5 s
        reg = client.table.lookup("T_SOLL")
        link.hold_reply(mt.encode_write_word(19, reg.number, 700), late)
        sm.write("T_SOLL", 700)
        assert link.held == 1 and m.read("T_SOLL")[0] == 700
    finally:
        client.close()


def test_a_run_whose_write_is_never_answered_in_time_leaves_the_motor_passive(linked_twin):
    # the motor carries out the write to position mode but its accept comes after the client
    # gave up: the run fails with the motor moving, and the stop still leaves it passive
    from jvl_gym.protocol.errors import NoAnswerError
    from jvl_gym.protocol.mactalk import codec16 as mt

    m, server, link = linked_twin
    number = m.table.lookup("MODE_REG").number
    link.hold_reply(mt.encode_write_word(19, number, 2), 4.0)
    said: list[str] = []
    with pytest.raises(NoAnswerError, match=f"did not answer WRITE {number} = 0x0002"):
        autotune_over_serial(link.url, "MAC140", address=19, progress=said.append,
                             clock=server.twin.advance)
    assert link.held == 1
    assert m.read("MODE_REG")[0] == PASSIVE
    assert said[-1] == "the motor is passive (MODE_REG read back)"
