"""The shared vector implementation of every jvl_gym environment.

:class:`MotorVectorEnv` runs ``num_envs`` copies of one task over one batched
:class:`~jvl_gym.MotorArray` (one motor per copy). It owns what all tasks share, each concept
in a part of its own:

- :mod:`~jvl_gym.envs.validation`: the arguments, the family (from the motor types and the
  capabilities the task needs) and the randomisation ranges;
- :mod:`~jvl_gym.envs.randomisation`: seeding (one ``numpy.random.Generator`` per copy, so copy
  ``i`` of a vector env seeded ``s`` equals a single env seeded ``s + i``), the draws of the
  ranges and the motor-type pool at every reset;
- :mod:`~jvl_gym.envs.stepping`: control decimation, the step of every copy, the autoreset
  modes (NEXT_STEP, SAME_STEP, DISABLED) and the termination reasons;
- :mod:`~jvl_gym.envs.rendering`: the scope history for ``render_mode="rgb_array"``.

A task is a subclass with a :class:`~jvl_gym.envs.task.Task` (``task``: the capabilities it
needs, its named state, its compiled hooks), its labels and ranges, :meth:`_build` (allocate
the state), :meth:`_motor_params` and :meth:`_task_reset`. The step of every copy runs in one
compiled call (:meth:`_step_copies`: action, motor kernel, process, reward, termination, noisy
clipped observation, :mod:`jvl_gym.envs.compiled`), the observation after a reset likewise
(:meth:`_observe_copies`). Observations are normalised, noisy (counter-based noise) and clipped
into finite Box spaces.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from gymnasium import spaces
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from ..engine import two_cores
from ..engine.entry import entry_point
from ..engine.packed import PackedArguments
from ..families import Capability, Family, family
from .compiled import OBS_BOUND
from .randomisation import Randomisation
from .rendering import Rendering
from .stepping import TIME_LIMIT, Stepping
from .task import Task
from .validation import Validation, env_name, keywords, real, whole

__all__ = ["MotorVectorEnv", "Field", "OBS_BOUND", "TIME_LIMIT"]


class Field:
    """A named (N,) view of the field of this attribute's name in a record array of the
    task's state (``state.<table>``, :func:`~jvl_gym.envs.task.record`)."""

    def __init__(self, table: str = "copies") -> None:
        self.table = table
        self.name = ""

    def __set_name__(self, owner: type, name: str) -> None:
        self.name = name

    def __get__(self, obj: Any, objtype: Any = None) -> Any:
        if obj is None:
            return self
        return getattr(obj.state, self.table)[self.name]

    def __set__(self, obj: Any, value: Any) -> None:
        getattr(obj.state, self.table)[self.name] = value


