"""Ray throughput (``make bench``): prints its figures, asserts nothing.

- sweep throughput: the same 4-trial sweep (PPO on GearSync-v0, ``--timesteps`` env steps per
  trial, 16 copies of the native vector env, 1 CPU per trial, evaluation on 2 held-out seeds
  x 2 episodes) run with 1 and with 2 trials at once on a local Ray of 2 CPUs; trials per hour
  = 4 / wall time (Ray's start excluded; the workers' start, which each run pays, included),
  the training env-steps/s of one trial (PPO updates included, one core) and its CPU time
  (trials per core-hour: independent of other jobs on the machine, which Ray's workers, at
  nice 15, yield to);
- fleet throughput (``--motors N``, 0 to skip): N simulated motors autotuned as Ray tasks on
  2 CPUs; motors tuned per hour and per core-hour.

    python benchmarks/bench_scale.py [--timesteps 100000] [--motors 4]

The figures also go to the generated page ``docs/benchmarks.md`` (section "scale",
:mod:`bench_page`).
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from bench_page import table, update_section  # benchmarks/ is the script's directory
from tuning.fleet import run_fleet
from tuning.fleet_spec import parse_fleet

from jvl_gym.scale.ray_session import connect
from jvl_gym.scale.sweep import run_sweep
from jvl_gym.scale.sweep_spec import parse_sweep


def _quiet(_: str) -> None:
    return None


def sweep_rate(timesteps: int, workers: int, out: Path) -> tuple[float, float, float]:
    """(trials per hour, mean training env-steps/s of a trial, mean CPU seconds of a trial)
    with ``workers`` trials at once."""
    spec = parse_sweep({
        "env": "jvl_gym/GearSync-v0", "search": "grid", "seeds": [0, 1],
        "parameters": {"hyperparams.learning_rate": [0.0003, 0.001]},
        "budget": {"timesteps": timesteps, "n_envs": 16},
        "resources": {"cpus_per_trial": 1}, "eval": {"n_seeds": 2, "episodes_per_seed": 2}})
    t0 = time.perf_counter()
    outcome = run_sweep(spec, out, max_concurrent=workers, progress=_quiet)
    wall = time.perf_counter() - t0
    if not outcome.complete:
        raise RuntimeError(f"sweep with {workers} workers did not finish: {outcome}")
    import csv

    rows = list(csv.DictReader((out / "results.csv").open()))
    rate = sum(float(r["env_steps_per_s"]) for r in rows) / len(rows)
    cpu = sum(float(r["cpu_s"]) for r in rows) / len(rows)
    return 4 / wall * 3600, rate, cpu


def fleet_rate(n: int, out: Path) -> tuple[float, float]:
    """(motors tuned per hour, mean CPU seconds of a motor's task) for ``n`` simulated motors
    on the local Ray."""
    spec = parse_fleet({"seed": 3, "motors": [
        {"type": "MAC140", "count": n, "load_ratio": {"uniform": [0, 10]},
         "viscous": {"uniform": [0, 1e-5]}, "coulomb": {"uniform": [0, 0.019]}}]})
    t0 = time.perf_counter()
    rows = run_fleet(spec, out, progress=_quiet)
    cpu = sum(float(r.get("cpu_s", 0.0)) for r in rows) / n
    return n / (time.perf_counter() - t0) * 3600, cpu


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--timesteps", type=int, default=100000, help="env steps per trial")
    p.add_argument("--motors", type=int, default=4, help="fleet size (0: skip)")
    a = p.parse_args()
    connect(num_cpus=2)
    rows = []
    with tempfile.TemporaryDirectory(prefix="bench-scale-") as tmp:
        # the first sweep also loads the compiled env into the workers: not timed
        sweep_rate(2048, 2, Path(tmp) / "warm")
        for workers in (1, 2):
            tph, sps, cpu = sweep_rate(a.timesteps, workers, Path(tmp) / f"w{workers}")
            print(f"sweep GearSync-v0, {a.timesteps} env steps/trial, {workers} worker(s): "
                  f"{tph:.0f} trials/hour, {sps:.0f} training env-steps/s per trial, "
                  f"{cpu:.1f} CPU s per trial ({3600 / cpu:.0f} trials per core-hour)")
            rows.append([f"sweep, PPO on GearSync-v0, {a.timesteps} env steps per trial",
                         workers, f"{tph:.0f} trials", f"{3600 / cpu:.0f} trials",
                         f"{sps:.0f} training env-steps/s per trial"])
        if a.motors:
            mph, cpu = fleet_rate(a.motors, Path(tmp) / "fleet")
            print(f"fleet autotune, {a.motors} MAC140 motors, 2 workers: {mph:.0f} motors/hour, "
                  f"{cpu:.1f} CPU s per motor ({3600 / cpu:.0f} motors per core-hour)")
            rows.append([f"fleet autotune, {a.motors} simulated MAC140 motors", 2,
                         f"{mph:.0f} motors", f"{3600 / cpu:.0f} motors",
                         f"{cpu:.1f} CPU s per motor"])
    page = update_section("scale", "`benchmarks/bench_scale.py`, local Ray with 2 CPUs "
                          "(docs/scale.md):\n\n" + table(
                              ["workload", "workers", "per hour", "per core-hour", "detail"],
                              rows, ["l", "r", "r", "r", "l"]))
    if page is not None:
        print(f"wrote {page}")

if __name__ == "__main__":
    main()
