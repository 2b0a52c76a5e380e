"""The tuning toolkit as ``jvl-gym studio`` takes it (:class:`jvl_gym.studio.toolkit.
TuningToolkit`): the ``jvl-tune autotune`` pipeline (:func:`tuning.pipeline.autotune`, the
family's strategy from the contract, :func:`tuning.strategy.strategy_of`), its report and plots
(:func:`tuning.report.write_report`) and its setup writer (:func:`tuning.pipeline.write_setup`).

Announced as the entry point ``studio_tuning`` of the group ``jvl_gym.toolkits``
(pyproject.toml): :data:`TOOLKIT`. The methods import the pipeline (and SciPy, python-control
and Matplotlib under it) when they run, so that loading the entry point, which the studio does
as it starts, does not.
"""

from __future__ import annotations

import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from jvl_gym.studio.toolkit import TuningOutcome

if TYPE_CHECKING:
    from .pipeline import Result
    from .strategy import Strategy

__all__ = ["StudioTuning", "TOOLKIT"]

#: the report's plots by the file :func:`tuning.report.write_report` writes
_PLOTS = {"fits": "fits.png", "Bode (margins)": "bode.png", "speed step": "steps.png"}


def _outcome(strategy: Strategy, res: Result, note: str, step: tuple[Any, Any]
             ) -> TuningOutcome:
    """The report and plots of ``res`` (written to a temporary folder and read back)."""
    from .report import write_report

    with tempfile.TemporaryDirectory() as tmp:
        files = write_report(tmp, strategy, res, None, *step)
        plots = {title: (Path(tmp) / name).read_bytes() for title, name in _PLOTS.items()}
        report = files[0].read_text()
    bad = strategy.failures(res.chosen)
    lines = [res.reason, *([f"FAILED: {'; '.join(bad)}"] if bad else [])]
    return TuningOutcome(res.ident.motor.name, report, dict(res.chosen.registers), lines, note,
                         plots)


class StudioTuning:
    """The studio's tuning toolkit (:class:`jvl_gym.studio.toolkit.TuningToolkit`)."""

    def autotune(self, m: Any, seed: int, progress: Callable[[str], None]) -> TuningOutcome:
        """``jvl-tune autotune`` on the simulated motor ``m`` (one motor, at rest): the
        family's strategy with its default settings, and the speed step of the kept registers
        on a fresh simulator of the motor type."""
        from jvl_gym import MotorArray

        from .pipeline import autotune as run_autotune
        from .strategy import strategy_of

        motor = m.motor_configs[0].name
        strategy = strategy_of(motor)
        res = run_autotune(m, strategy, None, seed=seed, progress=progress)[0]
        progress("time simulation on the MotorArray")
        sim = MotorArray(motor, n=1, seed=seed)
        sim.load_setup({"registers": dict(res.chosen.registers)})
        return _outcome(strategy, res, strategy.setup_note(res), strategy.speed_step(sim))

    def autotune_line(self, port: str, motor: str, address: int,
                      progress: Callable[[str], None], time_scale: float = 1.0
                      ) -> TuningOutcome:
        """``jvl-tune autotune --port --time-scale`` without ``--write``
        (:func:`tuning.serial_source.autotune_over_serial`); ``time_scale``: simulated seconds
        per wall-clock second of the other end (a twin's ``--speed``, 1 for a real motor)."""
        from .serial_source import autotune_over_serial
        from .strategy import strategy_of

        ident, res = autotune_over_serial(port, motor, address, time_scale, progress=progress)
        note = f"jvl-gym studio autotune over {port}: identified J = {ident.mechanics.J:.4g}"
        return _outcome(strategy_of(motor), res, note, (None, None))

    def write_setup(self, path: Path, motor: str, registers: dict[str, float],
                    note: str) -> Path:
        """:func:`tuning.pipeline.write_setup`."""
        from .pipeline import write_setup

        return write_setup(path, motor, registers, note)


TOOLKIT = StudioTuning()  #: the entry point's object
