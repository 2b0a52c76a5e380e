"""Motors on a serial line or a twin's TCP endpoint, through the project's MacTalk client.

One :class:`Line` holds one :class:`~jvl_gym.protocol.client.MacTalkClient` (a device path or a
pyserial URL such as ``socket://127.0.0.1:5000``) and addresses each request to the motor that
asks (MAC050–141 manual 5.1: one master, several units by MYADDR). A line that fails (the twin
stopped, the cable pulled) is closed and opened again on the next request, so the studio keeps
running and the motors come back when the other end does. :class:`LineMotor` is one motor on
it; :func:`scan` lists the addresses that answer.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Iterable, Mapping
from typing import Any

from ..protocol.dialect import MACTALK16
from ..protocol.errors import ProtocolError
from ..registers import Format, RegisterError, to_raw
from .motor import ACTIONS, StudioMotor

__all__ = ["Line", "LineMotor", "LineDown", "scan"]


class LineDown(ConnectionError):
    """The line cannot be reached now (one line: what, where, what to do)."""


class Line:
    """One MacTalk master on ``port``, opened on first use and again after a failure.

    Parameters
    ----------
    port : str
        Device path or pyserial URL.
    timeout : float
        Seconds to wait for each reply.
    retries : int
        Extra attempts after a timeout.
    table : RegisterTable
        The register table of the motors' family (typed access of the client).
    """

    def __init__(self, port: str, *, timeout: float = 0.3, retries: int = 1,
                 table: Any = None) -> None:
        self.port = port
        self.timeout = timeout
        self.retries = retries
        self.table = table
        self.lock = threading.RLock()
        self._client: Any = None
        #: the last failure, None while the line works
        self.problem: str | None = None

    def _open(self) -> Any:
        from ..protocol.client import MacTalkClient

        try:
            return MacTalkClient(self.port, 1, timeout=self.timeout, retries=self.retries,
                                 table=self.table)
        except Exception as exc:  # pyserial raises SerialException (an OSError) or ValueError
            raise LineDown(f"cannot open {self.port}: {exc}; check that the twin (jvl-gym "
                           "serve) or the motor is running and the port is right") from None

    def call(self, address: int, fn: Callable[[Any], Any]) -> Any:
        """Run ``fn(client)`` with the client addressed to ``address``; a failed line is
        closed (and opened again by the next call) and raised as :class:`LineDown`; a
        refused value (:class:`RegisterError`) passes through with the line kept."""
        with self.lock:
            if self._client is None:
                try:
                    self._client = self._open()
                except LineDown as exc:
                    self.problem = str(exc)
                    raise
            self._client.address = address
            try:
                out = fn(self._client)
            except RegisterError:
                raise
            except (OSError, ProtocolError, ValueError) as exc:
                self._drop(exc)
                raise LineDown(self.problem) from None
            self.problem = None
            return out

    def _drop(self, exc: BaseException) -> None:
        self.problem = f"{self.port}: {exc}"
        try:
            self._client.close()
        except Exception:  # noqa: BLE001 - the port is gone already
            pass
        self._client = None

    def close(self) -> None:
        """Close the port."""
        with self.lock:
            if self._client is not None:
                self._client.close()
                self._client = None


class LineMotor(StudioMotor):
    """A motor at ``address`` on ``line``.

    Raises
    ------
    ValueError
        The motor type's family speaks a MacTalk the project's client does not
        (:mod:`jvl_gym.protocol.dialect`).
    """

    def __init__(self, line: Line, motor_type: str, address: int) -> None:
        super().__init__(motor_type, address)
        dialect = self.family.twin.dialect
        if dialect != MACTALK16:
            raise ValueError(f"{motor_type}: the {self.facts.title} speak {dialect}; the "
                             f"protocol client speaks {MACTALK16} (MAC050–141 manual 5.1) only: "
                             "simulate it in-process with --motor instead")
        if line.table is None:
            line.table = self.table
        self.line = line
        self._t0 = time.monotonic()

    def read_raw(self, key: str | int) -> int:
        number = self.register(key).number
        return int(self.line.call(self.address, lambda c: c.read_raw(number)))

    def read_raws(self, numbers: Iterable[int]) -> dict[int, int]:
        """Stored integers of several registers, read two numbers per request (manual 5.1:
        a read returns registers N and N+1)."""
        from ..registers import from_word16, join_longint

        numbers = sorted(set(numbers))
        out: dict[int, int] = {}

        def read_all(client: Any) -> None:
            words: dict[int, int] = {}
            for n in numbers:
                if n not in words:
                    words[n], words[n + 1] = client.read_words(n)
            for n in numbers:
                reg = self.register(n)
                if reg.format == Format.LONGINT:
                    if n + 1 not in words:
                        words[n + 1] = client.read_words(n + 1)[0]
                    out[n] = int(join_longint(words[n], words[n + 1]))
                elif reg.access.value == "reserved":
                    out[n] = words[n]
                else:
                    out[n] = int(from_word16(reg, words[n]))

        self.line.call(self.address, read_all)
        return out

    def write(self, key: str | int, value: float) -> None:
        reg = self.register(key)
        self.line.call(self.address, lambda c: c.write(reg.number, value))

    def load_setup(self, registers: Mapping[str, float]) -> None:
        regs = {self.register(k).name: float(v) for k, v in registers.items()}
        if self.facts.mode_register in regs:
            raise RegisterError("a setup must not contain MODE_REG (manual 3.2.2: a mode is "
                                "requested after the parameters are written)")
        for name, value in regs.items():  # validate all before the first write
            reg = self.register(name)
            if reg.access.value != "rw":
                raise RegisterError(f"{name} (register {reg.number}) is {reg.access.value}; "
                                    "a setup holds writable registers only. Nothing was changed.")
            to_raw(reg, value)
        self.line.call(self.address, lambda c: c.write_registers(regs))

    def now(self) -> float:
        return time.monotonic() - self._t0

    def actions(self) -> dict[str, Callable[[], None]]:
        """MacTalk commands of manual 5.1 (go safe mode, go init mode, write flash, reset),
        those whose capability the family declares (:data:`~.motor.ACTIONS`)."""
        def cmd(command: Callable[[Any], None]) -> Callable[[], None]:
            return lambda: self.line.call(self.address, command)
        commands: dict[str, Callable[[Any], None]] = {
            "safe mode": lambda c: c.go_safe_mode(), "leave safe mode": lambda c: c.go_init_mode(),
            "save in flash": lambda c: c.write_flash(), "reset": lambda c: c.reset()}
        out: dict[str, Callable[[], None]] = {"passive": self.passive}
        for label, (capability, _) in ACTIONS.items():
            if self.family.supports(capability):
                out[label] = cmd(commands[label])
        out["clear errors"] = self.clear_errors
        return out

    def sample_buffer(self) -> dict[str, Any]:
        """The motor's sample buffer in user units (MAC050–141 manual 3.2.112–3.2.116)."""
        return self.line.call(self.address, lambda c: c.read_sample_buffer())


def scan(line: Line, addresses: Iterable[int], register: int = 2) -> list[int]:
    """The addresses of ``addresses`` at which a motor answers a read of ``register``."""
    found = []
    for a in addresses:
        try:
            line.call(a, lambda c: c.read_words(register))
        except LineDown:
            if line.problem and "did not answer" not in line.problem:
                raise
            continue
        found.append(a)
    return found
