"""The machine around a served motor, drawn per episode as its env draws it: a twin's motors.

A deployed policy (:mod:`jvl_gym.rl.deploy`) meets the motor's load, and for GearSync more than
a motor: a master roll whose encoder drives the motor's pulse input, a web whose tension loads
the winder, and a load cell. An :class:`EnvMachine` is an env's machine around one motor, to be
served by a twin (``jvl-gym serve --line ENV_ID``) in place of a bare ``MotorArray``: it is the
env itself with one copy (one outer sample a step), so the load (:class:`PositioningLoad`:
inertia and friction) or the web, the master profile and the load cell (:class:`GearSyncLine`)
are the simulation's, sample by sample, and the k-th episode is drawn with the seed
``seed + k``, as the env draws it (the controller draws what it knows, the target or the
reference tension, with the same seed). A machine's episode begins when the motor leaves the
passive mode; writing the passive mode after a run draws the next.

The wiring is the one a bus-trimmed winder has: the master encoder on the pulse input (read as
V_EXT, MAC050–141 manual 3.2.120), and the load cell's amplifier on the analogue input, 0 to
+10 V for 0 to :data:`LOADCELL_FULL_SCALE` newtons (read as ANINP, manual 3.2.122: ±10 V =
±1023). The controller trims the gear over the bus (GEARF1 in GP_MODE), so the analogue input
is free for the load cell.

A line runs while its winder is engaged: the line starts (the master runs up) when the motor
leaves the passive mode, and while the motor is passive it waits at rest, the web held at its
pre-tension (the motor steps without a load). Writing the passive mode after a run threads a
new web: the line is reset to its next episode, drawn as the env draws it with the seed
``seed + k`` for the k-th line (so the controller, which knows the reference tension it set,
draws it with the same seed). A web that breaks or goes slack ends the line's episode: the
motor runs on without a load until it is made passive.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from gymnasium.vector import AutoresetMode

from ..envs.link import LOADCELL_FULL_SCALE

__all__ = ["EnvMachine", "PositioningLoad", "GearSyncLine", "LOADCELL_FULL_SCALE", "LINES",
           "make_line"]

#: outer samples a line's episode may last (the line never ends by time while served)
_LINE_SAMPLES = 10_000_000


class EnvMachine:
    """One motor inside an env's machine, drawn per episode as the env draws it: a twin's
    motor backend (module docstring).

    Parameters
    ----------
    motor_type : str
        The motor type.
    seed : int
        Seed of the first episode's draw (the k-th: ``seed + k``).
    **env_kwargs
        Arguments of the env's vector class.

    Attributes
    ----------
    episodes : int
        Episodes drawn so far (the present one is ``episodes - 1``).
    running : bool
        Whether the machine runs (the motor engaged; for a line, the web whole).
    ended : str
        Why the present episode's machine stopped (a web break …), or "".
    """

    env_id = ""

    def __init__(self, motor_type: str = "MAC140", seed: int = 0, **env_kwargs: Any) -> None:
        from ..envs.registration import vector_class

        env = vector_class(self.env_id)(1, motor_type=motor_type, decimation=1,
                                        max_episode_steps=_LINE_SAMPLES,
                                        autoreset_mode=AutoresetMode.DISABLED, **env_kwargs)
        self.env = env
        self.m = env.motors
        self.seed = int(seed)
        self.episodes = 0
        self.running = False
        self.ran = False
        self.ended = ""
        self._mode_reg = int(self.m.table.lookup("MODE_REG").number)
        self._passive = int(env.fam.twin.passive_mode)
        self._action = np.zeros((1, 1))
        # a first step loads the compiled code: the first one while served must not be late
        env.reset(seed=self.seed)
        env.step(self._action)
        self._new_episode()

    def __getattr__(self, name: str) -> Any:
        # everything else is the motor's (MotorTwin's backend protocol)
        if name in ("m", "env"):
            raise AttributeError(name)
        return getattr(self.m, name)

    def _new_episode(self) -> None:
        """The env's reset with the next seed; the motor passive."""
        self.env.reset(seed=self.seed + self.episodes)
        self.episodes += 1
        self.m.write_raw(self._mode_reg, self._passive)
        self.running = self.ran = False
        self.ended = ""
        self._waiting()

    def _waiting(self) -> None:
        """Set the machine's inputs while it waits for the motor."""

    def _started(self) -> None:
        """The motor was engaged."""

    def _mode_written(self, mode: int) -> None:
        if mode == self._passive:
            if self.ran:
                self._new_episode()
        elif not self.running and not self.ended:
            self.running = self.ran = True
            self._started()

    def write_raw(self, key: Any, raw: Any, index: Any = None) -> None:
        """The motor's ``write_raw``; the mode written starts or redraws the machine."""
        self.m.write_raw(key, raw, index=index)
        if self.m.table.lookup(key).number == self._mode_reg:
            self._mode_written(int(np.asarray(raw).reshape(-1)[0]))

    def write_raw_many(self, values: Mapping[Any, Any], index: Any = None) -> None:
        """The motor's ``write_raw_many``; the mode written starts or redraws the machine."""
        self.m.write_raw_many(values, index=index)
        for key, raw in values.items():
            if self.m.table.lookup(key).number == self._mode_reg:
                self._mode_written(int(np.asarray(raw).reshape(-1)[0]))

    def step(self, n_outer: int = 1) -> None:
        """``n_outer`` outer samples of the motor and its load."""
        self.m.step(int(n_outer))


