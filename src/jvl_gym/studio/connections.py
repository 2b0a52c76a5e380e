"""The Connections view's logic: serial ports, lines opened and closed, a scan that names the
motors it finds, and motors added to and removed from the running studio.

A scan probes each address of a range (:func:`~.line.scan`: the MacTalk dialect of the reply)
and reads, in that dialect, the identification registers each family's manual gives:

=============  ==========================  ==========================  ========================
family         type                        firmware version            serial number
=============  ==========================  ==========================  ========================
MAC050–141     MOTOR_TYPE (3.2.153)        PROG_VERSION (3.2.1)        SERIAL_NMB (3.2.154)
MAC800/MAC400  MOTOR_TYPE (overview §1.2)  PROG_VERSION (overview §1.2) SERIAL_NUMBER (§1.2)
MIS/SMC        MOTORTYPE (§8.2.89)         PROG_VERSION (§8.2.2)       SERIAL_NUMBER (§8.2.90)
=============  ==========================  ==========================  ========================

The type register holds a code; the motor type is the one of the families speaking that
dialect whose motor config has that code (``motor_type_code``). Two families share the 32-bit
MacTalk (MIS and MAC800), so the code also tells them apart; a code no family knows leaves the
type open ("—"), and the engineer picks it when adding the motor. A register a family's table
lacks shows "—" with the reason.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

from ..families import Family, families, family, family_of_motor
from ..registers import RegisterError
from .line import Line, LineDown, LineMotor, scan
from .motor import SimMotor, StudioMotor
from .session import Session

__all__ = ["Found", "address_range", "serial_ports", "identify", "version_text", "NONE",
           "IDENTITY_REGISTERS", "Connections"]

#: what a field of a found motor shows where it has no value
NONE = "—"

#: the identification registers of the manuals, by role: the first name a family's table has
IDENTITY_REGISTERS: dict[str, tuple[str, ...]] = {
    "type": ("MOTOR_TYPE", "MOTORTYPE"),
    "firmware": ("PROG_VERSION",),
    "serial": ("SERIAL_NMB", "SERIAL_NUMBER"),
}


def address_range(text: str) -> range:
    """``"1-32"`` → range(1, 33); ``"19"`` → range(19, 20); unit addresses 1..254 (MYADDR).

    Raises
    ------
    ValueError
        Not FIRST-LAST, or outside 1..254, or FIRST > LAST (one line).
    """
    lo, _, hi = text.strip().partition("-")
    try:
        a, b = int(lo), int(hi or lo)
    except ValueError:
        raise ValueError(f"an address range is FIRST-LAST, e.g. 1-32, not {text!r}") from None
    if not 1 <= a <= b <= 254:
        raise ValueError(f"address range {text}: addresses are 1..254 (MYADDR), "
                         "first <= last")
    return range(a, b + 1)


def serial_ports() -> list[tuple[str, str]]:
    """The serial ports of this machine (pyserial's ``list_ports``): (device, description)."""
    from serial.tools import list_ports

    return [(p.device, p.description or "") for p in sorted(list_ports.comports())]


#: a bit field of a version register's description: "bits 0-5 minor", "6-12 major", "13 beta"
_FIELD = re.compile(r"(\d+)(?:-(\d+))? (minor|major|beta)")
#: a worked example of a version register's description: "78 = 4Eh = version 4.14"
_EXAMPLE = re.compile(r"(\d+) = [0-9A-Fa-f]+h = version (\d+)\.(\d+)")


def version_text(fam: Family, raw: int) -> str:
    """PROG_VERSION ``raw`` as the family's manual reads it, from the register's description
    in the family's table: its bit fields (MAC800 register overview §1.2: bits 0–5 minor,
    6–12 major, 13 beta; MIS manual §8.2.2: bits 0–3 minor, 4–12 major, 13 beta), or its worked
    example (MAC050–141 manual 3.2.1: 78 = 4Eh = version 4.14, the minor version in the bits
    below the major one); the plain number where the description gives neither."""
    reg = _register(fam, "firmware")
    text = reg.description if reg is not None else ""
    fields = {m.group(3): (int(m.group(1)), int(m.group(2) or m.group(1)))
              for m in _FIELD.finditer(text)}
    if "major" in fields and "minor" in fields:
        def bits(name: str) -> int:
            lo, hi = fields[name]
            return (raw >> lo) & ((1 << (hi - lo + 1)) - 1)
        beta = "beta" in fields and bits("beta")
        return f"{bits('major')}.{bits('minor')}" + (" beta" if beta else "")
    example = _EXAMPLE.search(text)
    if example:
        value, major, minor = (int(g) for g in example.groups())
        for shift in range(1, 16):  # the split that the example's value shows
            if value >> shift == major and value & ((1 << shift) - 1) == minor:
                return f"{raw >> shift}.{raw & ((1 << shift) - 1)}"
    return str(raw)


@dataclass(frozen=True)
class Found:
    """A motor a scan found.

    Attributes
    ----------
    address : int
        Its unit address.
    dialect : str
        The MacTalk it answered in.
    motor_type : str or None
        Its motor type, None where the type code names none of the dialect's families.
    firmware, serial : str
        Its firmware version and serial number, :data:`NONE` where unknown.
    note : str
        Why a field is :data:`NONE` ("" where none is).
    """

    address: int
    dialect: str
    motor_type: str | None
    firmware: str
    serial: str
    note: str = ""

    @property
    def type_text(self) -> str:
        """The motor type, or :data:`NONE`."""
        return self.motor_type or NONE


def _register(fam: Family, role: str) -> Any:
    """The register of ``role`` in the family's table, None if it has none."""
    for name in IDENTITY_REGISTERS[role]:
        try:
            return fam.table.lookup(name)
        except (KeyError, RegisterError):
            continue
    return None


def identify(line: Line, address: int, dialect: str) -> Found:
    """Read the identification registers of the unit at ``address`` (which answers in
    ``dialect``) and name its motor type, firmware version and serial number."""
    notes: list[str] = []
    speaking = [family(k) for k in families() if family(k).twin.dialect == dialect]
    matches: list[tuple[Family, str]] = []
    codes: list[str] = []
    for fam in speaking:
        reg = _register(fam, "type")
        if reg is None:
            notes.append(f"the {fam.title} have no motor type register")
            continue
        try:
            code = int(line.call(address, lambda c, n=reg.number: c.read_raw(n),
                                 dialect=dialect, table=fam.table))
        except (RegisterError, LineDown):
            continue
        codes.append(f"{reg.name} {code}")
        by_code = {fam.load_motor(t).motor_type_code: t for t in fam.motor_types()}
        if code in by_code:
            matches.append((fam, by_code[code]))
    if len(matches) == 1:
        fam, motor_type = matches[0]
    else:
        fam, motor_type = (speaking[0] if len(speaking) == 1 else None), None
        notes.append(f"type code {', '.join(codes) or 'unread'} names no motor type of the "
                     f"{' or '.join(f.title for f in speaking)}: pick the type")
    fields = {}
    for role in ("firmware", "serial"):
        reg = None if fam is None else _register(fam, role)
        if reg is None:
            fields[role] = NONE
            if fam is not None:
                notes.append(f"the {fam.title} have no {role} register")
            continue
        try:
            raw = int(line.call(address, lambda c, n=reg.number: c.read_raw(n),
                                dialect=dialect, table=fam.table))
        except (RegisterError, LineDown) as exc:
            fields[role] = NONE
            notes.append(f"{reg.name} unread: {exc}")
            continue
        fields[role] = version_text(fam, raw) if role == "firmware" else str(raw)
    return Found(address, dialect, motor_type, fields["firmware"], fields["serial"],
                 "; ".join(notes))


class Connections:
    """Lines and motors of a running studio, as the Connections view changes them.

    Every operation checks its input first: a port that cannot be opened, a malformed range,
    a scan that finds nothing raise one line (:class:`ValueError` or
    :class:`~.line.LineDown`) and change nothing.

    Parameters
    ----------
    session : Session
        The studio's motors and lines.
    line_factory : callable, optional
        Makes a :class:`~.line.Line` of a port (default: a :class:`~.line.Line` that waits the
        session's ``answer_timeout`` for each reply).
    """

    def __init__(self, session: Session,
                 line_factory: Callable[[str], Line] | None = None) -> None:
        self.session = session
        self.line_factory = line_factory or (
            lambda port: Line(port, timeout=session.answer_timeout))
        #: port → the motors its last scan found
        self.found: dict[str, list[Found]] = {}

    def connect(self, port: str) -> Line:
        """Open the line at ``port`` (a device or a pyserial URL such as
        ``socket://127.0.0.1:5000``) and hold it; a port held already is kept as it is."""
        port = port.strip()
        if not port:
            raise ValueError("give a serial port (e.g. /dev/ttyUSB0) or a twin's URL "
                             "(socket://127.0.0.1:PORT)")
        if port in self.session.lines:
            return self.session.lines[port]
        line = self.line_factory(port)
        line.open()  # LineDown (one line) if it cannot be opened: nothing is held
        return self.session.add_line(line)

    def disconnect(self, port: str) -> list[str]:
        """Remove the motors on the line at ``port`` (each stopped first) and close it."""
        said = self.session.drop_line(port)
        self.found.pop(port, None)
        return said

    def scan(self, port: str, text: str) -> list[Found]:
        """Probe the addresses ``text`` (FIRST-LAST) on the open line at ``port`` and identify
        each unit that answers (:func:`identify`).

        Raises
        ------
        ValueError
            A malformed range, a line that is not open, or no unit answered.
        """
        addresses = address_range(text)
        line = self._line(port)
        found = [identify(line, a, d) for a, d in scan(line, addresses).items()]
        if not found:
            raise ValueError(f"no motor answered on {port} at addresses "
                             f"{addresses.start}..{addresses.stop - 1}")
        self.found[port] = found
        return found

    def add(self, port: str, address: int, motor_type: str | None = None) -> StudioMotor:
        """Add the motor at ``address`` of the open line at ``port`` to the studio, of
        ``motor_type`` (default: the type its scan found), and take its settings now as its
        flash record (:attr:`~.line.LineMotor.flash_record`)."""
        from .parameters import settings_of

        line = self._line(port)
        for m in self.session.motors:
            if getattr(m, "line", None) is line and m.address == address:
                raise ValueError(f"{m.label} is in the studio already")
        if motor_type is None:
            found = {f.address: f for f in self.found.get(port, [])}
            if address not in found or found[address].motor_type is None:
                raise ValueError(f"the type of the motor at address {address} on {port} is "
                                 "not known: pick one")
            motor_type = found[address].motor_type
        motor = LineMotor(line, family_of_motor(motor_type).canonical_name(motor_type),
                          address)
        if motor.label in self.session.labels():
            motor.with_port = True
        try:
            motor.flash_record = settings_of(motor)
        except (LineDown, RegisterError) as exc:
            raise ValueError(f"{motor.label} does not answer on {port}: {exc}") from None
        return self.session.add(motor)

    def add_found(self, port: str) -> list[StudioMotor]:
        """Add every motor of the last scan of ``port`` whose type it found and that the
        studio does not hold yet."""
        held = {(getattr(m, "line", None), m.address) for m in self.session.motors}
        line = self._line(port)
        return [self.add(port, f.address) for f in self.found.get(port, [])
                if f.motor_type is not None and (line, f.address) not in held]

    def add_simulated(self, motor_type: str, address: int | None = None, seed: int = 0
                      ) -> StudioMotor:
        """Add a simulated motor of ``motor_type`` at ``address`` (default: the lowest
        address no motor of the studio has)."""
        used = {m.address for m in self.session.motors}
        if address is None:
            address = next(a for a in range(1, 255) if a not in used)
        if not 1 <= int(address) <= 254:
            raise ValueError(f"address {address} is no unit address (1..254, MYADDR)")
        motor = SimMotor(motor_type, int(address), seed=seed)
        return self.session.add(motor)

    def remove(self, label: str) -> str:
        """Stop and remove the motor ``label`` (:meth:`~.session.Session.remove`)."""
        return self.session.remove(label)

    def _line(self, port: str) -> Line:
        if port not in self.session.lines:
            raise ValueError(f"{port!r} is not connected; connect it first (open: "
                             f"{', '.join(self.session.lines) or 'none'})")
        return self.session.lines[port]


def motor_types() -> list[str]:
    """Every motor type of every family, for the simulated motor's choice."""
    return [t for k in families() for t in family(k).motor_types()]


def lines_of(session: Session) -> Iterable[tuple[str, list[StudioMotor]]]:
    """Each open line's port with the studio's motors on it."""
    for port, line in session.lines.items():
        yield port, [m for m in session.motors if getattr(m, "line", None) is line]
