"""MacTalkClient: talk to a MAC50–141 (or the twin) over a serial port (manual 5.1).

pyserial based: ``port`` is a device path (``/dev/ttyUSB0``, a twin's pty) or any pyserial URL
(``socket://127.0.0.1:5000`` for the twin's TCP endpoint, ``rfc2217://…``). Reads and writes are
typed by register name with the register table's formats (manual 3.1, 3.2); raw word access is
available too. Each request waits ``timeout`` seconds for its reply and is sent again up to
``retries`` times; a motor that never answers raises :class:`NoAnswerError` with what to check.

Examples
--------
>>> with MacTalkClient("socket://127.0.0.1:5000", address=19) as c:  # doctest: +SKIP
...     c.write("V_SOLL", 1600)
...     c.read("P_IST")
"""

from __future__ import annotations

import time
from collections.abc import Iterable
from typing import Any

import numpy as np

from ...registers import RegisterTable
from ..errors import RefusedError, UnexpectedReplyError
from . import codec16 as mt
from .master import DEFAULT_BAUDRATE, RegisterMaster

__all__ = ["MacTalkClient", "DEFAULT_BAUDRATE", "SAMPLE_BYTES"]

#: data bytes of a sample (SAMPLE1..4, 4 bytes each) in a read-sample-buffer reply (manual 5.1)
SAMPLE_BYTES = 16

def _default_table() -> RegisterTable:
    """The register table of the first registered family that speaks this client's MacTalk
    (:data:`~.codec16.DIALECT`, ``jvl_gym.families``)."""
    from ...families import families, family

    return next(family(k).table for k in families() if family(k).twin.dialect == mt.DIALECT)


