"""The motion panel's logic: enable and passive, jog, run at speed, moves and home.

The modes and registers behind each motion are the family's own, read from its constants
(``MOTION_MODES``, ``MOTION_REGISTERS``; MAC050–141 manual 4.4, MAC800 overview §1.2, MIS
manual §6 and §8.2.3): velocity mode with a signed V_SOLL for a jog and a run at speed,
position mode with P_SOLL as the target and V_SOLL as the top speed for a move, the zero
search modes for home. Speeds are in rpm and positions in the unit the motor's
:class:`~.units_view.UnitsView` shows positions in (turns by default, or degrees).

Every motion checks all its values against the register ranges and the motor's software
position limits before it writes anything: a refused motion raises :class:`MotionError` (one
line) and changes nothing.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..registers import Register, RegisterError, to_raw
from .motor import StudioMotor
from .units_view import UnitsView

__all__ = ["MotionError", "Limits", "Motion", "has_motion"]


class MotionError(ValueError):
    """A motion the motor cannot make (one line: which value and its limits)."""


def has_motion(motor: StudioMotor) -> bool:
    """Whether ``motor``'s family states the modes and registers of a motion panel."""
    const = motor.facts.constants
    return bool(getattr(const, "MOTION_MODES", None) and getattr(const, "MOTION_REGISTERS", None))


@dataclass(frozen=True)
class Limits:
    """What the motion panel shows as the motor's limits.

    Attributes
    ----------
    speed : tuple of float
        Lowest and highest speed a motion may ask for [rpm] (the speed register's range).
    rated_speed : float or None
        The motor's rated speed [rpm], where its data gives one.
    position : tuple of float or None
        The software position limits in :attr:`position_unit`; None while they are off (both
        0: MAC050–141 manual 3.2.28, MIS manual §8.2.26).
    position_unit : str
        The unit of positions.
    """

    speed: tuple[float, float]
    rated_speed: float | None
    position: tuple[float, float] | None
    position_unit: str

    def text(self) -> str:
        """The limits in one line."""
        out = f"speed {self.speed[0]:.6g} … {self.speed[1]:.6g} rpm"
        if self.rated_speed:
            out += f" (rated {self.rated_speed:.6g} rpm)"
        if self.position is None:
            out += "; position limits off"
        else:
            out += (f"; position {self.position[0]:.6g} … {self.position[1]:.6g} "
                    f"{self.position_unit}")
        return out


