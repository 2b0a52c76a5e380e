"""The results page (``jvl-gym evaluate --all``): every registered env × family × {trained,
baseline, random}, deterministic; per-family configs; one-line errors for bad options."""

from __future__ import annotations

import shutil

import pytest

pytest.importorskip("stable_baselines3")

from cli_checks import one_line_error, run_cli  # noqa: E402
from jvl_gym.cli.main import app as gym_cli  # noqa: E402
from jvl_gym.envs import ENV_IDS  # noqa: E402
from jvl_gym.envs.registration import vector_class  # noqa: E402
from jvl_gym.families import family  # noqa: E402
from jvl_gym.rl.config import env_families, rl_config, rl_runs  # noqa: E402
from jvl_gym.rl.train import SHIPPED_DIR, log_path, model_path, training_log  # noqa: E402

TINY = ["--seeds", "1", "--episodes", "2", "--max-steps", "6"]


def _run(args, capsys):
    return run_cli(gym_cli, args, capsys)


_one_line_error = one_line_error


def test_every_env_and_family_is_configured_and_families_come_from_the_env():
    runs = rl_runs()
    for env_id in ENV_IDS:
        for key in env_families(env_id):
            cfg = rl_config(env_id, family=key)
            assert cfg["eval"]["n_seeds"] >= 5
            assert (env_id, key, cfg["algo"]) in runs
    # a second algorithm on every task and family (every action space is continuous)
    for env_id in ENV_IDS:
        for key in env_families(env_id):
            assert (env_id, key, "SAC") in runs
    # a family other than the env's first runs that family's default motor type
    assert rl_config("jvl_gym/GearSync-v0", family="mac800")["env_kwargs"] == {
        "motor_type": "MAC800"}
    # ``motor_type: all``: every type of the family, drawn per episode
    assert rl_config("jvl_gym/FilterTuning-v0", family="mac800")["env_kwargs"][
        "motor_type"] == list(family("mac800").motor_types())
    with pytest.raises(KeyError, match="mis"):
        rl_config("jvl_gym/GearSync-v0", family="mis")


@pytest.fixture(scope="module")
def pages(tmp_path_factory):
    """Two runs of ``evaluate --all`` on a tiny budget; the StepperIndexing model in RUNS with
    a training log (a copy of the shipped one)."""
    root = tmp_path_factory.mktemp("results")
    runs = root / "runs"
    runs.mkdir()
    shipped = model_path(SHIPPED_DIR, "jvl_gym/StepperIndexing-v0", "mis", "PPO")
    ran = model_path(runs, "jvl_gym/StepperIndexing-v0", "mis", "PPO")
    shutil.copy(shipped, ran)
    log_path(ran).write_text('#{"t_start": 0.0, "env_id": "None"}\nr,l,t\n'
                             + "".join(f"{-20 + k * 0.1},{300 - k},{k}\n" for k in range(150)))
    texts = []
    for k in range(2):
        out = root / f"docs{k}"
        with pytest.raises(SystemExit) as info:
            gym_cli(["evaluate", "--all", "--out", str(out), "--runs", str(runs), *TINY])
        assert info.value.code in (0, None)
        texts.append((out / "results.md").read_text())
        assert (out / "results" / f"{log_path(ran).stem}.png").stat().st_size > 1000
    return texts


def test_the_page_has_every_env_and_family_with_baseline_and_random(pages):
    page = pages[0]
    for env_id in ENV_IDS:
        section = page.split(f"## {env_id}\n", 1)[1].split("\n## ", 1)[0]
        for key in env_families(env_id):
            assert f"### {key}\n" in section
            block = section.split(f"### {key}\n", 1)[1].split("\n### ", 1)[0]
            assert "\n| baseline |" in block and "\n| random |" in block
            # a column per episode statistic, a value in it for every controller that ran
            stats = vector_class(env_id).episode_stats
            header = next(line for line in block.splitlines() if line.startswith("| controller"))
            assert header.endswith("| ended |" + "".join(f" {s} |" for s in stats.values()))
            baseline = next(line for line in block.splitlines() if line.startswith("| baseline"))
            assert "—" not in baseline.split("|")[-2]
            shipped = [a for e, f, a in rl_runs() if (e, f) == (env_id, key)
                       and model_path(SHIPPED_DIR, e, f, a).is_file()]
            for algo in shipped:
                assert f"| {algo} (" in block
            if not shipped:
                assert "no trained policy" in block
    # the model in RUNS takes precedence over the shipped one, and its log is plotted
    assert "`StepperIndexing-v0-mis-ppo.zip` in the runs directory" in page
    assert "](results/StepperIndexing-v0-mis-ppo.monitor.png)" in page
    assert "episodes cut at 6 steps" in page
    assert "time limit" in page  # every 6-step episode of the longer tasks is truncated


def test_every_shipped_policy_has_its_learning_curve_on_the_page(pages):
    shipped = [model_path(SHIPPED_DIR, e, f, a) for e, f, a in rl_runs()]
    shipped = [m for m in shipped if m.is_file()]
    assert len(shipped) >= 16
    for model in shipped:
        log = training_log(model)
        assert log is not None and log.name.endswith(".monitor.csv.gz"), model
        assert f"](results/{log_path(model).stem}.png)" in pages[0], model


