"""What the CANopen slave needs to know of a motor family, in one place.

The slave (:mod:`.slave`) reads and writes a motor only through the :class:`~jvl_gym.MotorArray`
register API; which registers, bits, modes and commands it uses is this record. A family says it
has the CANopen interface by naming ``"canopen"`` in ``FIELDBUSES`` of its public ``constants``
module; :func:`facts_of` then gives its :class:`CanopenFacts`, with every register looked up by
name in the motors' register table. The values are those of the MIS/SMC manual, the one family
with a CANopen interface; when the family contract declares them, :func:`facts_of` reads them
from there instead.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass, replace
from typing import Any, ClassVar

from ...registers import RegisterError

__all__ = ["CanopenFacts", "FIELDBUS", "facts_of", "has_canopen"]

#: the name a family lists in ``constants.FIELDBUSES`` when its motors have a CANopen slave
FIELDBUS = "canopen"


@dataclass(frozen=True)
class CanopenFacts:
    """The registers, bits, modes and identity a CANopen slave of a motor uses.

    Register attributes hold register *numbers* (looked up by name in the table by
    :func:`facts_of`; the defaults are the names). Citations: MIS manual.

    Attributes
    ----------
    node_id, baud : int
        Node id (1 … 127, default 5) and bit-rate code registers (§11.2.4, §8.2.98–99).
    mode, p_soll, v_soll, a_soll, d_soll, p_ist, v_ist, flwerr, flwerrmax : int
        MODE_REG and the profile registers (§8.2.3–8.2.19, D_SOLL §8.2.1).
    err_bits, statusbits, command, inputs, outputs, setup_bits : int
        Error bits (§8.2.31), status bits (§8.2.24), the command register (§8.2.20), the
        digital inputs and outputs (§8.2.16–17), SETUP_BITS (§8.2.68).
    run_current, home_mask, nl_mask, pl_mask, v_home, v_home_crawl, p_home, t_home : int
        Running current (§8.2.7) and the zero search registers (§8.2.34–37, §8.2.72–74,
        §8.2.125).
    motor_type, serial, version, hardware : int
        Identity registers (§8.2.89–92, §8.2.2).
    passive, velocity, position, zero_search_1, zero_search_2 : int
        MODE_REG values (§8.2.3).
    st_in_position, st_at_velocity, st_zero_search_done : int
        STATUSBITS masks (§8.2.24).
    err_general, err_follow, err_low_bus, err_position, err_zero_search_timeout : int
        ERR_BITS masks (§8.2.31).
    cmd_clear_errors, cmd_save : int
        Commands: clear errors (97, §8.2.21), save to flash and continue (269, §8.2.22; a
        passive motor only).
    beckhoff_bit : int
        SETUP_BITS bit 14 "UseBeckhoff" (§8.2.68, §11.4.11).
    counts_per_rev : int
        Position counts per revolution (409 600, §8.2.4): object 608Fh.
    vendor_id, device_type : int
        0x117, JVL's vendor id, and 0x40192 (§11.4.1).
    device_name : str
        Object 1008h (§11.4.1: "JVL A/S").
    """

    node_id: Any = "FBUS_NODE_ID"
    baud: Any = "FBUS_BAUD"
    mode: Any = "MODE_REG"
    p_soll: Any = "P_SOLL"
    v_soll: Any = "V_SOLL"
    a_soll: Any = "A_SOLL"
    d_soll: Any = "D_SOLL"
    p_ist: Any = "P_IST"
    v_ist: Any = "V_IST"
    flwerr: Any = "FLWERR"
    flwerrmax: Any = "FLWERRMAX"
    err_bits: Any = "ERR_BITS"
    statusbits: Any = "STATUSBITS"
    command: Any = "COMMAND"
    inputs: Any = "INPUTS"
    outputs: Any = "OUTPUTS"
    setup_bits: Any = "SETUP_BITS"
    run_current: Any = "RUN_CURRENT"
    home_mask: Any = "HOME_MASK"
    nl_mask: Any = "NL_MASK"
    pl_mask: Any = "PL_MASK"
    v_home: Any = "V_HOME"
    v_home_crawl: Any = "V_HOME_CRAWL"
    p_home: Any = "P_HOME"
    t_home: Any = "T_HOME"
    motor_type: Any = "MOTORTYPE"
    serial: Any = "SERIAL_NUMBER"
    version: Any = "PROG_VERSION"
    hardware: Any = "HARDWARE_REV"
    passive: int = 0
    velocity: int = 1
    position: int = 2
    zero_search_1: int = 13
    zero_search_2: int = 14
    st_in_position: int = 1 << 4
    st_at_velocity: int = 1 << 3
    st_zero_search_done: int = 1 << 7
    err_general: int = 1 << 0
    err_follow: int = 1 << 1
    err_low_bus: int = 1 << 4
    err_position: int = 1 << 3
    err_zero_search_timeout: int = 1 << 16
    cmd_clear_errors: int = 97
    cmd_save: int = 269
    beckhoff_bit: int = 1 << 14
    counts_per_rev: int = 409600
    vendor_id: int = 0x117
    device_type: int = 0x40192
    device_name: str = "JVL A/S"
    #: the attributes that name registers
    REGISTER_FIELDS: ClassVar[tuple[str, ...]] = (
        "node_id", "baud", "mode", "p_soll", "v_soll", "a_soll", "d_soll", "p_ist", "v_ist",
        "flwerr", "flwerrmax", "err_bits", "statusbits", "command", "inputs", "outputs",
        "setup_bits", "run_current", "home_mask", "nl_mask", "pl_mask", "v_home",
        "v_home_crawl", "p_home", "t_home", "motor_type", "serial", "version", "hardware")

    def numbered(self, table: Any) -> CanopenFacts:
        """This record with every register name replaced by its number in ``table``.

        Raises
        ------
        ValueError
            The table lacks a register the slave needs (naming it).
        """
        numbers = {}
        for name in self.REGISTER_FIELDS:
            key = getattr(self, name)
            try:
                numbers[name] = table.lookup(key).number
            except RegisterError:
                raise ValueError(f"the motors' register table has no {key} register, which "
                                 "the CANopen slave needs") from None
        return replace(self, **numbers)


def _constants(motors: Any) -> Any:
    package = type(motors).__module__.rpartition(".")[0]
    try:
        return importlib.import_module(f"{package}.constants") if package else None
    except ModuleNotFoundError:
        return None


def has_canopen(motors: Any) -> bool:
    """Whether ``motors``' family declares a CANopen interface (``FIELDBUSES`` in its public
    ``constants`` module names :data:`FIELDBUS`)."""
    return FIELDBUS in tuple(getattr(_constants(motors), "FIELDBUSES", ()))


def facts_of(motors: Any) -> CanopenFacts:
    """The CANopen facts of ``motors`` (a :class:`~jvl_gym.MotorArray`), registers by number.

    Raises
    ------
    ValueError
        The family declares no CANopen interface, or its table lacks a register the slave
        uses (one line).
    """
    if not has_canopen(motors):
        title = getattr(getattr(motors, "family", None), "title", type(motors).__name__)
        raise ValueError(f"the {title} have no CANopen interface (only families that list "
                         f"{FIELDBUS!r} in FIELDBUSES do)")
    return CanopenFacts().numbered(motors.table)