class MotorVectorEnv(Validation, Randomisation, Stepping, Rendering, VectorEnv, ABC):
    """Base class: ``num_envs`` copies of a motor task, natively vectorised.

    Parameters
    ----------
    num_envs : int
        Number of copies.
    motor_type : str or sequence of str, optional
        Motor type, or types drawn uniformly at every reset, all of one family the task runs on
        (:meth:`supported_families`; e.g. ``"MAC050"`` … ``"MAC141"``, or ``"MAC800"``,
        ``"MAC400"``); the env's family follows from them (:attr:`family_key`), a mix of
        families is refused. Default: the task's :attr:`default_motor_type`.
    randomization : mapping, optional
        Overrides of the task's domain-randomisation ranges, ``name -> (low, high)``; see the
        task's ``default_ranges``. ``(x, x)`` fixes a parameter.
    decimation : int, optional
        Outer samples (of the family's outer rate) per environment step; default: the
        task's.
    obs_noise : float
        Standard deviation of Gaussian noise added to the normalised observation.
    max_episode_steps : int, optional
        Truncation horizon in environment steps; default: the task's.
    render_mode : {"rgb_array", None}
        ``"rgb_array"`` records a scope history and draws it on :meth:`render`.
    autoreset_mode : AutoresetMode or str
        ``NEXT_STEP`` (default), ``SAME_STEP`` or ``DISABLED``.
    setup : str, path or mapping, optional
        The register set the motors power on with at every reset (``MotorArray``'s
        ``setup``: over the register table's defaults), e.g. a tuned setup
        (:func:`jvl_gym.envs.identified.env_kwargs_from_identification`); default: each motor
        type's own. What the task writes at its reset comes after.

    Notes
    -----
    Reset options (``reset(options=...)``): ``"randomization"`` (a mapping as above, for this
    reset only), ``"motor_type"`` (str or sequence, for this reset only) and ``"reset_mask"``
    (bool array of shape (num_envs,): reset only those copies).
    """

    metadata: dict[str, Any] = {"render_modes": ["rgb_array"], "render_fps": 25,
                                "autoreset_mode": AutoresetMode.NEXT_STEP}

    #: the task's declaration: the capabilities it needs, its state, its compiled hooks
    task: Task = Task("task", __file__)
    #: the motor family of an instance (``jvl_gym.families``): the family of its motor types
    family_key: str
    #: (name, bit) of the error bits that end an episode, in :attr:`error_register` (None:
    #: the ``TERMINAL_ERRORS`` of the family's task interface)
    terminal_errors: tuple[tuple[str, int], ...] | None = None
    error_register: str = "ERR_STAT"
    #: motor type when none is given ("": the ``DEFAULT_MOTOR_TYPE`` of the task interface of
    #: the first family the task runs on)
    default_motor_type: str = ""
    #: names of the observation components (normalised)
    obs_labels: tuple[str, ...] = ()
    #: names of the action components (each in [-1, 1])
    act_labels: tuple[str, ...] = ()
    #: domain randomisation ranges, name -> (low, high), on the family of the default type
    default_ranges: dict[str, tuple[float, float]] = {}
    #: ranges of a load behind an elastic coupling (docs/envs.md, "Compliant loads"), every
    #: task: the resonance of the coupled rotor and load [Hz] (0, the default: the rigid shaft)
    #: and its modal damping ratio; the load inertia is the task's. Drawn only when the
    #: resonance range is above 0, on families whose motors take a coupling.
    coupling_ranges: dict[str, tuple[float, float]] = {"resonance_hz": (0.0, 0.0),
                                                       "coupling_damping_ratio": (0.02, 0.02)}
    #: names of ranges of viscous friction [N·m·s/rad]: stated for the default motor type; on
    #: another family scaled by the ratio of rated torque to rated speed of its default motor
    #: type to that of the default type's family (:meth:`_family_ranges`)
    viscous_ranges: tuple[str, ...] = ()
    default_decimation: int = 1
    default_max_episode_steps: int = 1000
    #: the task's state (an instance of ``task.state``; None for a task without one), built by
    #: :meth:`_build`
    state: Any = None

    def __init__(self, num_envs: int = 1, *, motor_type: str | Sequence[str] | None = None,
                 randomization: Mapping[str, tuple[float, float]] | None = None,
                 decimation: int | None = None, obs_noise: float = 0.0,
                 max_episode_steps: int | None = None, render_mode: str | None = None,
                 autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP,
                 setup: str | Mapping[str, Any] | None = None, **unknown: Any) -> None:
        from ..motor.array import MotorArray  # lazy: building an env compiles/loads the kernel

        if unknown:
            names = ", ".join(repr(k) for k in sorted(unknown))
            hint = " (the motor type is motor_type=)" if "motor" in unknown else ""
            raise TypeError(f"{env_name(type(self))} env: unknown keyword argument {names}"
                            f"{hint}; known: {', '.join(keywords(type(self)))}")

        num_envs = whole("num_envs", num_envs, 1)
        if render_mode not in (None, "rgb_array"):
            raise ValueError(f"render_mode must be None or 'rgb_array', got {render_mode!r}")
        self.num_envs = int(num_envs)
        self.render_mode = render_mode
        self.autoreset_mode = AutoresetMode(autoreset_mode)
        self.metadata = {**type(self).metadata, "autoreset_mode": self.autoreset_mode}
        self.decimation = whole("decimation", decimation if decimation is not None
                                else self.default_decimation, 1)
        self.max_episode_steps = whole("max_episode_steps", max_episode_steps
                                       if max_episode_steps is not None
                                       else self.default_max_episode_steps, 1)
        if real("obs_noise", obs_noise) < 0:
            raise ValueError(f"obs_noise must be finite and >= 0, got {obs_noise!r}")
        self.obs_noise = float(obs_noise)
        if motor_type is None:
            motor_type = self._default_type()
        self.family_key = self._family_of(motor_type)
        if self.terminal_errors is None:
            self.terminal_errors = self.fam.task.TERMINAL_ERRORS
        self.motor_types = self._check_types(motor_type)
        self.default_ranges = self._family_ranges()
        self.ranges = self._check_ranges(randomization or {})
        self._range_names = tuple(sorted(self.default_ranges))
        self._range_cache = ({}, np.zeros(0), np.zeros(0))

        n = self.num_envs
        self.single_observation_space = spaces.Box(-OBS_BOUND, OBS_BOUND,
                                                   (len(self.obs_labels),), np.float32)
        self.single_action_space = spaces.Box(-1.0, 1.0, (len(self.act_labels),), np.float32)
        self.observation_space = batch_space(self.single_observation_space, n)
        self.action_space = batch_space(self.single_action_space, n)

        self.setup = None if setup is None else (dict(setup) if isinstance(setup, Mapping)
                                                  else str(setup))
        self.motors = MotorArray(self.motor_types[0], n=n, seed=0, setup=self.setup)
        self._configs: dict[str, Any] = {}
        self._type_names = np.full(n, self.motor_types[0], dtype=object)
        self._rngs = [None] * n
        self._noise_key = np.zeros(n, dtype=np.uint64)
        self._t = np.zeros(n, dtype=np.int64)
        self._prev_action = np.zeros((n, len(self.act_labels)))
        self._obs = np.zeros((n, len(self.obs_labels)), dtype=np.float32)
        self._reward = np.zeros(n)
        self._terminated = np.zeros(n, dtype=np.bool_)
        self._truncated = np.zeros(n, dtype=np.bool_)
        #: the fields of a ``jvl_gym.engine.Episode`` for the compiled task drivers
        self._episode = (self._prev_action, self._t, self._noise_key, self._obs, self._reward,
                         self._terminated, self._truncated)
        self._action_shape = (n, len(self.act_labels))
        self._autoreset = np.zeros(n, dtype=np.bool_)
        self._has_reset = False
        self._scope = None
        self._scope_count = np.zeros(n, dtype=np.int64)
        self._figures = {}
        self._error_texts: dict[int, str] = {}
        self._build()
        self._set_transient()
        if self.task.beside is not None:  # on a cold cache, compiled beside the first reset
            two_cores.start_beside(self.task.tag, self._beside)

    # ------------------------------------------------------------------ the task's parts
    def _build(self) -> None:
        """Allocate the task's per-copy state, :attr:`state` (called once by ``__init__``)."""

    def _motor_params(self, idx: np.ndarray, draws: dict[str, np.ndarray]
                      ) -> dict[str, np.ndarray]:
        """Per-motor parameters (``MotorArray.reset`` keywords) of the copies being reset."""
        return {}

    @abstractmethod
    def _task_reset(self, idx: np.ndarray, draws: dict[str, np.ndarray],
                    rngs: list[np.random.Generator]) -> None:
        """Reset copies ``idx``: motors (already powered on), process state, registers."""

    def _step_copies(self, actions: np.ndarray) -> bool:
        """One step of every copy with the (N, A) float64, C-contiguous ``actions`` (not yet
        clipped): the task's compiled step on the env's family.

        Returns False, changing nothing, when an action is not finite. Otherwise fills
        ``self._obs`` (noisy, clipped), ``self._reward``, ``self._terminated`` and
        ``self._truncated``, counts the step in ``self._t`` and stores the clipped action in
        ``self._prev_action``.
        """
        view = self.motors.engine_view()
        if view is not self._step_view:  # the first step, or the motors' arrays bound anew
            return self._bind_step(view, actions)
        return self._run(*self._step_head, actions, self.decimation)

    def _bind_step(self, view: tuple, actions: np.ndarray) -> bool:
        """:meth:`_step_copies` through the driver's compiled step for ``view`` (the motors'
        :meth:`~jvl_gym.MotorArray.engine_view`), which it compiles or loads on the first
        step; then keep the step's own entry for the types of these arguments, which stay
        (``jvl_gym.engine.entry``), with the arguments before the actions: the motors',
        episode's and task's arrays packed once (``TaskDriver.pack``)."""
        if self.task.beside is not None:
            two_cores.finish_beside(self.task.tag, self._beside)
        compiled = self._driver.runner(view)
        head = (self._packed(view),)
        done = compiled(*head, actions, self.decimation)
        self._run = entry_point(compiled, (*head, actions, self.decimation))
        self._step_head = head
        self._step_view = view
        return done

    def _beside(self) -> list[tuple[Any, tuple]]:
        """The task's functions with argument types (``Task.beside``) a second process may
        compile at a cold start."""
        return self.task.beside(self)

    def _packed(self, view: tuple) -> PackedArguments:
        """The arguments of the compiled step and observation before the actions for the
        motors' arrays ``view``, packed once per ``view`` (``TaskDriver.pack``)."""
        if view is not self._packed_view:
            self._packed_args = self._driver.pack(view, self._episode, self._task_args)
            self._packed_view = view
        return self._packed_args

    def _observe_copies(self, idx: np.ndarray) -> None:
        """Fill ``self._obs[idx]`` (noisy, clipped) after a reset of copies ``idx``."""
        self._driver.observe(self._packed(self.motors.engine_view()), idx)

    # ------------------------------------------------------------------ helpers for tasks
    @property
    def fam(self) -> Family:
        """The env's family record (looked up, not kept, so that the env pickles)."""
        return family(self.family_key)

    def _type_configs(self, idx: np.ndarray) -> list[Any]:
        """Motor configs of the types of copies ``idx`` (set at their reset)."""
        names = self._type_names[idx].tolist()
        missing = [name for name in names if name not in self._configs]
        if missing:
            load_motor = self.fam.array_class.load_motor
            for name in missing:
                self._configs[name] = load_motor(name)
        return [self._configs[name] for name in names]

    def rotor_inertia(self, idx: np.ndarray) -> np.ndarray:
        """Rotor inertia J_m [kg·m²] of the motor types of copies ``idx``."""
        return np.array([cfg.rotor_inertia for cfg in self._type_configs(idx)])

    def rated_torque(self, idx: np.ndarray) -> np.ndarray:
        """Rated torque [N·m] of the motor types of copies ``idx``."""
        return np.array([cfg.rated_torque for cfg in self._type_configs(idx)])

    def peak_torque(self, idx: np.ndarray) -> np.ndarray:
        """Peak torque (T_SOLL = 1023) [N·m] of the motor types of copies ``idx``."""
        return np.array([cfg.peak_torque for cfg in self._type_configs(idx)])

    def copper_loss(self, idx: np.ndarray) -> np.ndarray:
        """Copper loss of copies ``idx`` since their last reset [J], (M,): the motors' "copper"
        energy account (kept from power-on; a reset powers a copy's motor on), NaN on a family
        without energy accounts (:attr:`~jvl_gym.families.Capability.ENERGY`). Read from the
        account's column (the family's task interface, ``COPPER_COLUMN``) for these copies
        alone: ``MotorArray.energy`` copies every account of every motor."""
        if not self.fam.supports(Capability.ENERGY):
            return np.full(idx.size, np.nan)
        return self.motors.state[idx, self.fam.task.COPPER_COLUMN]

    def _load_writes(self, inertia_ratio: np.ndarray) -> dict[str, np.ndarray]:
        """The register writes that match the motors' speed loop to their load: KVOUT = 1 +
        ``inertia_ratio`` (J_load/J_m, (M,)) when the family's task interface says its tasks
        set it (``KVOUT_FROM_LOAD``), else none; a task puts them first in the transaction of
        its reset's writes."""
        return {"KVOUT": 1.0 + inertia_ratio} if self.fam.task.KVOUT_FROM_LOAD else {}

    # ------------------------------------------------------------------ pickling
    def _transient(self) -> dict[str, Any]:
        """Attributes the env keeps but does not pickle, rebuilt after unpickling: the compiled
        step of the task on the env's family, the plain tuple of its state's arrays and the
        driver's compiled step for the env's number of copies (taken on the first step)."""
        if not self.task.compiled:
            return {}
        args = () if self.state is None else tuple(self.state)
        return {"_driver": self.task.driver(self.family_key), "_task_args": args, "_run": None,
                "_step_head": (), "_step_view": None, "_packed_args": None,
                "_packed_view": None}

    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        state["_figures"] = {}
        for name in self._transient():
            state.pop(name, None)
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        for name, value in state.items():
            setattr(self, name, value)
        self._set_transient()

    def _set_transient(self) -> None:
        """Set the attributes of :meth:`_transient` (as attributes: the instance keeps the
        interpreter's fast attribute layout, which touching ``__dict__`` would give up)."""
        for name, value in self._transient().items():
            setattr(self, name, value)
