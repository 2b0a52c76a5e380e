"""Simulator speed and memory (``make bench``): prints its figures, asserts nothing.

- motor-inner-steps per second at N = 1, 64, 4096 (full fidelity: all 15 current-loop samples
  of every outer sample are simulated);
- outer steps per second at N = 1, one ``step(1)`` call per outer sample (the RL pattern) and in
  one long call;
- memory per motor at N = 4096 (all per-motor arrays; the sample buffer is allocated only when a
  recording is started and is reported separately).
"""

from __future__ import annotations

import time

import numpy as np
from best_rate import best_rate  # benchmarks/ is the script's directory

from jvl_gym import MotorArray
from jvl_gym import constants as c


def _array(n: int) -> MotorArray:
    m = MotorArray("MAC140", n=n, seed=0, load_inertia=np.linspace(0, 1e-4, n))
    m.write("V_SOLL", np.linspace(-4000, 4000, n).round())
    m.write("MODE_REG", 1)
    m.step(2)  # compile / warm up
    return m


def inner_steps_per_second(n: int, seconds: float = 2.0) -> float:
    m = _array(n)
    outer = max(1, int(2e5 / (n * c.INNER_PER_OUTER)))
    return best_rate(m.step, outer, seconds) * c.INNER_PER_OUTER * n


def outer_steps_per_second_single(calls: bool, seconds: float = 2.0) -> float:
    m = _array(1)
    done = 0
    t0 = time.perf_counter()
    while time.perf_counter() - t0 < seconds:
        if calls:
            for _ in range(1000):
                m.step(1)
            done += 1000
        else:
            m.step(5000)
            done += 5000
    return done / (time.perf_counter() - t0)


def memory_per_motor(n: int = 4096) -> tuple[float, float]:
    m = _array(n)
    arrays = (m.regs, m.state, m.params, m.inputs, m.keys, m._type_of, m._scratch)
    base = sum(a.nbytes for a in arrays) / n
    buffer = c.REC_CNT_MAX * 4 * 8
    return base, buffer


def main() -> None:
    print("jvl_gym simulator benchmark (2-core machine; goals from the core issue)")
    for n in (1, 64, 4096):
        rate = inner_steps_per_second(n)
        goal = "   goal >= 1e7" if n == 4096 else ""
        print(f"  N = {n:5d}: {rate:12.4g} motor-inner-steps/s{goal}")
    print(f"  N = 1: {outer_steps_per_second_single(True):10.0f} outer steps/s "
          "(one step(1) call each)   goal >= 50000")
    print(f"  N = 1: {outer_steps_per_second_single(False):10.0f} outer steps/s (one long call)")
    base, buf = memory_per_motor()
    print(f"  memory per motor at N = 4096: {base:.0f} B   goal <= 4096 B"
          f"   (+{buf} B only while a sample buffer is allocated)")


if __name__ == "__main__":
    main()
