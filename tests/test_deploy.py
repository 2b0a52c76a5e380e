"""jvl-gym deploy against a twin: killing the loop's process, stalling its policy and cutting
its link each put the twin's motor passive within the supervisor's stated time, for each task
with a bridge (Positioning on a bare motor, GearSync on its web line: ``jvl_gym.rl.lines``); no
command beyond the bounds reaches the motor (a property over a fake link; GearSync's in
tests/test_deploy_gear_sync.py); the engineering metrics from a trace equal the env's own
statistics.

Times are wall-clock against a twin served on a slow clock (a quarter of real time: less CPU
for the simulation, whose thread shares the interpreter with the loop), so every bound is the
stated time plus a margin measured on this machine just before (a MacTalk round trip and the
overshoot of a short sleep, many times over): a loaded machine widens the margin instead of
failing the test. The motor counts as stopped when it leaves the running mode (it has taken the
passive command; the MAC050–141 runs its stop on the way to passive), and it must then reach
passive.
"""

from __future__ import annotations

import contextlib
import os
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from jvl_gym.families import family_of_motor
from jvl_gym.motor.array import MotorArray
from jvl_gym.protocol.mactalk.client16 import MacTalkClient
from jvl_gym.protocol.mactalk.twin16 import Twin
from jvl_gym.protocol.serving.transport import TwinServer
from jvl_gym.rl.deploy import PositioningBridge, deploy
from jvl_gym.rl.lines import GearSyncLine
from jvl_gym.rl.metrics import engineering_metrics
from jvl_gym.rl.supervisor import Limits, Supervisor, register_bounds

ENV = "jvl_gym/Positioning-v0"
MOTOR = "MAC140"
ADDRESS = 19
FAM = family_of_motor(MOTOR)
PASSIVE = int(FAM.twin.passive_mode)
RUNNING = int(FAM.task.VELOCITY_MODE)
ROOT = Path(__file__).resolve().parents[1]
#: each task with a bridge: its env, the motor's running mode, the twin's motor
TASKS = {"positioning": (ENV, RUNNING, lambda: MotorArray(MOTOR, n=1, seed=0)),
         # a slow line without steps, so that the web holds for the whole test untrimmed
         "gear_sync": ("jvl_gym/GearSync-v0", int(FAM.constants.GP_MODE),
                       lambda: GearSyncLine(MOTOR, 0, randomization={
                           "line_speed": (0.1, 0.1), "ramp_time": (1.0, 1.0),
                           "speed_step": (0.0, 0.0), "walk": (0.0, 0.0),
                           "ripple": (0.0, 0.0)}))}


class Served(str):
    """The twin's URL, with the task's env id and running mode."""

    env: str
    running: int


@pytest.fixture(params=sorted(TASKS))
def twin_url(request):
    env, running, motors = TASKS[request.param]
    twin = Twin(motors(), [ADDRESS])
    twin.advance(0.01)  # compiled before it is served (numba compiles on first use)
    with TwinServer(twin, tcp=("127.0.0.1", 0), speed=0.25) as server:
        url = Served(server.endpoint("mactalk", "tcp").url)
        url.env, url.running = env, running
        yield url


def _margin(read) -> float:
    """Slack for scheduling on this machine now, measured: a round trip of ``read()`` and the
    overshoot of a short sleep, the worst of five each, many times over."""
    rtt = []
    for _ in range(5):
        t = time.monotonic()
        read()
        rtt.append(time.monotonic() - t)
    over = []
    for _ in range(5):
        t = time.monotonic()
        time.sleep(0.005)
        over.append(time.monotonic() - t - 0.005)
    return 20 * (max(rtt) + max(over)) + 0.05


def _loop_limits(margin: float) -> dict[str, float]:
    """The loop's link time-out and its watchdog's heartbeat time-out, from the measured
    ``margin``: on a busy machine (load average 25 on two cores) the defaults (0.1 s, 0.25 s)
    ran out in the middle of a run, which then ended for the link or the watchdog, not for what
    a test is about."""
    return {"timeout": max(0.1, margin), "watchdog_timeout": max(2.0, 10 * margin)}


