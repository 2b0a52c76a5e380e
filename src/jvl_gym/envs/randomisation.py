"""How an env starts episodes: seeds, one generator per copy, the draws of the randomisation
ranges, the motor-type pool and the compliant coupling (a part of
:class:`~jvl_gym.envs.base.MotorVectorEnv`).

Copy ``i`` of a vector env seeded ``s`` draws from its own ``numpy.random.Generator`` seeded
``s + i``, so that it equals a single env seeded ``s + i``. Per copy and reset, in this order:
a uniform number per range (in the order of the range names) and one for the motor type, two
full-range noise keys (the motors' and the observation noise's), the coupling's two uniform
numbers when a resonance is drawn, then what the task draws (:meth:`_task_reset`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from ..physics.coupling import coupling_for
from .compiled import reset_counters
from .generator_draws import draw_rows, uniform_rows

__all__ = ["Randomisation", "seed_list"]


def seed_list(seed: int | Sequence[int | None] | None, n: int) -> list[int | None]:
    """One seed per copy: ``seed + i`` for an int ``seed``, the list as given, or None."""
    if seed is None:
        return [None] * n
    if isinstance(seed, (int, np.integer)):
        return [int(seed) + i for i in range(n)]
    seeds = list(seed)
    if len(seeds) != n:
        raise ValueError(f"expected {n} seeds, got {len(seeds)}")
    return seeds


class Randomisation:
    """The resets of an env's copies."""

    num_envs: int
    ranges: dict[str, tuple[float, float]]
    motor_types: tuple[str, ...]
    motors: Any
    _range_names: tuple[str, ...]
    _range_cache: tuple[dict[str, tuple[float, float]], np.ndarray, np.ndarray]
    _rngs: list[np.random.Generator | None]
    _type_names: np.ndarray
    _noise_key: np.ndarray
    _t: np.ndarray
    _prev_action: np.ndarray
    _scope_count: np.ndarray
    _autoreset: np.ndarray
    _has_reset: bool
    _obs: np.ndarray

    def _reset_envs(self, idx: np.ndarray, seeds: Sequence[int | None],
                    options: Mapping[str, Any] | None) -> None:
        options = dict(options or {})
        randomization = options.pop("randomization", None)
        ranges = (self.ranges if randomization is None
                  else self._check_ranges({**self.ranges, **randomization}))
        types = (self._check_types(options.pop("motor_type")) if "motor_type" in options
                 else self.motor_types)
        if options:
            raise ValueError(f"unknown reset options {sorted(options)}; known: "
                             "randomization, motor_type, reset_mask")
        rngs = [self._rng(i, seed) for i, seed in zip(idx.tolist(), seeds)]
        names = self._range_names
        # per copy: the ranges' uniform numbers and the motor type's (the last column), then
        # two full-range uint64 noise keys: what rng.integers(0, 2**64 - 1, size=2,
        # dtype=np.uint64, endpoint=True) returns (raw draws), without its per-call overhead
        u, keys = draw_rows(rngs, len(names) + 1, 2)
        low, span = self._range_arrays(ranges)
        # rows of a C-ordered (R, M) array: contiguous for one copy and for many, so that a
        # compiled reset taking draws compiles once for both
        draws = dict(zip(names, np.ascontiguousarray(low[:, None] + u[:, :-1].T * span[:, None])))
        # one type: every copy's, given once (its draw is made all the same)
        motor_type: str | list[str] = (
            types[0] if len(types) == 1 else
            [types[min(int(x * len(types)), len(types) - 1)] for x in u[:, -1].tolist()])
        self._type_names[idx] = motor_type
        params = self._motor_params(idx, draws)
        if ranges["resonance_hz"][1] > 0.0:  # then each copy's resonance and damping ratio
            (f_lo, f_hi), (z_lo, z_hi) = ranges["resonance_hz"], ranges["coupling_damping_ratio"]
            c = uniform_rows(rngs, 2)
            k, d = coupling_for(self.rotor_inertia(idx), params.get("load_inertia", 0.0),
                                f_lo + c[:, 0] * (f_hi - f_lo), z_lo + c[:, 1] * (z_hi - z_lo))
            params.update(coupling_stiffness=k, coupling_damping=d)
        reset_counters(idx, keys, self._noise_key, self._t, self._prev_action,
                       self._scope_count)
        self.motors.reseed(keys[:, 0], idx)
        self.motors.reset(index=idx, motor_type=motor_type, **params)
        self._task_reset(idx, draws, rngs)
        self._observe_copies(idx)

    def _rng(self, i: int, seed: int | None) -> np.random.Generator:
        """Copy ``i``'s generator, new when seeded (or on its first use)."""
        if seed is not None or self._rngs[i] is None:
            self._rngs[i] = np.random.default_rng(seed)
        return self._rngs[i]  # type: ignore[return-value]

    def _range_arrays(self, ranges: Mapping[str, tuple[float, float]]
                      ) -> tuple[np.ndarray, np.ndarray]:
        """Lows and widths (high − low) of ``ranges`` in the order of the range names, (R,)
        each (kept while the ranges are equal)."""
        cached, low, span = self._range_cache
        if ranges != cached:
            low = np.array([ranges[name][0] for name in self._range_names], dtype=np.float64)
            high = np.array([ranges[name][1] for name in self._range_names], dtype=np.float64)
            span = high - low
            self._range_cache = (dict(ranges), low, span)
        return low, span

    def reset(self, *, seed: int | Sequence[int | None] | None = None,
              options: dict[str, Any] | None = None) -> tuple[np.ndarray, dict[str, Any]]:
        """Reset all copies (or those in ``options["reset_mask"]``).

        An int ``seed`` seeds copy ``i`` with ``seed + i``; a list gives one seed per copy.
        """
        seeds = seed_list(seed, self.num_envs)
        options = dict(options or {})
        mask = options.pop("reset_mask", None)
        if mask is None:
            idx = np.arange(self.num_envs)
        else:
            mask = np.asarray(mask)
            if mask.dtype != np.bool_ or mask.shape != (self.num_envs,) or not mask.any():
                raise ValueError("reset_mask must be a bool array of shape (num_envs,) with at "
                                 "least one True value")
            idx = np.flatnonzero(mask)
            if not self._has_reset and idx.size != self.num_envs:
                raise ValueError("the first reset must reset every copy")
        self._reset_envs(idx, [seeds[i] for i in idx], options)
        self._autoreset[idx] = False
        self._has_reset = True
        self._record_scope()
        return self._obs.copy(), {}
