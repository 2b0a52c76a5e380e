"""Modbus RTU of the twin's motors (MIS manual §12): each motor of a 32-bit register family as a
Modbus slave.

:class:`MotorRegisters` is the :class:`~.server.RegisterAccess` of one motor of a twin
(:class:`~jvl_gym.protocol.serving.twin.MotorTwin`): register read and write by number through
the simulator (refusals are the
simulator's :class:`~jvl_gym.registers.RegisterError`, which the slave answers with an exception
reply, :func:`~.server.exception_code`), the slave address is the motor's MacTalk address
(MY_ADDR, MIS manual §12.1: "This address is the same as the MacTalk motor address"; its
default 254 is no valid Modbus address, so serve the motor at an address 1 … 247).
:func:`modbus_registers` finds the registers the slave itself uses (set-up, baud rate, time-out,
time-out response, frame delay; MIS manual §12.1) by name in the family's table, and
:func:`modbus_bus` puts all motors of a twin on one :class:`~.server.ModbusBus`.

Everything else (function codes 03h/10h only, the 2n and 40 000 + n windows with the low word
first, at most 16 words, whole registers only, broadcast, PDO1/PDO2, the time-out and its
action, the MacTalk → Modbus switch) is :mod:`.codec` and :mod:`.server`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

from ...families.capability import motors_of
from ...registers import RegisterError, UnknownRegisterError
from ...registers.table import is_signed
from ..serving.twin import MotorTwin
from .server import ModbusBus, ModbusRegisters

__all__ = ["MotorRegisters", "modbus_registers", "modbus_bus", "REGISTER_NAMES"]

#: the names of the registers :class:`~.server.ModbusRegisters` holds, in the 32-bit
#: families' tables (MIS manual §12.1 and §8.2: MODBUS_SETUP 121, BAUD_RATE 146, time-out 199,
#: time-out response 200, frame delay 201; the time-out actions write V_SOLL and MODE_REG)
REGISTER_NAMES = {"setup": "MODBUS_SETUP", "baud": "BAUD_RATE", "timeout": "MODBUS_TIMEOUT",
                  "timeout_action": "MODBUS_TIMEOUT_RESPONSE",
                  "frame_delay": "MODBUS_FRAME_DELAY", "max_velocity": "V_SOLL",
                  "mode": "MODE_REG"}


def modbus_registers(table: Any, passive_mode: int) -> ModbusRegisters:
    """The Modbus slave's registers of ``table`` by name (:data:`REGISTER_NAMES`; None where
    the table has none); ``passive_mode`` is the MODE_REG value of passive mode (the family's
    :attr:`~jvl_gym.families.TwinSpec.passive_mode`; MIS manual §8.2.3: 0)."""
    numbers: dict[str, int | None] = {}
    for field, name in REGISTER_NAMES.items():
        try:
            numbers[field] = table.lookup(name).number
        except RegisterError:
            numbers[field] = None
    return ModbusRegisters(**numbers, passive_mode=passive_mode)


class MotorRegisters:
    """Motor ``index`` of ``twin`` as a device of 32-bit registers (a
    :class:`~.server.RegisterAccess`).

    Parameters
    ----------
    twin : MotorTwin
        A twin of motors whose registers are 32 bits at one number.
    index : int
        The motor.
    """

    def __init__(self, twin: MotorTwin, index: int) -> None:
        _require_wide_registers(twin)
        self.twin = twin
        self.index = index

    @property
    def node_id(self) -> int:
        """The slave address: the motor's MacTalk address (MY_ADDR) now (MIS manual §12.1)."""
        return int(self.twin.m.read_raw(self.twin.reg.MYADDR)[self.index])

    def _register(self, number: int) -> Any:
        if number not in self.twin.m.table:
            raise UnknownRegisterError(f"no register {number}")
        return self.twin.m.table.lookup(number)

    def read(self, number: int) -> int:
        """Register ``number``'s value (a reserved one reads 0).

        Raises
        ------
        UnknownRegisterError
            The table has no such register.
        """
        self._register(number)
        with self.twin.lock:
            return self.twin.value(self.index, number)

    def write(self, number: int, value: int) -> None:
        """Write the 32-bit ``value`` (the two Modbus words, MIS manual §12.3) to register
        ``number``: as a signed number, or for an unsigned register (Word32) as the same 32
        bits unsigned.

        Raises
        ------
        RegisterError
            Unknown, read-only or reserved register, value out of range, or a mode that
            forbids it: nothing has changed.
        """
        self.write_many([(number, value)])

    def write_many(self, values: Sequence[tuple[int, int]]) -> None:
        """Write the 32-bit values ``(number, value)`` (in this order, each as by :meth:`write`)
        as one transaction through the twin's
        :meth:`~jvl_gym.protocol.serving.twin.MotorTwin.store`: all are checked before the first
        is stored, and a refusal changes nothing (registers, state, flash, flash file).

        Raises
        ------
        RegisterError
            As :meth:`write`, for any of them: nothing has changed.
        """
        raws: dict[int, int] = {}
        for number, value in values:
            reg = self._register(number)
            raws[number] = int(value) if is_signed(reg.format) else int(value) & 0xFFFFFFFF
        if len(raws) < len(values):
            raise RegisterError("a register written twice in one request")
        with self.twin.lock:
            self.twin.store(self.index, raws)


def _require_wide_registers(twin: MotorTwin) -> None:
    """ValueError unless the twin's registers are 32 bits wide at one number."""
    if not twin.m.table.wide_registers:
        raise ValueError("Modbus RTU serves motors of 32-bit registers at one number (MIS "
                         f"manual §12.3); {twin.family.title} registers are 16 bits wide")


def modbus_bus(twin: MotorTwin) -> ModbusBus:
    """All motors of ``twin`` as Modbus slaves on one line, with the family's Modbus registers
    (:func:`modbus_registers`)."""
    _require_wide_registers(twin)
    if twin.spec.passive_mode is None:
        raise ValueError(f"{motors_of(twin.family.title)} have no passive mode for the Modbus "
                         "time-out (MIS manual §12.1)")
    regs = modbus_registers(twin.m.table, twin.spec.passive_mode)
    return ModbusBus([MotorRegisters(twin, i) for i in range(twin.m.n)], regs)
