"""A Modbus RTU slave (MIS manual §12) for any device of 32-bit registers, served over the
twin's transports (pseudo-terminal, TCP on localhost).

Layers, from the device up:

* :class:`RegisterAccess` — what a device must offer: ``node_id`` (the slave address),
  ``read(number) -> int`` and ``write(number, value)``, which raises a
  :class:`~jvl_gym.registers.RegisterError` subclass when it refuses. :class:`RegisterFile` is an
  in-memory implementation.
* :class:`ModbusSlave` — one device behind the Modbus frames: reads and writes through the 2n and
  40 000 windows and the PDO1/PDO2 remapping (MIS manual §12.3–§12.6), exception replies, the
  Modbus timeout and its action (§12.1, registers 199–201 on the MIS), the reply delay.
* :class:`ModbusBus` — the slaves on one line: frames in, replies out, broadcast, the timeout
  watchdog (:meth:`ModbusBus.poll`).
* :class:`ModbusSession` — a received byte stream (one TCP connection, a pty) → reply bytes, with
  RTU framing by 3.5-character silences (:class:`~.codec.RtuFramer`).
* :class:`ProtocolSwitch` and :class:`SwitchingSession` — MacTalk after power-on, Modbus after
  one second of silence when the set-up register enables it (MIS manual §12.2.1).
* :class:`ModbusServer` — the endpoints, reusing the shared transport's
  :class:`~jvl_gym.protocol.serving.transport.TwinServer`.

The register numbers the slave itself uses (set-up, baud rate, timeout, timeout action, frame
delay, and the registers the timeout action writes) are passed in as :class:`ModbusRegisters`;
:data:`MIS_REGISTERS` is the MIS/SMC mapping.

Examples
--------
>>> regs = RegisterFile(node_id=42, values={10: 123456789})
>>> bus = ModbusBus([regs])
>>> bus.handle(bytes.fromhex("2a 03 00 14 00 02 82 14"), now=0.0)[0].hex(" ")
'2a 03 04 cd 15 07 5b 0d 92'
"""

from __future__ import annotations

import enum
import logging
import threading
import time
from collections import Counter, deque
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol, runtime_checkable

from ...registers.errors import (
    ReadOnlyRegisterError,
    RegisterError,
    RegisterRangeError,
    UnknownRegisterError,
)
from ..errors import FrameError
from ..serving.transport import TwinServer, kept_sessions
from . import codec as mb

__all__ = [
    "RegisterAccess",
    "RegisterError",
    "RegisterFile",
    "ModbusRegisters",
    "MIS_REGISTERS",
    "TimeoutAction",
    "exception_code",
    "ModbusSlave",
    "ModbusBus",
    "ModbusSession",
    "ActiveProtocol",
    "ProtocolSwitch",
    "SwitchingSession",
    "ModbusServer",
]

log = logging.getLogger(__name__)


@runtime_checkable
class RegisterAccess(Protocol):
    """A device of 32-bit registers as the Modbus slave sees it.

    Attributes
    ----------
    node_id : int
        The slave address (on the MIS: register 150, the MacTalk address; MIS manual §12.1).
        Read at every frame, so a change takes effect at once.
    """

    node_id: int

    def read(self, number: int) -> int:
        """The value of register ``number`` (any int; the low 32 bits are sent).

        Raises
        ------
        RegisterError
            No such register (:class:`~jvl_gym.registers.UnknownRegisterError`) or not readable.
        """
        ...

    def write(self, number: int, value: int) -> None:
        """Write the signed 32-bit ``value`` (−2³¹ … 2³¹ − 1) to register ``number``.

        Raises
        ------
        RegisterError
            The device refuses: nothing has changed.
        """
        ...

    def write_many(self, values: Sequence[tuple[int, int]]) -> None:
        """Write ``(number, value)`` pairs (in this order) as one transaction: every one is
        checked before the first is stored, so that a refusal changes nothing, side effects
        of a command among them included.

        Raises
        ------
        RegisterError
            The device refuses one of them: nothing has changed.
        """
        ...


