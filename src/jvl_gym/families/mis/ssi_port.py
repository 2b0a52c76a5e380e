"""The SSI encoder port of the MIS motor array: commands 320–322 and the readings under way
(MIS manual §5.7, §8.2.22; the reading itself: :mod:`.firmware.ssi`).

The encoder's word is the world input ``ssi_word`` (``set_input``). A reading runs between
outer samples: :meth:`SsiPort.step` stops the compiled stepping at each outer sample a reading
needs (a transfer's start, an attempt's end) and serves it there (a transfer that starts within
an outer sample latches the word that sample holds: the one set before it runs); without a
reading under way it steps straight through. A reset or power-on ends the readings and the SSI
set-up, and zeroes EXTENCODER2 unless SETUP_BITS bit 13 keeps it over a reset (§8.2.68).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ...motor.arguments import outer_count
from . import constants as c
from . import layout as L
from .firmware import regs as R
from .firmware.ssi import (
    CMD_SSI_READ,
    CMD_SSI_READ_GRAY,
    CMD_SSI_SETUP,
    ERR_SSI,
    SETUP_KEEP_SSI,
    SETUP_NO_SSI_ERROR,
    WARN_SSI,
    SsiReading,
    SsiSetup,
)

__all__ = ["SsiPort", "SSI_COMMANDS"]

#: the user commands of the SSI port
SSI_COMMANDS = frozenset({CMD_SSI_SETUP, CMD_SSI_READ, CMD_SSI_READ_GRAY})


class SsiPort:
    """The SSI port of :class:`~.motors.MisMotorArray` (a mixin over its arrays)."""

    n: int
    regs: np.ndarray
    state: np.ndarray
    inputs: np.ndarray
    #: the motors whose RS422 is set up for SSI and the readings under way (:meth:`_ssi`); None
    #: while no SSI command has run (none set up, none under way)
    _ssi_ready: set[int] | None = None
    _ssi_reads: dict[int, SsiReading] | None = None

    def _ssi(self) -> tuple[set[int], dict[int, SsiReading]]:
        """The motors whose RS422 is set up for SSI (command 320) and the readings under way
        (created on first use)."""
        if self._ssi_ready is None or self._ssi_reads is None:
            self._ssi_ready = set()
            self._ssi_reads = {}
        return self._ssi_ready, self._ssi_reads

    def _ssi_command(self, i: int, cmd: int) -> None:
        """User command 320, 321 or 322 for motor ``i``: 320 sets the port up; 321/322 start
        a reading on a port set up (without 320 the lines carry no SSI clock and nothing is
        read); a reading under way goes on."""
        ready, reads = self._ssi()
        if cmd == CMD_SSI_SETUP:
            ready.add(i)
            return
        if i not in ready or i in reads:
            return
        setup = SsiSetup.of(int(self.regs[i, R.SSI_SETUP1]), int(self.regs[i, R.SSI_SETUP2]))
        reads[i] = SsiReading(setup, int(self.state[i, L.S_TICK]),
                              gray=cmd == CMD_SSI_READ_GRAY or setup.gray)
        self._ssi_serve()

    def _ssi_power_on(self, idx: np.ndarray) -> None:
        """Power-on of motors ``idx``: no SSI set-up, no reading (EXTENCODER2 = 0 unless
        SETUP_BITS bit 13, §8.2.68, is the firmware's start: ``firmware.start``)."""
        if self._ssi_ready or self._ssi_reads:
            ready, reads = self._ssi()
            for i in idx.tolist():
                ready.discard(i)
                reads.pop(i, None)

    def _ssi_keep(self, idx: np.ndarray, before: np.ndarray) -> None:
        """After a reset of motors ``idx``: EXTENCODER2 back to ``before`` (its values before
        the reset) where SETUP_BITS bit 13 says "do not zero the SSI data register at start-up"
        (§8.2.68)."""
        keep = (self.regs[idx, R.SETUP_BITS] & SETUP_KEEP_SSI) != 0
        self.regs[idx[keep], R.EXTENCODER2] = before[keep]

    def _ssi_serve(self, latch: bool = True) -> None:
        """Serve every reading whose next outer sample has come: judge an attempt at its end
        and (``latch``: before the next outer sample runs, when the encoder word it holds is
        set) latch the encoder's word at a transfer's start (:mod:`.firmware.ssi`)."""
        _, reads = self._ssi()
        for i in list(reads):
            r = reads[i]
            tick = int(self.state[i, L.S_TICK])
            while r.next_tick() <= tick:
                if len(r.samples) < r.setup.samples:
                    if not latch:
                        break
                    r.take(int(self.inputs[i, L.I_SSI_WORD]))
                elif r.attempt_good():
                    self.regs[i, R.EXTENCODER2] = r.samples[-1]
                    del reads[i]
                    break
                elif not r.retry():
                    self._ssi_failed(i)
                    del reads[i]
                    break

    def _ssi_failed(self, i: int) -> None:
        """A reading failed after its retries: EXTENCODER2 keeps the last good value; ERR_BITS
        bit 11 (with the general error bit 0), or WARN_BITS bit 7 with SETUP_BITS bit 20."""
        if self.regs[i, R.SETUP_BITS] & SETUP_NO_SSI_ERROR:
            self.regs[i, R.WARN_BITS] |= WARN_SSI
        else:
            self.regs[i, R.ERR_BITS] |= ERR_SSI | c.ERR_GENERAL

    def _ssi_next(self) -> int | None:
        """Outer samples to the next one a reading needs (None: no reading under way)."""
        _, reads = self._ssi()
        if not reads:
            return None
        return max(min(r.next_tick() - int(self.state[i, L.S_TICK]) for i, r in reads.items()),
                   1)

    def step(self, n_outer: int = 1) -> None:
        """Advance all motors by ``n_outer`` outer samples, serving the SSI readings under way
        at the outer samples they need (module docstring)."""
        left = outer_count(n_outer, "step")
        while left:
            self._ssi_serve()
            gap = self._ssi_next()
            if gap is None:  # (a program may start a reading within these samples)
                super().step(left)  # type: ignore[misc]
                self._ssi_serve(latch=False)
                return
            k = min(gap, left)
            super().step(k)  # type: ignore[misc]
            self._ssi_serve(latch=False)
            left -= k

    def _between_samples(self) -> None:
        """Served between two outer samples a program runs in (:mod:`.program.api`)."""
        self._ssi_serve()

    def _snapshot(self, idx: np.ndarray) -> tuple[Any, ...]:
        """What a register transaction may change (``RegisterBank._snapshot``) and the SSI
        port's set-up and readings (a refused transaction takes a command 320–322 back; None
        while no SSI command has run)."""
        ready, reads = self._ssi_ready, self._ssi_reads
        return (super()._snapshot(idx),  # type: ignore[misc]
                None if ready is None else set(ready), None if reads is None else dict(reads))

    def _restore(self, idx: np.ndarray, saved: tuple[Any, ...]) -> None:
        """Put back what :meth:`_snapshot` saved."""
        rows, ready, reads = saved
        super()._restore(idx, rows)  # type: ignore[misc]
        self._ssi_ready, self._ssi_reads = ready, reads
