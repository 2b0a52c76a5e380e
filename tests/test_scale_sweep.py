"""``jvl-gym sweep`` on a local Ray of 2 CPUs: a 4-trial sweep with a tiny budget, stopped
after its first finished trial and resumed."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest

ray = pytest.importorskip("ray")

from typer.testing import CliRunner  # noqa: E402

from jvl_gym.cli.main import app  # noqa: E402
from jvl_gym.scale.sweep import run_sweep  # noqa: E402
from jvl_gym.scale.sweep_spec import load_sweep  # noqa: E402

SWEEP = """
env: jvl_gym/GearSync-v0
search: grid
seeds: [0, 1]
parameters:
  hyperparams.learning_rate: [0.0003, 0.001]
budget: {timesteps: 2048, n_envs: 8}
resources: {cpus_per_trial: 1}
eval: {n_seeds: 2, episodes_per_seed: 2}
"""


def test_sweep_stops_resumes_and_reports(tmp_path: Path, local_ray: None) -> None:
    cfg = tmp_path / "sweep.yml"
    cfg.write_text(SWEEP)
    out = tmp_path / "out"
    spec = load_sweep(cfg)
    ids = [t.trial_id for t in spec.trials()]
    assert len(ids) == 4

    first = run_sweep(spec, out, max_concurrent=1, stop_after=1, progress=lambda _: None)
    assert first.finished == [ids[0]] and not first.complete
    entry = out / "trials" / ids[0] / "result.json"
    stamp = entry.stat().st_mtime_ns
    assert (out / "trials" / ids[0] / "GearSync-v0.zip").is_file()

    res = CliRunner().invoke(app, ["sweep", str(cfg), "--out", str(out)])
    assert res.exit_code == 0, res.output
    assert "1 finished earlier, 3 to run" in res.output
    assert entry.stat().st_mtime_ns == stamp  # the finished trial was not run again
    second_run = sorted(p.name for p in (out / "ray" / "run01").iterdir() if p.is_dir())
    assert second_run == ids[1:]

    rows = list(csv.DictReader((out / "results.csv").open()))
    assert [r["trial"] for r in rows] == ids
    assert {(float(r["hyperparams.learning_rate"]), int(r["seed"])) for r in rows} == {
        (lr, s) for lr in (0.0003, 0.001) for s in (0, 1)}
    for r in rows:
        assert int(r["n_seeds"]) == 2 and float(r["timesteps"]) >= 2048
        assert float(r["policy_std"]) >= 0 and float(r["baseline_std"]) >= 0
    table = (out / "results.md").read_text()
    assert table.count("| t00") == 4 and "learning_rate=0.001" in table
    png = (out / "learning_curves.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 10_000


def test_a_local_rays_workers_run_at_normal_priority(local_ray: None) -> None:
    """A local Ray's workers run at nice 0, not Ray's default 15: on a machine busy with other
    work (four busy processes on two cores) a nice-15 trial gets about 1 % of a core."""
    import os

    import ray

    @ray.remote
    def niceness() -> int:
        return os.nice(0)

    assert ray.get(niceness.remote(), timeout=300) == 0