class RegisterFile:
    """An in-memory device of 32-bit registers implementing :class:`RegisterAccess`.

    Parameters
    ----------
    node_id : int
        Slave address.
    values : mapping
        Register number → initial value; only these registers exist.
    read_only : iterable of int
        Registers that refuse writes (:class:`~jvl_gym.registers.ReadOnlyRegisterError`).
    ranges : mapping
        Register number → (lo, hi): writes outside raise
        :class:`~jvl_gym.registers.RegisterRangeError`.
    """

    def __init__(self, node_id: int, values: Mapping[int, int],
                 read_only: Iterable[int] = (),
                 ranges: Mapping[int, tuple[int, int]] | None = None) -> None:
        self.node_id = node_id
        self.values = {int(k): int(v) for k, v in values.items()}
        self.read_only = frozenset(read_only)
        self.ranges = dict(ranges or {})
        #: (number, value) of every accepted write, in order
        self.writes: list[tuple[int, int]] = []

    def read(self, number: int) -> int:
        """The value of register ``number``; :class:`UnknownRegisterError` if there is none."""
        if number not in self.values:
            raise UnknownRegisterError(f"no register {number}")
        return self.values[number]

    def write(self, number: int, value: int) -> None:
        """Set register ``number`` to ``value``, or raise a :class:`RegisterError` subclass
        (unknown, read-only, out of range) and change nothing."""
        self.write_many([(number, value)])

    def write_many(self, values: Sequence[tuple[int, int]]) -> None:
        """Set the registers of ``(number, value)`` in order, after checking every one as
        :meth:`write` does (a refusal changes nothing)."""
        for number, value in values:
            if number not in self.values:
                raise UnknownRegisterError(f"no register {number}")
            if number in self.read_only:
                raise ReadOnlyRegisterError(f"register {number} is read-only")
            lo, hi = self.ranges.get(number, (-(2**31), 2**31 - 1))
            if not lo <= value <= hi:
                raise RegisterRangeError(f"{value} is outside {lo}..{hi} for register {number}")
        for number, value in values:
            self.values[number] = int(value)
            self.writes.append((number, int(value)))


class TimeoutAction(enum.IntEnum):
    """Values of the time-out response register (MIS manual §12.1, register 200)."""

    EVENT = 0  #: no action, only an event
    STOP = 1  #: the max velocity is set to zero
    PASSIVE = 2  #: the motor is set to passive mode


@dataclass(frozen=True)
class ModbusRegisters:
    """The device registers the Modbus slave itself uses (None: the device has none).

    Attributes
    ----------
    setup : int or None
        Modbus set-up bits (MIS manual §12.1; decoded by :func:`~.codec.decode_setup`): parity
        and stop bits of the character format, bit 0 enables the switch from MacTalk.
    baud : int or None
        Baud-rate index into :data:`~.codec.BAUD_RATES` (MIS manual §12.1).
    timeout : int or None
        Modbus slave time-out [ms], 0 = off (MIS manual §12.1).
    timeout_action : int or None
        :class:`TimeoutAction` (MIS manual §12.1).
    frame_delay : int or None
        Reply delay, in units of ``frame_delay_unit``; 0 = the default of 2.5 characters (MIS
        manual §12.1).
    max_velocity, mode : int or None
        Registers the timeout actions write: ``max_velocity`` ← 0 (STOP), ``mode`` ←
        ``passive_mode`` (PASSIVE).
    passive_mode : int
    frame_delay_unit : float
        Seconds per count of ``frame_delay`` (the manual gives no unit; 1 ms is this project's
        decision, docs/protocol.md).
    default_baud : int
        Baud rate when there is no baud register (or it holds no valid index).
    """

    setup: int | None = None
    baud: int | None = None
    timeout: int | None = None
    timeout_action: int | None = None
    frame_delay: int | None = None
    max_velocity: int | None = None
    mode: int | None = None
    passive_mode: int = 0
    frame_delay_unit: float = 1e-3
    default_baud: int = 19200


