"""What the studio's tuning page needs of the tuning toolkit, and how it finds it.

The studio never imports the toolkit (``tuning``): it is given one. :class:`TuningToolkit` is
the interface; the toolkit provides it (``tuning.studio_adapter``) and announces it as the
package entry point ``studio_tuning`` of the group :data:`GROUP` (pyproject.toml, taken up
when the package is installed, ``make setup``). :func:`find_toolkit` returns the toolkit given
explicitly, else the one of the entry point, else None (the tuning page then says so);
:func:`load_toolkit` loads one named as an entry point's value is (``jvl-gym studio --toolkit
MODULE[:OBJECT]``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from importlib.metadata import entry_points
from pathlib import Path
from typing import Any, Protocol, runtime_checkable

__all__ = ["GROUP", "NAME", "MISSING", "DEFAULT_OBJECT", "TuningOutcome", "TuningToolkit",
           "find_toolkit", "load_toolkit"]

GROUP: str = "jvl_gym.toolkits"  #: entry-point group of the toolkits the studio takes
NAME: str = "studio_tuning"  #: entry-point name of the tuning toolkit
#: the object :func:`load_toolkit` takes from a module named without ``:OBJECT``
DEFAULT_OBJECT: str = "TOOLKIT"
#: the tuning page's line when no toolkit is given or installed
MISSING: str = ("tuning needs the tuning toolkit (jvl-tune), which is not installed: run "
                "`make setup`")


@dataclass
class TuningOutcome:
    """A finished autotune of one motor, as ``jvl-tune autotune`` reports it.

    Attributes
    ----------
    motor : str
        The identified motor's type (the setup file's ``motor:``).
    report : str
        The text of the report (identified values with their 95 % intervals, loop
        verification, acceptance step).
    registers : dict
        The kept (quantised) filter registers, name → value.
    acceptance : list of str
        The acceptance step's choice (one line) and any checks the kept design fails.
    note : str
        The header of the setup file.
    plots : dict
        Title → PNG bytes (fits, Bode with margins, speed step).
    """

    motor: str
    report: str
    registers: dict[str, float]
    acceptance: list[str]
    note: str
    plots: dict[str, bytes] = field(default_factory=dict)


@runtime_checkable
class TuningToolkit(Protocol):
    """The tuning toolkit as the studio uses it."""

    def autotune(self, m: Any, seed: int, progress: Callable[[str], None]) -> TuningOutcome:
        """Autotune the simulated motor ``m`` (a ``MotorArray`` of one motor, at rest) with
        its family's strategy, as ``jvl-tune autotune`` does."""

    def autotune_line(self, port: str, motor: str, address: int,
                      progress: Callable[[str], None], time_scale: float = 1.0
                      ) -> TuningOutcome:
        """Autotune motor type ``motor`` at unit ``address`` on the line at ``port`` (the
        line closed), as ``jvl-tune autotune --port --time-scale`` does, without writing;
        ``time_scale``: simulated seconds per wall-clock second of the other end (a twin's
        ``--speed``, 1 for a real motor)."""

    def write_setup(self, path: Path, motor: str, registers: dict[str, float],
                    note: str) -> Path:
        """Write a setup file of ``registers`` for motor type ``motor`` with header
        ``note`` (the file ``jvl-tune autotune`` writes); returns its path."""


def find_toolkit(given: TuningToolkit | None = None) -> TuningToolkit | None:
    """``given`` if not None, else the toolkit of the entry point :data:`NAME` in
    :data:`GROUP`, else None.

    Raises
    ------
    TypeError
        The toolkit found does not provide :class:`TuningToolkit`.
    """
    if given is None:
        found = [ep for ep in entry_points(group=GROUP) if ep.name == NAME]
        if not found:
            return None
        given = found[0].load()
    if not isinstance(given, TuningToolkit):
        raise TypeError(f"{given!r} is not a studio tuning toolkit (jvl_gym.studio.toolkit."
                        "TuningToolkit)")
    return given


def load_toolkit(spec: str) -> TuningToolkit:
    """The toolkit ``spec`` names: ``"package.module:OBJECT"`` (the form of an entry point's
    value) or ``"package.module"`` (its :data:`DEFAULT_OBJECT`).

    Raises
    ------
    ValueError
        The module cannot be imported or has no such object (one line, what to give).
    TypeError
        The object does not provide :class:`TuningToolkit`.
    """
    import importlib

    module, _, name = spec.partition(":")
    name = name or DEFAULT_OBJECT
    try:
        mod = importlib.import_module(module)
    except ImportError as exc:
        raise ValueError(f"--toolkit {spec}: cannot import {module!r} ({exc}); give an "
                         "importable module, e.g. tuning.studio_adapter:TOOLKIT") from None
    try:
        obj = getattr(mod, name)
    except AttributeError:
        raise ValueError(f"--toolkit {spec}: module {module!r} has no {name!r}; give "
                         "MODULE:OBJECT naming the toolkit object") from None
    if not isinstance(obj, TuningToolkit):
        raise TypeError(f"--toolkit {spec}: {module}.{name} is a {type(obj).__name__}, not a "
                        "tuning toolkit (a TuningToolkit: an object with autotune, "
                        "autotune_line and write_setup, e.g. tuning.studio_adapter:TOOLKIT)")
    return obj
