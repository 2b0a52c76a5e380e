"""Stored programs of the MIS/SMC motors (MIS manual chapter 9, "eRxP"): the commands of §9.7
(:mod:`.commands`), their text format (:mod:`.format`), their flash bytes (:mod:`.binary`), the
executor of the firmware (:mod:`.executor`), the motor array's program methods (:mod:`.api`)
and the test bench of an I/O script (:mod:`.bench`). This package is the family's
``Family.programs``.
"""

from __future__ import annotations

from .bench import IoScriptError, load_io_script, plot_trace, run_bench, write_csv
from .commands import SPECS, Command
from .executor import STATE_NAMES, ProgramStatus
from .format import MAX_TEXT_BYTES, ProgramError, parse_program, print_program, text_size_refusal

__all__ = ["SPECS", "Command", "ProgramError", "ProgramStatus", "STATE_NAMES", "parse_program",
           "print_program", "IoScriptError", "load_io_script", "run_bench", "write_csv",
           "plot_trace", "MAX_TEXT_BYTES", "text_size_refusal"]
