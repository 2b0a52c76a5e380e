"""The master's side of a MacTalk line, whatever the dialect: the port, the request/reply
exchange with its timeout and retries (MAC050–141 manual 5.1; MIS manual §18.2).

:class:`SerialMaster` owns (or shares) one pyserial port: a device path (``/dev/ttyUSB0``, a
twin's pty) or any pyserial URL (``socket://127.0.0.1:5000``, ``rfc2217://…``). A dialect's
client (:class:`~.client16.MacTalkClient`, :class:`~.client32.MacTalk32Client`) says how a reply
is framed and decoded; several clients of different dialects may share one open port
(``serial=``), as motors of several families share one RS-485 line. :class:`RegisterMaster` adds
what both dialects' clients do alike on top of their typed register access.
"""

from __future__ import annotations

import time
from abc import ABC, abstractmethod
from collections.abc import Callable
from typing import Any

import numpy as np

from ...compat import renamed_method
from ...registers.errors import echo
from ..errors import FrameError, NoAnswerError, UnexpectedReplyError

__all__ = ["SerialMaster", "RegisterMaster", "DEFAULT_BAUDRATE", "open_port",
           "READOUT_ATTEMPTS"]

#: read-outs of the sample buffer tried before :meth:`RegisterMaster.sample_buffer_raw` gives up
READOUT_ATTEMPTS = 3

#: the motors' serial speed (MAC800 quick guide: 19200 baud, 8 data bits, no parity)
DEFAULT_BAUDRATE = 19200


def open_port(port: str, timeout: float, baudrate: int = DEFAULT_BAUDRATE,
              **serial_kwargs: Any) -> Any:
    """Open ``port`` (device path or pyserial URL) with ``serial.serial_for_url``."""
    import serial

    return serial.serial_for_url(port, baudrate=baudrate, timeout=timeout, **serial_kwargs)