class MacTalkClient(RegisterMaster):
    """A MacTalk master for one unit address (the port's plumbing: :class:`~.master.SerialMaster`).

    Parameters
    ----------
    port, address, timeout, retries, baudrate, serial, serial_kwargs
        As :class:`~.master.SerialMaster` (address: MYADDR).
    table : RegisterTable, optional
        Register table for typed access (default: the table of the first registered family
        that speaks the 16-bit MacTalk, the MAC050–141).
    """

    dialect = mt.DIALECT

    def __init__(self, port: str, address: int = 1, *, timeout: float = 0.5, retries: int = 2,
                 baudrate: int = DEFAULT_BAUDRATE, table: Any = None, serial: Any = None,
                 **serial_kwargs: Any) -> None:
        super().__init__(port, address, timeout=timeout, retries=retries, baudrate=baudrate,
                         serial=serial, **serial_kwargs)
        self.table = table if table is not None else _default_table()

    def __enter__(self) -> MacTalkClient:
        return self

    def _read_reply(self, deadline: float) -> bytes:
        """Read one reply frame: an accept or a data reply (length from its datalength)."""
        head = self._read_exact(3, deadline)
        if head == mt.ACCEPT or len(head) < 3:
            return head
        head += self._read_exact(4, deadline)
        if len(head) < 7:
            return head
        dl = head[5]
        return head + self._read_exact(2 * dl + 2, deadline)

    def _decode(self, raw: bytes) -> mt.Frame:
        return mt.decode(raw)

    def _kind(self, frame: Any) -> str:
        if isinstance(frame, mt.Accept):
            return "accept"
        return "data" if isinstance(frame, mt.DataReply) else "other"

    # ------------------------------------------------------------------ raw access
    def read_words(self, register: int) -> tuple[int, int]:
        """Words of registers N and N+1 (a read always returns four bytes, manual 5.1; a data
        reply of another length is the late answer to an earlier request, passed over)."""
        rep = self.transact(mt.encode_read(self.address, register), f"READ {register}",
                            stale=lambda f: isinstance(f, mt.DataReply) and len(f.data) != 4)
        assert isinstance(rep, mt.DataReply)
        if len(rep.data) != 4:
            raise UnexpectedReplyError(f"READ {register}: expected 4 data bytes, got "
                                       f"{len(rep.data)}")
        w = mt.bytes_to_words(rep.data)
        return w[0], w[1]

    def read_block(self, register: int) -> list[int]:
        """Words of the block starting at ``register`` (the twin sends 16)."""
        rep = self.transact(mt.encode_read_block(self.address, register),
                            f"READ BLOCK {register}")
        assert isinstance(rep, mt.DataReply)
        return mt.bytes_to_words(rep.data)

    def read_raws(self, numbers: Iterable[int]) -> dict[int, int]:
        """Stored integers of several registers (:meth:`read_raw` each), read two numbers
        per request (a read returns registers N and N+1, manual 5.1)."""
        from ...registers import Format, from_word16, join_longint

        numbers = sorted(set(numbers))
        words: dict[int, int] = {}
        for n in numbers:
            if n not in words:
                words[n], words[n + 1] = self.read_words(n)
        out: dict[int, int] = {}
        for n in numbers:
            reg = self._reg(n)
            if reg.format == Format.LONGINT:
                if n + 1 not in words:
                    words[n + 1] = self.read_words(n + 1)[0]
                out[n] = int(join_longint(words[n], words[n + 1]))
            elif reg.access.value == "reserved":
                out[n] = words[n]
            else:
                out[n] = int(from_word16(reg, words[n]))
        return out

    def write_word(self, register: int, word: int) -> None:
        """Write one 16-bit word (datalength 2) and wait for the accept."""
        self.transact(mt.encode_write_word(self.address, register, word),
                      f"WRITE {register} = {word:#06x}", "accept")

    def write_long(self, register: int, value: int) -> None:
        """Write a 32-bit value (datalength 4) and wait for the accept."""
        self.transact(mt.encode_write_long(self.address, register, value),
                      f"WRITE {register} = {value}", "accept")

    # ------------------------------------------------------------------ typed access
    def read_raw(self, key: str | int) -> int:
        """Stored integer of a register (a LongInt's full 32-bit value; Fixed as integer)."""
        from ...registers import Format, from_word16, join_longint

        reg = self._reg(key)
        w0, w1 = self.read_words(reg.number)
        if reg.format == Format.LONGINT:
            return int(join_longint(w0, w1))
        if reg.access.value == "reserved":
            return w0
        return int(from_word16(reg, w0))

    def read(self, key: str | int) -> float | int:
        """Register value in user units (manual 3.1): Fixed formats as float, others int."""
        from ...registers import from_raw

        reg = self._reg(key)
        v = from_raw(reg, self.read_raw(reg.number))
        return float(v) if reg.scale != 1 else int(v)

    def write_raw(self, key: str | int, raw: int) -> None:
        """Write a stored integer, validated against the table before sending."""
        reg = self._reg(key)
        self.write(reg.number, raw / reg.scale)

    def write(self, key: str | int, value: float) -> None:
        """Write a register in user units; validated against the table first (range,
        read-only) so that a bad value raises at once instead of timing out."""
        from ...registers import Format, to_raw, to_word16

        reg = self._writable(key)
        raw = int(to_raw(reg, value))
        if reg.format == Format.LONGINT:
            self.write_long(reg.number, raw)
        else:
            self.write_word(reg.number, int(to_word16(reg, raw)))

    # ------------------------------------------------------------------ commands
    def enter_safe_mode(self) -> None:
        """MacTalk 'go safe mode' (5.1, 4.4.16): the bridge off, flash and reset allowed."""
        self.transact(mt.encode_go_safe_mode(self.address), "GO SAFE MODE", "accept")

    def go_init_mode(self) -> None:
        """MacTalk 'go init mode' (5.1): INIT_MODE, or out of SAFE_MODE when in it."""
        self.transact(mt.encode_go_init_mode(self.address), "GO INIT MODE", "accept")

    def exit_safe_mode(self) -> None:
        """Leave SAFE_MODE: MacTalk 'go init mode' (5.1), which a motor in safe mode takes as
        the way out."""
        self.go_init_mode()

    def write_flash(self, settle: float = 0.2) -> None:
        """Write parameters to flash and reset (only in SAFE_MODE; no accept, 5.1)."""
        if self.read("MODE_REG") != 15:
            raise RefusedError("write to flash needs SAFE_MODE (manual 2.2, 4.4.16): call "
                               "enter_safe_mode() first")
        self.transact(mt.encode_write_flash(self.address), "WRITE FLASH", "none")
        time.sleep(settle)

    def software_reset(self, settle: float = 0.2) -> None:
        """Software reset (only in INIT or SAFE mode; no accept, 5.1)."""
        self.transact(mt.encode_reset(self.address), "RESET", "none")
        time.sleep(settle)

    def read_sample(self) -> bytes:
        """One read-sample-buffer request: 16 bytes of a sample, or b"" at the end (a data
        reply of another length is the late answer to an earlier read, passed over)."""
        rep = self.transact(mt.encode_read_sample_buffer(self.address), "READ SAMPLE BUFFER",
                            stale=lambda f: isinstance(f, mt.DataReply)
                            and len(f.data) not in (0, SAMPLE_BYTES))
        assert isinstance(rep, mt.DataReply)
        return rep.data

    def sample_buffer(self) -> dict[str, np.ndarray]:
        """The sample buffer in user units, keyed by the names of SAMPLE1..SAMPLE4."""
        from ...registers import from_raw

        raw = self.sample_buffer_raw()
        out: dict[str, np.ndarray] = {}
        for ch in range(4):
            num = int(self.read(f"SAMPLE{ch + 1}"))
            reg = self._reg(num)
            col = raw[:, ch]
            if reg.format.value not in ("Word", "LongIntHigh", "LongInt"):
                col = ((col + 2**15) % 2**16) - 2**15
            name = reg.name if reg.name not in out else f"SAMPLE{ch + 1}"
            out[name] = np.asarray(from_raw(reg, col))
        return out

    def wait_mode(self, mode: int, timeout: float = 10.0, poll: float = 0.02) -> None:
        """Poll MODE_REG until it equals ``mode``."""
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            if self.read("MODE_REG") == mode:
                return
            time.sleep(poll)
        raise TimeoutError(f"MODE_REG did not become {mode} within {timeout} s")

    def run_test(self, mode: int, setup: dict[str, float], timeout: float = 10.0
                 ) -> dict[str, np.ndarray]:
        """Run TESTU (mode 8) or TESTA (mode 9) from INIT_MODE through the protocol and return
        the sample buffer (manual 4.4.9, 4.4.10): write ``setup`` (e.g. ``{"UMEAS": 100}``),
        write MODE_REG, wait for the motor to be back in INIT_MODE, read the buffer."""
        if mode not in (8, 9):
            raise ValueError("mode must be 8 (TESTU) or 9 (TESTA)")
        if self.read("MODE_REG") != 0:
            raise RefusedError("TESTU/TESTA start from INIT_MODE (manual 4.4.9, 4.4.10)")
        for name, value in setup.items():
            self.write(name, value)
        self.write("MODE_REG", mode)
        self.wait_mode(0, timeout)
        return self.sample_buffer()
