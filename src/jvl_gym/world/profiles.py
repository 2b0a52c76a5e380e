"""Speed profiles of a master axis or a spindle, vectorised over N motors [rev/s].

A profile is a function of time t [s] (scalar) returning an (N,) array of speeds. Profiles
compose by addition and multiplication; the constructors cover what a master axis or a
spindle does in a line: run-up ramp, constant, speed changes, stops, ripple from an eccentric
roll, random walk, recorded data.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

#: time step [s] of the grid on which :meth:`SpeedProfile.ripple` integrates the roll angle and
#: :meth:`SpeedProfile.random_walk` draws its path (a property of the profile, not of a motor)
GRID_DT = 1e-3


class SpeedProfile:
    """A speed profile ``t ↦ (N,)`` [rev/s].

    Parameters
    ----------
    fn : callable
        ``fn(t) -> array`` broadcastable to (N,).
    n : int
        Number of motors N.
    """

    def __init__(self, fn: Callable[[float], np.ndarray], n: int) -> None:
        self._fn = fn
        self.n = int(n)

    def __call__(self, t: float) -> np.ndarray:
        return np.broadcast_to(np.asarray(self._fn(t), dtype=np.float64), (self.n,))

    def __add__(self, other: SpeedProfile) -> SpeedProfile:
        return SpeedProfile(lambda t: self(t) + other(t), self.n)

    def __mul__(self, other: SpeedProfile) -> SpeedProfile:
        return SpeedProfile(lambda t: self(t) * other(t), self.n)

    @staticmethod
    def constant(rps: float | Sequence[float], n: int) -> SpeedProfile:
        """Constant speed [rev/s] per motor."""
        v = np.broadcast_to(np.asarray(rps, dtype=np.float64), (n,)).copy()
        return SpeedProfile(lambda t: v, n)

    @staticmethod
    def ramp(rps: float | Sequence[float], t_ramp: float, n: int, t0: float = 0.0
             ) -> SpeedProfile:
        """Run-up from 0 at ``t0`` to ``rps`` in ``t_ramp`` seconds, then constant."""
        v = np.broadcast_to(np.asarray(rps, dtype=np.float64), (n,)).copy()
        if t_ramp <= 0:
            raise ValueError("t_ramp must be > 0")
        return SpeedProfile(lambda t: v * np.clip((t - t0) / t_ramp, 0.0, 1.0), n)

    @staticmethod
    def steps(times: Sequence[float], speeds: Sequence[float] | np.ndarray, n: int,
              ramp: float = 0.0) -> SpeedProfile:
        """Piecewise-constant speed changes (stops are speed 0), optionally ramped.

        ``speeds`` has one row per time (shape (K,) or (K, N)); before ``times[0]`` it is 0.
        """
        times_a = np.asarray(times, dtype=np.float64)
        sp = np.asarray(speeds, dtype=np.float64)
        if sp.ndim == 1:
            sp = np.repeat(sp[:, None], n, axis=1)
        if times_a.ndim != 1 or sp.shape != (times_a.size, n) or np.any(np.diff(times_a) < 0):
            raise ValueError("times must be increasing and speeds of shape (K,) or (K, N)")
        knots_t = [0.0]
        knots_v = [np.zeros(n)]
        for k, tk in enumerate(times_a):
            knots_t += [tk, tk + max(ramp, 1e-12)]
            knots_v += [knots_v[-1], sp[k]]
        kt = np.asarray(knots_t)
        kv = np.asarray(knots_v)

        def fn(t: float) -> np.ndarray:
            return np.array([np.interp(t, kt, kv[:, i]) for i in range(n)])

        return SpeedProfile(fn, n)

    @staticmethod
    def ripple(amplitude: float | Sequence[float], base: SpeedProfile,
               per_rev: float = 1.0) -> SpeedProfile:
        """Eccentric-roll ripple: ``v(t)·(1 + a·sin θ(t))`` with θ the roll angle.

        The angle is integrated from ``base`` on a grid of :data:`GRID_DT`.
        """
        a = np.broadcast_to(np.asarray(amplitude, dtype=np.float64), (base.n,)).copy()
        state = {"t": 0.0, "theta": np.zeros(base.n)}

        def fn(t: float) -> np.ndarray:
            while state["t"] + 0.5 * GRID_DT < t:
                state["theta"] = state["theta"] + 2 * np.pi * per_rev * base(state["t"]) * GRID_DT
                state["t"] += GRID_DT
            return base(t) * (1.0 + a * np.sin(state["theta"]))

        return SpeedProfile(fn, base.n)

    @staticmethod
    def random_walk(mean: float | Sequence[float], sigma: float, tau: float, n: int,
                    seed: int | None = None, horizon: float = 60.0) -> SpeedProfile:
        """Mean-reverting random walk (Ornstein–Uhlenbeck) around ``mean`` [rev/s].

        ``sigma`` is the stationary standard deviation [rev/s], ``tau`` the correlation time [s].
        The path is drawn once per motor on a grid of :data:`GRID_DT` up to ``horizon`` seconds.
        """
        mu = np.broadcast_to(np.asarray(mean, dtype=np.float64), (n,)).copy()
        steps = int(horizon / GRID_DT) + 2
        rng = np.random.default_rng(seed)
        x = np.zeros((steps, n))
        k = np.exp(-GRID_DT / tau)
        noise = rng.standard_normal((steps, n)) * sigma * np.sqrt(1 - k * k)
        for j in range(1, steps):
            x[j] = k * x[j - 1] + noise[j]
        path = mu + x

        def fn(t: float) -> np.ndarray:
            j = min(int(t / GRID_DT), steps - 1)
            return path[j]

        return SpeedProfile(fn, n)

    @staticmethod
    def recorded(times: Sequence[float], speeds: np.ndarray, n: int) -> SpeedProfile:
        """A recorded profile, linearly interpolated; ``speeds`` (K,) or (K, N) [rev/s]."""
        tt = np.asarray(times, dtype=np.float64)
        sp = np.asarray(speeds, dtype=np.float64)
        if sp.ndim == 1:
            sp = np.repeat(sp[:, None], n, axis=1)
        if sp.shape != (tt.size, n):
            raise ValueError("speeds must have shape (K,) or (K, N)")
        return SpeedProfile(lambda t: np.array([np.interp(t, tt, sp[:, i]) for i in range(n)]), n)
