"""The link model (jvl_gym.envs.link): times from the codecs' frames, rate, latency,
quantisation, seeded randomisation, both env APIs."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

from jvl_gym.envs.link import Link, LinkEnv, make_link_vec, observed_registers, parse_link
from jvl_gym.protocol.mactalk import codec16 as mt
from jvl_gym.protocol.modbus import codec as mb

ENV = "jvl_gym/Positioning-v0"


def test_mactalk_times_are_the_frames_bytes_at_ten_bits_a_byte() -> None:
    link = parse_link("mactalk:19200")
    read = len(mt.encode_read(1, 1)) + len(mt.encode_data_reply(bytes(4)))
    write = len(mt.encode_write_word(1, 1, 0)) + len(mt.encode_accept())
    assert link.frame_bytes(1, 3) == (3 * read, write)
    period, latency = link.times(1, 3, 0.00192)
    assert period == pytest.approx((3 * read + write) * 10 / 19200)
    assert latency == pytest.approx(period - (len(mt.encode_read(1, 1)) + 3) * 10 / 19200)
    # twice the baud rate, half the time
    assert parse_link("mactalk:38400").times(1, 3, 0.00192)[0] == pytest.approx(period / 2)


def test_modbus_counts_the_silences() -> None:
    link = parse_link("modbus:9600")
    read, write = link.frame_bytes(1, 3)
    assert read == len(mb.encode_read_request(1, 0, 6)) + len(mb.encode_read_response(1, [0] * 6))
    period, _ = link.times(1, 3, 0.00192)
    gap = mb.silence(mb.SerialFormat(9600))
    assert period == pytest.approx((read + write) * 10 / 9600 + 4 * gap)


def test_canopen_and_dac() -> None:
    assert parse_link("canopen:4ms").times(1, 3, 0.002) == (0.004, 0.004)
    assert parse_link("canopen:0.004").sync_period == 0.004
    assert parse_link("dac:12").times(1, 3, 0.002) == (0.002, 0.0)


@pytest.mark.parametrize("text", ["serial:9600", "mactalk:fast", "mactalk:0", "canopen:-1ms",
                                  "mactalk:19200,drop=1", "mactalk:19200,colour=red",
                                  "dac:99"])
def test_bad_links_are_refused_in_one_line(text: str) -> None:
    with pytest.raises(ValueError) as err:
        parse_link(text)
    assert "\n" not in str(err.value) and text in str(err.value)


def test_quantisation_through_the_raw_format() -> None:
    a = np.array([0.12345, -0.5, 1.7, -1.0])
    q = Link("mactalk").quantise(a)
    assert np.allclose(q * 1023, np.round(q * 1023)) and q.max() == 1.0
    dac = Link("dac", bits=8, volts=5.0).quantise(a)
    lsb = 10.0 / 256 / 10.0  # 8 bits over ±5 V, against ±10 V
    assert np.allclose(dac / lsb, np.round(dac / lsb))
    assert dac.max() == pytest.approx(0.5)  # the DAC's range caps the command at 5 V


def test_observed_registers_leave_out_the_previous_action() -> None:
    assert observed_registers(("position_error", "speed", "previous_action")) == 2


def _spy(env):
    """Record the actions the wrapped env's motor receives."""
    seen = []
    inner = env.env.step

    def step(actions):
        seen.append(np.array(actions, dtype=float))
        return inner(actions)

    env.env.step = step
    return seen


def test_rate_and_latency_hold_and_delay_the_command() -> None:
    env = make_link_vec(ENV, 2, "canopen:7.68ms", max_episode_steps=60)  # 4 steps of 1.92 ms
    assert (env.period_steps, env.latency_steps) == (4, 4)
    seen = _spy(env)
    env.reset(seed=1)
    env.step(np.full((2, 1), 0.5))
    env.step(np.full((2, 1), -0.25))
    env.step(np.full((2, 1), 0.0))
    got = np.array(seen)[:, 0, 0]
    # one period of the command held before (0), then each action a period late
    q = Link("canopen").quantise(np.array([0.5, -0.25]))
    assert got.tolist() == [0.0] * 4 + [q[0]] * 4 + [q[1]] * 4


def test_latency_within_a_period_lands_mid_period() -> None:
    env = make_link_vec(ENV, 1, "mactalk:115200", max_episode_steps=60)
    k, d = env.period_steps, env.latency_steps
    assert 0 < d < k
    seen = _spy(env)
    env.reset(seed=0)
    env.step(np.full((1, 1), 0.5))
    env.step(np.full((1, 1), 0.5))
    got = np.array(seen)[:, 0, 0]
    half = Link("mactalk").quantise(np.array([0.5]))[0]
    assert got[:d].tolist() == [0.0] * d and got[d:2 * k].tolist() == [half] * (2 * k - d)


