"""The link-trained policies: each shipped one deploys over a twin of its env's machine for a
short episode and reports what a deployment reports; the transfer gap's arithmetic; the config
variants that train them."""

from __future__ import annotations

import numpy as np
import pytest

from jvl_gym.protocol.serving.transport import TwinServer
from jvl_gym.rl.config import rl_config
from jvl_gym.rl.deploy import deploy, load_policy, loop_period
from jvl_gym.rl.metrics import METRICS
from jvl_gym.rl.train import model_path, shipped_model
from jvl_gym.rl.transfer import kept, served_twin
from jvl_gym.rl.watchdog import passive_client
from test_deploy import _loop_limits, _margin

MOTOR = "MAC140"


def test_positioning_and_gear_sync_have_a_link_and_a_nolink_variant_shipped():
    for env in ("jvl_gym/Positioning-v0", "jvl_gym/GearSync-v0"):
        link = rl_config(env, variant="link")
        plain = rl_config(env, variant="nolink")
        assert link["link"] and plain["link"] is None
        # the same config but for the link
        assert {k: v for k, v in link.items() if k != "link"} == \
            {k: v for k, v in plain.items() if k != "link"}
        for name in ("link", "nolink"):
            path = shipped_model(env, "mac050_141", "PPO", name)
            assert path is not None and path.name == model_path(
                "x", env, "mac050_141", "PPO", name).name
            assert path.with_name(path.stem + ".monitor.csv.gz").is_file()


def test_an_unknown_variant_is_a_one_line_error():
    with pytest.raises(KeyError, match="no variant 'fast' of jvl_gym/Positioning-v0; "
                                       "configured: link, nolink"):
        rl_config("jvl_gym/Positioning-v0", variant="fast")


@pytest.mark.parametrize("env_id", ["jvl_gym/Positioning-v0", "jvl_gym/GearSync-v0"])
def test_a_shipped_link_policy_deploys_over_a_twin_and_reports(env_id, tmp_path):
    link = rl_config(env_id, variant="link")["link"]
    model = shipped_model(env_id, "mac050_141", "PPO", "link")
    policy = load_policy(str(model), env_id, 1, 0.0)
    twin = served_twin(env_id, MOTOR, 3, seed=7)
    twin.advance(0.01)
    with TwinServer(twin, tcp=("127.0.0.1", 0), speed=0.25) as server:
        url = server.endpoint("mactalk", "tcp").url
        # the link's period (11.5 ms over MacTalk TCP), or longer where this machine is busy
        # now: the test is about the report, not about holding a period under load
        margin = _margin(lambda: passive_client(url, 3, MOTOR, timeout=2.0).read("MODE_REG"))
        period = max(loop_period(env_id, link, MOTOR), margin)
        report = deploy(env_id, policy, url, 3, MOTOR, period=period, episodes=1, seed=7,
                        max_seconds=4 * period, trace=tmp_path / "trace.csv",
                        **{**_loop_limits(margin), "timeout": max(1.0, 5 * margin)})
    assert report.reason == "done" and len(report.returns) == 1
    # the episode runs its four periods, or ends sooner for a reason of the env's own (a
    # period stretched to this machine's margin can cost GearSync its web): either way the
    # report, the period count and the trace agree
    (length,), (ended,) = report.lengths, report.ended
    assert (length, ended) == (4, "") or (1 <= length < 4 and ended)
    assert np.isfinite(report.returns[0])
    assert set(report.stats) == set(METRICS[env_id])
    assert report.rate_hz > 0 and report.latency_max >= report.latency_mean > 0
    assert report.periods == length
    assert len((tmp_path / "trace.csv").read_text().splitlines()) == 1 + length


def test_kept_is_the_fraction_of_the_reference_for_either_sign():
    assert kept(100.0, 90.0) == pytest.approx(0.9)
    assert kept(-50.0, -55.0) == pytest.approx(0.9)
    assert kept(-50.0, -40.0) == pytest.approx(1.2)
    assert np.isnan(kept(0.0, 1.0))


def test_train_refuses_an_unknown_variant_in_one_line(capsys, tmp_path):
    from cli_checks import one_line_error, run_cli
    from jvl_gym.cli.main import app

    code, _, err = run_cli(app, ["train", "jvl_gym/Positioning-v0", "--variant", "fast",
                                 "--out", str(tmp_path)], capsys)
    assert code == 2 and "no variant 'fast'" in one_line_error(code, err)
    assert not any(tmp_path.iterdir())


def test_line_time_holds_each_write_to_the_links_latency():
    from jvl_gym.rl.deploy import link_latency

    hold = link_latency("jvl_gym/Positioning-v0", "mactalk:19200", MOTOR)
    assert hold > 0.04  # 43.75 ms: the line time of MacTalk's frames at 19200 baud
    twin = served_twin("jvl_gym/Positioning-v0", MOTOR, 3, seed=1)
    twin.advance(0.01)
    with TwinServer(twin, tcp=("127.0.0.1", 0), speed=0.25) as server:
        report = deploy("jvl_gym/Positioning-v0", lambda o: np.zeros((1, 1)),
                        server.endpoint("mactalk", "tcp").url, 3, MOTOR, period=0.2,
                        episodes=1, seed=1, max_seconds=0.8, hold=hold)
    assert report.reason == "done" and report.periods == 4
    # each write is to end the hold after its read (it starts the last write's duration
    # early, which a loaded machine may make too early by as much again); without the hold a
    # write ends a round trip after the read
    assert report.latency_mean >= 0.5 * hold
