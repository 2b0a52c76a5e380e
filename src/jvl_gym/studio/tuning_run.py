"""The ``jvl-tune autotune`` pipeline on the studio's selected motor, step by step.

The studio is given the tuning toolkit (:class:`~jvl_gym.studio.toolkit.TuningToolkit`,
:func:`~jvl_gym.studio.toolkit.find_toolkit`) and runs the command line's pipeline through it:
the family's strategy from the contract, its records and fits with their 95 % intervals, the
candidate designs quantised and verified, the acceptance step, the report and its plots. A
simulated motor is identified in place (the studio's clock pauses it meanwhile); a motor on a
line through the line's port, for a family with the TESTU/TESTA modes
(:attr:`~jvl_gym.families.Capability.TEST_MODES`). The result is written only by
:meth:`TuningRun.write` (the page asks for confirmation first), through the toolkit's setup
writer: the setup file is written, then loaded into the motor.
"""

from __future__ import annotations

import tempfile
import threading
from dataclasses import dataclass
from pathlib import Path

import yaml

from ..families import Capability, family_of_motor
from .motor import SimMotor, StudioMotor
from .toolkit import MISSING, TuningOutcome, TuningToolkit

__all__ = ["TuningResult", "TuningRun", "tuning_problem"]


def tuning_problem(motor: StudioMotor, toolkit: TuningToolkit | None) -> str | None:
    """Why ``motor`` cannot be tuned with ``toolkit`` (one line), or None if it can."""
    if toolkit is None:
        return MISSING
    fam = family_of_motor(motor.motor_type)
    if fam.tuning is None:
        return f"{motor.label}: the {fam.title} have no tuning procedure"
    if not motor.simulated and not fam.supports(Capability.TEST_MODES):
        return (f"{motor.label}: tuning over a line needs the TESTU/TESTA modes, which the "
                f"{fam.title} do not have; tune a simulated one")
    return None


@dataclass
class TuningResult:
    """What a finished run shows: the toolkit's outcome and the motor's registers before.

    Attributes
    ----------
    outcome : TuningOutcome
        Report, kept registers, acceptance, plots, setup header.
    present : dict
        The kept registers' values on the motor before the run, name → value.
    """

    outcome: TuningOutcome
    present: dict[str, float]


class TuningRun:
    """One autotune run on ``motor`` with ``toolkit`` in a background thread.

    Parameters
    ----------
    motor : StudioMotor
        The motor to tune (simulated, or on a line).
    toolkit : TuningToolkit or None
        The tuning toolkit.
    seed : int
        Noise seed of a simulated motor's acceptance step.
    time_scale : float
        For a motor on a line: simulated seconds per wall-clock second of the other end (the
        twin's ``--speed``; 1 for a real motor), finite and > 0.

    Attributes
    ----------
    progress : list of str
        The steps' messages so far.
    result : TuningResult or None
        Set when the run has finished.
    error : str or None
        Set when the run failed (one line).
    written : Path or None
        The setup file once :meth:`write` has written the result.

    Raises
    ------
    ValueError
        The motor cannot be tuned (:func:`tuning_problem`), or ``time_scale`` is not a finite
        number > 0.
    """

    def __init__(self, motor: StudioMotor, toolkit: TuningToolkit | None, seed: int = 0,
                 time_scale: float = 1.0) -> None:
        problem = tuning_problem(motor, toolkit)
        if problem:
            raise ValueError(problem)
        if not 0 < time_scale < float("inf"):
            raise ValueError(f"time_scale must be a finite number > 0, got {time_scale}")
        assert toolkit is not None
        self.motor = motor
        self.toolkit = toolkit
        self.seed = seed
        self.time_scale = float(time_scale)
        self.progress: list[str] = []
        self.result: TuningResult | None = None
        self.error: str | None = None
        self.written: Path | None = None
        self._thread: threading.Thread | None = None

    @property
    def running(self) -> bool:
        """True while the run's thread works."""
        return self._thread is not None and self._thread.is_alive()

    def start(self) -> None:
        """Start the run in a daemon thread."""
        self._thread = threading.Thread(target=self._main, daemon=True, name="studio-tuning")
        self._thread.start()

    def join(self, timeout: float | None = None) -> None:
        """Wait for the run to end."""
        if self._thread is not None:
            self._thread.join(timeout)

    def _say(self, text: str) -> None:
        self.progress.append(text)

    def _main(self) -> None:
        try:
            outcome = self._run()
            present = {n: self.motor.read(n) for n in outcome.registers}
            self.result = TuningResult(outcome, present)
            self._say("done: review the registers and write them to the motor")
        except Exception as exc:  # noqa: BLE001 - shown on the page
            from ..cli.app import one_line

            self.error = one_line(exc)
            self._say(f"failed: {self.error}")

    def _run(self) -> TuningOutcome:
        m = self.motor
        if m.read_raw(m.facts.mode_register) != 0:
            raise ValueError(f"{m.label}: tuning starts in mode 0 "
                             f"({m.facts.mode_name(0)}, at rest): press 'passive' first")
        if isinstance(m, SimMotor):
            m.paused = True
            try:
                with m.lock:
                    return self.toolkit.autotune(m.array, self.seed, self._say)
            finally:
                m.paused = False
        line = m.line  # type: ignore[attr-defined]
        with line.lock:
            line.close()
            return self.toolkit.autotune_line(line.port, m.motor_type, m.address, self._say,
                                              self.time_scale)

    def write(self, folder: Path | None = None) -> str:
        """Write the kept registers as a setup file into ``folder`` (default: a new temporary
        folder) through the toolkit's setup writer, load that file's registers into the motor
        (validated as a whole) and return a line saying so.

        Raises
        ------
        RuntimeError
            No finished result.
        """
        if self.result is None:
            raise RuntimeError("the run has no result to write")
        out = self.result.outcome
        folder = Path(folder) if folder is not None else Path(tempfile.mkdtemp(prefix="jvl-tune-"))
        path = self.toolkit.write_setup(folder / "setup.yaml", out.motor, out.registers, out.note)
        self.motor.load_setup(yaml.safe_load(path.read_text())["registers"])
        self.written = path
        return f"wrote {len(out.registers)} registers to {self.motor.label} (setup {path})"
