"""One motor as the studio sees it, and the simulated motor (one in-process MotorArray).

Every view works on a :class:`StudioMotor`: register access by name or number in user units and
raw counts (with the validation of the motor's own API: a refused value raises and changes
nothing), the family's actions, and, on a simulated motor, the physical signals. Two kinds
exist: :class:`SimMotor` here and :class:`~jvl_gym.studio.line.LineMotor` (a twin or a real
motor behind the protocol client).
"""

from __future__ import annotations

import threading
from abc import ABC, abstractmethod
from collections.abc import Callable, Iterable, Mapping
from typing import Any

import numpy as np

from ..families import Capability, Family, family_of_motor
from ..registers import Register, from_raw
from .facts import FamilyFacts, facts_of

__all__ = ["StudioMotor", "SimMotor", "ACTIONS", "PHYSICAL_SIGNALS"]

#: the family actions the Motors view offers: label → the capability the family declares for
#: it and the :class:`~jvl_gym.MotorArray` operation that does it (MAC050–141 manual 5.1 'go
#: safe mode', 'write flash', 'reset'; MIS manual §18.2 ENTER SAFEMODE, WRITE FLASH, RESET)
ACTIONS: dict[str, tuple[Capability, Callable[[Any], None]]] = {
    "safe mode": (Capability.SAFE_MODE, lambda m: m.enter_safe_mode()),
    "leave safe mode": (Capability.SAFE_MODE, lambda m: m.exit_safe_mode()),
    "save in flash": (Capability.FLASH, lambda m: m.write_flash()),
    "reset": (Capability.SOFTWARE_RESET, lambda m: m.software_reset()),
}

#: physical signals of a simulated motor: label → (MotorArray observable, unit, column names)
PHYSICAL_SIGNALS: dict[str, tuple[str, str, tuple[str, ...]]] = {
    "shaft speed": ("speed_rpm", "rpm", ("",)),
    "shaft angle": ("position_rad", "rad", ("",)),
    "torque": ("torque", "N·m", ("",)),
    "bus voltage": ("bus_voltage", "V", ("",)),
    "phase currents": ("phase_currents", "A", (" A", " B", " C")),
    "current amplitude": ("current_amplitude", "A", ("",)),
    "load speed": ("load_speed", "rad/s", ("",)),
}


class StudioMotor(ABC):
    """A motor of the studio: its type, family facts, address and registers.

    Attributes
    ----------
    motor_type : str
        The motor type (``"MAC140"``).
    address : int
        The unit address it is shown at.
    facts : FamilyFacts
        Its family's facts.
    family : Family
        Its family's record: the capabilities say which actions it offers.
    simulated : bool
        True for an in-process simulated motor.
    """

    simulated = False
    #: True while a long run (a tuning) has the motor to itself: the pages leave it alone
    paused = False

    def __init__(self, motor_type: str, address: int) -> None:
        self.motor_type = motor_type
        self.address = int(address)
        self.facts: FamilyFacts = facts_of(motor_type)
        self.family: Family = family_of_motor(motor_type)
        #: serialises access to the motor from the UI, the clock and long runs
        self.lock = threading.RLock()

    # ------------------------------------------------------------------ identity
    @property
    def label(self) -> str:
        """``"<type> @ <address>"``, unique within a studio."""
        return f"{self.motor_type} @ {self.address}"

    @property
    def table(self) -> Any:
        """The family's register table."""
        return self.facts.table

    def register(self, key: str | int) -> Register:
        """The register ``key`` (name or number) of the family's table."""
        return self.table.lookup(key)

    # ------------------------------------------------------------------ registers
    @abstractmethod
    def read_raw(self, key: str | int) -> int:
        """Stored integer of register ``key`` (a LongInt's whole value)."""

    def read_raws(self, numbers: Iterable[int]) -> dict[int, int]:
        """Stored integers of several registers, number → raw."""
        return {n: self.read_raw(n) for n in numbers}

    def read(self, key: str | int) -> float:
        """Value of register ``key`` in its unit."""
        reg = self.register(key)
        return float(from_raw(reg, self.read_raw(reg.number)))

    @abstractmethod
    def write(self, key: str | int, value: float) -> None:
        """Write register ``key`` in its unit; a refused value raises and changes nothing."""

    @abstractmethod
    def load_setup(self, registers: Mapping[str, float]) -> None:
        """Write a register set, validated as a whole before anything is written."""

    # ------------------------------------------------------------------ actions
    @abstractmethod
    def actions(self) -> dict[str, Callable[[], None]]:
        """The family's actions this motor offers: label → callable."""

    def passive(self) -> None:
        """Go to the family's passive mode (MODE_REG = 0: INIT_MODE of the MAC050–141,
        manual 3.2.2; passive of the MIS, §8.2.3)."""
        self.write(self.facts.mode_register, 0)

    def stop_motor(self) -> str:
        """Stop the motor the way its family's manual says, and say how (one line).

        A motor that is passive or in safe mode is left as it is. Otherwise MODE_REG gets the
        family's stop mode (:attr:`~jvl_gym.families.TwinSpec.stop_mode`: the MAC050–141's
        STOP_MODE, manual 4.1.8 and 4.4.12, and the MIS's mode 11 "Stop", §8.2.3, decelerate on
        the stop ramp and then go passive by themselves), or, where the family has none (the
        MAC800), its passive mode; a stop mode the motor refuses in its present state is
        followed by the passive mode.

        Returns
        -------
        str
            ``"<label>: <what was done>"``.
        """
        from ..registers import RegisterError

        twin = self.family.twin
        mode_register = self.facts.mode_register
        passive = twin.passive_mode if twin.passive_mode is not None else 0
        with self.lock:
            mode = self.read_raw(mode_register)
            if mode in (passive, twin.safe_mode):
                return f"{self.label}: already {self.facts.mode_name(mode)} ({mode})"
            target = twin.stop_mode if twin.stop_mode is not None else passive
            try:
                self.write(mode_register, target)
            except RegisterError:
                if target == passive:
                    raise
                target = passive
                self.write(mode_register, target)
        how = "ramp, then passive" if target != passive else "passive at once"
        return f"{self.label}: {self.facts.mode_name(target)} ({target}), {how}"

    def clear_errors(self) -> None:
        """Write 0 to every writable error bit register (MAC050–141 manual 3.2.35 ERR_STAT,
        MIS manual §8.2.31 ERR_BITS); status bits the firmware computes come back."""
        from .bits import status_registers

        for reg in status_registers(self.table):
            if reg.access.value == "rw" and "error" in reg.description.lower().split(":")[0]:
                self.write(reg.number, 0)

    # ------------------------------------------------------------------ time
    @abstractmethod
    def now(self) -> float:
        """The motor's time [s]: simulated time, or wall-clock time for a line motor."""

    def physical(self) -> dict[str, tuple[str, Callable[[], float]]]:
        """Physical signals of a simulated motor: label → (unit, reader); empty otherwise."""
        return {}

    @abstractmethod
    def sample_buffer(self) -> dict[str, np.ndarray]:
        """The motor's sample buffer in user units: channel name → samples."""


