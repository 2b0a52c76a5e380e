"""The shared vector implementation of every jvl_gym environment.

:class:`MotorVectorEnv` runs ``num_envs`` copies of one task over one batched
:class:`~jvl_gym.MotorArray` (one motor per copy). It owns what all tasks share: seeding (one
``numpy.random.Generator`` per copy, so copy ``i`` of a vector env seeded ``s`` equals a single env
seeded ``s + i``), domain randomisation (ranges as constructor arguments and reset options), the
motor-type pool, control decimation, counter-based observation noise, normalisation and clipping
into finite Box spaces, the autoreset modes (NEXT_STEP, SAME_STEP, DISABLED) and the scope
history for ``render_mode="rgb_array"``. A task subclass supplies the physics around the motor:
:meth:`_task_reset`, and the step of the copies, either

- compiled (:class:`MotorVectorEnv` itself): :meth:`_step_copies` runs the whole step of every
  copy in one numba call (``jvl_gym.envs.compiled``: action, motor kernel, process, reward,
  termination, noisy clipped observation) and :meth:`_observe_copies` observes at a reset —
  the fast path of GearSync, CoilWinding and Positioning; or
- in numpy (:class:`NumpyTaskEnv`): the hooks :meth:`~NumpyTaskEnv._apply_action`,
  :meth:`~NumpyTaskEnv._advance`, :meth:`~NumpyTaskEnv._reward_termination` and
  :meth:`~NumpyTaskEnv._observe` vectorised over the copies (FilterTuning, whose step is a
  whole trial).

Resets loop over the copies being reset, to draw from their own generators.
"""

from __future__ import annotations

import inspect
from abc import ABC, abstractmethod
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from gymnasium import spaces
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from ..coupling import coupling_for
from ..engine.driver import all_finite
from ..families import families, family
from ..noise import normals
from .compiled import OBS_BOUND, reset_counters
from .family_task import TaskFamily, task_family

__all__ = ["MotorVectorEnv", "NumpyTaskEnv", "Column", "OBS_BOUND"]
_FLOAT64 = np.dtype(np.float64)
#: ``info["termination_reason"]`` of a copy truncated at its horizon
TIME_LIMIT = "time limit: max_episode_steps reached (truncated)"


def _keywords(cls: type) -> list[str]:
    """The keyword arguments the constructors of ``cls`` and its bases take."""
    names: set[str] = set()
    for klass in cls.__mro__:
        init = klass.__dict__.get("__init__")
        if init is None or klass is object:
            continue
        try:
            params = inspect.signature(init).parameters.values()
        except (TypeError, ValueError):  # pragma: no cover - a builtin's __init__
            continue
        names.update(p.name for p in params if p.name != "self"
                     and p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY))
    return sorted(names)


def _whole(name: str, value: Any, low: int) -> int:
    """``value`` as an int if it is a whole number >= ``low`` (not a bool); ValueError."""
    try:
        ok = (not isinstance(value, (bool, np.bool_, str, bytes)) and int(value) == value
              and value >= low)
    except (TypeError, ValueError, OverflowError):
        ok = False
    if not ok:
        raise ValueError(f"{name} must be a whole number >= {low}, got {value!r}")
    return int(value)


