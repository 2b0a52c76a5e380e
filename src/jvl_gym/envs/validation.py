"""What an env checks of its arguments: numbers, the motor types and their family, the
randomisation ranges (a part of :class:`~jvl_gym.envs.base.MotorVectorEnv`).

The family of an env follows from its motor types; the families a task runs on are those that
declare every capability its :class:`~jvl_gym.envs.task.Task` needs, and a motor type of another
family is refused with the contract's reason (:class:`~jvl_gym.families.UnsupportedOperation`).
"""

from __future__ import annotations

import inspect
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from ..families import families, family
from ..physics.coupling import coupling_for

__all__ = ["Validation", "env_name", "keywords", "whole", "real"]


def keywords(cls: type) -> list[str]:
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


def whole(name: str, value: Any, low: int) -> int:
    """``value`` as an int if it is a whole number >= ``low`` (not a bool); ValueError."""
    try:
        ok = (not isinstance(value, (bool, np.bool_, str, bytes)) and int(value) == value
              and value >= low)
    except (TypeError, ValueError, OverflowError):
        ok = False
    if not ok:
        raise ValueError(f"{name} must be a whole number >= {low}, got {value!r}")
    return int(value)


def real(name: str, value: Any) -> float:
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


def _damping_scale(key: str) -> float:
    """Rated torque over rated speed [N·m·s/rad] of the default motor type of family ``key``
    (its motor config)."""
    fam = family(key)
    cfg = fam.array_class.load_motor(fam.task.DEFAULT_MOTOR_TYPE)
    return cfg.rated_torque / (cfg.rated_speed_rpm * 2.0 * np.pi / 60.0)


class Validation:
    """The argument checks of an env: its family, motor types and randomisation ranges."""

    task: Any
    default_motor_type: str
    default_decimation: int
    default_ranges: dict[str, tuple[float, float]]
    coupling_ranges: dict[str, tuple[float, float]]
    viscous_ranges: tuple[str, ...]
    family_key: str
    motor_types: tuple[str, ...]

    @classmethod
    def supported_families(cls) -> tuple[str, ...]:
        """Keys of the motor families the task runs on: those that declare every capability
        the task needs (:attr:`Task.needs <jvl_gym.envs.task.Task.needs>`)."""
        return cls.task.families()

    @classmethod
    def _default_type(cls) -> str:
        """The motor type when none is given: :attr:`default_motor_type`, else the
        ``DEFAULT_MOTOR_TYPE`` of the task interface of the first family the task runs on."""
        return (cls.default_motor_type
                or family(cls.supported_families()[0]).task.DEFAULT_MOTOR_TYPE)

    @classmethod
    def reference_family(cls) -> str:
        """The family of the default motor type, on which the task's ranges are stated."""
        return cls._family_of(cls._default_type())

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
        steps = whole("decimation", cls.default_decimation if decimation is None
                      else decimation, 1)
        return steps * family(key).constants.OUTER_DT

    @classmethod
    def _family_of(cls, motor_type: Any) -> str:
        """The family of ``motor_type`` (a name or a sequence of names): one of
        :meth:`supported_families`, the same for every name; ValueError otherwise (a family
        the task does not run on: the contract's reason)."""
        types = (motor_type,) if isinstance(motor_type, str) else motor_type
        try:
            types = tuple(types)
        except TypeError:
            types = ()
        name = env_name(cls)
        supported = cls.supported_families()
        found: dict[str, list[str]] = {}
        for t in types:
            if not isinstance(t, str):
                continue
            for key in (*supported, *(k for k in families() if k not in supported)):
                fam = family(key)
                if fam.canonical_name(t) in fam.motor_types():
                    found.setdefault(key, []).append(t)
                    break
        refused = [k for k in found if k not in supported]
        if refused:
            key = refused[0]
            raise ValueError(f"{name}: motor_type {found[key][0]!r} (family {key}) is refused: "
                             f"{cls.task.refusal(key)}")
        if len(found) > 1:
            mix = "; ".join(f"{k}: {', '.join(v)}" for k, v in found.items())
            raise ValueError(f"{name}: the motor types of one env must be of one family, got "
                             f"{mix}")
        if not found:  # unknown names: _check_types names those of the default type's family
            default = cls._default_type()
            return supported[0] if default in types else cls._family_of(default)
        return next(iter(found))

    def _family_ranges(self) -> dict[str, tuple[float, float]]:
        """The task's default randomisation ranges on the env's family: the class's
        :attr:`default_ranges`, those of :attr:`viscous_ranges` scaled to the family's motors
        (the same friction torque at rated speed relative to the rated torque)."""
        ranges = dict(type(self).default_ranges)
        first = self.reference_family()
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
                lo, hi = (real(f"randomisation range of {name!r}", v) for v in rng)
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
