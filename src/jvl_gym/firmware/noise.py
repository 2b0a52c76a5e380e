"""Per-motor noise streams: a counter-based generator (SplitMix64 hashing).

Each motor owns a 64-bit key. A noise sample is a pure function of (key, inner-sample counter,
channel), so it does not depend on how many motors share an array, on thread scheduling or on how
the run is split into calls. Seeding rule (docs/model.md §13): the key of motor ``i`` of an array
made with ``seed=s`` is ``motor_keys(s, n)[i]``, i.e. ``SeedSequence(s).spawn(n)[i]``'s first
64-bit word; a one-motor array given ``seed=[key]`` reproduces it.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_M1 = np.uint64(0xBF58476D1CE4E5B9)
_M2 = np.uint64(0x94D049BB133111EB)
_S30 = np.uint64(30)
_S27 = np.uint64(27)
_S31 = np.uint64(31)
_S11 = np.uint64(11)
_CH = np.uint64(0xD1B54A32D192ED03)


@njit(cache=True, inline="always")
def _mix(z: np.uint64) -> np.uint64:
    z = (z ^ (z >> _S30)) * _M1
    z = (z ^ (z >> _S27)) * _M2
    return z ^ (z >> _S31)


@njit(cache=True, inline="always")
def uniform(key: np.uint64, counter: float, channel: int) -> float:
    """Uniform sample in (0, 1) for ``(key, counter, channel)``."""
    z = key + _GOLDEN * (np.uint64(counter) + np.uint64(1)) + _CH * np.uint64(channel + 1)
    z = _mix(_mix(z))
    return ((z >> _S11) + np.uint64(1)) * (1.0 / 9007199254740993.0)


@njit(cache=True, inline="always")
def gauss(key: np.uint64, counter: float, channel: int) -> float:
    """Standard normal sample (Box–Muller) for ``(key, counter, channel)``."""
    u1 = uniform(key, counter, 2 * channel)
    u2 = uniform(key, counter, 2 * channel + 1)
    return math.sqrt(-2.0 * math.log(u1)) * math.cos(2.0 * math.pi * u2)


def motor_keys(seed: int | None, n: int) -> np.ndarray:
    """Noise keys of ``n`` motors for an integer seed (``SeedSequence(seed).spawn(n)``)."""
    children = np.random.SeedSequence(seed).spawn(n)
    return np.array([c.generate_state(1, dtype=np.uint64)[0] for c in children], dtype=np.uint64)
