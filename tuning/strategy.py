"""A family's tuning strategy: the steps of the pipeline (:mod:`tuning.pipeline`) that differ
between families, and how the toolkit finds it.

A family names its strategy in the family contract (``Family.tuning``, a
:class:`~jvl_gym.families.TuningSpec`): ``strategy`` is the key of a strategy of this package
(:data:`BUILT_IN`, modules of :mod:`tuning.strategies`), ``implementation`` optionally
``"package.module:Name"`` of a class of the family's own, loaded with importlib. Either way the
class is instantiated with the family's :class:`~jvl_gym.families.Family` record and must
satisfy :class:`Strategy`.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any, Protocol, runtime_checkable

from jvl_gym.families import Family

from .family import tuned_family
from .trial_types import Candidate, Move, Result

__all__ = ["Strategy", "Row", "BUILT_IN", "load_strategy", "strategy_of"]

#: the toolkit's strategies by the key a family's ``TuningSpec.strategy`` names
BUILT_IN: dict[str, str] = {
    "testu_pi": "tuning.strategies.testu_pi:TestuPiStrategy",
    "buffer_sixth_order": "tuning.strategies.buffer_sixth_order:BufferSixthOrderStrategy",
}

#: one row of the report's table of identified values: label, value, 95 % interval (None:
#: none), key of the simulated truth (None: none), flag text
Row = tuple[str, float, tuple[float, float] | None, str | None, str]


@runtime_checkable
class Strategy(Protocol):
    """The per-family steps of the tuning pipeline.

    Attributes
    ----------
    family : Family
        The family the strategy tunes (its contract record: ``tuning``, ``table``,
        ``config``, ``supports``).
    options : frozenset of str
        The ``jvl-tune autotune`` options the strategy takes beyond the common ones (motor,
        simulated load and friction, noise, seed, out), by their parameter names
        (``"structure"``, ``"notch_hz"``, …); the CLI refuses the others.
    """

    family: Family
    options: frozenset[str]

    def simulator(self, motor: str, load_inertia: float, viscous: float, coulomb: float,
                  noise: bool, settings: Mapping[str, Any]) -> dict[str, Any]:
        """``MotorArray`` keywords of the simulated motor ``jvl-tune autotune`` tunes.

        Parameters
        ----------
        motor : str
            The motor type.
        load_inertia : float
            Load inertia [kg·m²].
        viscous, coulomb : float
            Viscous [N·m·s/rad] and Coulomb [N·m] friction.
        noise : bool
            Measurement noise as a real motor has it.
        settings : mapping
            The strategy's options (:attr:`options`) as given.

        Returns
        -------
        dict
            Keyword → value.
        """

    def identify(self, m: Any, settings: Mapping[str, Any],
                 progress: Callable[[str], None]) -> list[Any]:
        """Identify every motor of ``m`` (a ``MotorArray`` or compatible, at rest).

        Returns
        -------
        list
            One identification per motor, each with ``motor`` (the identified
            :class:`tuning.models.MotorData`) and ``mechanics.J`` (total inertia [kg·m²]).
        """

    def candidates(self, ident: Any, settings: Mapping[str, Any]) -> list[Candidate]:
        """The designs to try for one identified motor, designed, quantised and verified, the
        one asked for first."""

    def default_candidate(self, ident: Any) -> Candidate:
        """The motor type's default setup as a candidate (name
        :data:`tuning.pipeline.DEFAULT_NAME`), verified on the identified motor where the
        strategy verifies it."""

    def failures(self, candidate: Candidate) -> list[str]:
        """The acceptance checks a candidate's design fails (empty: it passes, or it has no
        design to check)."""

    def simulation_motor(self, ident: Any) -> tuple[Any, dict[str, float]]:
        """The identified motor for a ``MotorArray``: its motor (type name or config) and the
        keywords (inertia, friction, coil) of what was identified."""

    def move(self, ident: Any) -> Move:
        """The acceptance move of one identified motor."""

    def trial(self, m: Any, move: Move) -> tuple[Any, Any]:
        """Run ``move`` on every motor of ``m`` (a ``MotorArray`` of one identified motor with
        a candidate per lane, at rest): settle times [s] (inf: never) and final errors
        [counts], arrays of shape (N,)."""

    def problems(self, ident: Any) -> list[str]:
        """What is not credible in an identification (empty: nothing)."""

    def setup_note(self, result: Result) -> str:
        """The header of the setup file ``jvl-tune autotune`` writes."""

    def identified_rows(self, ident: Any) -> list[Row]:
        """The report's table of identified values (:data:`Row`)."""

    def identification_lines(self, ident: Any) -> list[str]:
        """Lines under that table: fit quality, how the intervals were computed."""

    def loop_rows(self, candidate: Candidate, motor: Any, J: float) -> list[tuple[str, Any]]:
        """The report's loop verification table: ``(loop name, LoopMetrics)`` of the
        candidate's quantised registers on motor data ``motor`` with total inertia ``J``."""

    def design_lines(self, candidate: Candidate, motor: Any, J: float) -> list[str]:
        """Lines under that table: further checks, guidance, the designer's notes."""

    def fit_figure(self, ident: Any) -> Any:
        """A matplotlib figure of the identification's records with the fitted model."""

    def open_loops(self, candidate: Candidate, motor: Any, J: float) -> list[tuple[str, Any]]:
        """``(name, open-loop transfer function)`` of the loops of a candidate's registers on
        motor data ``motor`` with total inertia ``J`` (the Bode plot)."""

    def step_loop(self, candidate: Candidate, motor: Any, J: float) -> Any:
        """The closed speed loop, reference → speed as a fraction of the reference (the step
        plot)."""

    def speed_step(self, m: Any) -> tuple[Any, float]:
        """A speed step on the simulated motor ``m`` with the kept registers: the measured
        speed per servo sample, shape (n, N), and the step's reference in the reference's
        unit."""

    def truth(self, m: Any, load_inertia: float, viscous: float, coulomb: float
              ) -> dict[str, float]:
        """The true values of the simulated motor ``m`` (built with :meth:`simulator`) by the
        truth keys of :meth:`identified_rows`."""

    def synthesize(self, motor: str, inertia: float, settings: Mapping[str, Any]
                   ) -> tuple[Candidate, Any]:
        """``jvl-tune synthesize``: the design for motor type ``motor`` and total inertia
        ``inertia`` [kg·m²], quantised and verified, and the motor data it was designed for
        (``settings``: the command's options, e.g. ``resistance``, ``inductance``)."""

    def verify_setup(self, motor: str | None, setup: Path, inertia: float | None
                     ) -> tuple[list[str], list[str], bool]:
        """``jvl-tune verify``: notes for stderr (e.g. registers taken from the defaults), the
        lines to print of a setup file's loops (margins, bandwidths, pole radii, robustness)
        and whether every loop is stable."""

