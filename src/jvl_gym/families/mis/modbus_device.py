"""One motor of a :class:`~.motors.MisMotorArray` as a device of 32-bit registers, for the
Modbus RTU slave of :mod:`jvl_gym.protocol.modbus_server` (MIS manual §12).

The slave address is MY_ADDR (register 150, §12.1); a read returns the stored value; a write
goes through the array's validated register writes (range, access, the firmware's rules), so a
refused write raises a :class:`~jvl_gym.registers.RegisterError` and changes nothing. Modbus
carries signed 32-bit values; an unsigned (Word32) register takes their low 32 bits.
"""

from __future__ import annotations

from typing import Any

from ...registers import Format
from . import regs as R

__all__ = ["MisModbusDevice"]


class MisModbusDevice:
    """Motor ``index`` of ``array`` as a Modbus register device (module docstring)."""

    def __init__(self, array: Any, index: int) -> None:
        self.array = array
        self.index = int(index)

    @property
    def node_id(self) -> int:
        """The slave address: MY_ADDR (register 150)."""
        return int(self.array.regs[self.index, R.MY_ADDR])

    def read(self, number: int) -> int:
        """The stored value of register ``number`` (unknown numbers raise)."""
        return int(self.array.read_raw(int(number))[self.index])

    def write(self, number: int, value: int) -> None:
        """Write ``value`` (signed 32-bit) to register ``number`` through the array's rules."""
        reg = self.array.table.lookup(int(number))
        if reg.format == Format.WORD32:
            value = int(value) & 0xFFFFFFFF
        self.array.write_raw(reg.number, int(value), index=self.index)
