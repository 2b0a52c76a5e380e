"""Command lines: every error is one line on stderr with a non-zero exit status (the
traceback only with --debug); train/evaluate say what is missing; verify reads the motor from
the setup."""

from __future__ import annotations

import sys

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from tuning.cli import app as tune

from cli_checks import one_line_error, run_cli
from jvl_gym.cli.demo import main as demo_main
from jvl_gym.cli.main import app as gym_cli
from jvl_gym.families.config import ConfigError
from jvl_gym.families.mac050_141.config import SETUPS_DIR
from jvl_gym.scale.rllib import main as rllib_main

_run = run_cli
_one_line_error = one_line_error


def test_unknown_motor_is_one_line(capsys):
    code, _, err = _run(tune, ["autotune", "--motor", "MAC999"], capsys)
    line = _one_line_error(code, err)
    assert "MAC999" in line and "MAC140" in line


def test_debug_shows_the_exception(capsys):
    with pytest.raises(Exception) as info:  # the option's usage error, from the ConfigError
        tune(["--debug", "autotune", "--motor", "MAC999"])
    assert isinstance(info.value, ConfigError) or isinstance(info.value.__cause__, ConfigError)


def test_usage_error_is_one_line(capsys):
    code, _, err = _run(tune, ["synthesize", "--inertia", "1e-4"], capsys)
    assert code == 2
    assert "--motor" in _one_line_error(code, err)


@pytest.mark.parametrize("args", [["synthesize", "--motor", "MAC140", "--inertia", "nan"],
                                  ["synthesize", "--motor", "MAC140", "--inertia", "-1"],
                                  ["autotune", "--load-inertia", "inf"],
                                  ["synthesize", "--motor", "MAC140", "--inertia", "1e-4",
                                   "--speed-bw", "nan"]])
def test_nan_options_are_one_line(capsys, args):
    code, _, err = _run(tune, args, capsys)
    _one_line_error(code, err)


@pytest.mark.parametrize("args", [["autotune", "--out", "/proc/x"],
                                  ["fleet", "configs/fleets/example.yml", "--out", "/proc/x"]])
def test_unwritable_out_is_refused_before_the_run(capsys, args):
    code, _, err = _run(tune, args, capsys)
    line = _one_line_error(code, err)
    assert "/proc/x" in line and "--out" in line and "writable directory" in line


@pytest.mark.parametrize(("cli", "args"), [
    pytest.param(gym_cli, ["train", "jvl_gym/GearSync-v0"], id="train"),
    pytest.param(gym_cli, ["evaluate", "--all"], id="evaluate"),
    pytest.param(gym_cli, ["sweep", "configs/sweeps/none.yml"], id="sweep"),
    pytest.param(gym_cli, ["program", "run", "program.txt"], id="program"),
    pytest.param(tune, ["defaults"], id="defaults"),
])
@pytest.mark.parametrize("where", ["/proc/x", "/proc/x/y", "file"])
def test_every_output_directory_is_checked_before_the_run(tmp_path, capsys, cli, args, where):
    """Every command that writes an output directory refuses one it cannot write (a usage
    error naming it) before doing anything, and creates nothing."""
    if where == "file":
        where = str(tmp_path / "plain")
        (tmp_path / "plain").write_text("")
    code, _, err = _run(cli, [*args, "--out", where], capsys)
    line = _one_line_error(code, err)
    assert code == 2 and where in line and "--out" in line and "directory" in line
    assert [p.name for p in tmp_path.iterdir()] == (["plain"] if "plain" in where else [])


@pytest.mark.parametrize("main", [demo_main, rllib_main], ids=["demo", "rllib"])
@pytest.mark.parametrize("where", ["/proc/x", "/proc/x/y", "file"])
def test_module_entry_points_check_their_output_directory_first(tmp_path, capsys, main, where):
    """``python -m jvl_gym.demo`` and ``python -m jvl_gym.scale.rllib`` refuse an ``--out``
    they cannot write as a one-line usage error (exit status 2) before any motor or Ray runs,
    and create nothing."""
    if where == "file":
        where = str(tmp_path / "plain")
        (tmp_path / "plain").write_text("")
    with pytest.raises(SystemExit) as exc:
        main(["--out", where])
    err = capsys.readouterr().err.strip().splitlines()
    assert exc.value.code == 2 and "--out" in err[-1] and where in err[-1]
    assert [p.name for p in tmp_path.iterdir()] == (["plain"] if "plain" in where else [])