class PositioningLoad(EnvMachine):
    """Positioning-v0's load around one motor: inertia, viscous and Coulomb friction drawn per
    episode as the env draws them, so a deployed episode ``k`` moves the load the env's
    episode of the same seed moves (its target the controller draws with that seed)."""

    env_id = "jvl_gym/Positioning-v0"


class GearSyncLine(EnvMachine):
    """GearSync-v0's web line around one MAC050–141 motor (module docstring)."""

    env_id = "jvl_gym/GearSync-v0"

    def __init__(self, motor_type: str = "MAC140", seed: int = 0, **env_kwargs: Any) -> None:
        from ..families import family_of_motor

        fam = family_of_motor(motor_type)
        if getattr(fam.task, "GEAR_MODE", None) is None:
            raise ValueError(f"the GearSync line is wired for the MAC050–141 (its GP_MODE and "
                             f"analogue input), not the {fam.title}")
        super().__init__(motor_type, seed, loadcell_noise=0.0, **env_kwargs)

    @property
    def tension_ref(self) -> float:
        """The present line's reference tension [N]."""
        return float(self.env.tension_ref[0])

    @property
    def tension(self) -> float:
        """The web's tension now [N]."""
        return float(self.env.force[0])

    def _waiting(self) -> None:
        self.m.set_input(0, load_torque=0.0, pulse_counts=0.0)  # the web held, the master still
        self._wire_load_cell()
        self.m.step(1)  # the registers read the line's inputs (ANINP: the load cell) at once

    def _started(self) -> None:
        """The winder engaged: it takes the web's load as the env's winder starts, its speed
        regulator already holding it (``start_under_load``, where the family has it)."""
        env = self.env
        load = float(env.radius[0] * env.force[0] / env.gear_ratio)
        if hasattr(self.m, "start_under_load"):
            self.m.start_under_load(load, 0)
        else:
            self.m.set_input(0, load_torque=load)

    def step(self, n_outer: int = 1) -> None:
        """``n_outer`` outer samples of the line and its motor (the motor alone while the line
        waits or after its web ended)."""
        for _ in range(int(n_outer)):
            if self.running:
                # the env's action is its analogue input (10 V × action): the load cell's
                self._action[0, 0] = min(max(float(self.env.measured[0])
                                             / LOADCELL_FULL_SCALE, -1.0), 1.0)
                _, _, term, trunc, info = self.env.step(self._action)
                if term[0] or trunc[0]:
                    reasons = info.get("termination_reason")
                    self.ended = str(reasons[0]) if reasons is not None else "ended"
                    self.running = False
                    self.m.set_input(0, load_torque=0.0, pulse_counts=0.0)
            else:
                self._wire_load_cell()
                self.m.step(1)

    def _wire_load_cell(self) -> None:
        """The load cell's reading on the analogue input (none once the web has ended)."""
        force = 0.0 if self.ended else float(self.env.measured[0])
        volts = 10.0 * min(max(force / LOADCELL_FULL_SCALE, -1.0), 1.0)
        self.m.set_input(0, analog_volts=volts)


#: the machines ``jvl-gym serve --line`` knows, by env id
LINES = {c.env_id: c for c in (PositioningLoad, GearSyncLine)}


def make_line(env_id: str, motor_type: str, seed: int = 0) -> Any:
    """The line of ``env_id`` around a motor of ``motor_type`` (one-line ValueError for an env
    without one)."""
    if env_id not in LINES:
        raise ValueError(f"no line for {env_id}; known: {', '.join(LINES)}")
    return LINES[env_id](motor_type, seed)
