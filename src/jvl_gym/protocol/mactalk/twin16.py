"""Protocol server logic of the digital twin: request bytes → reply bytes + effects on motors.

Each twin speaks its motor family's MacTalk dialect (:mod:`.dialect`): the MAC050–141 MacTalk
described below, or the 32-bit MacTalk of the MAC800 and MIS families (:mod:`.twin32`). A
:class:`~.line.Bus` puts twins of several families on one line.

No I/O here (see :mod:`jvl_gym.protocol.serving.transport`): a :class:`Twin` is a
:class:`~jvl_gym.protocol.serving.twin.MotorTwin` (a :class:`~jvl_gym.MotorArray`, or anything
with the same subset of methods, :class:`MotorBackend`, with addresses, flash files and clock),
and sessions turn received byte chunks into reply bytes.

What the twin does on each MacTalk command (manual 5.1; decisions in ``docs/protocol.md``):

=====================  ===================================================================
read (50h)             reply ``52h×3 00h FFh 04h FBh`` + words N, N+1 (LongInt rule)
read block (51h)       reply with the 16 words N..N+15 (32 bytes; block size is a decision)
write (52h)            2 bytes: the 16-bit word of register N; 4 bytes: a 32-bit value to N
                       (a LongInt, or a 16-bit register whose format the value must fit).
                       Validated by the simulator; accept ``11h×3`` only if it was carried out
read sample buffer     the next sample: SAMPLE1..4 as four 32-bit values (16 bytes); after
(53h)                  the last of REC_CNT samples an empty reply (dl = 0), then from the start
go safe mode (54h)     MotorArray.enter_safe_mode (stops first, 4.4.16), accept
go init mode (55h)     leaves safe mode (exit_safe_mode) or goes to INIT_MODE, accept
write flash (56h)      only in safe mode: save registers to flash (and the flash file), reset;
                       no accept (5.1)
reset (57h)            only in INIT or SAFE mode: software reset; no accept (5.1)
=====================  ===================================================================

What the twin knows of the motors' family it takes from the family's contract
(:class:`~jvl_gym.families.TwinSpec` and the capabilities of ``motors.family``): the dialect,
the safe and init modes, the status bits by name, and which commands the family has; a command
the family does not support is refused (no reply) and changes nothing.

A refused request (range, read-only, wrong mode) changes nothing and gets **no reply**, as a
real unit that does not accept. Frames addressed to another unit, the master's data replies and
accepts (other units on the bus) are ignored. Broadcast (FFh) requests are carried out by every
motor; they are answered only when the twin serves a single motor (a point-to-point link), as a
bus of several units would collide.

The FastMAC/FlexMAC user interface (5.2) of motor *i* is served by :class:`UserInterfaceSession`
when its CNTRL_BITS USERINTF bits latched at power-on are 11 (manual 3.2.36); in SAFE_MODE it
accepts no command (4.4.16) but still reports status and answers reads.
"""

from __future__ import annotations

import logging
import os
from typing import Any

from ...families.contract import Capability, UnsupportedOperation
from ..errors import FrameError
from ..serving.twin import (
    FlashFileError,
    MotorBackend,
    MotorTwin,
    RegisterNumbers,
    TwinFamily,
)
from . import codec16 as mt
from . import codec32 as m32
from . import fastmac as fm
from . import flexmac as fx
from .dialect import MACTALK32, check_dialect
from .samples import SampleCursor
from .twin32 import MacTalk32Unit

__all__ = ["MotorBackend", "TwinFamily", "Twin", "MacTalkSession", "UserInterfaceSession",
           "BLOCK_WORDS", "RegisterNumbers"]

log = logging.getLogger(__name__)

#: words returned by a read-block request (twin decision, docs/protocol.md)
BLOCK_WORDS = 16


def _s16(word: int) -> int:
    return word - 0x10000 if word & 0x8000 else word


def _s32(value: int) -> int:
    value &= 0xFFFFFFFF
    return value - 2**32 if value & 0x80000000 else value