#: the MIS/SMC registers (MIS manual §12.1 and the register list §8.2): Modbus_setup 121,
#: BAUD_RATE 146, time-out 199, time-out response 200, frame delay 201; the timeout actions
#: write V_SOLL 5 ("max velocity") and MODE_REG 2 (0 = passive)
MIS_REGISTERS = ModbusRegisters(setup=121, baud=146, timeout=199, timeout_action=200,
                                frame_delay=201, max_velocity=5, mode=2, passive_mode=0)


def exception_code(exc: BaseException) -> mb.ExceptionCode:
    """The exception code that answers a device's refusal.

    An attribute ``modbus_exception`` on the error wins; otherwise unknown registers
    (:class:`UnknownRegisterError` or any ``LookupError``) and read-only ones give
    ILLEGAL_DATA_ADDRESS (2), a value out of range ILLEGAL_DATA_VALUE (3), any other refusal
    (e.g. a mode that forbids the write) SERVER_DEVICE_FAILURE (4).
    """
    code = getattr(exc, "modbus_exception", None)
    if code is not None:
        return mb.ExceptionCode(code)
    if isinstance(exc, (UnknownRegisterError, LookupError, ReadOnlyRegisterError)):
        return mb.ExceptionCode.ILLEGAL_DATA_ADDRESS
    if isinstance(exc, RegisterRangeError):
        return mb.ExceptionCode.ILLEGAL_DATA_VALUE
    return mb.ExceptionCode.SERVER_DEVICE_FAILURE


def _refused(exc: Exception, what: str) -> mb.ModbusError:
    return mb.ModbusError(exception_code(exc), f"{what}: {exc}")