def test_dropped_writes_keep_the_last_command() -> None:
    env = make_link_vec(ENV, 1, "canopen:1.92ms,drop=0.5", max_episode_steps=200)
    seen = _spy(env)
    env.reset(seed=5)
    sent = np.linspace(-1, 1, 100)
    for a in sent:
        env.step(np.full((1, 1), a))
    got = np.array(seen)[:, 0, 0]
    changes = np.count_nonzero(np.diff(got))
    assert 20 < changes < 80  # about half the frames lost
    assert set(np.round(got, 6)) <= set(np.round(Link("canopen").quantise(sent), 6)) | {0.0}


def test_seeded_runs_repeat_and_copies_equal_single_envs() -> None:
    link = "mactalk:57600,jitter=0.004,drop=0.1"

    def run(n, seed):
        env = make_link_vec(ENV, n, link, autoreset_mode="same_step", max_episode_steps=40)
        obs, _ = env.reset(seed=seed)
        trace = [obs.copy()]
        for t in range(15):
            obs, r, *_ = env.step(np.tanh(np.full((n, 1), np.sin(t)) - obs[:, :1]))
            trace.append(np.c_[obs, r])
        return trace

    a, b = run(2, 11), run(2, 11)
    assert all(np.array_equal(x, y) for x, y in zip(a, b))
    c = run(1, 12)
    assert all(np.array_equal(x[1:2], y) for x, y in zip(a, c))


def test_same_step_autoreset_reports_each_end_once() -> None:
    env = make_link_vec(ENV, 3, "canopen:5.76ms", autoreset_mode="same_step",
                        max_episode_steps=10)  # 3 steps a period: ends inside a period
    env.reset(seed=0)
    ends = 0
    for _ in range(8):
        obs, r, term, trunc, info = env.step(np.zeros((3, 1)))
        if (term | trunc).any():
            ends += int((term | trunc).sum())
            assert info["final_obs"][np.flatnonzero(term | trunc)[0]] is not None
            assert "settle_time" in info
    assert ends == 6  # two episodes of 10 steps each in 8 periods of 3 steps


def test_the_single_env_passes_check_env_without_warnings() -> None:
    from jvl_gym.envs.positioning import PositioningEnv

    env = LinkEnv(PositioningEnv(max_episode_steps=40), "dac:12,jitter=0.004")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_env(env, skip_render_check=True)


def test_train_refuses_a_bad_link_in_one_line(capsys) -> None:
    from cli_checks import one_line_error, run_cli
    from jvl_gym.cli.main import app

    code, _, err = run_cli(app, ["train", ENV, "--link", "mactalk:fast"], capsys)
    assert code == 2 and "mactalk:fast" in one_line_error(code, err)


def _tiny_config(tmp_path):
    import yaml

    cfg = {ENV: {"algo": "PPO", "n_envs": 2, "total_timesteps": 32, "seed": 0,
                 "env_kwargs": {"max_episode_steps": 60},
                 "hyperparams": {"n_steps": 16, "batch_size": 16, "n_epochs": 1},
                 "families": {"mac050_141": {}}}}
    folder = tmp_path / "rl"
    folder.mkdir()
    (folder / "positioning.yml").write_text(yaml.safe_dump(cfg))
    return folder


def test_train_takes_a_link(tmp_path) -> None:
    """A tiny training behind a MacTalk link: the SB3 env is the link's."""
    from jvl_gym.rl import sb3_adapter
    from jvl_gym.rl.train import train

    made = []
    real = sb3_adapter.make_sb3_env

    def spy(*args, **kwargs):
        venv = real(*args, **kwargs)
        made.append(venv.venv)
        return venv

    sb3_adapter.make_sb3_env = spy
    try:
        path = train(ENV, tmp_path, total_timesteps=32, progress_bar=False,
                     config_dir=_tiny_config(tmp_path), link="mactalk:19200")
    finally:
        sb3_adapter.make_sb3_env = real
    assert path.is_file()
    assert made and made[0].link == parse_link("mactalk:19200")


def test_evaluation_behind_a_link_uses_the_link() -> None:
    """run_episodes behind a CANopen link: the returns and statistics of the link's episodes
    (a constant action: the same as without the link but for the period it is late)."""
    from jvl_gym.rl.evaluate import run_episodes

    def policy(obs):
        return np.full((obs.shape[0], 1), 0.3)

    plain = run_episodes(ENV, policy, 7, 2, {"max_episode_steps": 40})
    linked = run_episodes(ENV, policy, 7, 2, {"max_episode_steps": 40}, link="canopen:7.68ms")
    assert linked.lengths.tolist() == [10, 10]  # 40 env steps in periods of 4
    assert plain.lengths.tolist() == [40, 40]
    assert set(linked.stats) == set(plain.stats)
    assert not np.allclose(linked.returns, plain.returns)


