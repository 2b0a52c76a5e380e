"""How the cost grows with the work (``make bench``): prints its figures, asserts nothing.

Motor-inner-steps/s of an array of N MAC140s in velocity mode (as ``bench_sim.py``: all 15
current-loop samples of every outer sample simulated) and env-steps/s of a Positioning-v0
vector env of N copies (random actions, NEXT_STEP autoreset), for N = 1, 16, 256, 1024, 4096
and 16 384, each with 1 and with 2 numba threads (``numba.set_num_threads``). Below
``PARALLEL_MIN`` motors or copies (``jvl_gym.engine.driver``) the drivers step in the calling
thread, so both thread counts run the same code there. Each rate is the best of equal windows
(``best_rate.py``); ``JVL_FAST=1`` measures for a third of the time.

The figures also go to the generated page ``docs/benchmarks.md`` (section "scaling",
:mod:`bench_page`).
"""

from __future__ import annotations

import os

import gymnasium as gym
import numba
import numpy as np
from bench_page import table, update_section  # benchmarks/ is the script's directory
from bench_sim import _array
from best_rate import best_rate

import jvl_gym  # noqa: F401  (registers the envs)
from jvl_gym.families.mac050_141 import constants as c

#: the numbers of motors / env copies measured
SIZES = (1, 16, 256, 1024, 4096, 16384)
#: the numba thread counts measured (at most the machine's)
THREADS = (1, 2)
ENV_ID = "jvl_gym/Positioning-v0"


def _threads() -> tuple[int, ...]:
    return tuple(k for k in THREADS if k <= numba.config.NUMBA_NUM_THREADS)


def motor_rates(n: int, seconds: float) -> dict[int, float]:
    """Motor-inner-steps/s of ``n`` motors per thread count."""
    m = _array(n)
    outer = max(1, int(2e5 / (n * c.INNER_PER_OUTER)))
    out = {}
    for k in _threads():
        numba.set_num_threads(k)
        out[k] = best_rate(m.step, outer, seconds) * c.INNER_PER_OUTER * n
    return out


def env_rates(n: int, seconds: float) -> dict[int, float]:
    """Env-steps/s of a vector env of ``n`` copies per thread count."""
    venv = gym.make_vec(ENV_ID, num_envs=n, vectorization_mode="vector_entry_point")
    venv.reset(seed=0)
    acts = np.random.default_rng(0).uniform(-1, 1, (64, *venv.action_space.shape)).astype(
        np.float32)
    batch = max(1, min(64, int(2e4 / n)))

    def run(n_acts: int) -> None:
        for a in acts[:n_acts]:
            venv.step(a)

    out = {}
    for k in _threads():
        numba.set_num_threads(k)
        run(2)
        out[k] = n * best_rate(run, batch, seconds)
    venv.close()
    return out


def section(motors: dict[int, dict[int, float]], envs: dict[int, dict[int, float]]) -> str:
    """The page section (Markdown): one row per N, a column per figure and thread count."""
    threads = sorted({k for rates in motors.values() for k in rates})
    headers = ["N"] + [f"motor-inner-steps/s, {k} thread{'s' if k > 1 else ''}"
                       for k in threads]
    headers += [f"Positioning env-steps/s, {k} thread{'s' if k > 1 else ''}" for k in threads]
    rows = []
    for n in motors:
        rows.append([f"{n:,}"] + [f"{motors[n][k]:,.0f}" for k in threads]
                    + [f"{envs[n][k]:,.0f}" for k in threads])
    return ("Rates against the number of motors (env copies) N and numba threads; below 32 "
            "motors every driver steps in one thread.\n\n" + table(headers, rows))


def main() -> None:
    seconds = 0.4 if os.environ.get("JVL_FAST") == "1" else 1.2
    motors, envs = {}, {}
    print(f"{'N':>6s} " + " ".join(f"{'motor ' + str(k) + 't':>14s}" for k in _threads())
          + " " + " ".join(f"{'env ' + str(k) + 't':>14s}" for k in _threads()))
    for n in SIZES:
        motors[n] = motor_rates(n, seconds)
        envs[n] = env_rates(n, seconds)
        print(f"{n:6d} " + " ".join(f"{r:14,.0f}" for r in motors[n].values()) + " "
              + " ".join(f"{r:14,.0f}" for r in envs[n].values()), flush=True)
    numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
    page = update_section("scaling", section(motors, envs))
    if page:
        print(f"written to {page}")


if __name__ == "__main__":
    main()
