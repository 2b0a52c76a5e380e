"""MacTalk32Client: talk to a motor of 32-bit registers (MAC800, MIS/SMC, or their twin) over a
serial port (MAC800 serial quick guide §1.3, MIS manual §18.2).

The frames are those of :mod:`.mactalk32` (the codec the twin uses); the port, the timeout and
the retries those of every MacTalk master (:class:`~.master.SerialMaster`). Every register is
32 bits wide at one number; reads and writes are typed by register name with the register
table's formats, and a value the table refuses raises before anything is sent.

Examples
--------
>>> with MacTalk32Client("socket://127.0.0.1:5000", address=7, table=t) as c:  # doctest: +SKIP
...     c.write("V_SOLL", 5000)
...     c.read("P_IST")
"""

from __future__ import annotations

import time
from collections.abc import Iterable
from typing import Any

import numpy as np

from ...compat import renamed_method
from ...registers.table import is_signed
from ..errors import RefusedError, UnexpectedReplyError
from . import codec32 as m32
from .master import DEFAULT_BAUDRATE, RegisterMaster

__all__ = ["MacTalk32Client"]


class MacTalk32Client(RegisterMaster):
    """A 32-bit MacTalk master for one unit address.

    Parameters
    ----------
    port, address, timeout, retries, baudrate, serial, serial_kwargs
        As :class:`~.master.SerialMaster` (address: MY_ADDR).
    table : RegisterTable
        The register table of the unit's family (typed access).
    """

    dialect = m32.DIALECT

    def __init__(self, port: str, address: int = 1, *, table: Any, timeout: float = 0.5,
                 retries: int = 2, baudrate: int = DEFAULT_BAUDRATE, serial: Any = None,
                 **serial_kwargs: Any) -> None:
        super().__init__(port, address, timeout=timeout, retries=retries, baudrate=baudrate,
                         serial=serial, **serial_kwargs)
        self.table = table

    def __enter__(self) -> MacTalk32Client:
        return self

    # ------------------------------------------------------------------ framing
    def _read_reply(self, deadline: float) -> bytes:
        """An accept (3 bytes), or a reply ``52h×3 00h FFh <reg> <!reg> <len> <!len> <data…>
        AAh AAh`` (quick guide §1.3.3) whose length is in its ``len``."""
        head = self._read_exact(3, deadline)
        if head == m32.ACCEPT or len(head) < 3:
            return head
        head += self._read_exact(6, deadline)
        if len(head) < 9:
            return head
        return head + self._read_exact(2 * head[7] + 2, deadline)

    def _decode(self, raw: bytes) -> m32.Frame:
        return m32.decode(raw)

    def _kind(self, frame: Any) -> str:
        if isinstance(frame, m32.Accept):
            return "accept"
        return "data" if isinstance(frame, m32.Reply) else "other"

    def _reply(self, request: bytes, what: str, register: int) -> bytes:
        """The data of the reply naming ``register`` ("always the same as requested", quick
        guide §1.3.3); a reply naming another register is the late answer to an earlier
        request and is passed over."""
        def stale(frame: Any) -> bool:
            return isinstance(frame, m32.Reply) and frame.register != register

        return bytes(self.transact(request, what, stale=stale).data)

    # ------------------------------------------------------------------ raw access
    def read_value(self, register: int, signed: bool = True) -> int:
        """The 32-bit value of register number ``register`` (quick guide §1.3.3, MIS
        §18.2.2), as a signed or unsigned number."""
        data = self._reply(m32.encode_read(self.address, register), f"READ {register}",
                           register)
        if len(data) != m32.READ_LENGTH:
            raise UnexpectedReplyError(f"READ {register}: expected 4 data bytes, got "
                                       f"{len(data)}")
        return m32.data_value(data, signed)

    def read_block(self, register: int) -> list[int]:
        """The signed 32-bit values of the :data:`~.mactalk32.BLOCK_REGISTERS` registers from
        ``register`` on (MIS §18.2.3)."""
        data = self._reply(m32.encode_read_block(self.address, register),
                           f"READ BLOCK {register}", register)
        return [m32.data_value(data[k:k + 4]) for k in range(0, len(data), 4)]

    def read_raws(self, numbers: Iterable[int]) -> dict[int, int]:
        """Stored integers of several registers (:meth:`read_raw` each), read a block of
        :data:`~.mactalk32.BLOCK_REGISTERS` per request (MIS §18.2.3)."""
        numbers = sorted(set(numbers))
        values: dict[int, int] = {}
        for n in numbers:
            if n not in values:
                values.update(zip(range(n, n + m32.BLOCK_REGISTERS), self.read_block(n)))
        out: dict[int, int] = {}
        for n in numbers:
            signed = n not in self.table or is_signed(self._reg(n).format)
            out[n] = values[n] if signed else values[n] & 0xFFFFFFFF
        return out

    def write_value(self, register: int, value: int) -> None:
        """Write the 32-bit number ``value`` (4 bytes, quick guide §1.3.2) and wait for the
        accept."""
        self.transact(m32.encode_write_value(self.address, register, value),
                      f"WRITE {register} = {value}", "accept")

    # ------------------------------------------------------------------ typed access
    def read_raw(self, key: str | int) -> int:
        """Stored integer of a register, signed unless its format is unsigned."""
        reg = self._reg(key)
        return self.read_value(reg.number, is_signed(reg.format))

    def read(self, key: str | int) -> float | int:
        """Register value in user units: scaled formats as float, others int."""
        from ...registers import from_raw

        reg = self._reg(key)
        v = from_raw(reg, self.read_raw(reg.number))
        return float(v) if reg.scale != 1 else int(v)

    def write(self, key: str | int, value: float) -> None:
        """Write a register in user units; validated against the table first (range,
        read-only), so that a bad value raises at once and nothing is sent."""
        from ...registers import to_raw

        reg = self._writable(key)
        self.write_value(reg.number, int(to_raw(reg, value)))

    # ------------------------------------------------------------------ commands
    def enter_safe_mode(self) -> None:
        """ENTER SAFEMODE (54h, MIS §18.2.5): the power stage off; flash and reset allowed."""
        self.transact(m32.encode_enter_safe_mode(self.address), "ENTER SAFE MODE", "accept")

    def exit_safe_mode(self) -> None:
        """EXIT SAFEMODE (55h, MIS §18.2.6)."""
        self.transact(m32.encode_exit_safe_mode(self.address), "EXIT SAFE MODE", "accept")

    #: the previous release's name of EXIT SAFEMODE (the 32-bit families have no init mode)
    go_init_mode = renamed_method("exit_safe_mode", "go_init_mode")

    def write_flash(self, settle: float = 0.2) -> None:
        """WRITE FLASH (56h, MIS §18.2.7): the registers to flash, then a reset. "The response
        will only be transmitted if the command failed": an accept within ``settle`` seconds
        raises :class:`~.errors.RefusedError`."""
        self.transact(m32.encode_write_flash(self.address), "WRITE FLASH", "none")
        if isinstance(self.answer_within(settle), m32.Accept):
            raise RefusedError(f"motor at address {self.address} did not write its flash (MIS "
                               "§18.2.7: flash is written in safe mode only): go to safe mode "
                               "first")

    def software_reset(self, settle: float = 0.2) -> None:
        """RESET (57h, MIS §18.2.8); no reply."""
        self.transact(m32.encode_reset(self.address), "RESET", "none")
        time.sleep(settle)

    # ------------------------------------------------------------------ sample buffer
    def read_sample(self) -> bytes:
        """One read-sample request (53h, MIS §8.2.63): 16 bytes of a sample, or b"" after
        the last."""
        rep = self.transact(m32.encode_read_sample(self.address), "READ SAMPLE")
        return bytes(rep.data)

    def sample_buffer(self) -> dict[str, np.ndarray]:
        """The sample buffer in user units, keyed by the names of the registers SAMPLE1..4
        select (a channel selecting no register, or one named twice: ``SAMPLEk``, raw)."""
        from ...registers import RegisterError, from_raw

        raw = self.sample_buffer_raw()
        out: dict[str, np.ndarray] = {}
        for ch in range(4):
            col = raw[:, ch]
            try:
                reg = self._reg(int(self.read(f"SAMPLE{ch + 1}")))
            except RegisterError:
                out[f"SAMPLE{ch + 1}"] = col
                continue
            if not is_signed(reg.format):
                col = col & 0xFFFFFFFF
            name = reg.name if reg.name not in out else f"SAMPLE{ch + 1}"
            out[name] = np.asarray(from_raw(reg, col))
        return out
