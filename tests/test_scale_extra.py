"""The scale commands without Ray, and their one-line errors on bad input."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest
from tuning.cli import app as tune_app
from typer.testing import CliRunner

from jvl_gym.cli import app as gym_app
from jvl_gym.scale.errors import UserError
from jvl_gym.scale.sweep_spec import parse_sweep

ROOT = Path(__file__).resolve().parents[1]


def _lines(text: str) -> list[str]:
    return [ln for ln in text.splitlines() if ln.strip()]


@pytest.mark.parametrize("app, args", [
    (gym_app, ["sweep", str(ROOT / "configs/sweeps/example.yml")]),
    (tune_app, ["fleet", str(ROOT / "configs/fleets/example.yml")]),
])
def test_missing_extra_is_one_line(monkeypatch: pytest.MonkeyPatch, tmp_path: Path, app, args
                                   ) -> None:
    monkeypatch.setitem(sys.modules, "ray", None)  # `import ray` raises ImportError
    res = CliRunner().invoke(app, [*args, "--out", str(tmp_path / "out")])
    assert res.exit_code != 0
    lines = _lines(res.output)
    assert len(lines) == 1, res.output
    assert "pip install -e '.[scale]'" in lines[0]
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("body, fragment", [
    ("env: jvl_gym/NoSuch-v0\nparameters: {}\n", "unknown env id 'jvl_gym/NoSuch-v0'"),
    ("env: jvl_gym/GearSync-v0\nparameters:\n  hyperparams.learnin_rate: [0.1]\n",
     "PPO has no argument 'learnin_rate'"),
    ("env: jvl_gym/GearSync-v0\nparameters:\n  gamma: [0.9]\n", "use n_envs, hyperparams."),
    ("env: jvl_gym/GearSync-v0\nparameters:\n  env_kwargs.decimaton: [1, 2]\n",
     "takes no argument 'decimaton'"),
    ("env: jvl_gym/GearSync-v0\nsearch: random\nparameters:\n"
     "  hyperparams.learning_rate: {logunif: [1, 2]}\nsamples: 2\n", "unknown distribution"),
    ("env: jvl_gym/GearSync-v0\nbudget: {steps: 10}\n", "budget: unknown keys ['steps']"),
    ("env: [unclosed\n", "is not valid YAML"),
])
def test_bad_sweep_file_is_one_line(tmp_path: Path, body: str, fragment: str) -> None:
    path = tmp_path / "bad.yml"
    path.write_text(body)
    res = CliRunner().invoke(gym_app, ["sweep", str(path), "--out", str(tmp_path / "out")])
    assert res.exit_code == 2
    lines = _lines(res.output)
    assert len(lines) == 1 and fragment in lines[0] and str(path) in lines[0], res.output


@pytest.mark.parametrize("body, fragment", [
    ("motors:\n  - {type: MAC999, count: 2}\n", "is not a motor type"),
    ("motors:\n  - {type: MAC140, count: 0}\n", "count: expected an integer >= 1"),
    ("motors:\n  - {type: MAC140, count: 20, coulomb: {normal: [0, 1]}}\n",
     "values must be numbers >= 0"),
    ("motors:\n  - {type: MAC140, load_ratio: 1, load_inertia: 1e-5}\n", "not both"),
    ("motor: []\n", "unknown keys ['motor']"),
])
def test_bad_fleet_file_is_one_line(tmp_path: Path, body: str, fragment: str) -> None:
    path = tmp_path / "bad.yml"
    path.write_text(body)
    res = CliRunner().invoke(tune_app, ["fleet", str(path), "--out", str(tmp_path / "out")])
    assert res.exit_code == 2
    lines = _lines(res.output)
    assert len(lines) == 1 and fragment in lines[0] and str(path) in lines[0], res.output


def test_bad_paths_are_one_line(tmp_path: Path) -> None:
    res = CliRunner().invoke(gym_app, ["sweep", str(tmp_path / "none.yml")])
    assert res.exit_code == 2 and len(_lines(res.output)) == 1
    assert "no such sweep file" in res.output
    empty = tmp_path / "records"
    empty.mkdir()
    res = CliRunner().invoke(tune_app, ["fleet", str(empty)])
    assert res.exit_code == 2 and len(_lines(res.output)) == 1
    assert "no subfolders with record CSVs" in res.output


def test_debug_shows_the_exception(tmp_path: Path) -> None:
    res = CliRunner().invoke(gym_app, ["sweep", str(tmp_path / "none.yml"), "--debug"])
    assert res.exit_code != 0 and isinstance(res.exception, UserError)


def test_grid_and_random_trials_are_stable() -> None:
    grid = parse_sweep({"env": "jvl_gym/GearSync-v0", "seeds": [0, 1],
                        "parameters": {"hyperparams.learning_rate": [1e-4, 3e-4],
                                       "hyperparams.n_epochs": [5, 10]}})
    trials = grid.trials()
    assert len(trials) == 8
    assert len({t.trial_id for t in trials}) == 8
    assert {(t.params["hyperparams.n_epochs"], t.seed) for t in trials} == {
        (e, s) for e in (5, 10) for s in (0, 1)}
    rnd = {"env": "jvl_gym/GearSync-v0", "search": "random", "samples": 3, "sampler_seed": 4,
           "parameters": {"hyperparams.learning_rate": {"loguniform": [1e-5, 1e-3]},
                          "hyperparams.n_epochs": [3, 5]}}
    a, b = parse_sweep(rnd).trials(), parse_sweep(rnd).trials()
    assert [t.trial_id for t in a] == [t.trial_id for t in b]
    assert all(1e-5 <= t.params["hyperparams.learning_rate"] <= 1e-3 for t in a)
    with pytest.raises(UserError, match="budget.timesteps"):
        parse_sweep({"env": "jvl_gym/GearSync-v0", "budget": {"timesteps": 0}})
