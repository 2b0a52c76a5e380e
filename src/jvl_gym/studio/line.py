"""Motors on a serial line or a twin's TCP endpoint, through the project's MacTalk clients.

One :class:`Line` holds one open port (a device path or a pyserial URL such as
``socket://127.0.0.1:5000``) and one master per MacTalk dialect on it
(:func:`~jvl_gym.protocol.mactalk.dialect.client_class`: the 16-bit MacTalk of the MAC050–141,
manual 5.1; the 32-bit MacTalk of the MAC800 and MIS, quick guide §1.3, MIS manual §18.2), and
addresses each request to the motor that asks, in the dialect its family declares (one master,
several units by MYADDR). A line that fails (the twin stopped, the cable pulled) is closed and
opened again on the next request, so the studio keeps running and the motors come back when
the other end does. :class:`LineMotor` is one motor on it; :func:`scan` lists the addresses
that answer, with the dialect each speaks.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Iterable, Mapping
from typing import Any

from ..protocol.errors import NoAnswerError, ProtocolError, RefusedError
from ..protocol.mactalk.dialect import MACTALK16, client_class
from ..registers import RegisterError, to_raw
from .motor import ACTIONS, StudioMotor

__all__ = ["Line", "LineMotor", "LineDown", "RefusedByMotor", "scan"]


#: seconds a line waits for each reply by default: a motor answers a MacTalk request within a
#: few milliseconds, and a slow baud rate or a gateway stays well inside this
ANSWER_TIMEOUT_S = 0.3


class LineDown(ConnectionError):
    """The line cannot be reached now (one line: what, where, what to do)."""


class RefusedByMotor(RegisterError):
    """The motor answers but did not carry out a request: a write it did not accept (no
    accept, MAC050–141 manual 5.1, MIS manual §18.2.4) or a command the client refuses to send
    (:class:`~jvl_gym.protocol.errors.RefusedError`); nothing was changed."""


class Line:
    """One MacTalk master per dialect on ``port``, opened on first use and again after a
    failure.

    Parameters
    ----------
    port : str
        Device path or pyserial URL.
    timeout : float
        Seconds to wait for each reply.
    retries : int
        Extra attempts after a timeout.
    """

    def __init__(self, port: str, *, timeout: float = ANSWER_TIMEOUT_S, retries: int = 1
                 ) -> None:
        if not 0 < timeout < float("inf"):
            raise ValueError(f"the answer timeout must be a finite number of seconds > 0, "
                             f"got {timeout}")
        self.port = port
        self.timeout = timeout
        self.retries = retries
        self.lock = threading.RLock()
        self._serial: Any = None
        self._masters: dict[str, Any] = {}
        #: the last failure, None while the line works
        self.problem: str | None = None

    def open(self) -> None:
        """Open the port now (it opens on first use otherwise).

        Raises
        ------
        LineDown
            The port cannot be opened: no such device, a TCP port nobody listens on, a
            malformed URL (one line).
        """
        with self.lock:
            self._port()

    def _port(self) -> Any:
        """The open port (opened if it is not)."""
        from ..protocol.mactalk.master import open_port

        if self._serial is None:
            try:
                self._serial = open_port(self.port, self.timeout)
            except Exception as exc:  # pyserial: SerialException (an OSError) or ValueError
                self.problem = (f"cannot open {self.port}: {exc}; check that the twin (jvl-gym "
                                "serve) or the motor is running and the port is right")
                raise LineDown(self.problem) from None
        return self._serial

    def _master(self, dialect: str) -> Any:
        """The master of ``dialect`` on the open port."""
        port = self._port()
        if dialect not in self._masters:
            self._masters[dialect] = client_class(dialect)(
                self.port, 1, timeout=self.timeout, retries=self.retries, serial=port,
                table=None)
        return self._masters[dialect]

    def call(self, address: int, fn: Callable[[Any], Any], *, dialect: str = MACTALK16,
             table: Any = None) -> Any:
        """Run ``fn(client)`` with the ``dialect`` master addressed to ``address`` (typed by
        ``table``); a failed line is closed (and opened again by the next call) and raised as
        :class:`LineDown`; a refused value (:class:`RegisterError`) passes through with the
        line kept."""
        with self.lock:
            client = self._master(dialect)
            client.address = address
            if table is not None:
                client.table = table
            try:
                out = fn(client)
            except RegisterError:
                raise
            except RefusedError as exc:
                raise RefusedByMotor(str(exc)) from None
            except NoAnswerError as exc:
                if self._answers(address):
                    raise RefusedByMotor(
                        f"the motor at address {address} answers but did not accept the "
                        f"request ({exc.request}): "
                        "a value it refuses in its present mode or state (MAC050–141 manual "
                        "5.1, MIS manual §18.2.4). Nothing was changed.") from None
                self._drop(exc)
                raise LineDown(self.problem) from None
            except (OSError, ProtocolError, ValueError) as exc:
                self._drop(exc)
                raise LineDown(self.problem) from None
            self.problem = None
            return out

    def _answers(self, address: int) -> bool:
        """Whether the unit at ``address`` answers a read now."""
        try:
            return self.probe(address) is not None
        except LineDown:
            return False

    def probe(self, address: int) -> str | None:
        """The dialect of the unit at ``address``, None if none answers
        (:class:`~jvl_gym.protocol.mactalk.probe.DialectProbe`)."""
        from ..protocol.mactalk.probe import DialectProbe

        with self.lock:
            probe = DialectProbe(self.port, address, timeout=self.timeout,
                                 retries=self.retries, serial=self._port())
            try:
                return probe.dialect(address)
            except (OSError, ProtocolError, ValueError) as exc:
                self._drop(exc)
                raise LineDown(self.problem) from None

    def _drop(self, exc: BaseException) -> None:
        self.problem = f"{self.port}: {exc}"
        self.close()

    def close(self) -> None:
        """Close the port."""
        with self.lock:
            self._masters.clear()
            if self._serial is not None:
                try:
                    self._serial.close()
                except Exception:  # noqa: BLE001 - the port is gone already
                    pass
                self._serial = None


class LineMotor(StudioMotor):
    """A motor at ``address`` on ``line``, spoken to in its family's MacTalk dialect
    (:attr:`~jvl_gym.families.TwinSpec.dialect`).

    Parameters
    ----------
    line : Line
        The line.
    motor_type : str
        Its motor type.
    address : int
        Its unit address (MYADDR).
    with_port : bool
        Name the port in the label (``"MAC140 @ 1 on /dev/ttyUSB1"``): for a motor whose
        type and address a motor on another line of the studio has too.
    """

    def __init__(self, line: Line, motor_type: str, address: int, *,
                 with_port: bool = False) -> None:
        super().__init__(motor_type, address)
        self.dialect = self.family.twin.dialect
        client_class(self.dialect)  # a dialect the protocol package speaks
        self.line = line
        self.with_port = with_port
        self._t0 = time.monotonic()
        #: the settings (register name → value) the flash is known to hold, since MacTalk
        #: has no command that reads the flash back: as read when the Connections view took
        #: the motor up (a motor loads its flash at power-on) and at each flash write from the
        #: Registers view (:func:`~.parameters.write_flash`); None until then
        self.flash_record: dict[str, float] | None = None

    @property
    def label(self) -> str:
        """``"<type> @ <address>"``, with ``" on <port>"`` where :attr:`with_port`."""
        base = f"{self.motor_type} @ {self.address}"
        return f"{base} on {self.line.port}" if self.with_port else base

    def call(self, fn: Callable[[Any], Any]) -> Any:
        """``fn(client)`` on the line, with the master of this motor's dialect and table."""
        return self.line.call(self.address, fn, dialect=self.dialect, table=self.table)

    def read_raw(self, key: str | int) -> int:
        number = self.register(key).number
        return int(self.call(lambda c: c.read_raw(number)))

    def read_raws(self, numbers: Iterable[int]) -> dict[int, int]:
        """Stored integers of several registers, in as few requests as the dialect allows
        (the clients' ``read_raws``)."""
        return self.call(lambda c: c.read_raws(numbers))

    def write(self, key: str | int, value: float) -> None:
        reg = self.register(key)
        self.call(lambda c: c.write(reg.number, value))

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
        self.call(lambda c: c.write_registers(regs))

    def now(self) -> float:
        return time.monotonic() - self._t0

    def actions(self) -> dict[str, Callable[[], None]]:
        """The MacTalk commands (MAC050–141 manual 5.1: go safe mode, go init mode, write
        flash, reset; MIS manual §18.2.5–§18.2.8: enter and exit safe mode, write flash,
        reset), those whose capability the family declares (:data:`~.motor.ACTIONS`)."""
        def cmd(command: Callable[[Any], None]) -> Callable[[], None]:
            return lambda: self.call(command)
        commands: dict[str, Callable[[Any], None]] = {
            "safe mode": lambda c: c.enter_safe_mode(),
            "leave safe mode": lambda c: c.exit_safe_mode(),
            "save in flash": lambda c: c.write_flash(), "reset": lambda c: c.software_reset()}
        out: dict[str, Callable[[], None]] = {"passive": self.passive}
        for label, (capability, _) in ACTIONS.items():
            if self.family.supports(capability):
                out[label] = cmd(commands[label])

        out["clear errors"] = self.clear_errors
        return out

    def sample_buffer(self) -> dict[str, Any]:
        """The motor's sample buffer in user units, read back with the read-sample command
        (MAC050–141 manual 3.2.112–3.2.116 and 5.1; MIS manual §8.2.60–§8.2.63)."""
        return self.call(lambda c: c.sample_buffer())


def scan(line: Line, addresses: Iterable[int]) -> dict[int, str]:
    """The addresses of ``addresses`` at which a unit answers, with the MacTalk dialect of its
    reply (:meth:`Line.probe`)."""
    found: dict[int, str] = {}
    for a in addresses:
        dialect = line.probe(a)
        if dialect is not None:
            found[a] = dialect
    return found
