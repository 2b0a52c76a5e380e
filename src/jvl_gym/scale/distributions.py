"""Scalar distributions of the sweep and fleet files.

A value in a file is either a constant (a number or a string) or a one-key mapping:

``{uniform: [low, high]}``, ``{loguniform: [low, high]}`` (low > 0), ``{normal: [mean, std]}``,
``{truncnormal: [mean, std, low, high]}``, ``{randint: [low, high]}`` (both included) or
``{choice: [a, b, ...]}``. Draws come from a numpy ``Generator``, so a file and a seed give the
same values on every run (a resumed sweep finds its trials again).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from .errors import UserError

__all__ = ["Distribution", "parse_distribution", "KINDS"]

KINDS = ("constant", "uniform", "loguniform", "normal", "truncnormal", "randint", "choice")
_N_ARGS = {"uniform": 2, "loguniform": 2, "normal": 2, "truncnormal": 4, "randint": 2}


@dataclass(frozen=True)
class Distribution:
    """One scalar distribution.

    Attributes
    ----------
    kind : str
        One of :data:`KINDS`.
    args : tuple
        Its parameters (the value itself for ``constant``, the options for ``choice``).
    """

    kind: str
    args: tuple[Any, ...]

    def sample(self, rng: np.random.Generator, n: int) -> list[Any]:
        """``n`` draws (Python scalars)."""
        a = self.args
        if self.kind == "constant":
            return [a[0]] * n
        if self.kind == "uniform":
            return [float(x) for x in rng.uniform(a[0], a[1], n)]
        if self.kind == "loguniform":
            return [float(math.exp(x)) for x in rng.uniform(math.log(a[0]), math.log(a[1]), n)]
        if self.kind == "normal":
            return [float(x) for x in rng.normal(a[0], a[1], n)]
        if self.kind == "truncnormal":
            out: list[Any] = []
            while len(out) < n:
                x = rng.normal(a[0], a[1], 4 * n)
                out += [float(v) for v in x[(x >= a[2]) & (x <= a[3])]]
            return out[:n]
        if self.kind == "randint":
            return [int(x) for x in rng.integers(a[0], a[1] + 1, n)]
        return [a[int(i)] for i in rng.integers(0, len(a), n)]

    @property
    def bounds(self) -> tuple[float, float] | None:
        """(low, high) for the bounded numeric kinds, else ``None``."""
        if self.kind in ("uniform", "loguniform", "randint"):
            return float(self.args[0]), float(self.args[1])
        if self.kind == "truncnormal":
            return float(self.args[2]), float(self.args[3])
        return None


def parse_distribution(value: Any, where: str, numeric: bool = False) -> Distribution:
    """A :class:`Distribution` from a file value (module docstring).

    Parameters
    ----------
    value : number, str or one-key mapping
        The value as read from YAML.
    where : str
        File and key, for the error message.
    numeric : bool
        The key is a quantity: a constant or a choice must be a finite number (not a bool or a
        string).

    Raises
    ------
    UserError
        Unknown kind, wrong number of parameters, non-numeric or inverted bounds.
    """
    if isinstance(value, (int, float, str, bool)):
        if numeric or isinstance(value, float):
            _finite([value], where, numeric)
        return Distribution("constant", (value,))
    if not isinstance(value, dict) or len(value) != 1:
        raise UserError(f"{where}: expected a number or one of "
                        f"{{{', '.join(k + ': [...]' for k in KINDS[1:])}}}, got {value!r}")
    kind, args = next(iter(value.items()))
    if kind not in KINDS[1:]:
        raise UserError(f"{where}: unknown distribution {kind!r}; use one of "
                        f"{', '.join(KINDS[1:])}")
    if not isinstance(args, list) or not args:
        raise UserError(f"{where}: {kind} needs a list of parameters, e.g. {{{kind}: [0, 1]}}")
    if kind == "choice":
        _finite(args, where, numeric)
        return Distribution(kind, tuple(args))
    if len(args) != _N_ARGS[kind]:
        raise UserError(f"{where}: {kind} needs {_N_ARGS[kind]} numbers, got {args!r}")
    _finite(args, where, True)
    if kind in ("uniform", "loguniform", "randint") and not args[0] <= args[1]:
        raise UserError(f"{where}: {kind} bounds must be [low, high] with low <= high")
    if kind == "loguniform" and args[0] <= 0:
        raise UserError(f"{where}: loguniform needs low > 0")
    if kind in ("normal", "truncnormal") and args[1] < 0:
        raise UserError(f"{where}: {kind} needs std >= 0")
    if kind == "truncnormal" and not args[2] <= args[0] <= args[3]:
        raise UserError(f"{where}: truncnormal needs [mean, std, low, high] with "
                        "low <= mean <= high")
    if kind == "randint":
        if not all(float(x).is_integer() for x in args):
            raise UserError(f"{where}: randint needs integer bounds")
        args = [int(x) for x in args]
    return Distribution(kind, tuple(args))


def _finite(values: list[Any], where: str, numeric: bool) -> None:
    """Refuse a bool, a non-number (when ``numeric``) or a NaN or infinity among ``values``."""
    for x in values:
        if isinstance(x, float) and not math.isfinite(x):
            raise UserError(f"{where}: {x!r} is not a finite number")
        if numeric and (isinstance(x, bool) or not isinstance(x, (int, float))):
            raise UserError(f"{where}: expected a number, got {x!r}")
