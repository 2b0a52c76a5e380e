"""The twin's side of the 32-bit MacTalk (MAC800 serial quick guide §1.3, MIS manual §18.2):
what a motor of 32-bit registers does on each command.

=====================  ===================================================================
read (50h)             reply ``52h×3 00h FFh <regnum> 04h FBh`` + the register's 4 bytes
read block (51h)       reply with the 32 registers N … N+31 (128 bytes)
write (52h)            4 bytes: the 32-bit value; 2 bytes: extended as the register's format
                       (sign for signed, zero for Word32; :mod:`.codec32`). Validated by the
                       simulator; accept only if carried out
read sample (53h)      the next sample, SAMPLE1..4 as four 32-bit values (16 bytes) in a
                       reply naming SAMPLE1; after the last of the recorded samples a reply
                       without data, then from the first again (MIS §8.2.63; the frame is a
                       decision, :mod:`.codec32`). A write of CNTRL_BITS, MODE_REG or
                       REC_CNT, a reset and a flash write start it at the first again
enter safe mode (54h)  ``enter_safe_mode``, accept (MIS §18.2.5)
exit safe mode (55h)   ``exit_safe_mode`` when in safe mode (else nothing to do), accept
                       (MIS §18.2.6)
write flash (56h)      only in safe mode: save registers to flash (and the flash file), reset;
                       no reply; an accept when it fails (MIS §18.2.7: "The response will only
                       be transmitted if the command failed")
reset (57h)            ``software_reset`` where the family has it, else the power-on
                       ``reset``; no reply (MIS §18.2.8)
program (61h)          the family's ``program_command`` (MIS: stored programs): start, stop,
                       pause, run an area, set/clear outputs, prepare the flash; reply 61h
                       with the 8 status bytes (MIS §18.2.10); no reply where the family has
                       no programs or refuses the command
group write (59h)      every motor whose GROUP_ID is the group writes the register, unless the
                       sequence is that of the last group write it received; the sequence is
                       then held in GROUP_SEQ; never answered (MIS §18.2.9, §8.2.86–87)
=====================  ===================================================================

A register number the table does not have, or a reserved one, reads as 0 and refuses writes.
Any other refusal (range, read-only, mode) changes nothing and gets no reply; so does a command
the motors' family does not support (its :class:`~jvl_gym.families.Capability` set; a failed
write flash excepted, which is accepted as the manual says).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ...families.contract import Capability, UnsupportedOperation
from ...registers.table import is_signed
from ..serving.twin import FlashFileError
from . import codec32 as m32

if TYPE_CHECKING:
    from ..serving.twin import MotorTwin
    from .samples import SampleCursor

__all__ = ["MacTalk32Unit", "is_signed"]


class MacTalk32Unit:
    """The motors of one twin behind the 32-bit MacTalk (the MacTalk twin,
    :class:`~.twin16.Twin`, holds one when it speaks this dialect).

    Parameters
    ----------
    twin : MotorTwin
        Its motors, register numbers, lock, flash files and statistics.
    samples : SampleCursor
        The 53h read cursor of each motor, which the twin shares with its other MacTalk.

    Attributes
    ----------
    group_seq : list of int or None
        Sequence of the last group write each motor received (None: none since power-on),
        which a repeat of it is told by; the motor holds it in its register GROUP_SEQ (0 before
        the first), where the family has that register.
    """

    def __init__(self, twin: MotorTwin, samples: SampleCursor) -> None:
        self.twin = twin
        self.samples = samples
        self.group_seq: list[int | None] = [None] * twin.m.n

    # ------------------------------------------------------------------ registers
    def value(self, i: int, reg: int) -> int:
        """The 32-bit value of register ``reg`` of motor ``i`` (0 where there is none)."""
        t = self.twin
        if reg not in t.m.table or t.m.table.lookup(reg).access.value == "reserved":
            return 0
        return int(t.m.read_raw(reg)[i])

    def data(self, i: int, reg: int, count: int) -> bytes:
        """``count`` registers from ``reg`` on, 4 bytes each, low byte first."""
        return b"".join((self.value(i, reg + k) & 0xFFFFFFFF).to_bytes(4, "little")
                        for k in range(count))

    def write(self, i: int, reg: int, data: bytes) -> bool:
        """Write 2 or 4 data bytes to register ``reg`` of motor ``i``, extended as the register's
        format (:func:`is_signed`); False (nothing changed) if refused."""
        from ...registers import RegisterError

        t = self.twin
        if reg not in t.m.table:
            t.refuse(f"no register {reg}")
            return False
        value = m32.data_value(data, signed=is_signed(t.m.table.lookup(reg).format))
        try:
            t.store(i, {reg: value})
        except (RegisterError, ValueError) as exc:
            t.refuse(str(exc))
            return False
        if reg in (t.reg.CNTRL_BITS, t.reg.MODE_REG, t.reg.REC_CNT):
            self.samples.restart(i)
        return True

    # ------------------------------------------------------------------ frames
    def handle(self, frame: m32.Frame) -> bytes:
        """Carry out one decoded frame; the reply bytes (maybe empty)."""
        t = self.twin
        if isinstance(frame, m32.GroupWrite):
            with t.lock:
                self._group_write(frame)
            return b""
        if not isinstance(frame, m32.Request):
            t.stats["ignored"] += 1
            return b""
        return t.dispatch(frame.address, m32.BROADCAST, lambda i: self._one(i, frame))

    def _group_write(self, f: m32.GroupWrite) -> None:
        t = self.twin
        t.stats["GROUP_WRITE"] += 1
        if t.reg.GROUP_ID < 0:
            t.stats["ignored"] += 1
            return
        groups = t.m.read_raw(t.reg.GROUP_ID)
        for i in range(t.m.n):
            if int(groups[i]) != f.group or self.group_seq[i] == f.sequence:
                continue
            self.group_seq[i] = f.sequence
            self._hold_group_seq(i, f.sequence)
            self.write(i, f.register, f.data)

    def _hold_group_seq(self, i: int, sequence: int) -> None:
        """Motor ``i``'s GROUP_SEQ := ``sequence`` (a read-only register the motor's own
        group-write reception sets, MIS §8.2.87), where its family has that register."""
        t = self.twin
        if t.reg.GROUP_SEQ >= 0:
            t.m.regs[i, t.reg.GROUP_SEQ] = sequence

    def _one(self, i: int, f: m32.Request) -> bytes:
        t = self.twin
        c = m32.Command
        cmd = f.command
        t.stats[cmd.name] += 1
        try:
            if cmd == c.READ:
                return m32.encode_reply(f.register or 0, self.data(i, f.register or 0, 1))
            if cmd == c.READ_BLOCK:
                return m32.encode_reply(f.register or 0,
                                        self.data(i, f.register or 0, m32.BLOCK_REGISTERS))
            if cmd == c.WRITE:
                return m32.ACCEPT if self.write(i, f.register or 0, f.data) else b""
            if cmd == c.READ_SAMPLE:
                t.require(Capability.SAMPLE_BUFFER)
                return m32.encode_reply(t.reg.SAMPLE1, self.samples.next(i))
            if cmd == c.ENTER_SAFE_MODE:
                t.require(Capability.SAFE_MODE)
                t.m.enter_safe_mode(i)
                return m32.ACCEPT
            if cmd == c.EXIT_SAFE_MODE:
                if t.in_safe_mode(i):
                    t.m.exit_safe_mode(i)
                return m32.ACCEPT
            if cmd == c.WRITE_FLASH:
                try:
                    t.require(Capability.FLASH)
                    before = t.m.flash_image(i)
                    t.m.write_flash(i)  # refuses unless in safe mode
                except (ValueError, UnsupportedOperation) as exc:
                    t.refuse(f"WRITE_FLASH for motor {i}: {exc}")
                    return m32.ACCEPT  # MIS §18.2.7: a response only if the command failed
                try:
                    t.save_flash_file(i, before)
                except FlashFileError as exc:
                    t.refuse(f"WRITE_FLASH for motor {i}: {exc}")
                    self.power_on(i)
                    return m32.ACCEPT  # the save failed: answered as a failed command
                self.power_on(i)
                return b""
            if cmd == c.PROGRAM:
                method = getattr(t.m, "program_command", None)
                if method is None:
                    raise ValueError("the motor family has no stored programs")
                return m32.encode_program_reply(method(i, f.data[0], f.data[1:]))
            if cmd == c.RESET:
                t.power_on(i)
                self.power_on(i)
                return b""
        except (ValueError, UnsupportedOperation) as exc:  # RegisterError, ModeError
            t.refuse(f"{cmd.name} for motor {i}: {exc}")
            return b""
        raise AssertionError(cmd)  # pragma: no cover

    def power_on(self, i: int) -> None:
        """Protocol state of motor ``i`` after a reset: no group write received, the sample
        buffer read from its first sample."""
        self.group_seq[i] = None
        self._hold_group_seq(i, 0)
        self.samples.restart(i)