class ModbusSlave:
    """One device behind Modbus RTU frames (MIS manual §12.3–§12.6).

    Parameters
    ----------
    device : RegisterAccess
    registers : ModbusRegisters
        The device's set-up, timeout and frame-delay registers (default: none).
    address_map : AddressMap
        Windows of the Modbus indices (default: 2n, 40 000 + n, PDO blocks at F200h…).

    Attributes
    ----------
    pdo : dict
        PDO set (1, 2) → :class:`~.codec.PdoTable`; cleared by :meth:`power_on`.
    timed_out : bool
        The timeout has fired since the last message.
    events : list of str
        Timeout events, oldest first.
    """

    def __init__(self, device: RegisterAccess, registers: ModbusRegisters | None = None,
                 address_map: mb.AddressMap | None = None) -> None:
        self.device = device
        self.registers = registers or ModbusRegisters()
        self.map = address_map or mb.AddressMap()
        self.pdo = {p: mb.PdoTable() for p in self.map.pdo_bases}
        self.stats: Counter[str] = Counter()
        self.events: list[str] = []
        self.last_message: float | None = None
        self.timed_out = False

    @property
    def node_id(self) -> int:
        """The device's slave address now."""
        return int(self.device.node_id)

    def power_on(self) -> None:
        """State after power-on: PDO set-up forgotten (MIS manual §12.6.1), timeout idle."""
        for table in self.pdo.values():
            table.clear()
        self.last_message = None
        self.timed_out = False

    # ------------------------------------------------------------------ configuration
    def config(self, number: int | None, default: int = 0) -> int:
        """Value of a configuration register, ``default`` if there is none or it is unreadable."""
        if number is None:
            return default
        try:
            return int(self.device.read(number))
        except (ValueError, LookupError):
            return default

    def serial_format(self) -> mb.SerialFormat:
        """Character format from the baud-rate and set-up registers (MIS manual §12.1)."""
        r = self.registers
        k = self.config(r.baud, -1)
        baud = mb.BAUD_RATES[k] if 0 <= k < len(mb.BAUD_RATES) else r.default_baud
        setup = mb.decode_setup(self.config(r.setup, 0))
        return mb.SerialFormat(baud, setup.parity, setup.stop_bits)

    def reply_delay(self) -> float:
        """Delay before a reply [s] (MIS manual §12.1, frame delay): 2.5 characters when the
        frame-delay register is 0 (or absent), else its value × ``frame_delay_unit``."""
        n = self.config(self.registers.frame_delay, 0)
        if n > 0:
            return n * self.registers.frame_delay_unit
        return mb.silence(self.serial_format(), 2.5)

    # ------------------------------------------------------------------ register access
    def _read32(self, area: mb.Area, pdo: int, k: int) -> int:
        if area == mb.Area.REGISTER:
            number = k
        elif area in (mb.Area.RX_SETUP, mb.Area.TX_SETUP):
            return self.pdo[pdo].setup_word_value(area, k)
        else:
            number = self.pdo[pdo].target(k, write=False)
        try:
            return int(self.device.read(number))
        except (ValueError, LookupError) as exc:
            raise _refused(exc, f"read of register {number}") from None

    def read_words(self, index: int, count: int) -> list[int]:
        """``count`` words from Modbus index ``index`` (MIS manual §12.3, §12.4, §12.6.2).

        Raises
        ------
        ModbusError
        """
        refs = self.map.resolve(index, count)
        values: dict[tuple[mb.Area, int, int], int] = {}
        out = []
        for ref in refs:
            if ref.target not in values:
                values[ref.target] = self._read32(ref.area, ref.pdo, ref.number)
            lo, hi = mb.words_of(values[ref.target])
            out.append(hi if ref.high else lo)
        return out

    def write_words(self, index: int, words: Sequence[int]) -> None:
        """Write whole 32-bit registers from Modbus index ``index`` (MIS manual §12.3, §12.5,
        §12.6) in index order, as one transaction of the device
        (:meth:`RegisterAccess.write_many`): it checks every register before the first is
        stored, so that a refused request changes nothing, a command's reset or save included.

        Raises
        ------
        ModbusError
        """
        refs = self.map.resolve(index, len(words))
        targets = mb.whole_registers(refs)
        values = [mb.value_of(lo, hi) for lo, hi in zip(words[0::2], words[1::2])]
        area, pdo, first = targets[0]
        if area in (mb.Area.RX_SETUP, mb.Area.TX_SETUP):
            self.pdo[pdo].configure(area, first, values)
            return
        numbers = [k if a == mb.Area.REGISTER else self.pdo[p].target(k, write=True)
                   for a, p, k in targets]
        try:
            self.device.write_many(list(zip(numbers, values)))
        except (ValueError, LookupError) as exc:
            raise _refused(exc, f"write of {values} to registers {numbers}") from None

    # ------------------------------------------------------------------ frames
    def execute(self, req: mb.Request, now: float) -> bytes:
        """Carry out a request addressed to this slave (or broadcast); return the reply frame
        (empty for a broadcast, MIS manual §12.4, §12.5)."""
        self.last_message = now
        self.timed_out = False
        broadcast = req.slave == mb.BROADCAST
        function = req.function if isinstance(req, mb.OtherRequest) else (
            mb.READ_HOLDING_REGISTERS if isinstance(req, mb.ReadRequest)
            else mb.WRITE_MULTIPLE_REGISTERS)
        try:
            mb.check_request(req)
            if isinstance(req, mb.ReadRequest):
                if broadcast:
                    self.stats["broadcast_read"] += 1
                    return b""
                words = self.read_words(req.index, req.count)
                self.stats["read"] += 1
                return mb.encode_read_response(self.node_id, words)
            assert isinstance(req, mb.WriteRequest)
            self.write_words(req.index, req.words)
            self.stats["write"] += 1
            if broadcast:
                return b""
            return mb.encode_write_response(self.node_id, req.index, req.count)
        except mb.ModbusError as exc:
            self.stats[f"exception_{int(exc.code)}"] += 1
            log.info("Modbus exception %d to slave %d: %s", exc.code, req.slave, exc.reason)
            if broadcast:
                return b""
            return mb.encode_exception(self.node_id, function, exc.code)

    def poll(self, now: float) -> bool:
        """Check the Modbus timeout (MIS manual §12.1, registers 199/200 on the MIS): when more
        than the time-out [ms] has passed since the last message to this slave, carry out the
        time-out response once (re-armed by the next message). A time-out of 0 disables it; the
        timer starts with the first message. Returns True when it fires."""
        if self.timed_out or self.last_message is None:
            return False
        ms = self.config(self.registers.timeout, 0)
        if ms <= 0 or now - self.last_message < ms / 1000:
            return False
        self.timed_out = True
        action = self.config(self.registers.timeout_action, 0)
        self.stats["timeout"] += 1
        self.events.append(f"Modbus timeout after {ms} ms, action {action}")
        log.info("slave %d: Modbus timeout (%d ms), action %d", self.node_id, ms, action)
        r = self.registers
        target = {TimeoutAction.STOP: (r.max_velocity, 0),
                  TimeoutAction.PASSIVE: (r.mode, r.passive_mode)}.get(action)
        if target is not None and target[0] is not None:
            try:
                self.device.write(target[0], target[1])
            except (ValueError, LookupError) as exc:
                log.warning("timeout action %d refused: %s", action, exc)
        return True


