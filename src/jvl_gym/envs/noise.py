"""Counter-based observation noise, vectorised over environments.

A sample is a pure function of (episode key, step counter, channel) (SplitMix64 hashing, the
scheme of ``jvl_gym.firmware.noise``), so an environment's noise does not depend on how many
copies share a vector env, on autoreset order or on which other copies were reset: a single env
and copy ``i`` of a vector env see the same noise for the same seed.
"""

from __future__ import annotations

import numpy as np

_GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_M1 = np.uint64(0xBF58476D1CE4E5B9)
_M2 = np.uint64(0x94D049BB133111EB)
_CH = np.uint64(0xD1B54A32D192ED03)


def _mix(z: np.ndarray) -> np.ndarray:
    z = (z ^ (z >> np.uint64(30))) * _M1
    z = (z ^ (z >> np.uint64(27))) * _M2
    return z ^ (z >> np.uint64(31))


def uniforms(keys: np.ndarray, counters: np.ndarray, k: int) -> np.ndarray:
    """Uniform samples in (0, 1), shape (N, k), for per-env ``keys`` and ``counters`` (N,)."""
    ch = (np.arange(1, k + 1, dtype=np.uint64) * _CH)[None, :]
    z = keys.astype(np.uint64)[:, None] + _GOLDEN * (counters.astype(np.uint64)[:, None]
                                                     + np.uint64(1)) + ch
    z = _mix(_mix(z))
    return ((z >> np.uint64(11)).astype(np.float64) + 1.0) * (1.0 / 9007199254740993.0)


def normals(keys: np.ndarray, counters: np.ndarray, k: int) -> np.ndarray:
    """Standard normal samples (Box–Muller), shape (N, k)."""
    u = uniforms(keys, counters, 2 * k)
    return np.sqrt(-2.0 * np.log(u[:, :k])) * np.cos(2.0 * np.pi * u[:, k:])
