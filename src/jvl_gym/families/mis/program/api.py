"""Stored programs of the MIS motor array: storing, running, stopping and stepping them.

The program lives in the motor's program flash: it survives a reset and, unless SETUP_BITS bit 1
("Don't start program after power up", §8.2.68) is set, starts at power-on with the motor in
position mode (§9.1: "When a program is made and stored the motor will always startup in
position mode"; the power-up zero search of HOMEMODE is not done: §6.5.2 "unless a eRXP program
exist"). The executor (:mod:`.executor`) runs between the outer samples of :meth:`step`; motors
without a running program step in one compiled call as before.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from ....motor.arguments import MotorIndex, as_index, motor_index, outer_count
from ....motor.stepping import driver
from .. import constants as c
from ..firmware import regs as R
from .binary import FLASH_BYTES, encode_command
from .commands import Command
from .executor import ProgramRunner, ProgramStatus
from .format import ProgramError, parse_program, print_program

__all__ = ["ProgramMixin", "SETUP_NO_PROGRAM_START"]

#: SETUP_BITS bit 1: "Don't start program after power up" (§8.2.68)
SETUP_NO_PROGRAM_START = 1 << 1


def _checked(program: str | Sequence[Command]) -> list[Command]:
    """A program as commands, refused (ProgramError) if malformed or too big for the flash."""
    if isinstance(program, str):
        cmds = parse_program(program)
    else:
        cmds = list(program)
        if not cmds or not all(isinstance(x, Command) for x in cmds):
            raise ProgramError(1, None, "a program is its text or a non-empty list of Commands")
        cmds = parse_program(print_program(cmds))  # the same checks as text
    size = 2
    for n, cmd in enumerate(cmds, 1):
        size += len(encode_command(cmd))
        if size > FLASH_BYTES:
            raise ProgramError(n, None, f"the program does not fit the {FLASH_BYTES}-byte "
                                        "program flash from this line on")
    return cmds


class ProgramMixin:
    """Program methods of :class:`~jvl_gym.families.mis.motors.MisMotorArray`."""

    n: int
    regs: np.ndarray
    _runners: list[ProgramRunner | None] | None = None

    # ------------------------------------------------------------------ flash
    def store_program(self, program: str | Sequence[Command], index: MotorIndex = None) -> None:
        """Store a program in the program flash of the motors (MacTalk "Save in motor").

        The program is checked whole first; a refused program leaves the stored program,
        the registers and a running program as they were. A stored program replaces the old
        one (which stops) and runs from the next power-on, or at once by :meth:`program_start`.

        Parameters
        ----------
        program : str or sequence of Command
            Program text (:mod:`.format`) or its commands.
        index : int, slice, bool mask or int array, optional
            The motors (default all).

        Raises
        ------
        ProgramError
            Malformed (its line and field), or larger than the 3072-byte program flash.
        """
        cmds = _checked(program)
        idx = as_index(index, self.n)
        if self._runners is None:
            self._runners = [None] * self.n
        for i in idx.tolist():
            self._runners[i] = ProgramRunner(cmds)

    def erase_program(self, index: MotorIndex = None) -> None:
        """Clear the program flash (user command 342, §8.2.22: "Clear all flash sectors in the
        RXP area")."""
        if self._runners is not None:
            for i in as_index(index, self.n).tolist():
                self._runners[i] = None

    def program_image(self, index: int = 0) -> bytes:
        """The program flash of one motor: the program bytes (:mod:`.binary`) and their 16-bit
        checksum, low byte first (``b""``: no program)."""
        r = self._runner(index, "program_image", need=False)
        return b"" if r is None else r.flash + r.stored_checksum.to_bytes(2, "little")

    def load_program_image(self, index: int, image: bytes) -> None:
        """Restore a program flash saved by :meth:`program_image` (e.g. from a file). The bytes
        are taken as they are, as the motor's flash would hold them: bytes that are no program
        or a wrong checksum show when the program starts (states 10 and 11, §18.2.10).

        Raises
        ------
        ValueError
            ``image`` is not 4 … 3074 bytes.
        """
        i = motor_index(index, self.n, "load_program_image")
        if not isinstance(image, (bytes, bytearray)) or not 4 <= len(image) <= FLASH_BYTES + 2:
            raise ValueError("load_program_image: a program image is 4 … 3074 bytes (as "
                             "program_image gives it). Nothing was changed.")
        if self._runners is None:
            self._runners = [None] * self.n
        data = bytes(image)
        self._runners[i] = ProgramRunner([], (data[:-2], int.from_bytes(data[-2:], "little")))

    def program_text(self, index: int = 0) -> str | None:
        """The stored program of one motor as text (None: no program, or flash bytes that are
        no program)."""
        r = self._runner(index, "program_text", need=False)
        return None if r is None or r.corrupt else print_program(r.cmds)

    # ------------------------------------------------------------------ control
    def program_start(self, index: MotorIndex = None) -> None:
        """Start program execution (program command 1, §18.2.10): a paused program resumes,
        otherwise it starts at line 1."""
        for r in self._each(index, "program_start"):
            r.start(resume=True)

    def program_restart(self, index: MotorIndex = None) -> None:
        """Start the program at line 1 whatever its state."""
        for r in self._each(index, "program_restart"):
            r.start(resume=False)

    def program_stop(self, index: MotorIndex = None) -> None:
        """Stop program execution (program command 2); the motor keeps its mode."""
        for r in self._each(index, "program_stop"):
            r.stop()

    def program_pause(self, index: MotorIndex = None) -> None:
        """Pause program execution (program command 3); :meth:`program_start` resumes."""
        for r in self._each(index, "program_pause"):
            r.pause()

    def program_step(self, index: MotorIndex = None) -> None:
        """Run the line at the program pointer, then pause (program command 4 with the area of
        that line); a line that waits completes when its wait ends."""
        for r in self._each(index, "program_step"):
            r.step_line()

    def program_command(self, index: int, command: int, data: bytes = b"") -> bytes:
        """The serial command "Program status and command" (61h, MIS manual §18.2.10) for one
        motor: carry out ``command`` with its data and return the 8 status bytes.

        Commands: 0 no operation, 1 start, 2 stop, 3 pause, 4 run while the program pointer
        is inside [data 1, data 2] (16-bit each), 5 set (data 1) and clear (data 2) outputs,
        6 reserved (nothing), 7 prepare the flash for a new program (the stored program is
        erased). Status: state, program pointer (16 bit), stack pointer, checksum (16 bit),
        inputs, outputs (§18.2.10 "returned data"); numbers low byte first as the register
        data of §18.2. The program pointer is the index of the line (line 1 is 0: the
        manual's example answers a start with pointer 0); the stack pointer is 0 (a line
        leaves nothing on the stack).

        Raises
        ------
        ValueError
            An unknown command, data of the wrong length, or a command that needs a program
            where there is none.
        """
        i = motor_index(index, self.n, "program_command")
        need = {0: 0, 1: 0, 2: 0, 3: 0, 4: 4, 5: 2, 6: 0, 7: 2}
        if command not in need or len(data) != need[command]:
            raise ValueError(f"program command {command} with {len(data)} data bytes is not one "
                             "of §18.2.10. Nothing was changed.")
        if command == 5:
            out = int(self.regs[i, R.OUTPUTS])
            self.regs[i, R.OUTPUTS] = (out | data[0]) & ~data[1] & 0xFF
        elif command == 7:
            self.erase_program(i)
        elif command in (1, 2, 3, 4):
            r = self._runner(i, "program_command")
            assert r is not None
            if command == 4:
                r.run_area(int.from_bytes(data[:2], "little") + 1,
                           int.from_bytes(data[2:], "little") + 1)
            else:
                (r.start, r.stop, r.pause)[command - 1]()
        s = self.program_status(i)
        return (bytes([s.state]) + max(s.line - 1, 0).to_bytes(2, "little") + bytes([0])
                + s.checksum.to_bytes(2, "little")
                + bytes([int(self.regs[i, R.INPUTS]) & 0xFF, int(self.regs[i, R.OUTPUTS]) & 0xFF]))

    def program_status(self, index: int = 0) -> ProgramStatus:
        """Program state, line, error flag and checksum of one motor (§18.2.10)."""
        r = self._runner(index, "program_status", need=False)
        if r is None:
            return ProgramStatus(0, "passive", 0, False, 0)
        return r.status()

    def program_refusals(self, index: int = 0) -> list[str]:
        """Register writes of the program the firmware refused (e.g. an active mode while
        ERR_BITS ≠ 0), oldest first (the latest 100)."""
        r = self._runner(index, "program_refusals", need=False)
        return [] if r is None else list(r.refusals)

    def _runner(self, index: int, what: str, need: bool = True) -> ProgramRunner | None:
        i = motor_index(index, self.n, what)
        r = None if self._runners is None else self._runners[i]
        if r is None and need:
            raise ValueError(f"{what}: motor {i} has no stored program (store_program)")
        return r

    def _each(self, index: MotorIndex, what: str) -> list[ProgramRunner]:
        idx = as_index(index, self.n).tolist()
        runners = [self._runner(i, what) for i in idx]
        return [r for r in runners if r is not None]

    # ------------------------------------------------------------------ hooks
    def _snapshot(self, idx: np.ndarray) -> tuple[Any, ...]:
        """What a register transaction on motors ``idx`` may change
        (:meth:`~jvl_gym.motor.bank.RegisterBank._snapshot`) and their stored programs: COMMAND 342
        erases a program and a reset (267, 268) restarts it, each by replacing the motor's
        runner, so the runners as they are now are what a refused transaction puts back."""
        runners = self._runners
        kept = None if runners is None else [runners[i] for i in idx.tolist()]
        return super()._snapshot(idx), kept  # type: ignore[misc]

    def _restore(self, idx: np.ndarray, saved: tuple[Any, ...]) -> None:
        """Put back what :meth:`_snapshot` saved, the stored programs of motors ``idx`` too."""
        rows, runners = saved
        super()._restore(idx, rows)  # type: ignore[misc]
        if runners is not None and self._runners is not None:
            for i, runner in zip(idx.tolist(), runners):
                self._runners[i] = runner

    def _program_power_on(self, idx: np.ndarray) -> None:
        """Power-on of the motors ``idx``: a stored program restarts from line 1 in position
        mode unless SETUP_BITS says not to (module docstring)."""
        if self._runners is None:
            return
        for i in idx.tolist():
            old = self._runners[i]
            if old is None:
                continue
            r = ProgramRunner(old.cmds, (old.flash, old.stored_checksum))
            self._runners[i] = r
            if not int(self.regs[i, R.SETUP_BITS]) & SETUP_NO_PROGRAM_START:
                self.regs[i, R.MODE_REG] = c.POSITION
                r.start(resume=False)

    def _between_samples(self) -> None:
        """What the firmware serves between two outer samples a program runs in besides the
        program (the motor array's other parts override it)."""

    def step(self, n_outer: int = 1) -> None:
        """Advance all motors by ``n_outer`` outer samples; running programs run their lines
        before each outer sample (:mod:`.executor`)."""
        runners = self._runners
        if runners is None or not any(r is not None and r.active for r in runners):
            super().step(n_outer)  # type: ignore[misc]
            return
        left = outer_count(n_outer, "step")
        while left:
            live = [(i, r) for i, r in enumerate(runners) if r is not None and r.active]
            if not live:
                super().step(left)  # type: ignore[misc]
                return
            self._between_samples()
            for i, r in live:
                r.sample(self, i)  # type: ignore[arg-type]
            world = getattr(self, "world", None)
            plan = None if world is None else world.schedule(self, 1)
            driver(self.FAMILY_KEY).run(self.engine_view(plan), 1, serial=True)  # type: ignore[attr-defined]
            left -= 1