def test_errors_name_the_whole_subcommand(tmp_path, capsys):
    """An error of a nested command names the command as typed (``jvl-gym program run``)."""
    code, _, err = _run(gym_cli, ["program", "run", str(tmp_path / "missing.txt")], capsys)
    line = _one_line_error(code, err)
    assert line.startswith("jvl-gym program run: error:") and "missing.txt" in line


@pytest.mark.parametrize("where", ["/proc/x", "/proc/x/y/setup.yaml", "dir"])
def test_synthesize_output_file_is_checked_before_the_design(tmp_path, capsys, where):
    """``jvl-tune synthesize --out FILE`` refuses a file it could not write (a directory, a
    place no file can be made) before designing, and creates nothing."""
    if where == "dir":
        where = str(tmp_path / "d")
        (tmp_path / "d").mkdir()
    code, _, err = _run(tune, ["synthesize", "--motor", "MAC140", "--inertia", "1e-4",
                               "--out", where], capsys)
    line = _one_line_error(code, err)
    assert code == 2 and where in line and "--out" in line
    assert [p.name for p in tmp_path.iterdir()] == (["d"] if where.endswith("/d") else [])
    assert not any((tmp_path / "d").iterdir()) if where.endswith("/d") else True


def test_list_shaped_and_partial_setups(tmp_path, capsys):
    bad = tmp_path / "list.yaml"
    bad.write_text("- 1\n- 2\n")
    code, _, err = _run(tune, ["verify", "--motor", "MAC140", "--setup", str(bad)], capsys)
    assert "list.yaml" in _one_line_error(code, err)
    ro = tmp_path / "ro.yaml"
    ro.write_text("motor: MAC140\nregisters:\n  V_IST: 5\n")
    code, _, err = _run(tune, ["verify", "--setup", str(ro)], capsys)
    assert "V_IST" in _one_line_error(code, err)
    partial = tmp_path / "partial.yaml"
    partial.write_text("motor: MAC140\nregisters:\n  KVOUT: 2.0\n")
    code, out, err = _run(tune, ["verify", "--setup", str(partial)], capsys)
    assert code == 0, err
    assert "all stable True" in out
    assert "defaults" in err


def test_verify_reads_the_motor_from_the_setup(tmp_path, capsys):
    setup = tmp_path / "setup.yaml"
    data = yaml.safe_load((SETUPS_DIR / "MAC095.yaml").read_text())
    data["motor"] = "MAC095"
    setup.write_text(yaml.safe_dump(data))
    code, out, err = _run(tune, ["verify", "--setup", str(setup)], capsys)
    assert code == 0, err
    assert "current: PM" in out
    code, _, err = _run(tune, ["verify", "--motor", "MAC140", "--setup", str(setup)], capsys)
    assert "MAC095" in _one_line_error(code, err)
    del data["motor"]
    setup.write_text(yaml.safe_dump(data))
    code, _, err = _run(tune, ["verify", "--setup", str(setup)], capsys)
    assert "--motor" in _one_line_error(code, err)


def test_train_without_the_rl_extra_says_how_to_get_it(monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "stable_baselines3", None)
    monkeypatch.setitem(sys.modules, "torch", None)
    code, _, err = _run(gym_cli, ["train", "jvl_gym/GearSync-v0"], capsys)
    line = _one_line_error(code, err)
    assert "RL extra" in line and "pip install" in line


def test_evaluate_without_a_model_says_so(monkeypatch, tmp_path, capsys):
    import jvl_gym.rl.evaluate as ev
    import jvl_gym.rl.train as tr

    monkeypatch.setattr(tr, "SHIPPED_DIR", tmp_path / "no_policies")

    monkeypatch.setattr(ev, "evaluate", lambda env_id, path, *a, **k: {"baseline": (1.0, 0.5)})
    code, out, err = _run(gym_cli, ["evaluate", "jvl_gym/GearSync-v0", "--runs",
                                    str(tmp_path)], capsys)
    line = _one_line_error(code, err)
    assert "GearSync" in line and "jvl-gym train" in line
    assert "1.00 ± 0.50" in out