def load_strategy(fam: Family) -> Strategy:
    """The strategy of family ``fam`` (module docstring), instantiated with ``fam``.

    Raises
    ------
    ValueError
        The family has no tuning procedure, names an unknown strategy, or its implementation
        cannot be loaded or is not a :class:`Strategy`.
    """
    spec = fam.tuning
    if spec is None:
        raise ValueError(f"{fam.title} have no tuning procedure")
    where = spec.implementation or BUILT_IN.get(spec.strategy)
    if where is None:
        raise ValueError(f"{fam.title}: unknown tuning strategy {spec.strategy!r}; the toolkit "
                         f"has {', '.join(sorted(BUILT_IN))} (or give TuningSpec.implementation)")
    module, _, name = where.partition(":")
    try:
        cls = getattr(importlib.import_module(module), name)
    except (ImportError, AttributeError) as exc:
        raise ValueError(f"{fam.title}: cannot load the tuning strategy {where!r} ({exc})") from exc
    strategy = cls(fam)
    if not isinstance(strategy, Strategy):
        raise ValueError(f"{fam.title}: {where} is not a tuning strategy (tuning.strategy."
                         "Strategy)")
    return strategy


def strategy_of(motor: Any) -> Strategy:
    """The strategy of ``motor``'s family (a motor type name, config path or config).

    Raises
    ------
    ValueError
        The family has no tuning procedure (:func:`tuning.family.tuned_family`).
    """
    return load_strategy(tuned_family(motor))
