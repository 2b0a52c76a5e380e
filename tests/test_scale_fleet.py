"""``jvl-tune fleet`` on a local Ray of 2 CPUs: the example fleet of 8 simulated motors as drawn,
and run as one motor of each of its four types (the example's groups with count 1)."""

from __future__ import annotations

import csv
import shutil
from pathlib import Path

import pytest

ray = pytest.importorskip("ray")

import yaml  # noqa: E402
from tuning.cli import app  # noqa: E402
from tuning.fleet_spec import load_fleet  # noqa: E402
from typer.testing import CliRunner  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "configs" / "fleets" / "example.yml"


def test_example_fleet_is_drawn_as_specified() -> None:
    spec = load_fleet(EXAMPLE)
    assert [m.type for m in spec.motors] == ["MAC050"] * 2 + ["MAC095"] * 2 + \
        ["MAC140"] * 2 + ["MAC141"] * 2
    assert len({m.motor_id for m in spec.motors}) == 8
    mac140 = [m for m in spec.motors if m.type == "MAC140"]
    assert all(1e-5 <= m.load_inertia <= 1.5e-4 for m in mac140)
    assert [m.load_inertia for m in load_fleet(EXAMPLE).motors] == \
        [m.load_inertia for m in spec.motors]  # the same seed draws the same fleet


def _one_of_each_type(tmp_path: Path) -> Path:
    """The example fleet file with one motor per group: every motor type of the example, with
    its distributions, noise, structure and move."""
    data = yaml.safe_load(EXAMPLE.read_text())
    for group in data["motors"]:
        group["count"] = 1
    path = tmp_path / "fleet.yml"
    path.write_text(yaml.safe_dump(data))
    return path


def test_fleet_of_each_motor_type(tmp_path: Path, local_ray: None) -> None:
    fleet = _one_of_each_type(tmp_path)
    out = tmp_path / "fleet"
    res = CliRunner().invoke(app, ["fleet", str(fleet), "--out", str(out), "--save-records"])
    assert res.exit_code == 0, res.output
    spec = load_fleet(fleet)
    assert [m.type for m in spec.motors] == ["MAC050", "MAC095", "MAC140", "MAC141"]
    for m in spec.motors:
        setup = yaml.safe_load((out / "motors" / m.motor_id / "setup.yaml").read_text())
        assert setup["motor"] == m.type
        assert {"KIFX2", "KVFX4", "KVOUT"} <= set(setup["registers"])
        assert (out / "motors" / m.motor_id / "report.txt").read_text().strip()
    rows = list(csv.DictReader((out / "fleet.csv").open()))
    assert [r["motor"] for r in rows] == [m.motor_id for m in spec.motors]
    for r, m in zip(rows, spec.motors):
        assert float(r["true_J"]) == pytest.approx(m.truth["J"])
        assert abs(float(r["J"]) / m.truth["J"] - 1) < 0.05, r
        assert r["checks"] == "ok"
        assert float(r["settle_tuned_s"]) > 0
    report = (out / "fleet.md").read_text()
    assert "credible identifications" in report and report.count("| m00") == 4
    assert (out / "fleet.png").read_bytes()[:4] == b"\x89PNG"

    # the saved records of two motors, as a records folder, identify the same J again
    folder = tmp_path / "records"
    for m in (spec.motors[0], spec.motors[-1]):
        shutil.copytree(out / "motors" / m.motor_id, folder / m.motor_id)
    res = CliRunner().invoke(app, ["fleet", str(folder), "--out", str(tmp_path / "again")])
    assert res.exit_code == 0, res.output
    again = {r["motor"]: r for r in csv.DictReader((tmp_path / "again" / "fleet.csv").open())}
    for r in (rows[0], rows[-1]):
        assert again[r["motor"]]["source"] == "records"
        assert float(again[r["motor"]]["J"]) == pytest.approx(float(r["J"]), rel=1e-9)
        assert float(again[r["motor"]]["true_J"]) == pytest.approx(float(r["true_J"]))
