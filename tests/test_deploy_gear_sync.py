"""GearSync over the bus: the bridge's gear in GP_MODE is the env's in AG_MODE; the line a twin
serves draws its webs as the env does, per seed; a deployed episode over the line reads the
registers into the env's observation and reports its return and metrics; no GEARF1 beyond the
task's bounds reaches the motor (a property over a fake link)."""

from __future__ import annotations

import csv

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from jvl_gym.families import family_of_motor
from jvl_gym.motor.array import MotorArray
from jvl_gym.protocol.mactalk.twin16 import Twin
from jvl_gym.protocol.serving.transport import TwinServer
from jvl_gym.rl.deploy import GearSyncBridge, deploy
from jvl_gym.rl.lines import GearSyncLine
from jvl_gym.rl.supervisor import Limits, Supervisor, register_bounds

ENV = "jvl_gym/GearSync-v0"
MOTOR = "MAC140"
FAM = family_of_motor(MOTOR)
#: a slow line without steps, ripple or walk: the web holds for seconds without a trim
GENTLE = {"line_speed": (0.1, 0.1), "ramp_time": (1.0, 1.0), "speed_step": (0.0, 0.0),
          "walk": (0.0, 0.0), "ripple": (0.0, 0.0)}


@pytest.mark.parametrize("a", [-1.0, -0.37, 0.0, 0.5, 1.0])
def test_the_bridges_gear_in_gp_mode_follows_the_master_as_ag_mode_does(a):
    """MAC050–141 manual 4.1.9 and 4.4.19 (AG) against 4.4.4 (GP): the same pulses, the AG
    factor at ANINP = round(1023·a) in the gear itself."""
    k = FAM.constants
    bridge = GearSyncBridge(FAM)
    bridge.set_nominal(4321)
    ag, gp = MotorArray(MOTOR, n=1, seed=0), MotorArray(MOTOR, n=1, seed=0)
    v_soll = round(FAM.task.rpm_to_v_soll(3000.0))
    ag.write_many({"GEARF1": 4321, "GEARF2": 1000, "V_SOLL": v_soll,
                   "MODE_REG": int(k.AG_MODE)})
    ag.set_input(0, analog_volts=10.0 * a)
    gp.write_many({**bridge.to_registers(np.array([a])), "GEARF2": 1000, "V_SOLL": v_soll,
                   "MODE_REG": bridge.gp_mode})
    for m in (ag, gp):
        m.step(2)
        m.set_input(0, pulse_counts=3.0)
        m.step(400)
    assert int(ag.read_raw("ANINP")[0]) == round(1023 * a)
    # the gear to GEARF1's resolution: one count in 4321 of 1200 pulses × the gear
    assert float(gp.read_raw("P_IST")[0]) == pytest.approx(float(ag.read_raw("P_IST")[0]),
                                                           abs=6.0)
    assert abs(float(ag.read_raw("P_IST")[0])) > 1000.0


def test_the_line_draws_each_web_as_the_env_does_with_its_seed():
    import gymnasium as gym

    import jvl_gym  # noqa: F401

    line = GearSyncLine(MOTOR, seed=40)
    env = gym.make(ENV, motor_type=MOTOR).unwrapped
    refs = []
    for k in range(3):
        env.reset(seed=40 + k)
        refs.append(float(env.core.tension_ref[0]))
        assert line.tension_ref == pytest.approx(refs[-1])
        nominal = int(line.m.read_raw("GEARF1")[0])
        assert nominal == int(round(env.core.gear[0] * 1000))
        line.write_raw("MODE_REG", line.m.family.twin.passive_mode)
        assert line.episodes == k + 1  # passive before a run draws nothing
        line.write_raw("MODE_REG", int(FAM.constants.GP_MODE))
        assert line.running
        line.step(5)
        line.write_raw("MODE_REG", line.m.family.twin.passive_mode)  # the next web
    assert len(set(refs)) == 3


def test_the_load_cell_reads_the_webs_tension_on_the_analogue_input():
    line = GearSyncLine(MOTOR, seed=2, randomization=GENTLE)
    line.write_raw("MODE_REG", int(FAM.constants.GP_MODE))
    line.step(300)
    aninp = int(line.m.read_raw("ANINP")[0])
    # 0..10 V for 0..100 N, ±10 V = ±1023; the load cell lags the tension by its filter
    assert aninp / 1023 * 100.0 == pytest.approx(line.tension, abs=0.3)
    assert int(line.m.read_raw("V_EXT")[0]) > 0  # the master's pulses


