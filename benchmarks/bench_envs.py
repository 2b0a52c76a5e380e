"""Environment speed (``make bench``): prints its figures, asserts nothing.

- single env steps/s of every jvl_gym env (the env class itself, one ``step`` call per step,
  random actions, reset when an episode ends), at the env's default decimation and at
  decimation 1 (one firmware sample per step: 1.92 ms on the MAC050–141, 1 ms on the MIS),
  all measured before the first vector env;
- vector env-steps/s with 1024 copies (native vector env, NEXT_STEP autoreset), the same in
  outer samples (firmware samples of motor time) per second, and env-steps/s at decimation 1;
- gym-electric-motor's ``Cont-CC-PMSM-v0`` single env steps/s, measured in the same run in a
  separate venv (``.venv-bench``, created here on first use: its dependencies conflict with
  ours), as a reference point for a single env's speed, also as simulated seconds per second
  (its step is ``tau`` = 100 µs of motor time, ours ``decimation`` firmware samples).

Every rate, GEM's included, is the best of equal windows of its measuring time (best_rate.py).
The figures also go to the generated page ``docs/benchmarks.md`` (section "Environments",
:mod:`bench_page`). ``JVL_FAST=1`` measures for a third of the time.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import gymnasium as gym
import numpy as np
from bench_page import table, update_section  # benchmarks/ is the script's directory
from best_rate import best_rate

import jvl_gym  # noqa: F401
from jvl_gym.envs import ENV_IDS

ROOT = Path(__file__).resolve().parents[1]
BENCH_VENV = ROOT / ".venv-bench"
BEST_RATE_SOURCE = (Path(__file__).parent / "best_rate.py").read_text()
GEM_SCRIPT = """
import time, warnings
warnings.filterwarnings("ignore")
import numpy as np
import gym_electric_motor as gem
env = gem.make("Cont-CC-PMSM-v0")
env.reset(seed=0)
acts = [env.action_space.sample() for _ in range(1000)]
for a in acts[:100]:
    _, _, term, trunc, _ = env.step(a)
    if term or trunc:
        env.reset()

def run(n_acts):
    for a in acts[:n_acts]:
        _, _, term, trunc, _ = env.step(a)
        if term or trunc:
            env.reset()


