"""The ``jvl-tune autotune`` pipeline on the studio's selected motor, step by step.

The steps and their code are the command line's (:mod:`tuning`): the records and the fits with
their 95 % intervals (:func:`tuning.autotune.identify_motors`, :func:`tuning.report.text_table`,
:func:`tuning.report.plot_fits`), the candidate designs with their margins and quantised
registers (:func:`tuning.report.bode_figure`, :func:`tuning.report.steps_figure`), the
acceptance move against the motor type's default setup
(:func:`tuning.acceptance.autotune_designs`) and against the motor's present setup
(:func:`tuning.acceptance.accept`); a family with a sixth-order main filter runs
:func:`tuning.autotune_sixth_order.autotune_sixth_order`. A simulated motor is identified in
place (the studio's clock pauses it meanwhile); a motor on a line through
:func:`tuning.serial_source.autotune_over_serial`. The result is written only by
:meth:`TuningRun.write` (the page asks for confirmation first).
"""

from __future__ import annotations

import io
import threading
from dataclasses import dataclass, field
from typing import Any

from .motor import SimMotor, StudioMotor

__all__ = ["TuningResult", "TuningRun", "tuning_problem"]


def tuning_problem(motor: StudioMotor) -> str | None:
    """Why ``motor`` cannot be tuned (one line), or None if it can."""
    from tuning.family import tuning_family

    try:
        fam = tuning_family(motor.motor_type)
    except ValueError as exc:
        return str(exc)
    if not motor.simulated and not fam.test_modes:
        return (f"{motor.label}: tuning over a line needs the TESTU/TESTA modes, which the "
                f"{motor.facts.title} do not have; tune a simulated one")
    return None


def _filter_registers() -> list[str]:
    """The filter registers a design of :mod:`tuning.autotune` sets (current and speed loop)."""
    from tuning.autotune import CURRENT_KEYS, SPEED_KEYS

    return [*CURRENT_KEYS, *SPEED_KEYS]


def _png(fig: Any) -> bytes:
    import matplotlib.pyplot as plt

    out = io.BytesIO()
    fig.savefig(out, format="png", dpi=90)
    plt.close(fig)
    return out.getvalue()


@dataclass
class TuningResult:
    """What a finished run shows.

    Attributes
    ----------
    table : str
        Identified values with their intervals, margins and bandwidths (text table).
    registers : dict
        The kept (quantised) filter registers, name → value.
    present : dict
        The same registers on the motor before the run.
    acceptance : list of str
        The acceptance move: each candidate's settle time, and the reason for the choice.
    plots : dict
        Title → PNG bytes (fits, Bode, steps).
    """

    table: str
    registers: dict[str, float]
    present: dict[str, float]
    acceptance: list[str]
    plots: dict[str, bytes] = field(default_factory=dict)