def test_evaluate_refuses_a_bad_link_in_one_line(capsys) -> None:
    from cli_checks import one_line_error, run_cli
    from jvl_gym.cli.main import app

    code, _, err = run_cli(app, ["evaluate", ENV, "--link", "canopen:x"], capsys)
    assert code == 2 and "canopen:x" in one_line_error(code, err)


def test_the_single_env_equals_a_copy_of_the_vector_env() -> None:
    from jvl_gym.envs.positioning import PositioningEnv

    link = "modbus:115200,jitter=0.004,drop=0.2"
    vec = make_link_vec(ENV, 2, link, max_episode_steps=60)
    single = LinkEnv(PositioningEnv(max_episode_steps=60), link)
    vo, _ = vec.reset(seed=20)
    so, _ = single.reset(seed=21)
    assert np.array_equal(vo[1], so)
    for t in range(8):
        a = np.full((2, 1), np.cos(t), dtype=np.float32)
        vo, vr, *_ = vec.step(a)
        so, sr, *_ = single.step(a[1])
        assert np.array_equal(vo[1], so) and vr[1] == sr


def test_next_step_autoreset_starts_the_new_episode_on_the_next_period() -> None:
    env = make_link_vec(ENV, 2, "canopen:7.68ms", max_episode_steps=8)  # 2 periods an episode
    env.reset(seed=0)
    ends = []
    for _ in range(6):
        obs, r, term, trunc, info = env.step(np.full((2, 1), 0.2))
        ends.append(bool((term | trunc).all()))
        if ends[-2:-1] == [True]:  # the period after an end: the new episode, no reward
            assert not (term | trunc).any() and (r == 0).all()
    assert ends == [False, True, False, False, True, False]


def test_next_step_autoreset_of_some_copies_starts_them_afresh() -> None:
    """One copy ends a period before the other: the period after, it returns the first
    observation of a new episode (a reset's), reward 0, and then runs a whole episode."""
    env = make_link_vec(ENV, 2, "canopen:7.68ms", max_episode_steps=8)
    env.reset(seed=0)
    env.step(np.zeros((2, 1)))
    env.env.reset(options={"reset_mask": np.array([False, True])})  # copy 1 one period behind
    env.step(np.zeros((2, 1)))  # copy 0 ends
    obs, r, term, trunc, _ = env.step(np.zeros((2, 1)))  # copy 1 at 8 steps: ends; copy 0 new
    assert r[0] == 0 and not term[0] and not trunc[0] and trunc[1]
    assert env.env._t[0] == 0  # copy 0 stands at the start of its new episode
    _, _, term, trunc, _ = env.step(np.zeros((2, 1)))
    assert not (term | trunc)[0]
    _, _, term, trunc, _ = env.step(np.zeros((2, 1)))
    assert trunc[0]  # 8 steps of its own: the whole episode


def test_mactalk_over_tcp_states_its_period_and_latency() -> None:
    link = parse_link("mactalk-tcp:10ms")
    assert link.times(1, 3, 0.00192) == (0.010, 0.004)
    assert parse_link("mactalk-tcp:0.02,latency=5ms").times(1, 3, 0.00192) == (0.02, 0.005)
    assert str(parse_link("mactalk-tcp:10ms,max_step=0.5")) == "mactalk-tcp:10ms,max_step=0.5"
    env = make_link_vec(ENV, 1, "mactalk-tcp:10ms", max_episode_steps=60)
    assert (env.period_steps, env.latency_steps) == (6, 2)  # 11.52 ms, 3.84 ms
    with pytest.raises(ValueError, match="shorter than the period") as err:
        parse_link("mactalk-tcp:4ms,latency=5ms")
    assert "\n" not in str(err.value)


def test_the_rate_limit_moves_the_action_at_most_max_step_a_period() -> None:
    env = make_link_vec(ENV, 1, "canopen:1.92ms,max_step=0.5", max_episode_steps=60)
    seen = _spy(env)
    env.reset(seed=0)
    for a in (1.0, 1.0, -1.0, -1.0, -1.0):
        env.step(np.full((1, 1), a))
    got = [float(x[0, 0]) for x in seen]
    q = Link("canopen").quantise(np.array([0.5, 1.0, 0.5, 0.0, -0.5]))
    # one period late (canopen): the held command steps by 0.5 at most
    assert got == [0.0, *q[:4].tolist()]