def test_unknown_env_is_one_line(capsys):
    code, _, err = _run(gym_cli, ["evaluate", "jvl_gym/NoSuch-v0"], capsys)
    _one_line_error(code, err)


def _testa_files(tmp_path, pairs):
    from tuning.models import MotorData
    from tuning.records import save_csv, simulate_testa

    md = MotorData.from_config("MAC140")
    return [str(save_csv(simulate_testa(md, j, t, 30), tmp_path / f"a{k}.csv"))
            for k, (j, t) in enumerate(pairs)]


def test_identify_flags_estimates_that_are_not_credible(tmp_path, capsys):
    files = _testa_files(tmp_path, [(2e-5, 100), (4e-4, 200)])  # two different loads
    args = ["identify", "--motor", "MAC140", "--testa", files[0], "--testa", files[1]]
    code, out, err = _run(tune, args, capsys)
    assert code == 1
    # J is not detected (its interval reaches zero) and the fit is poor: both are named
    assert "NOT CREDIBLE" in err and "J = 0 is not positive" in err and "fit" in err
    assert "Tc not detected" in out and "Tc -" not in out
    code, out, err = _run(tune, [*args, "--accept"], capsys)
    assert code == 0 and "NOT CREDIBLE" in err


def test_identify_of_consistent_records_is_credible(tmp_path, capsys):
    files = _testa_files(tmp_path, [(1e-4, 20), (1e-4, 40)])
    code, out, err = _run(tune, ["identify", "--motor", "MAC140", "--testa", files[0],
                                 "--testa", files[1]], capsys)
    assert code == 0, err
    assert "NOT CREDIBLE" not in err
    assert "b not detected" in out  # the estimate is slightly negative: no viscous friction


def test_identify_needs_records_and_a_readable_setup(tmp_path, capsys):
    code, _, err = _run(tune, ["identify", "--motor", "MAC140"], capsys)
    assert "--testu" in _one_line_error(code, err)
    files = _testa_files(tmp_path, [(1e-4, 20), (1e-4, 40)])
    bad = tmp_path / "list.yaml"
    bad.write_text("- 1\n")
    code, _, err = _run(tune, ["identify", "--motor", "MAC140", "--testa", files[0],
                               "--setup", str(bad)], capsys)
    assert "list.yaml" in _one_line_error(code, err)


@pytest.mark.parametrize("args", [["train", "jvl_gym/GearSync-v0", "--timesteps", "0"],
                                  ["train", "jvl_gym/GearSync-v0", "--threads", "0"],
                                  ["evaluate", "jvl_gym/GearSync-v0", "--seeds", "0"]])
def test_counts_must_be_positive(capsys, args):
    code, _, err = _run(gym_cli, args, capsys)
    assert code == 2
    _one_line_error(code, err)


def test_evaluate_uses_a_shipped_policy_when_runs_has_none(monkeypatch, tmp_path, capsys):
    import jvl_gym.rl.evaluate as ev
    import jvl_gym.rl.train as tr

    shipped = tmp_path / "policies"
    shipped.mkdir()
    (shipped / "GearSync-v0-mac050_141-ppo.zip").write_bytes(b"model")
    monkeypatch.setattr(tr, "SHIPPED_DIR", shipped)
    used = []

    def fake(env_id, path, *a, **k):
        used.append(path)
        return {"baseline": (1.0, 0.5), "policy": (2.0, 0.1), "seeds_won": (5.0, 5.0)}

    monkeypatch.setattr(ev, "evaluate", fake)
    code, out, err = _run(gym_cli, ["evaluate", "jvl_gym/GearSync-v0", "--runs",
                                    str(tmp_path / "runs")], capsys)
    assert code == 0
    assert used == [shipped / "GearSync-v0-mac050_141-ppo.zip"]
    assert "shipped" in err and "2.00 ± 0.10" in out


