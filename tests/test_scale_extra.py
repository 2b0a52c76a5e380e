"""The scale commands without Ray, and their one-line errors on bad input."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest
from tuning.cli import app as tune_app

from jvl_gym.cli.app import CliError
from jvl_gym.cli.main import app as gym_app
from jvl_gym.scale.errors import UserError
from jvl_gym.scale.sweep_spec import parse_sweep

ROOT = Path(__file__).resolve().parents[1]


def _run(app, args: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str]:
    """Run a command line as the installed script does; (exit status, stderr)."""
    with pytest.raises(SystemExit) as info:
        app(args)
    return info.value.code, capsys.readouterr().err


def _one_line(code: int, err: str) -> str:
    assert code not in (0, None)
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1, err
    assert "Traceback" not in err
    return lines[0]


@pytest.mark.parametrize("app, args", [
    (gym_app, ["sweep", str(ROOT / "configs/sweeps/example.yml")]),
    (tune_app, ["fleet", str(ROOT / "configs/fleets/example.yml")]),
])
def test_missing_extra_is_one_line(monkeypatch: pytest.MonkeyPatch, tmp_path: Path,
                                   capsys: pytest.CaptureFixture[str], app, args) -> None:
    monkeypatch.setitem(sys.modules, "ray", None)  # `import ray` raises ImportError
    code, err = _run(app, [*args, "--out", str(tmp_path / "out")], capsys)
    assert "pip install -e '.[scale]'" in _one_line(code, err)
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
    ("env: jvl_gym/GearSync-v0\nresources: {cpus_per_trial: .nan}\n",
     "resources.cpus_per_trial: expected a finite number, got nan"),
    ("env: jvl_gym/GearSync-v0\nresources: {cpus_per_trial: .inf}\n",
     "resources.cpus_per_trial: expected a finite number, got inf"),
    ("env: jvl_gym/GearSync-v0\nsampler_seed: 1.5\n",
     "sampler_seed: expected an integer >= 0, got 1.5"),
    ("env: jvl_gym/GearSync-v0\nsampler_seed: x\n",
     "sampler_seed: expected an integer >= 0, got 'x'"),
])
def test_bad_sweep_file_is_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                    body: str, fragment: str) -> None:
    path = tmp_path / "bad.yml"
    path.write_text(body)
    code, err = _run(gym_app, ["sweep", str(path), "--out", str(tmp_path / "out")], capsys)
    line = _one_line(code, err)
    assert line.startswith("jvl-gym sweep: error: ") and fragment in line and str(path) in line


@pytest.mark.parametrize("body, fragment", [
    ("motors:\n  - {type: MAC999, count: 2}\n", "is not a motor type"),
    ("motors:\n  - {type: MAC140, count: 0}\n", "count: expected an integer >= 1"),
    ("motors:\n  - {type: MAC140, count: 20, coulomb: {normal: [0, 1]}}\n",
     "values must be finite numbers >= 0"),
    ("motors:\n  - {type: MAC140, load_ratio: 1, load_inertia: 1e-5}\n", "not both"),
    ("motor: []\n", "unknown keys ['motor']"),
    ("noise: 'false'\nmotors:\n  - {type: MAC140}\n", "noise: expected true or false, got 'false'"),
    ("motors:\n  - {type: MAC140, coulomb: true}\n", "coulomb: expected a number, got True"),
    ("move: {distance: true}\nmotors:\n  - {type: MAC140}\n",
     "move.distance: expected a finite number, got True"),
    ("move: {seconds: .inf}\nmotors:\n  - {type: MAC140}\n",
     "move.seconds: expected a finite number, got inf"),
    ("motors:\n  - {type: MAC140, viscous: .nan}\n", "viscous: nan is not a finite number"),
    ("motors:\n  - {type: MAC140, load_inertia: .inf}\n",
     "load_inertia: inf is not a finite number"),
    ("motors:\n  - {type: MAC140, load_ratio: {uniform: [0, .inf]}}\n",
     "load_ratio: inf is not a finite number"),
])
def test_bad_fleet_file_is_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                    body: str, fragment: str) -> None:
    path = tmp_path / "bad.yml"
    path.write_text(body)
    code, err = _run(tune_app, ["fleet", str(path), "--out", str(tmp_path / "out")], capsys)
    line = _one_line(code, err)
    assert line.startswith("jvl-tune fleet: error: ") and fragment in line and str(path) in line


def test_bad_paths_are_one_line(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code, err = _run(gym_app, ["sweep", str(tmp_path / "none.yml")], capsys)
    assert "no such sweep file" in _one_line(code, err)
    empty = tmp_path / "records"
    empty.mkdir()
    code, err = _run(tune_app, ["fleet", str(empty)], capsys)
    assert "no subfolders with record CSVs" in _one_line(code, err)


def test_debug_shows_the_exception(tmp_path: Path) -> None:
    with pytest.raises(CliError) as info:
        gym_app(["--debug", "sweep", str(tmp_path / "none.yml")])
    assert isinstance(info.value.__cause__, UserError)


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
