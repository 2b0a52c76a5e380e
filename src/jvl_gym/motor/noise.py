"""The one counter-based noise generator of jvl_gym (SplitMix64 hashing).

A sample is a pure function of (64-bit key, counter, channel), so noise never depends on how
many motors or env copies share an array, on thread scheduling, on autoreset order or on how a
run is split into calls. Motor noise uses the motor's key and its inner-sample counter
(docs/model.md §13); observation noise uses an episode key and the env step counter.

Seeding rule: the key of motor ``i`` of an array made with ``seed=s`` is
``motor_keys(s, n)[i]``, the first 64-bit word of ``SeedSequence(s).spawn(n)[i]``; a one-motor
array given ``seed=[key]`` reproduces it.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..engine.jit import KERNEL

__all__ = ["uniform", "gauss", "normal", "normals", "motor_keys"]

_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_M1 = np.uint64(0xBF58476D1CE4E5B9)
_M2 = np.uint64(0x94D049BB133111EB)
_S30 = np.uint64(30)
_S27 = np.uint64(27)
_S31 = np.uint64(31)
_S11 = np.uint64(11)
_CH = np.uint64(0xD1B54A32D192ED03)


@njit(cache=True, inline="always")
def _mix(z: np.uint64) -> np.uint64:  # pragma: no cover - compiled
    z = (z ^ (z >> _S30)) * _M1
    z = (z ^ (z >> _S27)) * _M2
    return z ^ (z >> _S31)


@njit(cache=True, inline="always")
def uniform(key: np.uint64, counter: float, channel: int) -> float:  # pragma: no cover
    """Uniform sample in (0, 1) for ``(key, counter, channel)`` (``counter`` >= 0, whole)."""
    z = key + _GOLDEN * (np.uint64(counter) + np.uint64(1)) + _CH * np.uint64(channel + 1)
    z = _mix(_mix(z))
    return ((z >> _S11) + np.uint64(1)) * (1.0 / 9007199254740993.0)


@njit(cache=True, inline="always")
def gauss(key: np.uint64, counter: float, channel: int) -> float:  # pragma: no cover
    """Standard normal sample (Box–Muller) of the motor noise channel ``channel``: uniforms
    ``2·channel`` and ``2·channel + 1``."""
    u1 = uniform(key, counter, 2 * channel)
    u2 = uniform(key, counter, 2 * channel + 1)
    return math.sqrt(-2.0 * math.log(u1)) * math.cos(2.0 * math.pi * u2)


@njit(cache=True, inline="always")
def normal(key: np.uint64, counter: int, k: int, n: int) -> float:  # pragma: no cover
    """Standard normal sample of channel ``k`` of an ``n``-channel observation (Box–Muller of
    uniforms ``k`` and ``n + k``)."""
    u1 = uniform(key, counter, k)
    u2 = uniform(key, counter, n + k)
    return math.sqrt(-2.0 * math.log(u1)) * math.cos(2.0 * math.pi * u2)


@njit(**KERNEL)
def _normals(keys: np.ndarray, counters: np.ndarray, out: np.ndarray) -> None:  # pragma: no cover
    n = out.shape[1]
    for i in range(out.shape[0]):
        for k in range(n):
            out[i, k] = normal(keys[i], counters[i], k, n)


def normals(keys: np.ndarray, counters: np.ndarray, k: int) -> np.ndarray:
    """:func:`normal` of channels ``0 .. k-1`` for per-copy ``keys`` (N,) uint64 and
    ``counters`` (N,) int64: shape (N, k)."""
    out = np.empty((keys.shape[0], int(k)))
    _normals(np.ascontiguousarray(keys, dtype=np.uint64),
             np.ascontiguousarray(counters, dtype=np.int64), out)
    return out


def motor_keys(seed: int | None, n: int) -> np.ndarray:
    """Noise keys of ``n`` motors for an integer seed (``SeedSequence(seed).spawn(n)``)."""
    children = np.random.SeedSequence(seed).spawn(n)
    return np.array([c.generate_state(1, dtype=np.uint64)[0] for c in children], dtype=np.uint64)