class SerialMaster(ABC):
    """A MacTalk master for one unit address on an open port.

    Parameters
    ----------
    port : str
        Device path or pyserial URL.
    address : int
        Unit address (MYADDR, 1..254) or 255 (broadcast, point-to-point links only).
    timeout : float
        Seconds to wait for a reply.
    retries : int
        Extra attempts after a timeout or a garbled reply.
    baudrate : int
        Serial speed (ignored by socket URLs).
    serial : serial.SerialBase, optional
        An open port to share (``port`` then only names it); closing this master leaves it
        open.
    serial_kwargs
        Passed to ``serial.serial_for_url``.
    """

    #: the dialect's name (:mod:`.dialect`)
    dialect: str = ""

    def __init__(self, port: str, address: int = 1, *, timeout: float = 0.5, retries: int = 2,
                 baudrate: int = DEFAULT_BAUDRATE, serial: Any = None, **serial_kwargs: Any
                 ) -> None:
        if not 1 <= address <= 255:
            raise ValueError(f"unit address must be 1..255, got {address}")
        self.port = port
        self.address = address
        self.timeout = timeout
        self.retries = retries
        self._owns_port = serial is None
        self.ser = serial if serial is not None else open_port(port, timeout, baudrate,
                                                                 **serial_kwargs)
        #: counters: requests sent, of them sent again
        self.requests = 0
        self.retried = 0

    # ------------------------------------------------------------------ the port
    def close(self) -> None:
        """Close the port (unless it was given open: its owner closes it)."""
        if self._owns_port:
            self.ser.close()

    def __enter__(self) -> SerialMaster:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _read_exact(self, n: int, deadline: float) -> bytes:
        out = bytearray()
        while len(out) < n:
            left = deadline - time.monotonic()
            if left <= 0:
                break
            self.ser.timeout = left
            chunk = self.ser.read(n - len(out))
            if not chunk:
                break
            out += chunk
        return bytes(out)

    # ------------------------------------------------------------------ the dialect
    @abstractmethod
    def _read_reply(self, deadline: float) -> bytes:
        """Read one reply frame (an accept or a data reply) by its own length fields."""

    @abstractmethod
    def _decode(self, raw: bytes) -> Any:
        """Decode one reply frame; :class:`~.errors.FrameError` if it is garbled."""

    @abstractmethod
    def _kind(self, frame: Any) -> str:
        """``"accept"``, ``"data"`` or ``"other"``: what ``frame`` is."""

    # ------------------------------------------------------------------ exchange
    def transact(self, request: bytes, what: str, expect: str = "data",
                 stale: Callable[[Any], bool] | None = None) -> Any:
        """Send ``request`` and return the decoded reply (``expect`` = "data", "accept" or
        "none"), with retries; raise :class:`NoAnswerError` if nothing valid comes back.
        A reply for which ``stale(frame)`` is true (the late answer to an earlier request) is
        passed over and the next one awaited. When the answer came only after the request was
        sent again, the answers still due to the earlier sends are awaited and dropped
        (:meth:`_pass_over_late`)."""
        self.requests += 1
        problems: list[str] = []
        for attempt in range(self.retries + 1):
            if attempt:
                self.retried += 1
            self.ser.reset_input_buffer()
            self.ser.write(request)
            self.ser.flush()
            if expect == "none":
                return None
            deadline = time.monotonic() + self.timeout
            while True:
                raw = self._read_reply(deadline)
                if not raw:
                    problems.append("no answer")
                    break
                try:
                    frame = self._decode(raw)
                except FrameError as err:
                    problems.append(f"garbled reply ({err.reason})")
                    time.sleep(min(0.05, self.timeout))
                    break
                if stale is not None and stale(frame):
                    continue
                if self._kind(frame) == expect:
                    if attempt:
                        self._pass_over_late(attempt)
                    return frame
                wanted = "an accept" if expect == "accept" else "a data reply"
                raise UnexpectedReplyError(f"{what}: expected {wanted}, got {echo(frame)}")
        raise NoAnswerError(what,
            f"motor at address {self.address} on {self.port} did not answer {what} "
            f"({self.retries + 1} attempts, timeout {self.timeout} s; {', '.join(problems)}). "
            "Check the port and baud rate, the address (MYADDR), that the motor is powered, "
            "and whether it refused the request: a write that is out of range or not allowed "
            "in the present mode gets no accept (MAC050–141 manual 5.1, MIS manual §18.2).")

    def _pass_over_late(self, n: int) -> None:
        """After an answer that came only when the request had been sent again: read and drop
        the up to ``n`` answers still due to the earlier sends (waiting one timeout at most),
        so that the next request is not given one of them as its answer (a MacTalk answer
        does not say which request it answers, MAC050–141 manual 5.1)."""
        deadline = time.monotonic() + self.timeout
        for _ in range(n):
            if not self._read_reply(deadline):
                break
        self.ser.reset_input_buffer()

    def answer_within(self, seconds: float) -> Any:
        """The reply frame that arrives within ``seconds`` after a request sent with
        ``expect="none"``, or None if none does."""
        raw = self._read_reply(time.monotonic() + seconds)
        if not raw:
            return None
        try:
            return self._decode(raw)
        except FrameError:
            return None