class ModbusBus:
    """The slaves on one serial line: request frames in, replies out.

    Parameters
    ----------
    devices : RegisterAccess or sequence of them
    registers, address_map
        As for :class:`ModbusSlave` (shared by all slaves).

    Attributes
    ----------
    lock : threading.RLock
        Held while a frame is carried out or the timeouts are checked.
    stats : Counter
        ``frames``, ``errors`` (bad frames), ``ignored`` (other slaves), ``replies``.
    """

    def __init__(self, devices: RegisterAccess | Sequence[RegisterAccess],
                 registers: ModbusRegisters | None = None,
                 address_map: mb.AddressMap | None = None) -> None:
        if isinstance(devices, RegisterAccess):
            devices = [devices]
        self.slaves = [ModbusSlave(d, registers, address_map) for d in devices]
        self.lock = threading.RLock()
        self.stats: Counter[str] = Counter()

    def serial_format(self) -> mb.SerialFormat:
        """The line's character format (the first slave's registers)."""
        with self.lock:
            return self.slaves[0].serial_format() if self.slaves else mb.SerialFormat()

    def power_on(self) -> None:
        """Power-on state of every slave (:meth:`ModbusSlave.power_on`)."""
        with self.lock:
            for s in self.slaves:
                s.power_on()

    def handle(self, frame: bytes, now: float) -> tuple[bytes, float]:
        """Carry out one received frame; return (reply bytes, delay before sending them [s]).

        A frame with a bad CRC or length is dropped (no reply, nothing changed); frames for
        other slaves are ignored; a broadcast (address 0) write is carried out by every slave
        and not answered. When several slaves share an address all carry the request out and the
        first one answers.
        """
        try:
            req = mb.decode_request(frame)
        except FrameError as exc:
            self.stats["errors"] += 1
            log.info("Modbus frame dropped: %s", exc.reason)
            return b"", 0.0
        self.stats["frames"] += 1
        with self.lock:
            if req.slave == mb.BROADCAST:
                for s in self.slaves:
                    s.execute(req, now)
                return b"", 0.0
            targets = [s for s in self.slaves if s.node_id == req.slave]
            if not targets:
                self.stats["ignored"] += 1
                return b"", 0.0
            replies = [s.execute(req, now) for s in targets]
            delay = targets[0].reply_delay()
        self.stats["replies"] += 1
        return replies[0], delay

    def poll(self, now: float) -> None:
        """Check every slave's Modbus timeout (:meth:`ModbusSlave.poll`)."""
        with self.lock:
            for s in self.slaves:
                s.poll(now)