class Twin(MotorTwin):
    """Simulated motors behind the MacTalk / FastMAC / FlexMAC protocols.

    A :class:`~jvl_gym.protocol.serving.twin.MotorTwin` (addresses, flash files, clock, lock)
    that answers MacTalk in its dialect (:meth:`session`, :meth:`handle`) and the FastMAC and
    FlexMAC user interface of each motor (:attr:`user`); the other buses serve the same twin.

    Parameters
    ----------
    motors, addresses, flash_dir
        As for :class:`~jvl_gym.protocol.serving.twin.MotorTwin`; the flash files are also
        written by MacTalk's 'write flash' (56h).
    fastmac_code : dict
        FastMAC register code (:data:`~.fastmac.EXAMPLE_CODE` or ``TABLE_CODE``).
    dialect : str, optional
        MacTalk dialect (:data:`~.dialect.DIALECTS`); default: the one the motors' family
        declares first (:attr:`~jvl_gym.families.TwinSpec.dialects`).

    Attributes
    ----------
    dialect : str
        The MacTalk dialect the twin speaks.
    user : list of UserInterfaceSession
        The FastMAC/FlexMAC user interface of each motor.
    unit32 : MacTalk32Unit or None
        The 32-bit MacTalk commands (None when the twin speaks the 16-bit MacTalk).
    """

    def __init__(self, motors: MotorBackend, addresses: list[int] | None = None,
                 flash_dir: str | os.PathLike[str] | None = None,
                 fastmac_code: dict[str, tuple[int, int]] = fm.DEFAULT_CODE,
                 dialect: str | None = None) -> None:
        self.dialect = check_dialect(dialect if dialect is not None
                                     else motors.family.twin.dialect)
        super().__init__(motors, addresses, flash_dir)
        self.fastmac_code = fastmac_code
        #: the 53h read cursor of each motor
        self.samples = SampleCursor(motors)
        self.user = [UserInterfaceSession(self, i) for i in range(motors.n)]
        self.unit32 = MacTalk32Unit(self, self.samples) if self.dialect == MACTALK32 else None

    def targets(self, address: int, broadcast: int | None = None) -> list[int]:
        """Motors addressed by ``address``; none for the master's address (00h, manual 5.1)."""
        return [] if address == mt.MASTER else super().targets(address, broadcast)

    def value(self, i: int, reg: int) -> int:
        """The register's stored integer (in the 32-bit MacTalk, 0 for a register number the
        table does not have or reserves)."""
        if self.unit32 is not None:
            return self.unit32.value(i, reg)
        return super().value(i, reg)

    def word(self, i: int, reg: int) -> int:
        """The 16-bit word of register number ``reg`` of motor ``i`` (0 where there is none)."""
        if reg not in self.m.table:
            return 0
        r = self.m.table.lookup(reg)
        if r.access.value == "reserved":
            return 0
        return int(self.m.read_raw(reg)[i]) & 0xFFFF

    def words(self, i: int, reg: int, n: int) -> bytes:
        return mt.words_to_bytes([self.word(i, reg + k) for k in range(n)])

    def write_bytes(self, i: int, reg: int, data: bytes) -> bool:
        """Write 2 bytes (a word to register ``reg``) or 4 bytes (a 32-bit value) to motor ``i``;
        False (nothing changed) if refused."""
        from ...registers import Format, RegisterError

        if reg not in self.m.table:
            self.refuse(f"no register {reg}")
            return False
        r = self.m.table.lookup(reg)
        if len(data) == 2:
            w = int.from_bytes(data, "little")
            if r.format == Format.LONGINT:
                raw = _s32((int(self.m.read_raw(reg)[i]) & ~0xFFFF) | w)
            elif r.format in (Format.WORD, Format.LONGINT_HIGH):
                raw = w
            else:
                raw = _s16(w)
        else:
            v = int.from_bytes(data, "little")
            if r.format == Format.LONGINT_HIGH:
                self.refuse(f"a 32-bit write to {r.name}, the high word of a LongInt")
                return False
            raw = v if r.format == Format.WORD else _s32(v)
        try:
            self.store(i, {reg: raw})
        except (RegisterError, ValueError) as exc:
            self.refuse(str(exc))
            return False
        if reg in (self.reg.CNTRL_BITS, self.reg.MODE_REG, self.reg.REC_CNT):
            self.samples.restart(i)
        return True

    # ------------------------------------------------------------------ MacTalk

    def handle(self, frame: mt.Frame | m32.Frame) -> bytes:
        """Carry out one decoded MacTalk frame of the twin's dialect; return the reply bytes
        (maybe empty)."""
        if self.unit32 is not None:
            return self.unit32.handle(frame)  # type: ignore[arg-type]
        if not isinstance(frame, mt.Request):
            self.stats["ignored"] += 1
            return b""
        return self.dispatch(frame.address, mt.BROADCAST, lambda i: self._one(i, frame))

    def _one(self, i: int, f: mt.Request) -> bytes:
        c = mt.Command
        cmd = f.command
        self.stats[cmd.name] += 1
        try:
            if cmd == c.READ:
                return mt.encode_data_reply(self.words(i, f.register or 0, 2))
            if cmd == c.READ_BLOCK:
                return mt.encode_data_reply(self.words(i, f.register or 0, BLOCK_WORDS))
            if cmd == c.WRITE:
                return mt.ACCEPT if self.write_bytes(i, f.register or 0, f.data) else b""
            if cmd == c.READ_SAMPLE_BUFFER:
                self.require(Capability.SAMPLE_BUFFER)
                return mt.encode_data_reply(self.samples.next(i))
            if cmd == c.GO_SAFE_MODE:
                self.require(Capability.SAFE_MODE)
                self.m.enter_safe_mode(i)
                return mt.ACCEPT
            if cmd == c.GO_INIT_MODE:
                if self.in_safe_mode(i):
                    self.m.exit_safe_mode(i)
                else:
                    self.require(Capability.INIT_MODE)
                    self.m.go_init_mode(i)
                return mt.ACCEPT
            if cmd == c.WRITE_FLASH:
                self.require(Capability.FLASH)
                before = self.m.flash_image(i)
                self.m.write_flash(i)  # refuses unless in safe mode
                try:
                    self.save_flash_file(i, before)
                except FlashFileError:
                    # 56h has no answer (manual 5.1): the motor stays in SAFE_MODE, its flash
                    # as before, which the requester reads back (MODE_REG 15)
                    self.m.enter_safe_mode(i)
                    raise
                self._after_reset(i)
                return b""
            if cmd == c.RESET:
                self.power_on(i)  # the MAC050–141 refuses unless INIT or SAFE
                self._after_reset(i)
                return b""
        except (ValueError, UnsupportedOperation) as exc:  # RegisterError, ModeError
            self.refuse(f"{cmd.name} for motor {i}: {exc}")
            return b""
        raise AssertionError(cmd)  # pragma: no cover

    def _after_reset(self, i: int) -> None:
        self.samples.restart(i)
        self.user[i].power_on()

    def session(self) -> MacTalkSession:
        """A new MacTalk session (one per connection)."""
        return MacTalkSession(self)


