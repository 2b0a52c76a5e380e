"""The DMX512 receiver of one MIS motor (MIS manual §13.1.5–§13.1.10).

Addresses (§13.1.6): Start Address 1 (SA1) holds the position, coarse (SA1 + 0, high byte) and
fine (SA1 + 1), and the control channel (SA1 + 2); Start Address 2 (SA2) the acceleration
(SA2 + 0) and the maximum velocity (SA2 + 1).

Scaling (§13.1.7)::

    P_SOLL = position (16 bit) · PosNom / PosDen + PosOffset (32 bit)
    A_SOLL = acceleration (8 bit) · AccNom / AccDen + AccOffset (16 bit)
    V_SOLL = velocity (8 bit) · VelNom / VelDen + VelOffset (16 bit)

Control channel (§13.1.8): 0–9 passive, 60–69 position mode (the scaled values are
transferred whenever a new value arrives), 180–189 homing once ten identical values in a row
have arrived (it is not aborted when the value changes), 200–209 reset errors; other values
keep the mode and transfer nothing. "Auto clear errors" clears the errors before a command.

Jogging (§13.1.9): input 1 Off → On puts the motor in velocity mode at 0 RPM and the DMX data
are ignored; input 2 On runs at +Jog Velocity, input 3 On at −Jog Velocity, Off stops; input 1
On → Off ends jogging: passive, V_SOLL = Default Velocity, P_SOLL = P_IST, and a homing is
needed before position commands are taken again.

Decisions where the manual is silent or reads two ways (``docs/protocol.md``, "DMX512"):

* The result of a scaling is the register's own unit (V_SOLL in 0.01 RPM, A_SOLL in RPM/s, as
  the formulas name the registers; the MacTalk tab's "Offset 0.00 RPM" is such a V_SOLL
  value); integer arithmetic, the product divided with truncation towards zero, then stored
  within the register's range (A_SOLL at least 1).
* Nominators and denominators are 16 bit (position and velocity nominators signed, the others
  unsigned; a denominator is at least 1: "MacTalk will limit the ranges to prevent … division
  by zero"); the position offset is signed 32 bit, the velocity offset signed 16 bit, the
  acceleration offset unsigned 16 bit.
* "The motor is kept in its configured start-up mode until 10 identical values in the range
  180..189 have been received": with homing enabled, position values (60–69) are taken only
  after a completed homing; with homing disabled (an absolute encoder) at once. A homing starts
  when the run of identical values reaches ten; another needs a new run. While it runs the
  control channel is not acted on ("Homing will not be aborted"); when it is done (MODE_REG
  leaves 13/14 without an error) the motor is put in position mode.
* Jogging with inputs 2 and 3 both On runs at 0; the input levels at the receiver's start are
  its reference (an input that is On at power-on has not been switched On).
* A packet too short to hold the motor's slots is ignored; so are packets of another start code.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, fields
from typing import Any

from ...families import Capability
from ...registers import RegisterError
from ...registers.errors import echo
from .frames import DmxPacket

__all__ = ["DmxSettings", "DmxReceiver", "MODE_NAMES"]

log = logging.getLogger(__name__)

#: the MODE_REG modes the receiver commands, by their names in the family's ``MODE_NAMES``
#: (MIS manual §8.2.3): velocity, position and the zero searches of the homing; passive is the
#: twin spec's ``passive_mode`` and "clear errors" its ``commands["clear_errors"]`` (§8.2.21)
MODE_NAMES = {"velocity": "velocity", "position": "position",
              "homing": ("zero search type 1", "zero search type 2")}

_S16 = (-(2**15), 2**15 - 1)
_U16 = (0, 2**16 - 1)
_LIMITS: dict[str, tuple[int, int]] = {
    "start_address1": (1, 510), "start_address2": (1, 511),
    "default_velocity": (0, 300000), "jog_velocity": (0, 300000),
    "pos_nom": _S16, "pos_den": (1, _U16[1]), "pos_offset": (-(2**31), 2**31 - 1),
    "acc_nom": _U16, "acc_den": (1, _U16[1]), "acc_offset": _U16,
    "vel_nom": _S16, "vel_den": (1, _U16[1]), "vel_offset": _S16,
    "homing_mode": (13, 14)}


@dataclass(frozen=True)
class DmxSettings:
    """The MacTalk "DMX512 Setup" tab of one motor (§13.1.3–13.1.9; defaults as the tab shows
    them: Default Velocity 1000.00 RPM, Jog Velocity 100.00 RPM, Start Address 1 = 1, Start
    Address 2 = 500, position and acceleration 1/1 + 0, velocity 10/1 + 0, sensor type 2).

    Velocities in 0.01 RPM (V_SOLL units); ``homing_mode`` 13 or 14 (sensor type 1 or 2);
    ``homing`` False: the homing is disabled (absolute encoder).
    """

    start_address1: int = 1
    start_address2: int = 500
    default_velocity: int = 100000
    jog_velocity: int = 10000
    pos_nom: int = 1
    pos_den: int = 1
    pos_offset: int = 0
    acc_nom: int = 1
    acc_den: int = 1
    acc_offset: int = 0
    vel_nom: int = 10
    vel_den: int = 1
    vel_offset: int = 0
    auto_clear_errors: bool = False
    acceleration_at_standstill: bool = False
    values_with_position: bool = False
    homing: bool = True
    homing_mode: int = 14
    jog_reset_errors: bool = False

    def __post_init__(self) -> None:
        for f in fields(self):
            v = getattr(self, f.name)
            if f.name not in _LIMITS:
                if not isinstance(v, bool):
                    raise ValueError(f"DMX512 setting {f.name} must be true or false, "
                                     f"got {echo(v)}")
                continue
            lo, hi = _LIMITS[f.name]
            if isinstance(v, bool) or not isinstance(v, int) or not lo <= v <= hi:
                raise ValueError(f"DMX512 setting {f.name} must be a whole number {lo} … {hi}, "
                                 f"got {echo(v)}")

    def position(self, coarse: int, fine: int) -> int:
        """P_SOLL of a DMX position (§13.1.7)."""
        return _div((coarse << 8 | fine) * self.pos_nom, self.pos_den) + self.pos_offset

    def acceleration(self, value: int) -> int:
        """A_SOLL of a DMX acceleration (§13.1.7)."""
        return _div(value * self.acc_nom, self.acc_den) + self.acc_offset

    def velocity(self, value: int) -> int:
        """V_SOLL of a DMX velocity (§13.1.7)."""
        return _div(value * self.vel_nom, self.vel_den) + self.vel_offset


def _div(a: int, b: int) -> int:
    q = abs(a) // b
    return q if a >= 0 else -q


class DmxReceiver:
    """The DMX512 side of motor ``index`` of a motor array (module docstring).

    Parameters
    ----------
    motors : MotorArray
        Read and written by register name (``read_raw``, ``write_raw``); its family declares
        :attr:`~jvl_gym.families.Capability.DMX512` and names the modes of :data:`MODE_NAMES`.
    index : int
        The motor.
    settings : DmxSettings

    Raises
    ------
    UnsupportedOperation
        The motors' family has no DMX512 interface.
    """

    def __init__(self, motors: Any, index: int, settings: DmxSettings | None = None) -> None:
        self.m = motors
        self.i = index
        fam = motors.family
        fam.require(Capability.DMX512)
        modes = {name: value for value, name in fam.constants.MODE_NAMES.items()}
        self.passive = fam.twin.passive_mode
        self.velocity = modes[MODE_NAMES["velocity"]]
        self.position = modes[MODE_NAMES["position"]]
        self.homing_modes = tuple(modes[n] for n in MODE_NAMES["homing"])
        self.clear_errors_command = fam.twin.commands["clear_errors"]
        self.s = settings or DmxSettings()
        self.last_control: int | None = None
        self.same = 0
        self.homing = False
        self.homed = not self.s.homing
        self.jogging = False
        self.sent: dict[str, int] = {}
        self.last_position: int | None = None
        self.inputs = self._read("INPUTS") & 7
        self.refusals = 0

    # ------------------------------------------------------------------ registers
    def _read(self, name: str) -> int:
        return int(self.m.read_raw(name)[self.i])

    def _write(self, name: str, value: int) -> None:
        reg = self.m.table.lookup(name)
        value = min(max(int(value), reg.raw_min), reg.raw_max)
        try:
            self.m.write_raw(name, value, index=self.i)
        except (RegisterError, ValueError) as exc:
            self.refusals += 1
            log.info("DMX512 write refused: %s", exc)

    def _clear_errors(self) -> None:
        if self._read("ERR_BITS") != 0:
            self._write("COMMAND", self.clear_errors_command)

    # ------------------------------------------------------------------ DMX data
    def packet(self, packet: DmxPacket) -> None:
        """Take one received packet."""
        s = self.s
        a1, a2 = s.start_address1 - 1, s.start_address2 - 1
        slots = packet.slots
        if packet.start_code != 0 or len(slots) < max(a1 + 3, a2 + 2) or self.jogging:
            return
        self._homing_done()
        control = slots[a1 + 2]
        self.same = self.same + 1 if control == self.last_control else 1
        self.last_control = control
        if self.homing:
            return  # "Homing will not be aborted if the value … is changed" (§13.1.8)
        command = control // 10
        if s.auto_clear_errors and command in (0, 6, 18, 20):
            self._clear_errors()
        if command == 0:
            self._write("MODE_REG", self.passive)
        elif command == 6 and self.homed:
            if self._read("MODE_REG") != self.position:
                self._write("MODE_REG", self.position)
            self._transfer(s.position(slots[a1], slots[a1 + 1]), s.acceleration(slots[a2]),
                           s.velocity(slots[a2 + 1]), slots[a1] << 8 | slots[a1 + 1])
        elif command == 18 and s.homing and self.same == 10:
            self._write("MODE_REG", s.homing_mode)
            self.homing = self._read("MODE_REG") == s.homing_mode
        elif command == 20:
            self._write("COMMAND", self.clear_errors_command)

    def _transfer(self, position: int, acceleration: int, velocity: int, raw: int) -> None:
        """New values to the motor (velocity and acceleration first, so the move uses them)."""
        if self.s.values_with_position:
            if raw == self.last_position:
                return
            self.sent.clear()
        self.last_position = raw
        if self.sent.get("V_SOLL") != velocity:
            self._write("V_SOLL", velocity)
            self.sent["V_SOLL"] = velocity
        standstill = self._read("V_IST") == 0
        if self.sent.get("A_SOLL") != acceleration and (
                standstill or not self.s.acceleration_at_standstill):
            self._write("A_SOLL", acceleration)
            self.sent["A_SOLL"] = acceleration
        if self.sent.get("P_SOLL") != position:
            self._write("P_SOLL", position)
            self.sent["P_SOLL"] = position

    def _homing_done(self) -> None:
        if self.homing and self._read("MODE_REG") not in self.homing_modes:
            self.homing = False
            if self._read("ERR_BITS") == 0:
                self.homed = True
                self._write("MODE_REG", self.position)

    # ------------------------------------------------------------------ inputs
    def poll(self) -> None:
        """Watch inputs 1–3 for jogging and a homing for its end (call it often, e.g. every
        outer sample or every few ms of simulated time)."""
        self._homing_done()
        now = self._read("INPUTS") & 7
        was, self.inputs = self.inputs, now
        s = self.s
        if now & 1 and not was & 1:
            self.jogging = True
            self.homing = False
            if s.jog_reset_errors:
                self._clear_errors()
            self._write("MODE_REG", self.velocity)
            self._write("V_SOLL", 0)
        if not self.jogging:
            return
        if not now & 1:
            self.jogging = False
            self.homed = not s.homing
            self.sent.clear()
            self.last_position = None
            self._write("MODE_REG", self.passive)
            self._write("V_SOLL", s.default_velocity)
            self._write("P_SOLL", self._read("P_IST"))
            return
        if s.jog_reset_errors and (now ^ was) & 6:
            self._clear_errors()
        way = {2: 1, 4: -1}.get(now & 6, 0)
        if (now ^ was) & 7:
            self._write("V_SOLL", way * s.jog_velocity)