class Observer:
    """A connection of the test's own to the twin: MODE_REG, and the margin of this machine."""

    def __init__(self, url: str) -> None:
        self.running = getattr(url, "running", RUNNING)
        self.client = MacTalkClient(url, ADDRESS, timeout=2.0)
        #: slack for scheduling on this machine now, measured
        self.margin = _margin(lambda: self.client.read("MODE_REG"))
        self.loop_limits = _loop_limits(self.margin)

    def mode(self) -> int:
        return int(self.client.read("MODE_REG"))

    def wait_mode(self, mode: int, seconds: float, leave: bool = False) -> float | None:
        """Poll until MODE_REG == mode (``leave``: != mode); the time it was seen (monotonic)
        or None."""
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            if (self.mode() == mode) != leave:
                return time.monotonic()
            time.sleep(0.005)
        return None

    def wait_stop(self, seconds: float) -> float | None:
        """Poll until the motor leaves the running mode (the passive command accepted: the
        MAC050–141 runs its stop, STOP_MODE, on the way to passive); then check that it does
        reach passive. The time it left (monotonic) or None."""
        left = self.wait_mode(self.running, seconds, leave=True)
        if left is not None:
            assert self.wait_mode(PASSIVE, 60) is not None, "stopping, but never passive"
        return left


def _run_in_thread(env=ENV, **kwargs):
    out = {}

    def target():
        try:
            out["report"] = deploy(env, **kwargs)
        except BaseException as exc:  # noqa: BLE001
            out["error"] = exc

    th = threading.Thread(target=target, daemon=True)
    th.start()
    return th, out


def test_a_stalled_policy_puts_the_motor_passive_by_the_deadline(twin_url):
    obs = Observer(twin_url)
    release = threading.Event()
    stalled = {}
    calls = [0]

    def policy(o):
        calls[0] += 1
        if calls[0] == 5:
            stalled["t"] = time.monotonic()
            release.wait(30)
        return np.zeros((1, 1))

    # a long period: a loaded machine's late period (which stops the loop too) is unlikely
    period, deadline = 0.2, 0.03
    th, out = _run_in_thread(twin_url.env, policy=policy, url=twin_url, address=ADDRESS,
                             motor_type=MOTOR, period=period, deadline=deadline,
                             max_seconds=5.0, **obs.loop_limits)
    assert obs.wait_mode(obs.running, 60) is not None
    seen = obs.wait_stop(30)
    release.set()
    th.join(30)
    assert seen is not None and "t" in stalled, out
    stated = deadline  # the supervisor's stated time: the policy's deadline
    assert seen - stalled["t"] <= stated + obs.margin
    assert out["report"].reason.startswith("policy stalled")


def test_a_tripped_watchdog_ends_the_loop_before_its_next_command(twin_url):
    """A watchdog whose heartbeats come too late puts the motor passive and ends; the loop must
    then stop at once and send no further command (which would set the motor running again
    behind the watchdog's back)."""
    obs = Observer(twin_url)
    period = 0.2
    th, out = _run_in_thread(twin_url.env, policy=lambda o: np.zeros((1, 1)), url=twin_url,
                             address=ADDRESS, motor_type=MOTOR, period=period,
                             max_seconds=5.0, timeout=obs.loop_limits["timeout"],
                             watchdog_timeout=0.02)  # shorter than a period: it trips
    th.join(120)
    report = out.get("report")
    assert report is not None, out
    assert report.reason.startswith("watchdog"), report.reason
    # ended within the periods the watchdog takes to write passive and end, not after 5 s
    assert report.periods < 5.0 / period / 2
    assert obs.mode() == PASSIVE


class Proxy:
    """A TCP relay between the loop and the twin that the test can cut."""

    def __init__(self, url: str) -> None:
        host, port = url.removeprefix("socket://").split(":")
        self.target = (host, int(port))
        self.server = socket.create_server(("127.0.0.1", 0))
        self.url = f"socket://127.0.0.1:{self.server.getsockname()[1]}"
        self.socks: list[socket.socket] = []
        self.cut_event = threading.Event()
        threading.Thread(target=self._accept, daemon=True).start()

    def _accept(self) -> None:
        while not self.cut_event.is_set():
            try:
                conn, _ = self.server.accept()
            except OSError:
                return
            up = socket.create_connection(self.target)
            self.socks += [conn, up]
            for a, b in ((conn, up), (up, conn)):
                threading.Thread(target=self._pipe, args=(a, b), daemon=True).start()

    def _pipe(self, a: socket.socket, b: socket.socket) -> None:
        while not self.cut_event.is_set():
            try:
                data = a.recv(4096)
            except OSError:
                return
            if not data or self.cut_event.is_set():
                return  # cut: swallow, as a broken cable does
            with contextlib.suppress(OSError):
                b.sendall(data)

    def cut(self) -> None:
        """Stop relaying: requests get no answer (the sockets stay open)."""
        self.cut_event.set()


