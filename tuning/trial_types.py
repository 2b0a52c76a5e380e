"""What a tuning trial is made of, shared by the pipeline (:mod:`tuning.pipeline`) and every
strategy (:mod:`tuning.strategy`): a candidate setup, the acceptance move and one motor's
result."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

__all__ = ["DEFAULT_NAME", "Candidate", "Move", "Result"]

DEFAULT_NAME: str = "default setup"  #: the candidate of the motor type's default setup


@dataclass
class Candidate:
    """One setup the acceptance step tries.

    Attributes
    ----------
    name : str
        What it is (``"pi"``, ``"pi + low-pass"``, :data:`DEFAULT_NAME`, …).
    registers : dict
        Filter registers (name → value, quantised).
    design : object or None
        The strategy's design with its verification (None where there is none, e.g. a default
        setup the strategy does not verify).
    """

    name: str
    registers: dict[str, float]
    design: Any = None


@dataclass(frozen=True)
class Move:
    """The acceptance move of one motor: ``distance`` [counts] at ``v_soll`` [1/16
    count/sample] with ``a_soll`` [1/16 count/sample²], settled within ``window`` counts
    (INPOSWIN), simulated for ``seconds``; ``kind`` names it in the report (the strategy's
    :meth:`~tuning.strategy.Strategy.trial` runs it)."""

    distance: int
    v_soll: int
    a_soll: int
    window: int = 10
    seconds: float = 2.0
    kind: str = "position-mode move"

    def describe(self) -> str:
        """The move in words, for the report."""
        return (f"{self.kind} of {self.distance} counts, V_SOLL {self.v_soll}, A_SOLL "
                f"{self.a_soll}")


@dataclass
class Result:
    """The autotune result of one motor.

    Attributes
    ----------
    ident : object
        The strategy's identification (``motor``: :class:`tuning.models.MotorData`,
        ``mechanics.J``: the identified total inertia [kg·m²]).
    chosen : Candidate
        The candidate kept.
    settle_s : dict
        Candidate name → settle time of the move on the identified motor [s] (inf: never).
    final_error : dict
        Candidate name → largest |P_IST − P_SOLL| over the last 0.2 s [counts].
    move : Move
        The acceptance move.
    reason : str
        One line for the report: why ``chosen`` was kept.
    candidates : list of Candidate
        Everything simulated, the preferred design first and the default setup last.
    """

    ident: Any
    chosen: Candidate
    settle_s: dict[str, float]
    final_error: dict[str, float]
    move: Move
    reason: str
    candidates: list[Candidate] = field(default_factory=list)