def test_the_page_is_deterministic(pages):
    """Everything but the transfer gap's section, whose deployed returns, loop rate and
    latency are measured in real time on the machine (``rl.results`` module docstring)."""
    from jvl_gym.rl.results import TRANSFER_HEADING

    computed = [page.split(TRANSFER_HEADING, 1)[0] for page in pages]
    assert all(TRANSFER_HEADING in page for page in pages)
    assert computed[0] == computed[1]


@pytest.mark.parametrize("args, words", [
    (["evaluate", "--all"], "--out"),
    (["evaluate", "--all", "--out", "x", "jvl_gym/GearSync-v0"], "--all"),
    (["evaluate", "jvl_gym/GearSync-v0", "--out", "x"], "--out"),
    (["evaluate"], "--all"),
    (["evaluate", "--all", "--out", "x", "--max-steps", "0"], "max-steps"),
    (["evaluate", "jvl_gym/CoilWinding-v0", "--family", "mac800"], "mac050_141"),
    (["train", "jvl_gym/Positioning-v0", "--family", "mis"], "mac800"),
    (["train", "jvl_gym/FilterTuning-v0", "--algo", "td3"], "PPO, SAC"),
])
def test_bad_options_are_one_line_errors(capsys, tmp_path, monkeypatch, args, words):
    monkeypatch.chdir(tmp_path)
    code, _, err = _run(args, capsys)
    assert words in _one_line_error(code, err)
    assert not (tmp_path / "x").exists()


def test_a_family_overrides_an_algorithm_for_itself_alone(tmp_path):
    """Entry, then its ``algos`` section, then the family's overrides, then the family's own
    ``algos`` section; a bad ``algos`` section is refused with the file and place named."""
    env = "jvl_gym/GearSync-v0"
    (tmp_path / "g.yml").write_text(
        f"{env}:\n  total_timesteps: 100\n  n_envs: 2\n  hyperparams: {{n_steps: 8}}\n"
        "  families:\n    mac050_141: {}\n"
        "    mac800:\n      total_timesteps: 300\n"
        "      algos: {SAC: {total_timesteps: 400, hyperparams: {buffer_size: 50}}}\n"
        "  algos: {SAC: {total_timesteps: 200, n_envs: 4, hyperparams: {buffer_size: 10}}}\n")
    got = {(f, a): rl_config(env, tmp_path, family=f, algo=a)
           for f in ("mac050_141", "mac800") for a in ("PPO", "SAC")}
    assert {k: (c["total_timesteps"], c["n_envs"], c["hyperparams"]) for k, c in got.items()} == {
        ("mac050_141", "PPO"): (100, 2, {"n_steps": 8}),
        ("mac050_141", "SAC"): (200, 4, {"buffer_size": 10}),
        ("mac800", "PPO"): (300, 2, {"n_steps": 8}),
        ("mac800", "SAC"): (400, 4, {"buffer_size": 50})}
    assert got[("mac800", "SAC")]["env_kwargs"] == {"motor_type": "MAC800"}
    for bad, words in [("{TD3: {}}", "TD3 is not one of PPO, SAC"),
                       ("{SAC: {gamma: 0.9}}", "unknown keys ['gamma']"),
                       ("[SAC]", "expected a mapping")]:
        (tmp_path / "g.yml").write_text(
            f"{env}:\n  families:\n    mac800:\n      algos: {bad}\n"
            "  algos: {SAC: {}}\n")
        with pytest.raises(ValueError, match="families: mac800") as info:
            rl_config(env, tmp_path, family="mac800")
        assert words in str(info.value)


@pytest.mark.parametrize("algo, hyper", [
    ("PPO", "{n_steps: 32, batch_size: 64, n_epochs: 1, policy_kwargs: {net_arch: [8]}}"),
    ("SAC", "{learning_starts: 32, batch_size: 16, buffer_size: 1000, gradient_steps: 2, "
            "policy_kwargs: {net_arch: [8]}}"),
])
def test_a_checkpoint_is_the_model_of_a_training_that_long(tmp_path, algo, hyper):
    """The checkpoint after n steps of a longer training equals a training of n steps."""
    import torch

    from jvl_gym.rl.train import algo_class, checkpoint_path, train

    env = "jvl_gym/Positioning-v0"
    cfg = tmp_path / "cfg"
    cfg.mkdir()
    (cfg / "p.yml").write_text(
        f"{env}:\n  algo: {algo}\n  n_envs: 4\n  total_timesteps: 384\n"
        f"  env_kwargs: {{max_episode_steps: 20}}\n  hyperparams: {hyper}\n")
    long = train(env, tmp_path / "long", progress_bar=False, config_dir=cfg,
                 checkpoint_every=256)
    short = train(env, tmp_path / "short", total_timesteps=256,
                  progress_bar=False, config_dir=cfg)
    ckpt = checkpoint_path(long, 256)
    assert ckpt.is_file() and not checkpoint_path(long, 128).exists()
    load = algo_class(algo).load
    a = load(ckpt, device="cpu").policy.state_dict()
    b = load(short, device="cpu").policy.state_dict()
    c = load(long, device="cpu").policy.state_dict()
    assert all(torch.equal(a[k], b[k]) for k in a)
    assert not all(torch.equal(a[k], c[k]) for k in a)