class ModbusSession:
    """One received byte stream (a TCP connection, a pty) served as Modbus RTU.

    Frames are split by :class:`~.codec.RtuFramer` at the line's character format, read from
    the slaves' registers at every chunk (a baud-rate change applies at once, MIS manual
    §12.2.1). Each reply is sent after the slave's reply delay.

    Parameters
    ----------
    bus : ModbusBus
    clock : callable
        Monotonic time [s].
    sleep : callable or None
        Waits the reply delay (None: replies are not delayed).
    """

    def __init__(self, bus: ModbusBus, clock: Callable[[], float] = time.monotonic,
                 sleep: Callable[[float], None] | None = time.sleep) -> None:
        self.bus = bus
        self.clock = clock
        self.sleep = sleep
        self.framer = mb.RtuFramer(bus.serial_format())

    def feed(self, chunk: bytes) -> bytes:
        """Received bytes → the replies they call for."""
        now = self.clock()
        self.framer.fmt = self.bus.serial_format()
        out = bytearray()
        for item in self.framer.feed(chunk, now):
            if isinstance(item, FrameError):
                self.bus.stats["errors"] += 1
                log.info("Modbus frame dropped: %s", item.reason)
                continue
            reply, delay = self.bus.handle(item, now)
            if reply:
                if self.sleep is not None and delay > 0:
                    self.sleep(delay)
                out += reply
        return bytes(out)

    def flush(self) -> bytes:
        """A silence: held bytes are a bad frame (dropped); the timeouts are checked."""
        for item in self.framer.flush():
            self.bus.stats["errors"] += 1
            log.info("Modbus frame dropped: %s", getattr(item, "reason", item))
        self.bus.poll(self.clock())
        return b""


class ActiveProtocol(enum.Enum):
    """Protocol of the main serial channel (MIS manual §12.2.1)."""

    MACTALK = "mactalk"
    MODBUS = "modbus"


class ProtocolSwitch:
    """MacTalk after power-on, Modbus after one second of silence if enabled (MIS manual
    §12.2.1: "The motor will switch to Modbus after 1 second of inactivity on the serial line
    (if Modbus has been enabled, bit 0 in register 121 is set)"; §8.2.66: MacTalk can be used in
    the first second after power-on).

    States: MACTALK → MODBUS when, at a received chunk or a :meth:`poll`, the line has been silent
    for ``quiet`` seconds (since power-on or the last received byte) and ``enabled()`` is true
    then. MODBUS stays until :meth:`power_on` (MacTalk cannot switch it back, §12.2.1).

    Parameters
    ----------
    enabled : callable
        Whether Modbus is enabled now (e.g. bit 0 of the set-up register); asked at each check.
    now : float
        Time of power-on [s].
    quiet : float
        Silence that switches [s].
    """

    def __init__(self, enabled: Callable[[], bool], now: float, quiet: float = 1.0) -> None:
        self.enabled = enabled
        self.quiet = quiet
        self.power_on(now)

    @classmethod
    def for_device(cls, device: RegisterAccess, setup_register: int, now: float,
                   quiet: float = 1.0) -> ProtocolSwitch:
        """A switch enabled by bit 0 of ``setup_register`` of ``device`` (MIS: 121)."""

        def enabled() -> bool:
            try:
                return mb.decode_setup(int(device.read(setup_register))).rs485
            except (ValueError, LookupError):
                return False

        return cls(enabled, now, quiet)

    def power_on(self, now: float) -> None:
        """Back to MacTalk; the silence counts from ``now``."""
        self.state = ActiveProtocol.MACTALK
        self.last_activity = now

    def poll(self, now: float) -> ActiveProtocol:
        """The protocol now (switching if the silence has lasted long enough)."""
        if (self.state == ActiveProtocol.MACTALK and now - self.last_activity >= self.quiet
                and self.enabled()):
            self.state = ActiveProtocol.MODBUS
            log.info("main channel switched to Modbus RTU")
        return self.state

    def on_bytes(self, now: float) -> ActiveProtocol:
        """Bytes arrive at ``now``: the protocol that receives them."""
        state = self.poll(now)
        self.last_activity = now
        return state


class _Stream(Protocol):
    def feed(self, chunk: bytes) -> bytes: ...
    def flush(self) -> bytes: ...


