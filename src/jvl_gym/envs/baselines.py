"""Baseline controllers of the environments, vectorised over copies.

- GearSync-v0: :class:`PITension`, a PI tension controller on the analogue input with
  conditional-integration anti-windup (gains tuned by grid search, ``docs/envs.md``).
- CoilWinding-v0: :class:`ZeroAction`, the firmware COIL_MODE with the nominal registers
  (no trim).
- Positioning-v0: the firmware P_MODE with the default setup (env argument ``baseline=True``;
  the action is ignored).
- FilterTuning-v0: the registers of the speed-loop designer the env is given (``designer``,
  e.g. ``tuning.baseline.speed_loop_registers``), else the default setup
  (env argument ``baseline=True``; the action is ignored).
- StepperIndexing-v0: the MIS firmware's trapezoid with the default registers (V_SOLL,
  A_SOLL, RUN_CURRENT; env argument ``baseline=True``; the action is ignored).

A baseline is used like a policy: ``actions = baseline(obs)``, with
``baseline.reset(done_mask)`` after each step so stateful controllers restart with episodes.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["PITension", "ZeroAction", "BASELINES", "make_baseline"]


class ZeroAction:
    """The zero action for every copy (nominal registers / 0 V)."""

    def __init__(self, num_envs: int, act_dim: int) -> None:
        self.shape = (num_envs, act_dim)

    def __call__(self, obs: np.ndarray) -> np.ndarray:
        return np.zeros(self.shape, dtype=np.float32)

    def reset(self, done: np.ndarray | None = None) -> None:
        """Nothing to reset."""


class PITension:
    """PI tension controller on the analogue input (GearSync-v0).

    ``u = −(kp·e + ki·Σe·dt)`` with ``e`` the normalised tension error (observation 0); the sum
    integrates only while ``u`` is not saturated or the error drives it back (anti-windup).

    Parameters
    ----------
    num_envs : int
        Number of copies.
    kp, ki : float
        Gains per unit tension error (action units, action units per second).
    dt : float
        Step period [s]: the env's decimation × its family's outer sample time
        (:meth:`~jvl_gym.envs.base.MotorVectorEnv.step_seconds`; :func:`make_baseline` sets
        it).
    """

    def __init__(self, num_envs: int, kp: float, ki: float, dt: float) -> None:
        self.kp, self.ki, self.dt = float(kp), float(ki), float(dt)
        self.integral = np.zeros(num_envs)

    def __call__(self, obs: np.ndarray) -> np.ndarray:
        e = np.asarray(obs, dtype=np.float64)[:, 0]
        trial = self.integral + e * self.dt
        u = -(self.kp * e + self.ki * trial)
        ok = (np.abs(u) <= 1.0) | (np.sign(u) != -np.sign(e))
        self.integral = np.where(ok, trial, self.integral)
        u = -(self.kp * e + self.ki * self.integral)
        return np.clip(u, -1.0, 1.0).astype(np.float32)[:, None]

    def reset(self, done: np.ndarray | None = None) -> None:
        """Clear the integrators of the copies in ``done`` (all when None)."""
        if done is None:
            self.integral[:] = 0.0
        else:
            self.integral[np.asarray(done, dtype=bool)] = 0.0


@dataclass(frozen=True)
class Baseline:
    """How to run an env's baseline: extra env kwargs and a policy factory."""

    env_kwargs: dict[str, Any]
    policy: str  # "zero", "pi_tension"
    description: str


BASELINES: dict[str, Baseline] = {
    "jvl_gym/GearSync-v0": Baseline({}, "pi_tension",
                                    "PI tension controller on the analogue input"),
    "jvl_gym/CoilWinding-v0": Baseline({}, "zero", "firmware COIL_MODE, nominal registers"),
    "jvl_gym/Positioning-v0": Baseline({"baseline": True}, "zero",
                                       "firmware P_MODE, default setup"),
    "jvl_gym/FilterTuning-v0": Baseline({"baseline": True}, "zero",
                                        "the designer it is given (else default setup)"),
    "jvl_gym/StepperIndexing-v0": Baseline({"baseline": True}, "zero",
                                           "firmware trapezoid, default registers"),
}

#: PI gains found by the grid search of docs/envs.md (decimation 2, MAC050–141)
PI_GAINS = {"kp": 2.0, "ki": 15.0}


def make_baseline(env_id: str, num_envs: int, act_dim: int, decimation: int | None = None,
                  motor_type: str | Sequence[str] | None = None) -> ZeroAction | PITension:
    """The baseline policy of ``env_id`` for ``num_envs`` copies.

    Parameters
    ----------
    env_id : str
        A key of :data:`BASELINES`.
    num_envs : int
        Number of copies.
    act_dim : int
        Number of action components.
    decimation, motor_type : optional
        The env's arguments of those names (default: the env's defaults); a stateful
        baseline's step period follows from them
        (:meth:`~jvl_gym.envs.base.MotorVectorEnv.step_seconds`).
    """
    from .registration import vector_class

    spec = BASELINES[env_id]
    if spec.policy == "pi_tension":
        dt = vector_class(env_id).step_seconds(motor_type, decimation)
        return PITension(num_envs, dt=dt, **PI_GAINS)
    return ZeroAction(num_envs, act_dim)