class MacTalkSession:
    """One MacTalk byte stream (a TCP connection, a pty) in the twin's dialect: bytes in →
    reply bytes out."""

    def __init__(self, twin: Twin) -> None:
        self.twin = twin
        self.decoder = (m32.MacTalk32Decoder() if twin.dialect == MACTALK32
                        else mt.MacTalkDecoder())

    def _run(self, items: list[Any]) -> bytes:
        out = bytearray()
        for item in items:
            if isinstance(item, FrameError):
                self.twin.stats["errors"] += 1
                log.info("MacTalk frame rejected: %s", item.reason)
                continue
            self.twin.stats["frames"] += 1
            out += self.twin.handle(item)
        return bytes(out)

    def feed(self, chunk: bytes) -> bytes:
        """Received bytes → the replies they call for."""
        return self._run(self.decoder.feed(chunk))

    def flush(self) -> bytes:
        """Inter-character timeout: a held-back partial frame is truncated."""
        return self._run(list(self.decoder.flush()))


class UserInterfaceSession:
    """FastMAC / FlexMAC on the user interface of motor ``index`` (manual 5.2).

    Active only when the CNTRL_BITS USERINTF bits latched at power-on are 11 (3.2.36). In FastMAC
    the motor answers every received byte with a status byte (the real motor sends status bytes
    continuously, 5.2.1.6); in FlexMAC it answers each write with a status byte and each read with
    the data (see :mod:`.flexmac`).
    """

    def __init__(self, twin: Twin, index: int) -> None:
        self.twin = twin
        self.i = index
        self.power_on()

    def power_on(self) -> None:
        """Protocol state after power-on / reset: FastMAC, rapid, toggle unsynchronised."""
        self.rx = fm.FastMacReceiver(self.twin.fastmac_code)
        self.flex = fx.FlexMacDecoder()
        self.flexmac = False
        self.toggle = 0
        self.slow = False
        self.send_myaddr = False

    @property
    def active(self) -> bool:
        """USERINTF = 11 at the last power-on (a family without the FastMAC/FlexMAC user
        interface, :attr:`~jvl_gym.families.Capability.USER_INTERFACE`, never is)."""
        if not self.twin.supports(Capability.USER_INTERFACE) or self.twin.unit32 is not None:
            return False
        return int(self.twin.m.interface_bits[self.i]) & 3 == 3

    def _bit(self, name: str) -> int:
        """Mask of the status bit ``name`` of the family's status register."""
        return self.twin.spec.bit(name)

    def status(self) -> int:
        """The status byte now (manual 5.2.1.6): IN_POS, ACC_FLAG, DEC_FLAG and the error bits
        of the family's status register."""
        spec = self.twin.spec
        st = int(self.twin.m.read_raw(spec.status_register)[self.i])
        dec, acc = bool(st & self._bit("DEC_FLAG")), bool(st & self._bit("ACC_FLAG"))
        return fm.encode_status(fm.Status(self.toggle, dec, acc and not dec,
                                          bool(st & self._bit("IN_POS")), self.flexmac, False,
                                          bool(st & spec.mask(spec.error_bits))))

    def feed(self, chunk: bytes) -> bytes:
        """Received bytes → status bytes / read replies."""
        if not self.active:
            self.twin.stats["user_inactive"] += len(chunk)
            return b""
        out = bytearray()
        with self.twin.lock:
            for b in chunk:
                out += self._flex_byte(b) if self.flexmac else self._fast_byte(b)
        return bytes(out)

    def flush(self) -> bytes:
        if self.flexmac:
            self.twin.stats["errors"] += len(self.flex.flush())
        return b""

    # ------------------------------------------------------------------ FastMAC
    def _fast_byte(self, b: int) -> bytes:
        got = self.rx.feed(b)
        if isinstance(got, FrameError):
            self.twin.stats["errors"] += 1
        elif got is not None:
            self.twin.stats["fastmac"] += 1
            if self.twin.in_safe_mode(self.i):
                self.twin.refuse("FastMAC command in SAFE_MODE (manual 4.4.16)")
            else:
                self.toggle = got.toggle
                self._fast(got)
        if self.send_myaddr:
            self.send_myaddr = False
            return bytes((self.twin.word(self.i, self.twin.reg.MYADDR) & 0xFF,))
        return bytes((self.status(),))

    def _w(self, reg: int, raw: int) -> bool:
        r = self.twin.reg
        return self.twin.write_bytes(self.i, reg, mt.long_to_bytes(_s32(raw))
                                     if reg in (r.P_SOLL, r.P_IST, r.P_FNC)
                                     else mt.words_to_bytes([raw & 0xFFFF]))

    def _err_stat(self, clear: str | tuple[str, ...] = (), set_: str = "") -> None:
        """Clear the status bits named ``clear`` and set the one named ``set_``."""
        spec = self.twin.spec
        number = self.twin.m.table.lookup(spec.status_register).number
        st = int(self.twin.m.read_raw(number)[self.i])
        off = spec.mask((clear,) if isinstance(clear, str) else clear)
        self._w(number, (st & ~off) | (spec.bit(set_) if set_ else 0))

    def _raw(self, reg: int) -> int:
        return int(self.twin.m.read_raw(reg)[self.i])

    def _fast(self, c: fm.FastMacByte) -> None:
        """Carry out a FastMAC command (manual 5.2.1.4)."""
        if c.mode != fm.Mode.COMMAND:
            assert c.group is not None and c.number is not None
            self._w(self.twin.reg.pointer[c.group], c.number)
            if self.twin.mode(self.i) != int(c.mode):
                self._w(self.twin.reg.MODE_REG, int(c.mode))
            return
        k = fm.FastCommand
        cmd = c.command
        if cmd == k.RESET_ERROR:
            self._err_stat(clear=self.twin.spec.clearable_bits)
        elif cmd == k.P_SOLL_ZERO:
            self._w(self.twin.reg.P_SOLL, 0)
            self._err_stat(clear="IN_POS")
        elif cmd == k.P_IST_ZERO:
            self._w(self.twin.reg.P_IST, 0)
        elif cmd == k.P_FNC_ZERO:
            self._w(self.twin.reg.P_FNC, 0)
            self._err_stat(clear="IN_POS")
        elif cmd == k.V_SOLL_ZERO:
            self._w(self.twin.reg.V_SOLL, 0)
        elif cmd == k.T_SOLL_ZERO:
            self._w(self.twin.reg.T_SOLL, 0)
        elif cmd == k.IN_POS_ZERO:
            self._err_stat(clear="IN_POS")
        elif cmd in (k.REL_P7_FNC, k.REL_P8_FNC):
            p = self._raw(self.twin.reg.P7 if cmd == k.REL_P7_FNC else self.twin.reg.P8)
            # literally as in 5.2.1.4
            self._w(self.twin.reg.P_FNC, (self._raw(self.twin.reg.FLWERR) - p) * 16)
            self._err_stat(clear="IN_POS")
        elif cmd in (k.SET1, k.SET2, k.SET3, k.SET4):
            n = int(cmd) - int(k.SET1) + 1
            for reg in self.twin.reg.pointer.values():
                self._w(reg, n)
            self._err_stat(clear="IN_POS")
        elif cmd == k.HOME:
            home = self._raw(self.twin.reg.HOME_MODE) >> 8
            if home in (12, 13, 14):
                self._w(self.twin.reg.MODE_REG, home)
        elif cmd in (k.MOVE_REL_P7, k.MOVE_REL_P8):
            p = self._raw(self.twin.reg.P7 if cmd == k.MOVE_REL_P7 else self.twin.reg.P8)
            r = self.twin.reg
            self._w(r.P_SOLL, self._raw(r.P_IST) + p - self._raw(r.FLWERR))
        elif cmd == k.TRANSMIT_SLOWLY:
            self.slow = True
        elif cmd == k.ABSOLUTE:
            self._err_stat(clear=("RELPOSPSOLL", "RELPOSPFNC"))
        elif cmd == k.RELATIVE_P_SOLL:
            self._err_stat(clear="RELPOSPFNC", set_="RELPOSPSOLL")
        elif cmd == k.RELATIVE_P_FNC:
            self._err_stat(clear="RELPOSPSOLL", set_="RELPOSPFNC")
        elif cmd == k.TRANSMIT_MYADDR:
            self.send_myaddr = True
        elif cmd == k.USE_FLEXMAC:
            self.flexmac = True
            self.flex = fx.FlexMacDecoder()
        # NOP, RAPID_COMM / SAFE_COMM (handled by the receiver), USE_FASTMAC: nothing to do

    # ------------------------------------------------------------------ FlexMAC
    def _flex_byte(self, b: int) -> bytes:
        out = bytearray()
        for item in self.flex.feed(bytes((b,))):
            if isinstance(item, FrameError):
                self.twin.stats["errors"] += 1
                continue
            self.twin.stats["flexmac"] += 1
            out += self._flex(item)
        return bytes(out)

    def _flex(self, msg: fx.FlexWrite | fx.FlexRead) -> bytes:
        reg = msg.register
        if isinstance(msg, fx.FlexRead):
            if msg.use_fastmac:
                self.flexmac = False
                self.rx = fm.FastMacReceiver(self.twin.fastmac_code)
                self.toggle ^= 1
                return bytes((self.status(),))
            if reg is None:
                self.twin.refuse(f"FlexMAC read of {msg}: no register there")
                return b""
            return fx.encode_read_reply(msg.header, self.twin.words(self.i, reg,
                                                                    2 if msg.long else 1))
        if self.twin.in_safe_mode(self.i):
            self.twin.refuse("FlexMAC write in SAFE_MODE (manual 4.4.16)")
        elif reg is None:
            self.twin.refuse(f"FlexMAC write to {msg}: no register there")
        elif self.twin.write_bytes(self.i, reg, msg.data):
            self.toggle ^= 1
        return bytes((self.status(),))