def test_the_trained_policies_ship_with_the_package():
    from jvl_gym.rl.train import shipped_model

    for env_id in ("jvl_gym/GearSync-v0", "jvl_gym/CoilWinding-v0",
                   "jvl_gym/StepperIndexing-v0"):
        path = shipped_model(env_id)
        assert path is not None and 10_000 < path.stat().st_size < 1_000_000


def _inconsistent_identification():
    from tuning.autotune import Identification
    from tuning.identify_coil import identify_coil
    from tuning.identify_mechanics import identify_mechanics
    from tuning.models import MotorData
    from tuning.records import simulate_testa, simulate_testu

    md = MotorData.from_config("MAC140")
    coil = identify_coil(simulate_testu(md, 100, 64), md)
    recs = [simulate_testa(md, 2e-5, 100, 30), simulate_testa(md, 4e-4, 200, 30)]
    return Identification(md, coil, identify_mechanics(recs, md), recs)


def test_autotune_refuses_an_identification_that_is_not_credible(capsys):
    import typer
    from tuning.cli import _check_credible
    from tuning.strategy import strategy_of

    ident = _inconsistent_identification()
    strategy = strategy_of("MAC140")
    with pytest.raises(typer.Exit):
        _check_credible(strategy, ident, accept=False)
    assert "NOT CREDIBLE" in capsys.readouterr().err
    _check_credible(strategy, ident, accept=True)


def test_report_prints_negative_friction_as_not_detected():
    from tuning.report import identification_table
    from tuning.strategy import strategy_of

    ident = _inconsistent_identification()
    # the fit's Coulomb friction is negative; the identification reports it as 0, not detected
    assert ident.mechanics.raw["coulomb"] < 0 and ident.mechanics.coulomb == 0.0
    assert not ident.mechanics.detected["coulomb"]
    table = identification_table(strategy_of("MAC140"), ident)
    row = [ln for ln in table if ln.startswith("Coulomb Tc")][0]
    assert "not detected" in row


@settings(max_examples=20, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(option=st.sampled_from(["--n-coil", "--n-mech"]), value=st.integers(-2**70, 0))
def test_record_lengths_below_one_are_usage_errors(capsys, option, value):
    """A record of no samples or fewer is refused before the motor is touched (not taken as
    "the default")."""
    code, _, err = _run(tune, ["autotune", option, str(value)], capsys)
    assert code == 2 and option in _one_line_error(code, err)


_BAD_SETUPS = {
    "yaml": "motor: MAC140\nregisters: {KVOUT: [1\n",
    "bytes": b"\xff\xfe motor",
    "list": "- 1\n",
    "registers": "motor: MAC140\nregisters: 5\n",
    "key": "motor: MAC140\nfoo: 1\nregisters: {}\n",
    "value": "motor: MAC800\nregisters: {KVOUT: abc}\n",
}


@pytest.mark.parametrize("motor", [[], ["--motor", "MAC140"], ["--motor", "MAC800"]])
@pytest.mark.parametrize("kind", [*_BAD_SETUPS, "missing", "folder"])
def test_verify_reads_the_setup_through_the_config_loader(tmp_path, capsys, kind, motor):
    """A malformed setup file is a usage error naming the file and --setup, whatever the
    motor (the loader of jvl_gym.config reads it, as everywhere else)."""
    setup = tmp_path / "s.yaml"
    if kind == "folder":
        setup.mkdir()
    elif kind != "missing":
        data = _BAD_SETUPS[kind]
        if isinstance(data, bytes):
            setup.write_bytes(data)
        else:
            setup.write_text(data)
    code, _, err = _run(tune, ["verify", *motor, "--setup", str(setup)], capsys)
    line = _one_line_error(code, err)
    assert code == 2 and "s.yaml" in line and "--setup" in line, line


@settings(max_examples=25, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(text=st.text(max_size=60))
def test_verify_of_any_setup_text_is_a_result_or_one_line(tmp_path, capsys, text):
    setup = tmp_path / "any.yaml"
    setup.write_text(text, encoding="utf-8")
    code, _, err = _run(tune, ["verify", "--motor", "MAC140", "--setup", str(setup)], capsys)
    if code not in (0, None):
        line = _one_line_error(code, err)
        assert "any.yaml" in line or "--setup" in line, line
