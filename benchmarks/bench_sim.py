"""Simulator speed and memory (``make bench``): prints its figures, asserts nothing.

- motor-inner-steps per second at N = 1, 64, 4096 (full fidelity: all 15 current-loop samples
  of every outer sample are simulated);
- outer steps per second at N = 1, one ``step(1)`` call per outer sample (the RL pattern) and in
  one long call;
- memory per motor at N = 4096 (all per-motor arrays; the sample buffer is allocated only when a
  recording is started and is reported separately);
- MIS/SMC step motors (``families/mis``): motor-outer-steps per second (1 ms firmware sample
  with its 10 plant samples) at N = 1, 64, 4096, MIS232s at speeds spread over ±3000 RPM.
- the MAC800 family beside the MAC140: motor-inner-steps per second at N = 4096 (its 15
  current-loop samples per servo sample) and outer steps per second at N = 1.

The figures also go to the generated page ``docs/benchmarks.md`` (section "Simulator",
:mod:`bench_page`).
"""

from __future__ import annotations

import time

import numpy as np
from bench_page import table, update_section  # benchmarks/ is the script's directory
from best_rate import best_rate

from jvl_gym import MotorArray
from jvl_gym.families.mac050_141 import constants as c
from jvl_gym.families.mac800 import constants as c800


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


def section(inner: dict[int, float], calls: float, long_call: float, base: float,
            buf: float) -> str:
    """The page section (Markdown) of one run's figures."""
    rows = [[f"motor-inner-steps/s, N = {n}", f"{rate:,.4g}"] for n, rate in inner.items()]
    rows += [["outer steps/s, N = 1, one `step(1)` call each", f"{calls:,.0f}"],
             ["outer steps/s, N = 1, one long call", f"{long_call:,.0f}"],
             ["memory per motor at N = 4096", f"{base:,.0f} B (+{buf:,.0f} B while a sample "
              "buffer is allocated)"]]
    return table(["figure", "value"], rows)


def mis_outer_steps_per_second(n: int, seconds: float = 2.0) -> float:
    """Motor-outer-steps per second of ``n`` MIS232s in velocity mode."""
    m = MotorArray("MIS232", n=n, seed=0, load_inertia=np.linspace(0, 1e-4, n))
    m.write_many({"V_SOLL": np.linspace(-300000, 300000, n).round(), "A_SOLL": 5000,
                  "MODE_REG": 1})
    m.step(2)  # compile / warm up
    return best_rate(m.step, max(1, int(2e5 / n)), seconds) * n


def mis_section(rates: dict[int, float]) -> str:
    """The MIS rows (Markdown) of one run's figures."""
    rows = [[f"MIS/SMC motor-outer-steps/s (1 ms + 10 plant samples), N = {n}",
             f"{rate:,.4g}"] for n, rate in rates.items()]
    return table(["figure", "value"], rows)


def _mac800_array(n: int) -> MotorArray:
    m = MotorArray("MAC800", n=n, seed=0, load_inertia=np.linspace(0, 1e-3, n))
    m.write("V_SOLL", np.linspace(-5541, 5541, n).round())  # ±2000 RPM
    m.write("MODE_REG", 1)
    m.step(2)  # compile / warm up
    return m


def mac800_rates(seconds: float = 2.0) -> tuple[float, float, float]:
    """MAC800: motor-inner-steps/s at N = 4096, outer steps/s at N = 1 in ``step(1)`` calls
    and in one long call (the MAC140 figures' patterns)."""
    n = 4096
    m = _mac800_array(n)
    outer = max(1, int(2e5 / (n * c800.INNER_PER_OUTER)))
    inner = best_rate(m.step, outer, seconds) * c800.INNER_PER_OUTER * n
    one = _mac800_array(1)

    def calls(k: int) -> None:
        for _ in range(k):
            one.step(1)

    return inner, best_rate(calls, 1000, seconds), best_rate(one.step, 5000, seconds)


def mac800_section(rates: tuple[float, float, float], mac140: tuple[float, float, float]
                   ) -> str:
    """The page section (Markdown) of the MAC800 figures beside the MAC140's of this run."""
    names = ["motor-inner-steps/s, N = 4096", "outer steps/s, N = 1, one `step(1)` call each",
             "outer steps/s, N = 1, one long call"]
    rows = [[name, f"{a:,.4g}", f"{b:,.4g}", f"{a / b:.2f}"]
            for name, a, b in zip(names, rates, mac140)]
    return table(["figure", "MAC800", "MAC140", "ratio"], rows)


def main() -> None:
    print("jvl_gym simulator benchmark (goals: the project's speed targets)")
    inner = {}
    for n in (1, 64, 4096):
        inner[n] = rate = inner_steps_per_second(n)
        goal = "   goal >= 1e7" if n == 4096 else ""
        print(f"  N = {n:5d}: {rate:12.4g} motor-inner-steps/s{goal}")
    calls = outer_steps_per_second_single(True)
    print(f"  N = 1: {calls:10.0f} outer steps/s (one step(1) call each)   goal >= 50000")
    long_call = outer_steps_per_second_single(False)
    print(f"  N = 1: {long_call:10.0f} outer steps/s (one long call)")
    base, buf = memory_per_motor()
    print(f"  memory per motor at N = 4096: {base:.0f} B   goal <= 4096 B"
          f"   (+{buf} B only while a sample buffer is allocated)")
    mis = {}
    for n in (1, 64, 4096):
        mis[n] = rate = mis_outer_steps_per_second(n)
        goal = "   goal >= 1e6" if n == 4096 else ""
        print(f"  MIS N = {n:5d}: {rate:12.4g} motor-outer-steps/s{goal}")
    rates = mac800_rates()
    mac140 = (inner[4096], calls, long_call)
    for name, a, b in zip(("N = 4096 motor-inner-steps/s", "N = 1 outer steps/s (calls)",
                           "N = 1 outer steps/s (long)"), rates, mac140):
        print(f"  MAC800 {name}: {a:12.4g}  ({a / b:.2f} of MAC140's)   goal >= 0.8")
    page = update_section("sim", section(inner, calls, long_call, base, buf) + "\n\n"
                          + mis_section(mis) + "\n\n" + mac800_section(rates, mac140))
    if page:
        print(f"  written to {page}")


if __name__ == "__main__":
    main()
