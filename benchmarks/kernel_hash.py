"""SHA-256 of every family's registers and state after a few hundred steps (a check, not a
benchmark): ``python benchmarks/kernel_hash.py`` prints one line per case; two source trees
whose compiled code computes the same print the same lines. Arguments: family keys (default:
every family).

Cases per family: a mixed array of 40 motors (every motor type of the family in turn, so the
threaded driver and partly filled blocks run; each motor in another mode, where the family
accepts it, with a velocity and position target and the recording bits of some motors set),
and one single motor of each of the first two types in the same setting as motor 0.
"""

from __future__ import annotations

import hashlib
import sys

import numpy as np

from jvl_gym import MotorArray
from jvl_gym.families import families, family

STEPS = 300
TRIES = {"V_SOLL": 800, "P_SOLL": 20000, "A_SOLL": 500, "T_SOLL": 300}


def _try(m: MotorArray, key: str, value: float, index: int) -> None:
    try:
        m.write(key, value, index=index)
    except Exception:  # noqa: BLE001  (a register or value the family does not have or take)
        pass


def _setting(m: MotorArray, offset: int) -> None:
    modes = [int(v) for v in range(0, 20)]
    for i in range(m.n):
        for key, value in TRIES.items():
            _try(m, key, value * (1 + (i + offset) % 3), i)
        _try(m, m.MODE_REGISTER, modes[(i + offset) % len(modes)], i)
        if (i + offset) % 4 == 1:
            _try(m, "CNTRL_BITS", 0xFFFF & ~0x1, i)


def _digest(m: MotorArray) -> str:
    h = hashlib.sha256()
    for a in (m.regs, m.state):
        h.update(np.ascontiguousarray(a).tobytes())
    return h.hexdigest()[:16]


def main() -> None:
    for key in sys.argv[1:] or families():
        types = family(key).motor_types()
        mixed = [types[i % len(types)] for i in range(40)]
        m = MotorArray(mixed, n=40, seed=1)
        _setting(m, 0)
        for _ in range(STEPS // 50):
            m.step(50)
        print(f"{key} mixed x40: {_digest(m)}")
        for t in types[:2]:
            one = MotorArray(t, n=1, seed=1)
            _setting(one, 0)
            for _ in range(STEPS // 50):
                one.step(50)
            print(f"{key} {t} x1: {_digest(one)}")


if __name__ == "__main__":
    main()