def _real(name: str, value: Any) -> float:
    """``value`` as a float if it is a finite real number (not a bool or a str); ValueError."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer,
                                                                      np.floating)):
        raise ValueError(f"{name} must be a finite number, got {value!r}")
    if not np.isfinite(value):
        raise ValueError(f"{name} must be a finite number, got {value!r}")
    return float(value)


def env_name(cls: type) -> str:
    """The task name of an env class (``GearSyncVectorEnv`` → ``GearSync``)."""
    return cls.__name__.removesuffix("VectorEnv").removesuffix("Env")


class Column:
    """A named (N,) view of column ``col`` of a task's per-copy state array ``table``
    (the compiled steps keep a task's state in one (N, K) float64 array; survives pickling)."""

    def __init__(self, table: str, col: int) -> None:
        self.table = table
        self.col = col

    def __get__(self, obj: Any, objtype: Any = None) -> np.ndarray:
        return getattr(obj, self.table)[:, self.col]

    def __set__(self, obj: Any, value: Any) -> None:
        getattr(obj, self.table)[:, self.col] = value


def _damping_scale(key: str) -> float:
    """Rated torque over rated speed [N·m·s/rad] of the default motor type of family ``key``
    (its motor config)."""
    tf = task_family(key)
    cfg = tf.family.array_class.load_motor(tf.task.DEFAULT_MOTOR_TYPE)
    return cfg.rated_torque / (cfg.rated_speed_rpm * 2.0 * np.pi / 60.0)


def _seed_list(seed: int | Sequence[int | None] | None, n: int) -> list[int | None]:
    if seed is None:
        return [None] * n
    if isinstance(seed, (int, np.integer)):
        return [int(seed) + i for i in range(n)]
    seeds = list(seed)
    if len(seeds) != n:
        raise ValueError(f"expected {n} seeds, got {len(seeds)}")
    return seeds


class MotorVectorEnv(VectorEnv, ABC):
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

    Notes
    -----
    Reset options (``reset(options=...)``): ``"randomization"`` (a mapping as above, for this
    reset only), ``"motor_type"`` (str or sequence, for this reset only) and ``"reset_mask"``
    (bool array of shape (num_envs,): reset only those copies).
    """

    metadata: dict[str, Any] = {"render_modes": ["rgb_array"], "render_fps": 25,
                                "autoreset_mode": AutoresetMode.NEXT_STEP}

    #: the motor family the task runs on (``jvl_gym.families``); on an instance of a task that
    #: runs on several (:attr:`families`), the family of its motor types
    family_key: str = ""
    #: the families the task runs on (empty: :attr:`family_key` alone); an env's family
    #: follows from its motor types
    families: tuple[str, ...] = ()
    #: families the task refuses, with the reason (one line)
    refused_families: dict[str, str] = {}
    #: (name, bit) of the error bits that end an episode, in :attr:`error_register` (None:
    #: the ``TERMINAL_ERRORS`` of the family's task module)
    terminal_errors: tuple[tuple[str, int], ...] | None = ()
    error_register: str = "ERR_STAT"
    #: motor type when none is given ("": the ``DEFAULT_MOTOR_TYPE`` of the first family's task
    #: module)
    default_motor_type: str = ""
    #: names of the observation components (normalised)
    obs_labels: tuple[str, ...] = ()
    #: names of the action components (each in [-1, 1])
    act_labels: tuple[str, ...] = ()
    #: domain randomisation ranges, name -> (low, high)
    default_ranges: dict[str, tuple[float, float]] = {}
    #: ranges of a load behind an elastic coupling (docs/envs.md, "Compliant loads"), every
    #: task: the resonance of the coupled rotor and load [Hz] (0, the default: the rigid shaft)
    #: and its modal damping ratio; the load inertia is the task's. Drawn only when the
    #: resonance range is above 0, on families whose motors take a coupling.
    coupling_ranges: dict[str, tuple[float, float]] = {"resonance_hz": (0.0, 0.0),
                                                       "coupling_damping_ratio": (0.02, 0.02)}
    #: names of ranges of viscous friction [N·m·s/rad]: stated for the default motor type of
    #: the first of :attr:`families`; on another family scaled by the ratio of rated torque to
    #: rated speed of its default motor type to that of the first's (:meth:`_family_ranges`)
    viscous_ranges: tuple[str, ...] = ()
    default_decimation: int = 1
    default_max_episode_steps: int = 1000
    #: names of the scope traces drawn by render (values from :meth:`_scope_values`)
    scope_channels: tuple[str, ...] = ()
    scope_length: int = 400

    def __init__(self, num_envs: int = 1, *, motor_type: str | Sequence[str] | None = None,
                 randomization: Mapping[str, tuple[float, float]] | None = None,
                 decimation: int | None = None, obs_noise: float = 0.0,
                 max_episode_steps: int | None = None, render_mode: str | None = None,
                 autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP,
                 **unknown: Any) -> None:
        from ..sim import MotorArray  # lazy: building an env compiles/loads the kernel

        if unknown:
            names = ", ".join(repr(k) for k in sorted(unknown))
            hint = " (the motor type is motor_type=)" if "motor" in unknown else ""
            raise TypeError(f"{env_name(type(self))} env: unknown keyword argument {names}"
                            f"{hint}; known: {', '.join(_keywords(type(self)))}")

        num_envs = _whole("num_envs", num_envs, 1)
        if render_mode not in (None, "rgb_array"):
            raise ValueError(f"render_mode must be None or 'rgb_array', got {render_mode!r}")
        self.num_envs = int(num_envs)
        self.render_mode = render_mode
        self.autoreset_mode = AutoresetMode(autoreset_mode)
        self.metadata = {**type(self).metadata, "autoreset_mode": self.autoreset_mode}
        self.decimation = _whole("decimation", decimation if decimation is not None
                                 else self.default_decimation, 1)
        self.max_episode_steps = _whole("max_episode_steps", max_episode_steps
                                        if max_episode_steps is not None
                                        else self.default_max_episode_steps, 1)
        if _real("obs_noise", obs_noise) < 0:
            raise ValueError(f"obs_noise must be finite and >= 0, got {obs_noise!r}")
        self.obs_noise = float(obs_noise)
        if motor_type is None:
            motor_type = self._default_type()
        self.family_key = self._family_of(motor_type)
        if self.terminal_errors is None:
            self.terminal_errors = task_family(self.family_key).task.TERMINAL_ERRORS
        self.motor_types = self._check_types(motor_type)
        self.default_ranges = self._family_ranges()
        self.ranges = self._check_ranges(randomization or {})
        self._range_names = tuple(sorted(self.default_ranges))
        self._range_cache: tuple[dict[str, tuple[float, float]], np.ndarray, np.ndarray] = (
            {}, np.zeros(0), np.zeros(0))

        n = self.num_envs
        self.single_observation_space = spaces.Box(-OBS_BOUND, OBS_BOUND,
                                                   (len(self.obs_labels),), np.float32)
        self.single_action_space = spaces.Box(-1.0, 1.0, (len(self.act_labels),), np.float32)
        self.observation_space = batch_space(self.single_observation_space, n)
        self.action_space = batch_space(self.single_action_space, n)

        self.motors = MotorArray(self.motor_types[0], n=n, seed=0)
        self._configs: dict[str, Any] = {}
        self._type_names = np.full(n, self.motor_types[0], dtype=object)
        self._rngs: list[np.random.Generator | None] = [None] * n
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
        self._scope: np.ndarray | None = None
        self._scope_count = np.zeros(n, dtype=np.int64)
        self._figures: dict[int, Any] = {}
        self._build()

    # ------------------------------------------------------------------ configuration
    @classmethod
    def supported_families(cls) -> tuple[str, ...]:
        """Keys of the motor families the task runs on."""
        return cls.families or (cls.family_key,)

    @classmethod
    def _default_type(cls) -> str:
        """The motor type when none is given: :attr:`default_motor_type`, else the
        ``DEFAULT_MOTOR_TYPE`` of the first family's task module."""
        return (cls.default_motor_type
                or task_family(cls.supported_families()[0]).task.DEFAULT_MOTOR_TYPE)

    @classmethod
    def step_seconds(cls, motor_type: str | Sequence[str] | None = None,
                     decimation: int | None = None) -> float:
        """Motor time per environment step [s]: ``decimation`` (default: the task's) outer
        samples of the family of ``motor_type`` (default: the task's default type), each the
        family's ``OUTER_DT`` (its ``constants`` module: 1.92 ms on the MAC050–141,
        docs/model.md §2; 1.2987 ms on the MAC800, docs/families/mac800.md "Sample rate and
        counts per revolution").

        Raises
        ------
        ValueError
            A motor type of a family the task refuses, or a decimation that is not a whole
            number >= 1.
        """
        key = cls._family_of(cls._default_type() if motor_type is None else motor_type)
        steps = _whole("decimation", cls.default_decimation if decimation is None
                       else decimation, 1)
        return steps * task_family(key).constants.OUTER_DT

    @classmethod
    def _family_of(cls, motor_type: Any) -> str:
        """The family of ``motor_type`` (a name or a sequence of names): one of
        :meth:`supported_families`, the same for every name; ValueError otherwise."""
        types = (motor_type,) if isinstance(motor_type, str) else motor_type
        try:
            types = tuple(types)
        except TypeError:
            types = ()
        name = env_name(cls)
        found: dict[str, list[str]] = {}
        for t in types:
            if not isinstance(t, str):
                continue
            for key in (*cls.supported_families(), *(k for k in families()
                                                      if k not in cls.supported_families())):
                fam = family(key)
                if fam.canonical_name(t) in fam.motor_types():
                    found.setdefault(key, []).append(t)
                    break
        refused = [k for k in found if k not in cls.supported_families()]
        if refused:
            key = refused[0]
            why = cls.refused_families.get(key, "the task is not written for it")
            raise ValueError(f"{name}: motor_type {found[key][0]!r} (family {key}) is refused: "
                             f"{why}")
        if len(found) > 1:
            mix = "; ".join(f"{k}: {', '.join(v)}" for k, v in found.items())
            raise ValueError(f"{name}: the motor types of one env must be of one family, got "
                             f"{mix}")
        if not found:  # unknown names: _check_types names the known ones
            return cls.supported_families()[0]
        return next(iter(found))

    def _family_ranges(self) -> dict[str, tuple[float, float]]:
        """The task's default randomisation ranges on the env's family: the class's
        :attr:`default_ranges`, those of :attr:`viscous_ranges` scaled to the family's motors
        (the same friction torque at rated speed relative to the rated torque)."""
        ranges = dict(type(self).default_ranges)
        first = self.supported_families()[0]
        if self.viscous_ranges and self.family_key != first:
            scale = _damping_scale(self.family_key) / _damping_scale(first)
            for name in self.viscous_ranges:
                lo, hi = ranges[name]
                ranges[name] = (lo * scale, hi * scale)
        return ranges

    def _check_types(self, motor_type: str | Sequence[str]) -> tuple[str, ...]:
        fam = family(self.family_key)
        known = fam.motor_types()
        if isinstance(motor_type, str):
            types: tuple[Any, ...] = (motor_type,)
        elif isinstance(motor_type, Sequence):
            types = tuple(motor_type)
        else:
            types = ()  # not a name nor a sequence of names: refused below
        types = tuple(fam.canonical_name(t) if isinstance(t, str) else t for t in types)
        if not types or any(t not in known for t in types):
            others = [t for key in self.supported_families() if key != self.family_key
                      for t in family(key).motor_types()]
            also = f" (or, in an env of its own, one or more of {others})" if others else ""
            raise ValueError(f"motor_type must be one or more of {known}{also}, got "
                             f"{motor_type!r}")
        return types

    def _check_ranges(self, overrides: Mapping[str, tuple[float, float]]
                      ) -> dict[str, tuple[float, float]]:
        out = {**self.coupling_ranges, **self.default_ranges}
        for name, rng in overrides.items():
            if name not in out:
                raise ValueError(f"unknown randomisation parameter {name!r}; known: "
                                 f"{sorted(out)}")
            try:
                lo, hi = (_real(f"randomisation range of {name!r}", v) for v in rng)
            except (TypeError, ValueError) as exc:  # not two finite numbers
                raise ValueError(f"randomisation range of {name!r} must be two finite numbers "
                                 f"(low, high), got {rng!r}") from exc
            if lo > hi:
                raise ValueError(f"randomisation range of {name!r} must be finite with "
                                 f"low <= high, got {rng!r}")
            out[name] = (lo, hi)
        self._check_coupling_ranges(out)
        return out

    def _check_coupling_ranges(self, ranges: Mapping[str, tuple[float, float]]) -> None:
        """Refuse coupling ranges (:attr:`coupling_ranges`) the env's motors cannot take: a
        negative resonance or damping ratio, a coupling on a family without one, a resonance
        the family's plant cannot integrate (its motor array says why)."""
        f_lo, f_hi = ranges["resonance_hz"]
        z_lo, z_hi = ranges["coupling_damping_ratio"]
        for name, lo in (("resonance_hz", f_lo), ("coupling_damping_ratio", z_lo)):
            if lo < 0.0:
                raise ValueError(f"randomisation range of {name!r} must be >= 0, got "
                                 f"{ranges[name]!r}")
        if f_hi <= 0.0:
            return
        fam = family(self.family_key)
        if "coupling_stiffness" not in fam.array_class.PARAMETER_KEYWORDS:
            raise ValueError(f"randomisation range of 'resonance_hz' {ranges['resonance_hz']!r}: "
                             f"the {fam.title} have no elastic coupling to a load; keep it "
                             "(0, 0)")
        # the coupled pair's worst case for the plant: the highest resonance and damping ratio
        # (the same for every inertia pair), on the first motor type with J_l = J_m
        j_m = fam.array_class.load_motor(self.motor_types[0]).rotor_inertia
        k, d = coupling_for(j_m, j_m, f_hi, z_hi)
        try:
            fam.array_class(self.motor_types[0], n=1, load_inertia=j_m,
                            coupling_stiffness=float(k), coupling_damping=float(d))
        except ValueError as exc:
            raise ValueError(f"randomisation ranges resonance_hz {ranges['resonance_hz']!r}, "
                             f"coupling_damping_ratio {ranges['coupling_damping_ratio']!r}: "
                             f"{exc}") from None

    # ------------------------------------------------------------------ task hooks
    def _build(self) -> None:
        """Allocate the task's per-copy state (called once by ``__init__``)."""

    def _motor_params(self, idx: np.ndarray, draws: dict[str, np.ndarray]
                      ) -> dict[str, np.ndarray]:
        """Per-motor parameters (``MotorArray.reset`` keywords) of the copies being reset."""
        return {}

    @abstractmethod
    def _task_reset(self, idx: np.ndarray, draws: dict[str, np.ndarray],
                    rngs: list[np.random.Generator]) -> None:
        """Reset copies ``idx``: motors (already powered on), process state, registers."""

    @abstractmethod
    def _step_copies(self, actions: np.ndarray) -> bool:
        """One step of every copy with the (N, A) float64 ``actions`` (not yet clipped).

        Returns False, changing nothing, when an action is not finite. Otherwise fills
        ``self._obs`` (noisy, clipped), ``self._reward``, ``self._terminated`` and
        ``self._truncated``, counts the step in ``self._t`` and stores the clipped action in
        ``self._prev_action``.
        """

    @abstractmethod
    def _observe_copies(self, idx: np.ndarray) -> None:
        """Fill ``self._obs[idx]`` (noisy, clipped) after a reset of copies ``idx``."""

    def _scope_values(self) -> np.ndarray:
        """Scope traces (N, C) in the units of :attr:`scope_channels`."""
        return np.zeros((self.num_envs, len(self.scope_channels)))

    def _termination_reasons(self, idx: np.ndarray) -> list[str]:
        """Why each of the copies ``idx``, terminated by the last step, ended (one text per
        copy). Here: the motor error bits; a task adds its own reasons."""
        return [text or "terminated by the task" for text in self._error_reasons(idx)]

    def _error_reasons(self, idx: np.ndarray) -> list[str]:
        """The error bits that end an episode of each copy of ``idx``, as text ('' if none)."""
        return [self._error_text(bits) for bits in self.error_bits()[idx].tolist()]

    def _error_text(self, bits: int) -> str:
        """``bits`` of :attr:`error_register` as text (kept per value: a step may end many
        copies)."""
        texts = self.__dict__.setdefault("_error_texts", {})
        text = texts.get(bits)
        if text is None:
            names = "+".join(name for name, bit in self.terminal_errors if bits & bit)
            text = texts[bits] = f"motor error {names} ({self.error_register})" if bits else ""
        return text

    def _end_info(self, ended: np.ndarray, terminated: np.ndarray) -> dict[str, np.ndarray]:
        """``{"termination_reason": (N,) object array, "_termination_reason": ended}`` for the
        copies ``ended`` (bool (N,)) whose episode ended with the last step: the task's reason
        when terminated (:meth:`_termination_reasons`), :data:`TIME_LIMIT` when truncated."""
        reasons = np.empty(self.num_envs, dtype=object)
        reasons.fill("")
        idx = np.flatnonzero(ended)
        term = idx[terminated[idx]]
        if term.size:
            reasons[term] = self._termination_reasons(term)
        reasons[idx[~terminated[idx]]] = TIME_LIMIT
        return {"termination_reason": reasons, "_termination_reason": ended.copy()}

    # ------------------------------------------------------------------ helpers for tasks
    def error_bits(self) -> np.ndarray:
        """The error bits that end an episode (:attr:`terminal_errors` of
        :attr:`error_register`), (N,) int64 (0 when none is set)."""
        if not self.terminal_errors:
            return np.zeros(self.num_envs, dtype=np.int64)
        mask = 0
        for _, bit in self.terminal_errors:
            mask |= bit
        return self.motors.read_raw(self.error_register) & mask

    def _type_configs(self, idx: np.ndarray) -> list[Any]:
        """Motor configs of the types of copies ``idx`` (set at their reset)."""
        names = self._type_names[idx].tolist()
        missing = [name for name in names if name not in self._configs]
        if missing:
            load_motor = family(self.family_key).array_class.load_motor
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

    @property
    def _fam(self) -> TaskFamily:
        """The public modules of the env's family (:func:`~jvl_gym.envs.family_task.task_family`;
        looked up, not kept, so that the env pickles)."""
        return task_family(self.family_key)

    def _kvout_for_load(self, idx: np.ndarray, inertia_ratio: np.ndarray) -> None:
        """Set KVOUT = 1 + ``inertia_ratio`` (J_load/J_m, (M,)) of copies ``idx`` when the
        family's task module says its tasks do (``KVOUT_FROM_LOAD``)."""
        if task_family(self.family_key).task.KVOUT_FROM_LOAD:
            self.motors.write("KVOUT", 1.0 + inertia_ratio, index=idx)

    # ------------------------------------------------------------------ reset
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
        width = len(names) + 1
        u = np.array([rng.random(width) for rng in rngs]).reshape(idx.size, width)
        keys = np.array([rng.bit_generator.random_raw(2) for rng in rngs],
                        dtype=np.uint64).reshape(idx.size, 2)
        low, span = self._range_arrays(ranges)
        draws = dict(zip(names, low[:, None] + u[:, :-1].T * span[:, None]))
        type_names = [types[min(int(x * len(types)), len(types) - 1)] for x in u[:, -1].tolist()]
        self._type_names[idx] = type_names
        params = self._motor_params(idx, draws)
        if ranges["resonance_hz"][1] > 0.0:  # then each copy's resonance and damping ratio
            (f_lo, f_hi), (z_lo, z_hi) = ranges["resonance_hz"], ranges["coupling_damping_ratio"]
            c = np.array([rng.random(2) for rng in rngs]).reshape(idx.size, 2)
            k, d = coupling_for(self.rotor_inertia(idx), params.get("load_inertia", 0.0),
                                f_lo + c[:, 0] * (f_hi - f_lo), z_lo + c[:, 1] * (z_hi - z_lo))
            params.update(coupling_stiffness=k, coupling_damping=d)
        reset_counters(idx, keys, self._noise_key, self._t, self._prev_action,
                       self._scope_count)
        self.motors.reseed(keys[:, 0], idx)
        self.motors.reset(index=idx, motor_type=type_names, **params)
        self._task_reset(idx, draws, rngs)
        self._observe_copies(idx)

    def _rng(self, i: int, seed: int | None) -> np.random.Generator:
        """Copy ``i``'s generator, new when seeded (or on its first use)."""
        if seed is not None or self._rngs[i] is None:
            self._rngs[i] = np.random.default_rng(seed)
        return self._rngs[i]

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
        seeds = _seed_list(seed, self.num_envs)
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

    # ------------------------------------------------------------------ step
    def _step_batch(self, actions: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray,
                                                  np.ndarray]:
        """One step of every copy, without autoreset.

        Returns the internal (obs, reward, terminated, truncated) buffers: copy what you keep.
        """
        if not self._has_reset:
            raise RuntimeError("call reset() before step()")
        a = actions if type(actions) is np.ndarray else np.asarray(actions)
        if a.shape != self._action_shape or a.dtype.kind not in "fiu":
            self._refuse_action(a)
        if a.dtype is not _FLOAT64:
            a = a.astype(np.float64)
        if not self._step_copies(a):
            raise ValueError("action must be finite")
        if self.render_mode is not None:
            self._record_scope()
        return self._obs, self._reward, self._terminated, self._truncated

    def _refuse_action(self, a: np.ndarray, shape: tuple[int, ...] | None = None) -> None:
        """Raise the ValueError of an action array ``a`` that is not real numbers of shape
        ``shape`` (default: (num_envs, actions))."""
        shape = self._action_shape if shape is None else shape
        labels = ", ".join(self.act_labels)
        if a.shape != shape:
            hint = " (transposed?)" if a.shape == shape[::-1] and len(shape) == 2 else ""
            raise ValueError(f"{env_name(type(self))}: action must have shape {shape} "
                             f"({labels}), got {a.shape}{hint}; nothing was stepped")
        raise ValueError(f"{env_name(type(self))}: action must be real numbers (a float "
                         f"array), got dtype {a.dtype}; nothing was stepped")

    def step(self, actions: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray,
                                          dict[str, Any]]:
        """Step every copy; finished copies are reset as ``autoreset_mode`` says."""
        done_before = self._autoreset.copy()
        if self.autoreset_mode == AutoresetMode.DISABLED and done_before.any():
            raise RuntimeError("AutoresetMode.DISABLED: reset the finished copies (reset_mask) "
                               "before stepping")
        infos: dict[str, Any] = {}
        if self.autoreset_mode == AutoresetMode.NEXT_STEP and done_before.all():
            # every copy starts a new episode: nothing to step (the actions are ignored)
            self._reset_envs(np.arange(self.num_envs), [None] * self.num_envs, None)
            self._autoreset[:] = False
            self._record_scope()
            zeros = np.zeros(self.num_envs, dtype=np.bool_)
            return self._obs.copy(), np.zeros(self.num_envs), zeros, zeros.copy(), infos
        obs, reward, terminated, truncated = self._step_batch(actions)
        reward = reward.copy()
        terminated = terminated.copy()
        truncated = truncated.copy()
        done = terminated | truncated
        any_done = done.any()
        if any_done:
            ended = done & ~done_before
            if ended.any():
                infos.update(self._end_info(ended, terminated))
        if self.autoreset_mode == AutoresetMode.NEXT_STEP and done_before.any():
            idx = np.flatnonzero(done_before)
            self._reset_envs(idx, [None] * idx.size, None)
            reward[idx] = 0.0
            terminated[idx] = False
            truncated[idx] = False
            done[idx] = False
        elif self.autoreset_mode == AutoresetMode.SAME_STEP:
            if any_done:
                idx = np.flatnonzero(done)
                final = np.full(self.num_envs, None, dtype=object)
                for i in idx:
                    final[i] = obs[i].copy()
                self._reset_envs(idx, [None] * idx.size, None)
                infos.update({"final_obs": final, "_final_obs": done.copy(),
                              "final_info": {}, "_final_info": done.copy()})
        self._autoreset = done
        return self._obs.copy(), reward, terminated, truncated, infos

    # ------------------------------------------------------------------ render
    def _record_scope(self) -> None:
        if self.render_mode is None:
            return
        if self._scope is None:
            self._scope = np.zeros((self.num_envs, len(self.scope_channels),
                                    self.scope_length), dtype=np.float32)
        k = self._scope_count % self.scope_length
        self._scope[np.arange(self.num_envs), :, k] = self._scope_values()
        self._scope_count += 1

    def scope_trace(self, index: int = 0) -> np.ndarray:
        """The recorded scope history of copy ``index``, (C, T) oldest first."""
        if self._scope is None:
            return np.zeros((len(self.scope_channels), 0), dtype=np.float32)
        count = int(self._scope_count[index])
        n = min(count, self.scope_length)
        order = (np.arange(count - n, count)) % self.scope_length
        return self._scope[index][:, order]

    def render_env(self, index: int = 0) -> np.ndarray | None:
        """Scope plot of copy ``index``: (H, W, 3) uint8 (``render_mode="rgb_array"``)."""
        if self.render_mode is None:
            return None
        from .scope import draw_scope

        dt = self.step_seconds(self.motor_types, self.decimation)
        return draw_scope(self._figures, index, self.scope_trace(index), self.scope_channels, dt,
                          title=f"{type(self).__name__.replace('VectorEnv', '')} #{index}")

    def render(self) -> tuple[np.ndarray, ...] | None:
        """One scope image per copy (``render_mode="rgb_array"``), else None."""
        if self.render_mode is None:
            return None
        return tuple(self.render_env(i) for i in range(self.num_envs))

    def close_extras(self, **kwargs: Any) -> None:
        """Release the scope figures."""
        from .scope import close_figures

        close_figures(self._figures)

    def _transient(self) -> dict[str, Any]:
        """Attributes the env keeps but does not pickle (compiled drivers): rebuilt after
        unpickling."""
        return {}

    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        state["_figures"] = {}
        for name in self._transient():
            state.pop(name, None)
        return state

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self.__dict__.update(self._transient())


class NumpyTaskEnv(MotorVectorEnv):
    """A task whose step is written in numpy over the copies, through four hooks.

    For tasks whose step is not dominated by the motor kernel (FilterTuning runs a whole
    commissioning trial per step); the fast tasks compile their step instead.
    """

    @abstractmethod
    def _apply_action(self, action: np.ndarray) -> None:
        """Apply the (N, A) action in [-1, 1] (inputs, register writes)."""

    def _advance(self) -> None:
        """Advance the motors and the process by ``self.decimation`` outer samples."""
        self.motors.step(self.decimation)

    @abstractmethod
    def _reward_termination(self, action: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Reward (N,) float64 and termination (N,) bool after a step."""

    @abstractmethod
    def _observe(self) -> np.ndarray:
        """Normalised observation (N, K) before noise and clipping."""

    def _finish_obs(self, obs: np.ndarray) -> np.ndarray:
        if self.obs_noise > 0.0:
            obs = obs + self.obs_noise * normals(self._noise_key, self._t, obs.shape[1])
        return np.clip(obs, -OBS_BOUND, OBS_BOUND).astype(np.float32)

    def _observe_copies(self, idx: np.ndarray) -> None:
        self._obs[idx] = self._finish_obs(self._observe())[idx]

    def _step_copies(self, actions: np.ndarray) -> bool:
        if not all_finite(actions):
            return False
        a = np.clip(actions, -1.0, 1.0)
        self._apply_action(a)
        self._advance()
        self._t += 1
        reward, terminated = self._reward_termination(a)
        self._reward[:] = reward
        self._terminated[:] = terminated
        self._truncated[:] = (self._t >= self.max_episode_steps) & ~terminated
        self._prev_action[:] = a
        self._obs[:] = self._finish_obs(self._observe())
        return True