class RegisterMaster(SerialMaster):
    """A master with typed register access (a register ``table``; ``read``, ``read_raw``,
    ``write``, ``read_sample`` of its dialect) and what follows from it alike in both dialects."""

    table: Any

    @abstractmethod
    def read_raw(self, key: str | int) -> int:
        """Stored integer of a register."""

    @abstractmethod
    def read(self, key: str | int) -> float | int:
        """Register value in user units."""

    @abstractmethod
    def write(self, key: str | int, value: float) -> None:
        """Write a register in user units, validated against the table first."""

    @abstractmethod
    def read_sample(self) -> bytes:
        """One read-sample request: 16 bytes of a sample, or b"" after the last."""

    @abstractmethod
    def enter_safe_mode(self) -> None:
        """The motor to safe mode (the array's :meth:`~jvl_gym.MotorArray.enter_safe_mode`)."""

    @abstractmethod
    def exit_safe_mode(self) -> None:
        """The motor out of safe mode (the array's ``exit_safe_mode``)."""

    @abstractmethod
    def software_reset(self, settle: float = 0.2) -> None:
        """Restart the motor's firmware from flash (the array's ``software_reset``)."""

    @abstractmethod
    def sample_buffer(self) -> dict[str, np.ndarray]:
        """The sample buffer in user units (the array's ``sample_buffer``)."""

    # the names of the previous release (one name for one operation: the motor array's)
    go_safe_mode = renamed_method("enter_safe_mode", "go_safe_mode")
    reset = renamed_method("software_reset", "reset")
    read_sample_buffer = renamed_method("sample_buffer", "read_sample_buffer")
    read_sample_buffer_raw = renamed_method("sample_buffer_raw", "read_sample_buffer_raw")

    def _reg(self, key: str | int) -> Any:
        """The table's register ``key`` (name or number)."""
        return self.table.lookup(key)

    def _writable(self, key: str | int) -> Any:
        """The table's register ``key``; :class:`~jvl_gym.registers.ReadOnlyRegisterError` if
        it cannot be written (checked before anything is sent)."""
        from ...registers import ReadOnlyRegisterError

        reg = self._reg(key)
        if reg.access.value != "rw":
            raise ReadOnlyRegisterError(f"{reg.name} (register {reg.number}) is "
                                        f"{reg.access.value}; it cannot be written")
        return reg

    def write_registers(self, values: dict[str, float], verify: bool = True) -> None:
        """Write several registers (e.g. synthesised filter coefficients) and read them back."""
        from ...registers import to_raw

        for name, value in values.items():
            self.write(name, value)
        if verify:
            for name, value in values.items():
                reg = self.table.lookup(name)
                if self.read_raw(reg.number) != int(to_raw(reg, value)):
                    raise UnexpectedReplyError(f"{name}: read back differs from {value}")

    def sample_buffer_raw(self) -> np.ndarray:
        """All recorded samples (REC_CNT of them) as raw signed values, shape (samples, 4) for
        SAMPLE1..4, each channel 4 bytes low byte first.

        The buffer is read sample by sample until the empty reply that marks its end; a
        partial read-out left over from an earlier call is drained first, so that the result
        always starts at the first sample. A read-sample request moves the motor's read
        position on (MAC050–141 manual 5.1), so a request sent again after its answer came
        late skips a sample, and the answers carry no sample number: a read-out during which
        a request was sent again, or that does not end right after REC_CNT samples, is read
        again from the first sample (:data:`READOUT_ATTEMPTS` times at most).

        Raises
        ------
        UnexpectedReplyError
            No read-out gave REC_CNT samples followed by the end of the buffer.
        """
        why = ""
        for _ in range(READOUT_ATTEMPTS):
            count = int(self.read("REC_CNT"))
            retried = self.retried
            rows, why = self._read_out(count)
            if rows is not None and self.retried != retried:
                rows, why = None, "a request was sent again"
            if rows is not None:
                return np.asarray(rows, dtype=np.int64).reshape(-1, 4)
        raise UnexpectedReplyError(
            f"the sample buffer of the motor at address {self.address} on {self.port} could "
            f"not be read out whole in {READOUT_ATTEMPTS} attempts ({why}): check the link, "
            "and that no other master reads the buffer meanwhile")

    def _read_out(self, count: int) -> tuple[list[list[int]] | None, str]:
        """One read-out of ``count`` samples: drain to the end marker, then read the samples
        and the end marker; (rows, "") or (None, what went wrong)."""
        for _ in range(count + 1):  # drain to the end marker, pointer back at the first
            if self.read_sample() == b"":
                break
        else:
            return None, f"no end of the buffer within {count + 1} samples"
        rows = []
        for _ in range(count + 1):
            d = self.read_sample()
            if d == b"":
                break
            rows.append([int.from_bytes(d[4 * k:4 * k + 4], "little", signed=True)
                         for k in range(4)])
        if len(rows) != count or d != b"":
            return None, f"{len(rows)} samples read where REC_CNT = {count}"
        return rows, ""
