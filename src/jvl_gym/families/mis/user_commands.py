"""Firmware state behind some COMMAND values of the MIS motor array (MIS manual §8.2.21–8.2.23):
the RelativeMove flag, the protection of commands by 999, and the K-phase flash.

- FastMac 20 (116) clears the RelativeMove flag, FastMac 21 and 22 (117, 118) set it
  (§8.2.21). The manual says nothing of what reads the flag (no register shows it, no program
  command of §9 names it), so the simulator keeps it, shows it as
  :attr:`UserCommands.relative_move` and lets it change nothing else
  (``docs/families/mis-sim.md``, "RelativeMove flag").
- Commands marked ``**`` in §8.2.22–23 (350, 383, 720, 721, 901, 902) are "protected from
  accidental writes. Must be preceded by 999 command": 999 arms the next command written to
  COMMAND, which takes the arming whatever it is; a protected command that is not armed does
  nothing.
- 720 saves KPHASE in the K-phase flash, 721 loads the K-phase flash into KPHASE (§8.2.23); the
  K-phase flash holds KPHASE's default until 720 writes it, and a reset keeps it. 350, 383, 901
  and 902 calibrate hardware (encoders, the motor's K-phase at speed) and do nothing here.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ...motor.arguments import MotorIndex, as_index
from .firmware import regs as R

__all__ = ["UserCommands", "CMD_UNLOCK", "PROTECTED", "RELATIVE_MOVE_CLEAR",
           "RELATIVE_MOVE_SET", "CMD_KPHASE_SAVE", "CMD_KPHASE_LOAD"]

CMD_UNLOCK = 999  #: arms the next command (§8.2.22: protected commands "must be preceded by 999")
CMD_KPHASE_SAVE = 720  #: KPHASE → the K-phase flash (§8.2.23)
CMD_KPHASE_LOAD = 721  #: the K-phase flash → KPHASE (§8.2.23)
#: the commands marked ** in §8.2.22–23
PROTECTED = frozenset({350, 383, CMD_KPHASE_SAVE, CMD_KPHASE_LOAD, 901, 902})
RELATIVE_MOVE_CLEAR = 116  #: FastMac 20 (§8.2.21)
RELATIVE_MOVE_SET = (117, 118)  #: FastMac 21 and 22 (§8.2.21)


class UserCommands:
    """The RelativeMove flag, the 999 arming and the K-phase flash of
    :class:`~.motors.MisMotorArray` (a mixin over its arrays; module docstring)."""

    n: int
    regs: np.ndarray
    #: per motor the RelativeMove flag, armed by 999, the K-phase flash (:meth:`_command_state`);
    #: None while no command has used them (every flag clear, nothing armed, the K-phase flash
    #: KPHASE's default)
    _relative_flag: np.ndarray | None = None
    _armed: np.ndarray | None = None
    _kphase_flash: np.ndarray | None = None

    def _command_state(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Per motor: RelativeMove flag, armed by 999, the K-phase flash (created on first
        use)."""
        if self._relative_flag is None:
            self._relative_flag = np.zeros(self.n, dtype=bool)
            self._armed = np.zeros(self.n, dtype=bool)
            self._kphase_flash = np.full(self.n, int(self.table.lookup("KPHASE").default),
                                         dtype=np.int64)
        return self._relative_flag, self._armed, self._kphase_flash  # type: ignore[return-value]

    @property
    def relative_move(self) -> np.ndarray:
        """The firmware's RelativeMove flag of each motor (FastMac 20–22, §8.2.21), (N,) bool
        (a copy)."""
        return self._command_state()[0].copy()

    def kphase_flash(self, index: MotorIndex = None) -> np.ndarray:
        """What the K-phase flash holds (command 720 writes it, 721 reads it), (M,) int64."""
        return self._command_state()[2][as_index(index, self.n)].copy()

    def _commands_power_on(self, idx: np.ndarray) -> None:
        """Power-on of motors ``idx``: the flag clear and nothing armed; the K-phase flash
        kept (nothing to do before a command has used them)."""
        flag, armed = self._relative_flag, self._armed
        if flag is None or armed is None:
            return
        flag[idx] = False
        armed[idx] = False

    def _snapshot(self, idx: np.ndarray) -> tuple[Any, ...]:
        """What a register transaction on motors ``idx`` may change
        (``RegisterBank._snapshot``) and this module's state of those motors (a refused
        transaction takes their commands back; a command changes its own motor's only; None
        while no command has used it)."""
        flag, armed, kflash = self._relative_flag, self._armed, self._kphase_flash
        kept = None if flag is None or armed is None or kflash is None else (
            flag[idx], armed[idx], kflash[idx])
        return super()._snapshot(idx), kept  # type: ignore[misc]

    def _restore(self, idx: np.ndarray, saved: tuple[Any, ...]) -> None:
        """Put back what :meth:`_snapshot` saved (the state unused again where it was)."""
        rows, kept = saved
        super()._restore(idx, rows)  # type: ignore[misc]
        if kept is None:
            self._relative_flag = self._armed = self._kphase_flash = None
            return
        state = self._command_state()
        state[0][idx], state[1][idx], state[2][idx] = kept

    def _user_command(self, i: int, cmd: int) -> bool:
        """Take the arming of motor ``i`` and run ``cmd`` if it is one of this module's; False
        if it is another command (not armed where it is protected: handled, nothing done)."""
        flag, armed, kflash = self._command_state()
        was_armed = bool(armed[i])
        armed[i] = cmd == CMD_UNLOCK
        if cmd == CMD_UNLOCK:
            return True
        if cmd in PROTECTED and not was_armed:
            return True
        if cmd == RELATIVE_MOVE_CLEAR:
            flag[i] = False
        elif cmd in RELATIVE_MOVE_SET:
            flag[i] = True
        elif cmd == CMD_KPHASE_SAVE:
            kflash[i] = self.regs[i, R.KPHASE]
        elif cmd == CMD_KPHASE_LOAD:
            self.regs[i, R.KPHASE] = kflash[i]
        else:
            return cmd in PROTECTED
        return True