class Motion:
    """The motions of one motor.

    Parameters
    ----------
    motor : StudioMotor
        The motor moved.
    prefer : iterable of str
        Preferred units (``{"°"}``: positions in degrees), as :class:`UnitsView` takes them.

    Raises
    ------
    MotionError
        The motor's family states no motion panel.
    """

    def __init__(self, motor: StudioMotor, prefer: tuple[str, ...] = ()) -> None:
        if not has_motion(motor):
            raise MotionError(f"{motor.label}: the {motor.facts.title} state no motion modes")
        const = motor.facts.constants
        self.motor = motor
        self.view = UnitsView(motor.motor_type, prefer)
        self.modes: dict[str, tuple[int, ...]] = {
            k: tuple(int(v) for v in vs) for k, vs in const.MOTION_MODES.items()}
        self._regs = {k: motor.register(v) for k, v in const.MOTION_REGISTERS.items()}
        #: the direction of the jog in progress (+1, -1), 0 when none
        self.jogging = 0
        speed = self._regs["speed"]
        rpm = [o for o in self.view.options(speed) if o.unit == "rpm"]
        if not rpm:
            raise MotionError(f"{motor.label}: {speed.name} has no rpm unit in the family's "
                              "ENGINEERING_UNITS")
        self._rpm = rpm[0]

    # ------------------------------------------------------------------ units
    @property
    def position_unit(self) -> str:
        """The unit of positions (turns or degrees)."""
        return self.view.unit_text(self._regs["position"])

    def _speed_value(self, rpm: float) -> float:
        """``rpm`` as the speed register's value, checked against its range."""
        reg = self._regs["speed"]
        value = round(self._rpm.to_register(float(rpm)) * reg.scale) / reg.scale
        self._check(reg, value, f"speed {rpm:g} rpm")
        return value

    def _position_value(self, position: float) -> float:
        reg = self._regs["target"]
        value = self.view.to_register(reg, float(position))
        self._check(reg, value, f"position {position:g} {self.position_unit}")
        lim = self._raw_limits()
        if lim is not None and not lim[0] <= value <= lim[1]:
            lo, hi = (self.view.value(reg, int(v)) for v in lim)
            raise MotionError(f"position {position:g} {self.position_unit} is outside the "
                              f"software limits {lo:.6g} … {hi:.6g} {self.position_unit} "
                              f"({self._regs['min_position'].name}, "
                              f"{self._regs['max_position'].name})")
        return value

    @staticmethod
    def _check(reg: Register, value: float, what: str) -> None:
        try:
            to_raw(reg, value)
        except RegisterError as exc:
            raise MotionError(f"{what}: {exc}") from None

    def _raw_limits(self) -> tuple[int, int] | None:
        lo = self.motor.read_raw(self._regs["min_position"].number)
        hi = self.motor.read_raw(self._regs["max_position"].number)
        return None if lo == 0 and hi == 0 else (lo, hi)

    # ------------------------------------------------------------------ state
    def limits(self) -> Limits:
        """The speed range, the motor's rated speed and the software position limits."""
        speed = self._regs["speed"]
        lo, hi = sorted((self._rpm.to_engineering(speed.minimum),
                         self._rpm.to_engineering(speed.maximum)))
        rated = getattr(self.view._motor, "rated_speed_rpm", None)
        raw = self._raw_limits()
        pos = self._regs["position"]
        position = None if raw is None else (self.view.value(pos, raw[0]),
                                             self.view.value(pos, raw[1]))
        return Limits((lo, hi), float(rated) if rated else None, position, self.position_unit)

    def position(self) -> float:
        """The actual position in :attr:`position_unit`."""
        reg = self._regs["position"]
        return self.view.value(reg, self.motor.read_raw(reg.number))

    def speed(self) -> float:
        """The actual velocity [rpm]."""
        reg = self._regs["velocity"]
        units = [o for o in self.view.options(reg) if o.unit == "rpm"]
        value = self.motor.read(reg.number)
        return units[0].to_engineering(value) if units else value

    def mode(self) -> int:
        """The mode register's value now."""
        return self.motor.read_raw(self.motor.facts.mode_register)

    # ------------------------------------------------------------------ motions
    def _set_mode(self, kind: str, choice: int | None = None) -> None:
        values = self.modes.get(kind, ())
        if not values:
            raise MotionError(f"{self.motor.label}: the {self.motor.facts.title} have no "
                              f"{kind} mode")
        mode = values[0] if choice is None else int(choice)
        if mode not in values:
            names = ", ".join(f"{self.motor.facts.mode_name(v)} ({v})" for v in values)
            raise MotionError(f"{kind}: mode {mode} is none of {names}")
        if self.mode() != mode:
            self.motor.write(self.motor.facts.mode_register, mode)

    def passive(self) -> None:
        """The family's passive mode (the motor's shaft free)."""
        self.jogging = 0
        self._set_mode("passive")

    def enable(self) -> None:
        """Position mode holding the position the motor is at (P_SOLL = P_IST first)."""
        with self.motor.lock:
            target, actual = self._regs["target"], self._regs["position"]
            self.motor.write(target.number, self.motor.read(actual.number))
            self._set_mode("position")

    def run(self, rpm: float) -> None:
        """Velocity mode at ``rpm`` (its sign the direction)."""
        value = self._speed_value(rpm)
        with self.motor.lock:
            self.motor.write(self._regs["speed"].number, value)
            self._set_mode("velocity")

    def jog_start(self, direction: int, rpm: float) -> None:
        """Start a jog: velocity mode at ``|rpm|`` in ``direction`` (+1 or -1) until
        :meth:`jog_stop` (a button pressed and held)."""
        if direction not in (1, -1):
            raise MotionError(f"a jog's direction is +1 or -1, got {direction!r}")
        self.run(direction * abs(float(rpm)))
        self.jogging = direction

    def jog_stop(self) -> None:
        """End a jog (the button released, or the page gone): speed 0 in velocity mode, the
        motor ramps down at its acceleration. Nothing if no jog is running."""
        if not self.jogging:
            return
        self.jogging = 0
        self.motor.write(self._regs["speed"].number, 0)

    def move_absolute(self, position: float, rpm: float) -> None:
        """A move to ``position`` (in :attr:`position_unit`) at most ``|rpm|``."""
        speed = self._speed_value(abs(float(rpm)))
        target = self._position_value(position)
        with self.motor.lock:
            self.motor.write(self._regs["speed"].number, speed)
            self.motor.write(self._regs["target"].number, target)
            self._set_mode("position")

    def move_relative(self, distance: float, rpm: float) -> None:
        """A move by ``distance`` (in :attr:`position_unit`) from the actual position."""
        self.move_absolute(self.position() + float(distance), rpm)

    def home(self, mode: int | None = None) -> None:
        """Start a zero search in the family's home ``mode`` (default: its first)."""
        self._set_mode("home", mode)

    def home_modes(self) -> dict[int, str]:
        """The family's home modes, value → name."""
        return {v: self.motor.facts.mode_name(v) for v in self.modes.get("home", ())}