class SimMotor(StudioMotor):
    """One simulated motor: a one-motor :class:`~jvl_gym.MotorArray`, run by the session's
    real-time clock unless :attr:`paused` (a tuning run steps it itself).

    Parameters
    ----------
    motor_type : str
        Motor type, any family.
    address : int
        The address it is shown at.
    seed : int
        Noise seed.
    """

    simulated = True

    def __init__(self, motor_type: str, address: int, seed: int = 0) -> None:
        from .. import MotorArray

        self.array = MotorArray(motor_type, n=1, seed=seed)
        super().__init__(self.array.motor_configs[0].name, address)
        self.paused = False

    def read_raw(self, key: str | int) -> int:
        with self.lock:
            return int(self.array.read_raw(key)[0])

    def read_raws(self, numbers: Iterable[int]) -> dict[int, int]:
        with self.lock:
            return {n: int(self.array.read_raw(n)[0]) for n in numbers}

    def write(self, key: str | int, value: float) -> None:
        with self.lock:
            self.array.write(key, value)

    def load_setup(self, registers: Mapping[str, float]) -> None:
        with self.lock:
            self.array.load_setup(dict(registers))

    def step(self, n_outer: int) -> None:
        """Advance ``n_outer`` firmware samples."""
        with self.lock:
            self.array.step(n_outer)

    def now(self) -> float:
        return float(np.asarray(self.array.time).reshape(-1)[0])

    def actions(self) -> dict[str, Callable[[], None]]:
        """Passive, the :data:`ACTIONS` whose capability the family declares, clear errors."""
        out: dict[str, Callable[[], None]] = {"passive": self.passive}
        for label, (capability, operation) in ACTIONS.items():
            if self.family.supports(capability):
                out[label] = self._locked(operation)
        out["clear errors"] = self.clear_errors
        return out

    def _locked(self, operation: Callable[[Any], None]) -> Callable[[], None]:
        def run() -> None:
            with self.lock:
                operation(self.array)
        return run

    def sample_buffer(self) -> dict[str, np.ndarray]:
        with self.lock:
            buf = self.array.sample_buffer()
        return {k: np.asarray(v)[0] for k, v in buf.items()}

    def physical(self) -> dict[str, tuple[str, Callable[[], float]]]:
        """The :data:`PHYSICAL_SIGNALS` the family's array declares (its contract's
        ``array_class.PHYSICAL``): label → (unit, reader)."""
        declared = self.family.array_class.PHYSICAL
        out: dict[str, tuple[str, Callable[[], float]]] = {}
        for label, (attr, unit, columns) in PHYSICAL_SIGNALS.items():
            if attr not in declared:
                continue
            for k, suffix in enumerate(columns):
                out[label + suffix] = (unit, self._observable(attr, k))
        return out

    def _observable(self, attr: str, column: int) -> Callable[[], float]:
        def read() -> float:
            with self.lock:
                value = getattr(self.array, attr)  # a property the family declares
            return float(np.asarray(value, dtype=float).reshape(1, -1)[0, column])
        return read