print(best_rate(run, len(acts), SECONDS), env.unwrapped.physical_system.tau)
"""


def single_steps_per_second(env_id: str, seconds: float = 3.0, **kwargs: object) -> float:
    env = gym.make(env_id, **kwargs).unwrapped
    env.reset(seed=0)
    acts = np.random.default_rng(0).uniform(-1, 1, (1000, *env.action_space.shape)).astype(
        np.float32)
    def run(n_acts: int) -> None:
        for a in acts[:n_acts]:
            _, _, term, trunc, _ = env.step(a)
            if term or trunc:
                env.reset()

    run(50)  # warm up (episodes that end are reset: a finished single env refuses a step)

    return best_rate(run, len(acts), seconds)


def vector_steps_per_second(env_id: str, num_envs: int = 1024, seconds: float = 5.0,
                            **kwargs: object) -> float:
    venv = gym.make_vec(env_id, num_envs=num_envs, vectorization_mode="vector_entry_point",
                        **kwargs)
    venv.reset(seed=0)
    acts = np.random.default_rng(0).uniform(-1, 1, (16, *venv.action_space.shape)).astype(
        np.float32)
    for a in acts[:3]:
        venv.step(a)

    def run(n_acts: int) -> None:
        for a in acts[:n_acts]:
            venv.step(a)

    return num_envs * best_rate(run, len(acts), seconds)


def gem_steps_per_second(seconds: float = 3.0) -> tuple[float, float] | None:
    python = BENCH_VENV / "bin" / "python"
    if not python.exists():
        print("creating .venv-bench with gym-electric-motor ...", flush=True)
        subprocess.run([sys.executable, "-m", "venv", str(BENCH_VENV)], check=True)
        subprocess.run([str(python), "-m", "pip", "install", "-q", "gym-electric-motor"],
                       check=True)
    script = f"{BEST_RATE_SOURCE}\nSECONDS = {seconds}\n{GEM_SCRIPT}"
    out = subprocess.run([str(python), "-c", script],
                         capture_output=True, text=True,
                         env={**os.environ, "MPLBACKEND": "Agg"})
    if out.returncode != 0:
        print(out.stderr[-2000:])
        return None
    rate, tau = out.stdout.strip().splitlines()[-1].split()
    return float(rate), float(tau)


def _ratio(x: float, g: float | None) -> str:
    return f"{x / g:.1f}" if g else "—"


def section(gem: tuple[float, float] | None, rows: list[dict]) -> str:
    """The page section (Markdown) of one run: GEM's rate, then one row per env.

    ``rows``: dicts with ``env``, ``trials`` (FilterTuning: one trial per step), ``dec``, ``dt``
    (the family's outer sample time [s]), ``single``, ``dec1``, ``copies``, ``vector``,
    ``vec1`` (rates per second)."""
    if gem:
        head = (f"gym-electric-motor `Cont-CC-PMSM-v0` single env (separate venv, same run): "
                f"{gem[0]:,.0f} steps/s, step {gem[1] * 1e6:.0f} µs = "
                f"{gem[0] * gem[1]:.2f} simulated s/s. × GEM: ratio to it.\n\n")
    else:
        head = "gym-electric-motor: not measured in this run.\n\n"
    g, gs = (gem[0], gem[0] * gem[1]) if gem else (None, None)
    out = []
    for r in rows:
        sim = r["single"] * r["dec"] * r["dt"]
        if r["trials"]:
            out.append([f"{r['env']} (trials)", "—", f"{r['single']:,.1f}", "—", "—", "—", "—",
                        f"{r['vector']:,.0f} ({r['copies']} copies)", "—", "—"])
            continue
        out.append([r["env"], r["dec"], f"{r['single']:,.0f}", _ratio(r["single"], g),
                    f"{sim:.1f}", _ratio(sim, gs), f"{r['dec1']:,.0f}",
                    f"{r['vector']:,.0f} ({r['copies']} copies)",
                    f"{r['vector'] * r['dec']:,.0f}", f"{r['vec1']:,.0f}"])
    headers = ["env", "decimation", "single steps/s", "× GEM", "simulated s/s", "× GEM",
               "single, decimation 1", "vector env-steps/s", "vector outer samples/s",
               "vector, decimation 1"]
    return head + table(headers, out)


def main() -> None:
    fast = os.environ.get("JVL_FAST") == "1"
    seconds = 1.0 if fast else 3.0
    gem = gem_steps_per_second(seconds)
    if gem:
        print(f"gym-electric-motor Cont-CC-PMSM-v0 single env: {gem[0]:,.0f} steps/s "
              f"(step {gem[1] * 1e6:.0f} µs: {gem[0] * gem[1]:.2f} simulated s/s)")
    else:
        print("gym-electric-motor: not measured")
    print(f"{'env':26s} {'dec':>3s} {'single steps/s':>14s} {'x GEM':>6s} {'sim s/s':>8s} "
          f"{'x GEM':>6s} {'dec 1 steps/s':>13s} {'x GEM':>6s} "
          f"{'vector(1024) steps/s':>20s} {'outer samples/s':>15s} {'vector dec 1':>12s}")
    # every single-env figure first: after a vector env, numba's idle worker threads still
    # compete for the cores and would slow a single env measured next
    singles = {}
    for env_id in ENV_IDS:
        trials = "FilterTuning" in env_id
        core = gym.make(env_id).unwrapped.core
        dec, dt = core.decimation, 1.0 / core.motors.OUTER_HZ
        single = single_steps_per_second(env_id, seconds)
        dec1 = single if dec == 1 or trials else single_steps_per_second(env_id, seconds,
                                                                         decimation=1)
        singles[env_id] = (trials, dec, dt, single, dec1)
    rows = []
    for env_id, (trials, dec, dt, single, dec1) in singles.items():
        n_vec = 256 if trials else 1024
        vector = vector_steps_per_second(env_id, n_vec, seconds)
        vec1 = vector if dec == 1 or trials else vector_steps_per_second(
            env_id, n_vec, seconds, decimation=1)
        sim = single * dec * dt
        rows.append({"env": env_id, "trials": trials, "dec": dec, "dt": dt, "single": single,
                     "dec1": dec1, "copies": n_vec, "vector": vector, "vec1": vec1})

        def ratio(x: float, g: float | None) -> str:
            return f"{x / g:6.1f}" if g else "     —"

        note = " (trials; 256 copies)" if trials else ""
        print(f"{env_id:26s} {dec:3d} {single:14,.0f} {ratio(single, gem and gem[0])} "
              f"{sim:8.1f} {ratio(sim, gem and gem[0] * gem[1])} {dec1:13,.0f} "
              f"{ratio(dec1, gem and gem[0])} {vector:20,.0f} {vector * dec:15,.0f} "
              f"{vec1:12,.0f}{note}")
    page = update_section("envs", section(gem, rows))
    if page:
        print(f"written to {page}")


if __name__ == "__main__":
    main()