def test_a_cut_link_puts_the_motor_passive_after_the_clients_time_out(twin_url):
    obs = Observer(twin_url)
    proxy = Proxy(twin_url)
    timeout, retries, period = max(0.05, obs.margin), 1, 0.2
    th, out = _run_in_thread(twin_url.env, policy=lambda o: np.full((1, 1), 0.1),
                             url=proxy.url, address=ADDRESS, motor_type=MOTOR, period=period,
                             watchdog_url=str(twin_url), timeout=timeout, max_seconds=10.0,
                             watchdog_timeout=obs.loop_limits["watchdog_timeout"])
    assert obs.wait_mode(obs.running, 60) is not None
    time.sleep(0.1)
    t_cut = time.monotonic()
    proxy.cut()
    seen = obs.wait_stop(30)
    th.join(30)
    assert seen is not None
    # the loop meets the cut link at its next read (within a period), gives the link up after
    # its time-outs, and the watchdog acts at once
    stated = period + timeout * (1 + retries)
    assert seen - t_cut <= stated + obs.margin
    assert out["report"].reason.startswith("link")


def _deploy_process(url: str, obs: Observer, *extra: str, preexec_fn=None
                    ) -> subprocess.Popen:
    """``jvl-gym deploy`` in a process of its own, with the time-outs of the measured margin
    (:func:`_loop_limits`): on a busy machine (load average 25 on two cores) the loop's
    heartbeats came more than 0.2 s apart, a watchdog of 0.2 s then stopped the motor and
    ended during the run, and killing the loop afterwards left the motor running."""
    env = {**os.environ, "PYTHONPATH": f"{ROOT / 'src'}{os.pathsep}{ROOT}"}
    limits = obs.loop_limits
    return subprocess.Popen(
        [sys.executable, "-m", "jvl_gym.cli", "deploy", getattr(url, "env", ENV), "--policy",
         "zero", "--url", str(url),
         "--address", str(ADDRESS), "--motor", MOTOR, "--period", "0.2", "--episodes", "50",
         "--watchdog-timeout", f"{limits['watchdog_timeout']:.3f}",
         "--timeout", f"{limits['timeout']:.3f}", *extra],
        env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, preexec_fn=preexec_fn)


def test_killing_the_loops_process_puts_the_motor_passive(twin_url):
    obs = Observer(twin_url)
    proc = _deploy_process(twin_url, obs)
    try:
        assert obs.wait_mode(obs.running, 120) is not None, proc.stderr.read1().decode()
        time.sleep(0.1)
        t_kill = time.monotonic()
        proc.send_signal(signal.SIGKILL)
        seen = obs.wait_stop(30)
    finally:
        proc.kill()
        proc.wait()
    assert seen is not None
    # the watchdog's heartbeat pipe closes with the process: it writes passive at once, long
    # before its heartbeat time-out
    assert seen - t_kill <= 0.2 + obs.margin


@pytest.mark.parametrize(("sig", "reason"), [(signal.SIGTERM, b"terminated (SIGTERM)"),
                                           (signal.SIGINT, b"interrupted (Ctrl-C)")])
def test_sigterm_and_ctrl_c_stop_the_loop_and_the_motor(twin_url, sig, reason):
    obs = Observer(twin_url)
    proc = _deploy_process(twin_url, obs)
    try:
        assert obs.wait_mode(obs.running, 120) is not None
        t_term = time.monotonic()
        proc.send_signal(sig)
        seen = obs.wait_stop(30)
        out, _ = proc.communicate(timeout=60)
    finally:
        proc.kill()
    assert seen is not None and seen - t_term <= obs.margin + 0.03
    assert proc.returncode == 1 and reason in out


def _ignore_ctrl_c() -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def test_ctrl_c_stops_a_loop_started_with_ctrl_c_ignored(twin_url):
    """A process started with SIGINT ignored (a shell's background job, or a parent that
    ignores it) would never see Ctrl-C: the loop installs its own handler, so Ctrl-C stops it
    and the motor all the same."""
    obs = Observer(twin_url)
    proc = _deploy_process(twin_url, obs, preexec_fn=_ignore_ctrl_c)
    try:
        assert obs.wait_mode(obs.running, 120) is not None
        t_term = time.monotonic()
        proc.send_signal(signal.SIGINT)
        seen = obs.wait_stop(30)
        out, _ = proc.communicate(timeout=60)
    finally:
        proc.kill()
    assert seen is not None and seen - t_term <= obs.margin + 0.03
    assert proc.returncode == 1 and b"interrupted (Ctrl-C)" in out