class TuningRun:
    """One autotune run on ``motor`` in a background thread.

    Attributes
    ----------
    progress : list of str
        The steps' messages so far.
    result : TuningResult or None
        Set when the run has finished.
    error : str or None
        Set when the run failed (one line).
    written : bool
        True once :meth:`write` has written the result.
    """

    def __init__(self, motor: StudioMotor, seed: int = 0) -> None:
        problem = tuning_problem(motor)
        if problem:
            raise ValueError(problem)
        self.motor = motor
        self.seed = seed
        self.progress: list[str] = []
        self.result: TuningResult | None = None
        self.error: str | None = None
        self.written = False
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
            self.result = self._run()
            self._say("done: review the registers and write them to the motor")
        except Exception as exc:  # noqa: BLE001 - shown on the page
            from ..cli_app import one_line

            self.error = one_line(exc)
            self._say(f"failed: {self.error}")

    def _present(self, names: list[str]) -> dict[str, float]:
        return {n: self.motor.read(n) for n in names}

    def _run(self) -> TuningResult:
        from tuning.family import tuning_family

        fam = tuning_family(self.motor.motor_type)
        if not fam.test_modes:
            return self._sixth_order()
        if isinstance(self.motor, SimMotor):
            return self._sim()
        return self._line()

    def _against_present(self, ident: Any, design: Any, present: dict[str, float]
                         ) -> list[str]:
        """The acceptance move of the kept design beside the motor's present setup, both
        simulated on the identified motor (:func:`tuning.acceptance.accept`)."""
        from tuning.acceptance import Candidate, accept

        self._say("acceptance move: the kept design against the present setup")
        kept = Candidate("kept design", dict(design.registers), design)
        res = accept([ident], [[kept, Candidate("present setup", present)]], seed=self.seed)[0]
        return [f"{k}: settle {v * 1e3:.1f} ms, final error {res.final_error[k]:.0f} counts"
                for k, v in res.settle_s.items() if k in ("kept design", "present setup")]

    def _design_result(self, ident: Any, acc: Any, design: Any,
                       present: dict[str, float]) -> TuningResult:
        from tuning.report import bode_figure, steps_figure, text_table

        against = self._against_present(ident, design, present)
        self._say("plots: fits, Bode with margins, steps")
        plots = {"fits": self._fits(ident),
                 "Bode (margins)": _png(bode_figure(design, ident.motor, ident.mechanics.J)),
                 "speed step": _png(steps_figure(design, ident.motor, ident.mechanics.J))}
        lines = [f"{k}: settle {v * 1e3:.1f} ms, final error "
                 f"{acc.final_error.get(k, float('nan')):.0f} counts"
                 for k, v in acc.settle_s.items()] if acc is not None else []
        if acc is not None:
            lines.append(f"kept: {acc.chosen.name}; {acc.reason}")
        regs = dict(design.registers)
        return TuningResult(text_table(ident, design), regs, present, against + lines, plots)

    def _fits(self, ident: Any) -> bytes:
        import tempfile
        from pathlib import Path

        from tuning.report import plot_fits

        with tempfile.TemporaryDirectory() as tmp:
            return plot_fits(ident, Path(tmp) / "fits.png").read_bytes()

    def _sim(self) -> TuningResult:
        from tuning.acceptance import autotune_designs
        from tuning.autotune import identify_motors

        m = self.motor
        assert isinstance(m, SimMotor)
        if m.read_raw(m.facts.mode_register) != 0:
            raise ValueError(f"{m.label}: tuning starts in mode 0 "
                             f"({m.facts.mode_name(0)}, at rest): press 'passive' first")
        present = self._present(_filter_registers())
        m.paused = True
        try:
            with m.lock:
                self._say("records: TESTU (coil) and TESTA (mechanics) on the motor")
                ident = identify_motors(m.array, progress=self._say)[0]
        finally:
            m.paused = False
        self._say("synthesis, quantisation, verification and the acceptance move")
        acc = autotune_designs([ident], seed=self.seed)[0]
        return self._design_result(ident, acc, acc.chosen.design, present)

    def _line(self) -> TuningResult:
        from tuning.serial_source import autotune_over_serial

        m = self.motor
        line = m.line  # type: ignore[attr-defined]
        present = self._present(_filter_registers())
        self._say(f"records over {line.port}: TESTU and TESTA, 11 samples each")
        with line.lock:
            line.close()
            ident, design = autotune_over_serial(line.port, m.motor_type, m.address,
                                                 progress=self._say)
        return self._design_result(ident, design.acceptance, design, present)

    def _sixth_order(self) -> TuningResult:
        from tuning.autotune_sixth_order import autotune_report, autotune_sixth_order

        m = self.motor
        assert isinstance(m, SimMotor)
        m.paused = True
        try:
            with m.lock:
                res = autotune_sixth_order(m.array, seed=self.seed, progress=self._say)[0]
        finally:
            m.paused = False
        lines = [f"{k}: settle {v * 1e3:.1f} ms" for k, v in res.settle_s.items()]
        lines.append(f"kept: {res.chosen.name}; {res.reason}")
        regs = dict(res.chosen.registers)
        return TuningResult(autotune_report(res), regs, self._present(list(regs)), lines)

    def write(self) -> str:
        """Write the kept registers to the motor (validated as a whole) and return a line
        saying so.

        Raises
        ------
        RuntimeError
            No finished result.
        """
        if self.result is None:
            raise RuntimeError("the run has no result to write")
        self.motor.load_setup(self.result.registers)
        self.written = True
        return f"wrote {len(self.result.registers)} registers to {self.motor.label}"