class SwitchingSession:
    """The main serial channel: bytes go to the MacTalk or the Modbus session as
    :class:`ProtocolSwitch` decides (MIS manual §12.2.1). The twin builds one per stream from its
    MacTalk session (``twin.session()``) and a :class:`ModbusSession`.

    Parameters
    ----------
    mactalk, modbus : objects with ``feed(bytes) -> bytes`` and ``flush() -> bytes``
    switch : ProtocolSwitch
    clock : callable
        Monotonic time [s], the clock of ``switch``.
    """

    def __init__(self, mactalk: _Stream, modbus: _Stream, switch: ProtocolSwitch,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self.mactalk = mactalk
        self.modbus = modbus
        self.switch = switch
        self.clock = clock

    @property
    def active(self) -> ActiveProtocol:
        """The protocol the channel speaks now."""
        return self.switch.state

    def _session(self, state: ActiveProtocol) -> _Stream:
        return self.modbus if state == ActiveProtocol.MODBUS else self.mactalk

    def feed(self, chunk: bytes) -> bytes:
        """Received bytes → the replies of the active protocol."""
        before = self.switch.state
        state = self.switch.on_bytes(self.clock())
        out = self.mactalk.flush() if state != before else b""
        return out + self._session(state).feed(chunk)

    def flush(self) -> bytes:
        """A silence: the active session's flush (a switch to Modbus may happen here)."""
        before = self.switch.state
        state = self.switch.poll(self.clock())
        out = self.mactalk.flush() if state != before else b""
        return out + self._session(state).flush()


@dataclass
class ModbusServer(TwinServer):
    """Serve a :class:`ModbusBus` as Modbus RTU over TCP on localhost and/or a pseudo-terminal,
    with the endpoints, threads and shutdown of the shared transport's
    :class:`~jvl_gym.protocol.serving.transport.TwinServer`.

    Over TCP the frames are RTU frames (address … CRC, no MBAP header), as a pymodbus client with
    ``framer=FramerType.RTU`` sends them; each connection is its own stream. A watchdog thread
    checks the Modbus timeouts every ``poll_interval`` seconds.

    Parameters
    ----------
    bus : ModbusBus
    tcp : tuple (host, port) or None
        Localhost only; port 0 picks a free one (``endpoint("modbus", "tcp").port``).
    pty : bool
    twin : object or None
        A twin to advance in real time when ``run_clock`` (see :class:`TwinServer`).
    frame_timeout : float
        Receive timeout [s] after which the session is flushed; frames are split by the RTU
        silences whatever its value.
    poll_interval : float
        Period of the timeout watchdog [s].
    make_session : callable or None
        Factory of the session of each stream (default: a :class:`ModbusSession` on ``bus``);
        e.g. a :class:`SwitchingSession` to serve MacTalk and Modbus on one channel.
    """

    twin: Any = None
    run_clock: bool = False
    frame_timeout: float = 0.05
    bus: ModbusBus | None = None
    poll_interval: float = 0.01
    make_session: Callable[[], Any] | None = None
    sessions: deque[Any] = field(default_factory=kept_sessions)

    def start(self) -> ModbusServer:
        """Open the endpoints and start the threads; return self."""
        if self.bus is None:
            raise ValueError("ModbusServer needs a bus")
        self.warm_up()
        if self.tcp is not None:
            self._listen(self.tcp[0], self.tcp[1], "modbus", self._session)  # type: ignore
        if self.pty:
            self._open_pty("modbus", self._session())  # type: ignore[arg-type]
        self._spawn(self._watch, "modbus-timeout")
        if self.run_clock and self.twin is not None:
            self._spawn(self._clock, "twin-clock")
        return self

    def _session(self) -> Any:
        assert self.bus is not None
        s = self.make_session() if self.make_session is not None else ModbusSession(self.bus)
        self.sessions.append(s)
        return s

    def _watch(self) -> None:
        assert self.bus is not None
        while not self._stop.wait(self.poll_interval):
            self.bus.poll(time.monotonic())