def test_a_deployed_gear_sync_episode_reports_its_return_and_metrics(tmp_path):
    line = GearSyncLine(MOTOR, seed=5, randomization=GENTLE)
    twin = Twin(line, [9])
    twin.advance(0.01)
    period = 0.1
    with TwinServer(twin, tcp=("127.0.0.1", 0), speed=0.25) as server:
        url = server.endpoint("mactalk", "tcp").url
        # a deadline of ten periods: the policy's thread may wait for the GIL on a busy machine
        report = deploy(ENV, lambda o: np.full((1, 1), 0.05), url, 9, MOTOR, period=period,
                        deadline=10 * period, episodes=2, seed=5, max_seconds=1.0,
                        trace=tmp_path / "t.csv")
        mode = int(line.m.read_raw("MODE_REG")[0])
    assert report.reason == "done" and report.lengths == [10, 10]
    assert report.ended == ["", ""]
    assert set(report.stats) == {"tension_error", "tension_error_max", "copper_loss"}
    assert line.episodes == 3  # a web per episode (seeds 5, 6), the next drawn at the end
    rows = list(csv.DictReader((tmp_path / "t.csv").open()))
    assert len(rows) == 20 and {"GEARF1", "tension_error", "master_speed"} <= set(rows[0])
    import gymnasium as gym

    env = gym.make(ENV, motor_type=MOTOR, randomization=GENTLE).unwrapped
    env.reset(seed=6)  # the second episode's web
    nominal = round(env.core.gear[0] * 1000)
    # the action 0.05 at once (within the rate limit): the AG factor at ANINP 51
    assert int(rows[-1]["GEARF1"]) == round(nominal * (1.01 + 0.14 * 51 / 1023))
    # the web is whole, the master runs: the observation is read from the registers
    assert abs(float(rows[-1]["tension_error"])) < 0.5
    assert float(rows[-1]["master_speed"]) > 0.0
    assert mode != int(FAM.constants.GP_MODE)  # stopped at the end
    # the reward of a period: the env's per step, over the period's env steps, linear between
    # the reads that begin and end it (the action held: no rate penalty)
    steps = period / (2 * FAM.constants.OUTER_DT)
    r = float(rows[3]["reward"])
    begin, end = (1 - min(abs(float(rows[k]["load_cell_error"])) / 0.1, 2.0) for k in (3, 4))
    assert r == pytest.approx(0.5 * (steps - 1) * begin + 0.5 * (steps + 1) * end, abs=1e-6)


def test_a_web_that_goes_slack_ends_the_episode_with_the_penalty():
    line = GearSyncLine(MOTOR, seed=3)
    twin = Twin(line, [9])
    twin.advance(0.01)
    with TwinServer(twin, tcp=("127.0.0.1", 0), speed=0.25) as server:
        url = server.endpoint("mactalk", "tcp").url
        # the gear at its lowest: the winder falls behind the master, the web goes slack
        report = deploy(ENV, lambda o: np.full((1, 1), -1.0), url, 9, MOTOR, period=0.1,
                        episodes=1, seed=3, max_seconds=6.0)
    assert report.reason == "done"
    assert report.ended[0].startswith("web slack")
    assert report.lengths[0] < 60
    steps = 0.1 / (2 * FAM.constants.OUTER_DT)
    assert report.returns[0] <= report.lengths[0] * steps - 100.0


def test_gear_sync_is_refused_on_a_family_without_its_registers_in_one_line(capsys):
    from cli_checks import one_line_error, run_cli
    from jvl_gym.cli.main import app

    code, _, err = run_cli(app, ["deploy", ENV, "--motor", "MAC800"], capsys)
    assert code != 0 and "MAC050–141" in one_line_error(code, err)


class FakeLink:
    def __init__(self) -> None:
        self.sent: list[dict[str, int]] = []

    def write_raws(self, values):
        self.sent.append(dict(values))

    def passive(self):
        pass


@settings(max_examples=200, deadline=None)
@given(st.lists(st.floats(allow_nan=True, allow_infinity=True, width=64), min_size=1,
                max_size=40),
       st.floats(0.01, 1.0), st.integers(1, 32767))
def test_no_gear_beyond_the_bounds_reaches_the_motor(actions, max_step, nominal):
    bridge = GearSyncBridge(FAM)
    bridge.set_nominal(nominal)
    link = FakeLink()
    sup = Supervisor(link, Limits((-1.0,), (1.0,), max_step), bridge.to_registers,
                     register_bounds(FAM.table, bridge.writes))
    sup.bounds.update(bridge.bounds)  # as the loop does once the nominal gear is read
    lo, hi = bridge.bounds["GEARF1"]
    assert lo >= round(0.87 * nominal) - 1 and hi <= min(round(1.15 * nominal) + 1, 32767)
    previous = min(max(bridge.to_registers(np.zeros(1))["GEARF1"], lo), hi)
    for a in actions:
        sup.command([a])
    for sent in link.sent:
        g = sent["GEARF1"]
        assert lo <= g <= hi
        # the rate limit: the AG factor moves 0.14 per unit of action, in ANINP's steps of
        # 1/1023 (one more at most by rounding), GEARF1 rounded
        assert abs(g - previous) <= 0.14 * nominal * (max_step + 1 / 1023) + 1
        previous = g


def test_serve_builds_the_line_around_one_motor_and_refuses_more_in_one_line():
    from jvl_gym.cli.serve import build_line

    twin, order = build_line([MOTOR], [4], seed=11, line_env=ENV)
    assert isinstance(twin.m, GearSyncLine) and twin.m.seed == 11 and order == [0]
    assert twin.addresses() == [4]
    with pytest.raises(ValueError, match="--line serves one motor"):
        build_line([MOTOR, MOTOR], [4, 5], line_env=ENV)
    with pytest.raises(ValueError, match="MAC050–141"):
        build_line(["MAC800"], [4], line_env=ENV)