class FakeLink:
    """Records every register write."""

    def __init__(self) -> None:
        self.sent: list[dict[str, int]] = []
        self.passives = 0

    def write_raws(self, values):
        self.sent.append(dict(values))

    def passive(self):
        self.passives += 1


@settings(max_examples=200, deadline=None)
@given(st.lists(st.floats(allow_nan=True, allow_infinity=True, width=64), min_size=1,
                max_size=40),
       st.floats(0.01, 1.0))
def test_no_command_beyond_the_bounds_reaches_the_motor(actions, max_step):
    bridge = PositioningBridge(FAM)
    link = FakeLink()
    limits = Limits((-0.8,), (0.6,), max_step)
    sup = Supervisor(link, limits, bridge.to_registers, bridge.bounds)
    table = register_bounds(FAM.table, bridge.writes)
    full = table["T_SOLL"][1]
    previous = 0.0
    for a in actions:
        bounded, _ = sup.command([a])
        assert -0.8 <= bounded[0] <= 0.6
        assert abs(bounded[0] - previous) <= max_step + 1e-12
        previous = bounded[0]
    t_prev = 0
    for sent in link.sent:
        for name, raw in sent.items():
            lo, hi = table[name]
            assert lo <= raw <= hi
        assert sent["T_SOLL"] <= round(0.8 * full)
        assert abs(sent["T_SOLL"] - t_prev) <= np.ceil(max_step * full) + 1
        t_prev = sent["T_SOLL"]


def test_the_metrics_from_a_trace_equal_the_envs_statistics():
    from jvl_gym.envs.positioning import PositioningEnv

    env = PositioningEnv(max_episode_steps=150)
    core = env.core
    o, _ = env.reset(seed=4)
    k = core.fam.constants
    step = core.decimation * k.OUTER_DT
    window = core.motors.read_raw("INPOSWIN")[0] / k.COUNTS_PER_REV
    error = [(core.target[0] - core.motors.read_raw("P_IST")[0]) / k.COUNTS_PER_REV]
    times = [0.0]
    done = False
    while not done:
        o, r, term, trunc, info = env.step(np.clip(3 * o[:1] - 0.5 * o[2:3], -1, 1))
        done = term or trunc
        error.append((core.target[0] - core.motors.read_raw("P_IST")[0]) / k.COUNTS_PER_REV)
        times.append(times[-1] + step)
    trace = {"t": np.array(times), "error": np.array(error),
             "direction": np.full(len(times), core.direction[0])}
    got = engineering_metrics(ENV, trace, window)
    for name in ("settle_time", "final_error", "overshoot"):
        assert got[name] == pytest.approx(info[name], abs=1e-12), name


def test_metrics_of_an_env_without_them_is_a_one_line_error():
    with pytest.raises(KeyError, match="no engineering metrics stated"):
        engineering_metrics("jvl_gym/CoilWinding-v0", {"t": np.zeros(1)})


def test_deploy_refuses_an_env_it_cannot_bridge_in_one_line(capsys):
    from cli_checks import one_line_error, run_cli
    from jvl_gym.cli.main import app

    code, _, err = run_cli(app, ["deploy", "jvl_gym/CoilWinding-v0"], capsys)
    assert code == 2 and "Positioning" in one_line_error(code, err)
    code, _, err = run_cli(app, ["deploy", ENV, "--period", "0"], capsys)
    assert code == 2 and "--period" in one_line_error(code, err)


def test_the_loop_period_is_the_link_models():
    from jvl_gym.cli.deploy import loop_period
    from jvl_gym.envs.link import make_link_vec

    env = make_link_vec(ENV, 1, "mactalk:19200")
    assert loop_period(ENV, "mactalk:19200", MOTOR) == pytest.approx(
        env.period_steps * env.step_seconds)


def test_settle_time_counts_to_the_last_sample_outside_the_window():
    from jvl_gym.rl.metrics import settle_time

    t = np.arange(6) * 0.5
    assert settle_time(t, [3, 2, 0.5, 2, 0.1, 0.0], 1.0) == 1.5
    assert settle_time(t, [0.2] * 6, 1.0) == 0.0
    assert settle_time(t, [0, 0, 0, 0, 0, 5], 1.0) == 2.5  # ends outside: the whole trace


