"""Envs of an identified motor (jvl_gym.envs.identified, docs/envs.md "Training for a measured
motor"): built from what ``jvl-tune autotune`` writes, refusing bad files in one line."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from jvl_gym.envs.identified import (
    IdentificationError,
    env_kwargs_from_identification,
    parse_report,
    read_identification,
)
from jvl_gym.envs.registration import vector_class

ROOT = Path(__file__).resolve().parents[1]
POS = "jvl_gym/Positioning-v0"
#: the simulated motor's hidden load: a MAC140 (J_m 17.3e-6 kg·m², rated 0.32 N·m)
LOAD, COULOMB, J_M, RATED = 5e-5, 0.004, 17.3e-6, 0.32


def _env() -> dict[str, str]:
    path = os.pathsep.join([str(ROOT / "src"), str(ROOT), os.environ.get("PYTHONPATH", "")])
    return {**os.environ, "PYTHONPATH": path}


@pytest.fixture(scope="module")
def autotuned(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """``jvl-tune autotune`` on a simulated MAC140 with a known load: its output folder."""
    out = tmp_path_factory.mktemp("autotune")
    subprocess.run([sys.executable, "-m", "tuning.cli", "autotune", "--motor", "MAC140",
                    "--load-inertia", str(LOAD), "--coulomb", str(COULOMB), "--n-coil", "32",
                    "--n-mech", "32", "--out", str(out)], check=True, env=_env(),
                   capture_output=True, text=True, timeout=600)
    return out



def test_identified_env_draws_within_the_intervals_that_hold_the_truth(autotuned: Path) -> None:
    kwargs = env_kwargs_from_identification(autotuned, POS)
    ranges = kwargs["randomization"]
    assert kwargs["motor_type"] == "MAC140"
    lo, hi = ranges["inertia_ratio"]
    assert lo <= LOAD / J_M <= hi and hi - lo < 0.5  # the identified interval, not the default
    c_lo, c_hi = ranges["coulomb_ratio"]
    assert c_lo <= COULOMB / RATED <= c_hi
    v_lo, v_hi = ranges["viscous_friction"]
    assert v_lo == 0.0 <= v_hi < 1e-4  # none simulated: not detected, [0, hi]
    env = vector_class(POS)(16, **kwargs)
    env.reset(seed=3)
    p = env.motors.parameters
    assert np.all((p["load_inertia"] >= lo * J_M - 1e-15) & (p["load_inertia"] <= hi * J_M + 1e-15))
    assert np.all((p["coulomb_friction"] >= c_lo * RATED - 1e-12)
                  & (p["coulomb_friction"] <= c_hi * RATED + 1e-12))
    assert np.ptp(p["load_inertia"]) > 0  # drawn, not fixed
    # the motors hold the written setup's loop registers after every reset
    written = read_identification(autotuned).registers
    for name in ("KVFX4", "KVFX3", "KIFX2", "KIFX1"):
        assert np.allclose(env.motors.read(name), written[name]), name
    env.reset(seed=4)
    assert np.allclose(env.motors.read("KVFX4"), written["KVFX4"])


def test_the_file_paths_of_one_autotune_give_one_env(autotuned: Path) -> None:
    by_dir = env_kwargs_from_identification(autotuned, POS)
    for name in ("report.txt", "setup.yaml"):
        assert env_kwargs_from_identification(autotuned / name, POS) == by_dir


def _copy(src: Path, dst: Path) -> Path:
    shutil.copytree(src, dst)
    return dst


@pytest.mark.parametrize("damage, words", [
    (lambda d: (d / "setup.yaml").unlink(), "no setup.yaml"),
    (lambda d: (d / "report.txt").write_text("Identified values\nnothing here\n"), "no row"),
    (lambda d: (d / "report.txt").write_bytes(b"\xff\xfe J"), "not UTF-8"),
    (lambda d: (d / "setup.yaml").write_text("motor: MAC140\nregisters:\n  NOPE: 1\n"),
     "NOPE"),
    (lambda d: (d / "setup.yaml").write_text("motor: MAC999\nregisters: {}\n"), "MAC999"),
    (lambda d: (d / "setup.yaml").write_text("registers: {KVOUT: 2.0}\n"), "motor"),
    (lambda d: (d / "setup.yaml").write_text("motor: [MAC140\n"), "setup.yaml"),
    (lambda d: (d / "report.txt").write_text(
        (d / "report.txt").read_text().replace("J total [kg m^2]    ", "J total [kg m^2]   -",
                                               1)), "J"),
])
def test_bad_files_are_refused_in_one_line(autotuned: Path, tmp_path: Path, damage,
                                           words: str) -> None:
    d = _copy(autotuned, tmp_path / "out")
    damage(d)
    with pytest.raises(IdentificationError) as err:
        env_kwargs_from_identification(d, POS)
    text = str(err.value)
    assert "\n" not in text and words in text


def test_a_report_larger_than_any_autotune_report_is_refused_by_its_size(
        autotuned: Path, tmp_path: Path, monkeypatch) -> None:
    from jvl_gym.envs import identified

    d = _copy(autotuned, tmp_path / "out")
    report = d / "report.txt"
    with report.open("ab") as f:  # a sparse tail: the size without the writing
        f.truncate(identified.MAX_REPORT_BYTES + 1)
    read = []
    monkeypatch.setattr(Path, "read_text", lambda self, *a, **k: read.append(self) or "")
    with pytest.raises(IdentificationError) as err:
        read_identification(d)
    text = str(err.value)
    assert "\n" not in text and f"{identified.MAX_REPORT_BYTES + 1} bytes" in text
    assert read == []  # refused unread


def test_a_missing_path_and_another_file_are_refused(tmp_path: Path) -> None:
    with pytest.raises(IdentificationError, match="not found"):
        read_identification(tmp_path / "nowhere")
    other = tmp_path / "notes.txt"
    other.write_text("J total [kg m^2] 1 [0, 2]\n")
    with pytest.raises(IdentificationError, match="not an autotune output"):
        read_identification(other)


def test_an_env_of_another_family_or_without_a_load_is_refused(autotuned: Path) -> None:
    with pytest.raises(IdentificationError, match="does not run on"):
        env_kwargs_from_identification(autotuned, "jvl_gym/StepperIndexing-v0")
    with pytest.raises(IdentificationError, match="unknown env"):
        env_kwargs_from_identification(autotuned, "jvl_gym/Nothing-v0")


def _row(label: str, value: float, lo: float, hi: float) -> str:
    """A row as ``tuning.report.identification_table`` writes it."""
    return f"{label:<24}{value:>14.5g}  {f'[{lo:.4g}, {hi:.4g}]':<30}{'':>12}"


def test_report_rows_parse_back_to_their_values() -> None:
    hypothesis = pytest.importorskip("hypothesis")
    st = hypothesis.strategies
    positive = st.floats(1e-9, 1e3, allow_nan=False)

    @hypothesis.given(positive, positive, positive, st.floats(0.0, 1.0), st.floats(0.0, 1.0))
    def check(j: float, b: float, tc: float, a: float, z: float) -> None:
        lo, hi = j * (1 - a / 2), j * (1 + a)
        text = "\n".join(["Identified values (95 % confidence intervals)",
                          _row("J total [kg m^2]", j, lo, hi),
                          _row("viscous b [N m s/rad]", b, 0.0, b * (1 + z)),
                          _row("Coulomb Tc [N m]", tc, tc * (1 - z / 2), tc * (1 + z))])
        got = parse_report(text)
        assert got["inertia"][0] == pytest.approx(j, rel=1e-4)
        assert got["inertia"][1] == pytest.approx(lo, rel=1e-3)
        assert got["inertia"][2] == pytest.approx(hi, rel=1e-3)
        assert got["coulomb"][0] == pytest.approx(tc, rel=1e-4)
        assert got["resonance"] is None

    check()


def test_any_text_is_parsed_or_refused_with_identification_error() -> None:
    hypothesis = pytest.importorskip("hypothesis")
    st = hypothesis.strategies
    line = st.one_of(st.text(max_size=60),
                     st.builds(lambda lab, v, lo, hi: f"{lab}  {v}  [{lo}, {hi}]",
                               st.sampled_from(["J total [kg m^2]", "viscous b [N m s/rad]",
                                                "Coulomb Tc [N m]"]),
                               st.floats(), st.floats(), st.floats()))

    @hypothesis.given(st.lists(line, max_size=6))
    def check(lines: list[str]) -> None:
        try:
            got = parse_report("\n".join(lines))
        except IdentificationError as exc:
            assert "\n" not in str(exc)
            return
        j, lo, hi = got["inertia"]
        assert 0 < j and lo <= hi

    check()


def test_cli_trains_on_the_identified_env_and_refuses_a_bad_file(autotuned: Path,
                                                                   tmp_path: Path) -> None:
    cfg = tmp_path / "rl"
    cfg.mkdir()
    (cfg / "positioning.yml").write_text(
        "jvl_gym/Positioning-v0:\n  algo: PPO\n  n_envs: 2\n  total_timesteps: 256\n"
        "  seed: 0\n  env_kwargs: {}\n  hyperparams: {n_steps: 64, batch_size: 64, "
        "n_epochs: 1}\n")
    runs = tmp_path / "runs"
    base = [sys.executable, "-m", "jvl_gym.cli", "train", POS, "--config-dir", str(cfg),
            "--timesteps", "256", "--link", "mactalk-tcp:10ms,max_step=0.5"]
    bad = subprocess.run([*base, "--out", str(runs), "--identified", str(tmp_path / "none")],
                         env=_env(), capture_output=True, text=True, timeout=300)
    assert bad.returncode != 0 and "--identified" in bad.stderr
    assert len(bad.stderr.strip().splitlines()) == 1 and not runs.exists()
    done = subprocess.run([*base, "--out", str(runs), "--identified", str(autotuned)],
                          env=_env(), capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    assert (runs / "Positioning-v0-mac050_141-ppo.zip").is_file()


def test_cli_evaluates_on_the_identified_env(autotuned: Path, tmp_path: Path) -> None:
    # no model in --runs: the shipped policy, against the baseline on the identified env
    scored = subprocess.run([sys.executable, "-m", "jvl_gym.cli", "evaluate", POS, "--runs",
                             str(tmp_path), "--seeds", "1", "--episodes", "2", "--identified",
                             str(autotuned)], env=_env(), capture_output=True, text=True,
                            timeout=300)
    assert scored.returncode == 0, scored.stderr[-2000:]
    assert "| jvl_gym/Positioning-v0 |" in scored.stdout
    bad = subprocess.run([sys.executable, "-m", "jvl_gym.cli", "evaluate", POS, "--runs",
                          str(tmp_path), "--identified", str(tmp_path)], env=_env(),
                         capture_output=True, text=True, timeout=300)
    assert bad.returncode != 0 and len(bad.stderr.strip().splitlines()) == 1
    assert "no report.txt" in bad.stderr


def test_deploy_option_refuses_another_motor_type(autotuned: Path) -> None:
    from jvl_gym.cli.main import app

    res = CliRunner().invoke(app, ["deploy", POS, "--identified", str(autotuned),
                                   "--motor", "MAC050"])
    assert res.exit_code != 0 and "is a MAC140, not --motor MAC050" in str(res.exception)


def test_a_result_in_memory_gives_the_env_its_files_give(autotuned: Path) -> None:
    from types import SimpleNamespace

    from jvl_gym.envs.identified import identification_of

    read = read_identification(autotuned)
    (j, *ci_j), (b, *ci_b), (tc, *ci_tc) = read.inertia, read.viscous, read.coulomb
    mech = SimpleNamespace(J=j, viscous=b, coulomb=tc,
                           ci={"J": tuple(ci_j), "viscous": tuple(ci_b), "coulomb": tuple(ci_tc)})
    result = SimpleNamespace(ident=SimpleNamespace(motor=SimpleNamespace(name="MAC140"),
                                                   mechanics=mech),
                             chosen=SimpleNamespace(registers=read.registers))
    assert (env_kwargs_from_identification(result, POS)
            == env_kwargs_from_identification(autotuned, POS))
    assert identification_of(result).registers == read.registers
    with pytest.raises(IdentificationError, match="not an identification"):
        identification_of(SimpleNamespace(motor=SimpleNamespace(name="MAC140")))


def test_a_mac800_setup_gives_a_mac800_env(autotuned: Path, tmp_path: Path) -> None:
    d = _copy(autotuned, tmp_path / "out")
    (d / "setup.yaml").write_text("motor: MAC800\nregisters:\n  KVOUT: 2.0\n")
    kwargs = env_kwargs_from_identification(d, POS)
    assert kwargs["motor_type"] == "MAC800"
    assert kwargs["setup"]["registers"]["KVOUT"] == 2.0
    env = vector_class(POS)(2, **kwargs)
    assert env.family_key == "mac800"
    with pytest.raises(IdentificationError, match="does not run on the MAC800"):
        env_kwargs_from_identification(d, "jvl_gym/CoilWinding-v0")


def test_deploy_draws_its_episodes_from_the_identified_env_of_that_motor(autotuned: Path) -> None:
    from jvl_gym.rl.deploy import deploy

    kwargs = env_kwargs_from_identification(autotuned, POS)
    with pytest.raises(ValueError, match="not the motor's"):  # before any connection
        deploy(POS, lambda obs: obs[:, :1] * 0, "socket://127.0.0.1:9", 1, "MAC050",
               period=0.01, env_kwargs=kwargs)


#: the two-mass section of ``jvl-tune autotune --resonance`` (a MAC140 with 5e-5 kg·m² behind
#: a coupling of 20 N·m/rad: 198.5 Hz)
TWO_MASS = ("\nTwo-mass load (tuning.identify_resonance, tuning.resonance_design)\n"
            "  resonance 198.4 Hz (95 % 195.1 .. 201.7), anti-resonance 100.5 Hz, load ratio "
            "J_l/J_m 2.89, damping ratio 0.067, detected {detected}\n"
            "  as recorded under the current loop: 194.9 Hz, damping ratio 0.084\n")


def test_a_detected_two_mass_resonance_puts_the_load_behind_its_coupling(autotuned: Path,
                                                                         tmp_path: Path) -> None:
    d = _copy(autotuned, tmp_path / "out")
    report = (d / "report.txt").read_text()
    (d / "report.txt").write_text(report + TWO_MASS.format(detected=True))
    kwargs = env_kwargs_from_identification(d, POS)
    assert kwargs["randomization"]["resonance_hz"] == (195.1, 201.7)
    assert kwargs["randomization"]["coupling_damping_ratio"] == (0.067, 0.067)
    env = vector_class(POS)(8, **kwargs)
    env.reset(seed=0)
    p = env.motors.parameters
    f = np.sqrt(p["coupling_stiffness"] * (1 / J_M + 1 / p["load_inertia"])) / (2 * np.pi)
    assert np.all((f > 195.1 - 1e-6) & (f < 201.7 + 1e-6))
    (d / "report.txt").write_text(report + TWO_MASS.format(detected=False))
    assert "resonance_hz" not in env_kwargs_from_identification(d, POS)["randomization"]