def test_gear_sync_metrics_from_a_tension_trace():
    got = engineering_metrics("jvl_gym/GearSync-v0",
                              {"t": np.arange(4.0), "tension_error": [1.0, -3.0, 2.0, 0.0],
                               "copper": [0.0, 1.0, 2.0, 2.5]})
    assert got == {"tension_error": 1.5, "tension_error_max": 3.0, "copper_loss": 2.5}


@contextlib.contextmanager
def _served_motor(motor: str):
    """A motor of type ``motor`` at address 7 served over TCP on a quarter-speed clock: its URL,
    a probe connection of the test's own and the loop's limits from the measured margin."""
    from jvl_gym.cli.serve import build_line
    from jvl_gym.rl.watchdog import passive_client

    twin, _ = build_line([motor], [7])
    twin.advance(0.01)
    with TwinServer(twin, tcp=("127.0.0.1", 0), speed=0.25) as server:
        url = server.endpoint("mactalk", "tcp").url
        probe = passive_client(url, 7, motor, timeout=2.0)
        yield url, probe, _loop_limits(_margin(lambda: probe.read("MODE_REG")))


@pytest.mark.parametrize("motor", ["MAC140", "MAC800"])
def test_a_deployed_episode_writes_its_trace_and_statistics(tmp_path, motor):
    import csv

    with _served_motor(motor) as (url, probe, limits):
        report = deploy(ENV, lambda o: np.full((1, 1), 0.2), url, 7, motor, period=0.05,
                        episodes=2, max_seconds=0.2, trace=tmp_path / "trace.csv", **limits)
        mode = int(probe.read("MODE_REG"))
    assert report.reason == "done" and report.lengths == [4, 4]
    assert set(report.stats) == {"settle_time", "final_error", "overshoot", "copper_loss"}
    assert report.rate_hz > 0 and report.latency_max >= report.latency_mean > 0
    rows = list(csv.DictReader((tmp_path / "trace.csv").open()))
    assert len(rows) == 8 and {"T_SOLL", "V_SOLL", "position_error", "latency_s"} <= set(rows[0])
    # the rate limit (0.5 a period) from 0: 0.2 at once; T_SOLL = 0.2 of its full scale
    assert [float(r["action"]) for r in rows[:2]] == pytest.approx([0.2, 0.2])
    assert int(rows[0]["T_SOLL"]) == round(0.2 * 1023)
    fam = family_of_motor(motor)
    assert mode != int(fam.task.VELOCITY_MODE)  # stopped at the end (passive, or on its way)


def test_the_loop_runs_with_the_heap_frozen_and_thaws_it_after():
    """A full collection of the loaded simulator, numba and torch takes many periods: a
    deployment runs with the heap frozen (``heap_frozen``), from before its watchdog starts,
    and leaves it as it found it."""
    import gc

    frozen_during: list[int] = []

    def policy(obs):
        frozen_during.append(gc.get_freeze_count())
        return np.zeros((1, 1))

    with _served_motor(MOTOR) as (url, _, limits):
        before = gc.get_freeze_count()
        # gc.get_freeze_count walks the frozen heap (tens of ms in a test process): periods
        # and a deadline that it does not overrun
        report = deploy(ENV, policy, url, 7, MOTOR, period=0.5, deadline=5.0, episodes=1,
                        max_seconds=1.0, **limits)
    assert report.reason == "done" and report.lengths == [2]
    # the warm-up call and every call in the loop see the heap frozen
    assert len(frozen_during) == 3 and all(c > 10_000 for c in frozen_during)
    assert gc.get_freeze_count() == before == 0


def test_the_rewards_compiled_code_is_ready_before_the_loop():
    """On a fresh install numba compiles Positioning's step reward at its first call, 100 ms
    and more: a deployment whose first period made that call overran it and stopped the
    motor. ``prepare`` (once, before the episodes) makes it ready; in a new process, so that
    nothing else has compiled it first."""
    code = (
        "from jvl_gym.families import family_of_motor\n"
        "from jvl_gym.envs.positioning import step_reward\n"
        "from jvl_gym.rl.deploy import PositioningBridge\n"
        "class Client:\n"
        "    def read_raw(self, name):\n"
        "        return 10\n"
        "class Link:\n"
        "    client = Client()\n"
        "bridge = PositioningBridge(family_of_motor('MAC140'))\n"
        "before = len(step_reward.signatures)\n"
        "bridge.prepare(Link())\n"
        "print(before, len(step_reward.signatures), bridge.window_counts, bridge.overshoot)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, cwd=ROOT)
    assert out.stdout.split() == ["0", "1", "10.0", "0.0"]

