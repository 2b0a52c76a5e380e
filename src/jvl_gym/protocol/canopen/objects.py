"""The object dictionary of a motor's CANopen slave, built once from the register table, the
family's :class:`~jvl_gym.families.CanopenSpec` and the objects of MIS manual §11.4 and §11.5;
the slave serves it and the EDS file is written from it.

============  ==========================================================================
1000h–1018h   the communication objects of §11.4.1 (device type 0x40192, error register,
              error field, SYNC COB-ID, name "JVL A/S", versions, guard time, life time factor,
              store "save", restore "load", EMCY COB-ID, consumer and producer heartbeat,
              identity with vendor 117h)
1005h, 1006h  SYNC COB-ID and communication cycle period (§11.9.5)
1400h–1417h   receive PDOs 1–6 and 21–24: communication and mapping parameters, default
1600h–1617h   mappings of §11.4.9 (§11.4.13 in Beckhoff mode)
1800h–1817h   transmit PDOs 1–4 and 21–24, default mappings of §11.4.10 (§11.4.14)
1A00h–1A17h
2010h–2100h   the manufacturer objects of §11.4.6: command, module parameters, the registers
              1–254 as 32 bit (2012h) and 16 bit (2014h), fast command, registers 257–510
              (2018h, 201Ah), homing torque
6007h–67FFh   the DSP-402 objects of §11.5.1
============  ==========================================================================

Sub-index *n* of 2012h/2014h is register *n*; of 2018h/201Ah register 256 + *n* (§11.4.6:
"Motor parameters 257 – 510"). Every object's access, type and default is here; where a value
comes from (a register, the DSP-402 drive, the communication state) is the slave's.
"""

from __future__ import annotations

from typing import Any

from canopen import ObjectDictionary
from canopen.objectdictionary import ODArray, ODRecord, ODVariable
from canopen.objectdictionary import datatypes as dt

from ...registers.table import Access
from .facts import CanopenFacts
from .homing import HOMING_METHODS as _HOMING_METHODS

__all__ = ["build_dictionary", "RPDOS", "TPDOS", "DEFAULT_RPDO_MAP", "DEFAULT_TPDO_MAP",
           "BECKHOFF_RPDO_MAP", "BECKHOFF_TPDO_MAP", "REGISTER_OBJECTS", "STORABLE_402",
           "SAVE", "LOAD", "SUPPORTED_MODES", "HOMING_METHODS"]

#: receive and transmit PDO numbers (§11.4.9, §11.4.10)
RPDOS = (1, 2, 3, 4, 5, 6, 21, 22, 23, 24)
TPDOS = (1, 2, 3, 4, 21, 22, 23, 24)

#: default mappings: PDO number → (index, sub-index, bits) entries (§11.4.9)
DEFAULT_RPDO_MAP: dict[int, tuple[tuple[int, int, int], ...]] = {
    1: ((0x6040, 0, 16),),
    2: ((0x6040, 0, 16), (0x6060, 0, 8)),
    3: ((0x607A, 0, 32), (0x6081, 0, 32)),
    4: ((0x6083, 0, 32), (0x60FF, 0, 32)),
    5: ((0x60C1, 1, 32),),
    6: ((0x6087, 0, 32), (0x6071, 0, 16)),
    21: ((0x2012, 3, 32), (0x2014, 5, 16), (0x2014, 6, 16)),
    22: ((0x2014, 7, 16), (0x2014, 2, 16)),
    23: ((0x2014, 0x18, 16),),
    # §11.4.9 prints "2014 Sub19h" for "Updates the output": register 25 (19h) is STATUSBITS,
    # read-only; OUTPUTS is register 19 = 13h, as in the Beckhoff RPDO 4 of the same purpose
    # (§11.4.13). The decimal 19 is taken (docs/protocol.md, CANopen decisions).
    24: ((0x2014, 0x13, 16),),
}
#: default mappings of the transmit PDOs (§11.4.10)
DEFAULT_TPDO_MAP: dict[int, tuple[tuple[int, int, int], ...]] = {
    1: ((0x6064, 0, 32), (0x6041, 0, 16)),
    2: ((0x60FD, 0, 32), (0x6064, 0, 32)),
    3: ((0x6041, 0, 16), (0x6061, 0, 8)),
    4: ((0x6074, 0, 16), (0x6077, 0, 16), (0x606C, 0, 32)),
    21: ((0x2012, 0x0A, 32), (0x2014, 0x0C, 16), (0x2014, 0x23, 16)),
    22: ((0x2014, 0x0C, 16),),
    23: tuple((0x2014, 0x59 + k, 16) for k in range(4)),
    24: tuple((0x2014, 0x5D + k, 16) for k in range(4)),
}
#: Beckhoff mode: PDOs 1–4 carry these mappings and are enabled at power-on (§11.4.13–14)
BECKHOFF_RPDO_MAP = {1: DEFAULT_RPDO_MAP[21], 2: DEFAULT_RPDO_MAP[22],
                     3: DEFAULT_RPDO_MAP[23], 4: ((0x2014, 0x13, 16),)}
BECKHOFF_TPDO_MAP = {1: DEFAULT_TPDO_MAP[21], 2: DEFAULT_TPDO_MAP[23],
                     3: DEFAULT_TPDO_MAP[24],
                     4: ((0x2014, 0x0C, 16), (0x2014, 0x23, 16), (0x2014, 0xA1, 16))}

#: the register objects: index → (first register − 1, bits) (§11.4.6)
REGISTER_OBJECTS = {0x2012: (0, 32), 0x2014: (0, 16), 0x2018: (256, 32), 0x201A: (256, 16)}
#: DSP-402 objects stored by "save" (§11.5.1, column "Stored Flash")
STORABLE_402 = (0x6091, 0x6092, 0x6094, 0x6097)
#: the store and restore signatures "save" and "load" (§11.4.4–5)
SAVE, LOAD = 0x65766173, 0x64616F6C
#: modes of operation the drive carries out (§11.5.1), as bits of 6502h (DSP-402)
SUPPORTED_MODES = {1: 1 << 0, 3: 1 << 2, 4: 1 << 3, 6: 1 << 5, 7: 1 << 6, 8: 1 << 7,
                   9: 1 << 8, 10: 1 << 9}
#: the homing methods 6098h takes (:mod:`.homing`; docs/protocol.md: the decision)
HOMING_METHODS = _HOMING_METHODS


def _var(name: str, index: int, sub: int, dtype: int, access: str, default: Any = None,
         pdo: bool = False, lo: int | None = None, hi: int | None = None,
         relative: bool = False) -> ODVariable:
    v = ODVariable(name, index, sub)
    v.data_type = dtype
    v.access_type = access
    v.pdo_mappable = pdo
    v.min, v.max = lo, hi
    if default is not None:
        v.default = default
        if relative:
            v.relative = True
            v.default_raw = f"$NODEID+0x{default:X}"
        elif isinstance(default, int) and default < 0:
            v.default_raw = str(default)  # canopen's EDS export writes "0x-…" otherwise
    return v


def _record(od: ObjectDictionary, name: str, index: int, subs: list[ODVariable],
            array: bool = False) -> None:
    rec: Any = ODArray(name, index) if array else ODRecord(name, index)
    for v in subs:
        rec.add_member(v)
    od.add_object(rec)


def _add(od: ObjectDictionary, *args: Any, **kw: Any) -> None:
    od.add_object(_var(*args, **kw))


def _comm(od: ObjectDictionary, facts: CanopenFacts) -> None:
    """§11.4.1, §11.9.5."""
    u8, u16, u32 = dt.UNSIGNED8, dt.UNSIGNED16, dt.UNSIGNED32
    _add(od, "Device type", 0x1000, 0, u32, "ro", facts.device_type)
    _add(od, "Error register", 0x1001, 0, u8, "ro", 0)
    _record(od, "Pre-defined error field", 0x1003, [
        _var("Number of errors", 0x1003, 0, u8, "rw", 0),
        _var("Pre-defined error field 1", 0x1003, 1, u32, "ro", 0),
        _var("Pre-defined error field 2", 0x1003, 2, u32, "ro", 0)], array=True)
    _add(od, "COB-ID SYNC", 0x1005, 0, u32, "rw", 0x80)
    _add(od, "Communication cycle period", 0x1006, 0, u32, "rw", 0)
    _add(od, "Manufacturer device name", 0x1008, 0, dt.VISIBLE_STRING, "const",
         facts.device_name)
    _add(od, "Manufacturer hardware version", 0x1009, 0, dt.VISIBLE_STRING, "const", "1.0")
    _add(od, "Manufacturer software version", 0x100A, 0, dt.VISIBLE_STRING, "const", "3.0")
    _add(od, "Guard time", 0x100C, 0, u16, "rw", 0)
    _add(od, "Life time factor", 0x100D, 0, u8, "rw", 0)
    _record(od, "Store parameters", 0x1010, [
        _var("Number of entries", 0x1010, 0, u8, "ro", 1),
        _var("Save all parameters", 0x1010, 1, u32, "rw", 1)], array=True)
    _record(od, "Restore default parameters", 0x1011, [
        _var("Number of entries", 0x1011, 0, u8, "ro", 1),
        _var("Restore all default parameters", 0x1011, 1, u32, "rw", 1)], array=True)
    _add(od, "COB-ID EMCY", 0x1014, 0, u32, "rw", 0x80, relative=True)
    _record(od, "Consumer heartbeat time", 0x1016, [
        _var("Number of entries", 0x1016, 0, u8, "ro", 3),
        *(_var(f"Consumer heartbeat time {k}", 0x1016, k, u32, "rw", 0) for k in (1, 2, 3))],
        array=True)
    _add(od, "Producer heartbeat time", 0x1017, 0, u16, "rw", 0)
    _record(od, "Identity object", 0x1018, [
        _var("Number of entries", 0x1018, 0, u8, "ro", 4),
        _var("Vendor-ID", 0x1018, 1, u32, "ro", facts.vendor_id),
        _var("Product code", 0x1018, 2, u32, "ro", 0),
        _var("Revision number", 0x1018, 3, u32, "ro", 0),
        _var("Serial number", 0x1018, 4, u32, "ro", 0)])


def _pdo_cob(n: int, receive: bool) -> int:
    """Default COB-ID of PDO ``n`` without the node id: 1–4 of the predefined connection set
    (§11.4.13), the others disabled without an identifier (bit 31)."""
    if n <= 4:
        return 0x80000000 | ((0x200 if receive else 0x180) + 0x100 * (n - 1))
    return 0x80000000


def _pdos(od: ObjectDictionary) -> None:
    """§11.4.7–11.4.10."""
    u8, u16, u32 = dt.UNSIGNED8, dt.UNSIGNED16, dt.UNSIGNED32
    for n in RPDOS:
        c, m = 0x1400 + n - 1, 0x1600 + n - 1
        cob = _pdo_cob(n, True)
        _record(od, f"Receive PDO {n} communication parameter", c, [
            _var("Number of entries", c, 0, u8, "ro", 2),
            _var("COB-ID", c, 1, u32, "rw", cob, relative=n <= 4),
            _var("Transmission type", c, 2, u8, "rw", 255)])
        entries = DEFAULT_RPDO_MAP[n]
        _record(od, f"Receive PDO {n} mapping parameter", m, [
            _var("Number of entries", m, 0, u8, "rw", len(entries), lo=0, hi=8),
            *(_var(f"Mapped object {k}", m, k, u32, "rw",
                   (e[0] << 16 | e[1] << 8 | e[2]) if k <= len(entries) else 0)
              for k, e in ((k, entries[k - 1] if k <= len(entries) else (0, 0, 0))
                           for k in range(1, 9)))])
    for n in TPDOS:
        c, m = 0x1800 + n - 1, 0x1A00 + n - 1
        cob = _pdo_cob(n, False)
        _record(od, f"Transmit PDO {n} communication parameter", c, [
            _var("Number of entries", c, 0, u8, "ro", 5),
            _var("COB-ID", c, 1, u32, "rw", cob, relative=n <= 4),
            _var("Transmission type", c, 2, u8, "rw", 1),
            _var("Inhibit time", c, 3, u16, "rw", 0),
            _var("Compatibility entry", c, 4, u8, "rw", 0),
            _var("Event timer", c, 5, u16, "rw", 0)])
        entries = DEFAULT_TPDO_MAP[n]
        _record(od, f"Transmit PDO {n} mapping parameter", m, [
            _var("Number of entries", m, 0, u8, "rw", len(entries), lo=0, hi=8),
            *(_var(f"Mapped object {k}", m, k, u32, "rw",
                   (e[0] << 16 | e[1] << 8 | e[2]) if k <= len(entries) else 0)
              for k, e in ((k, entries[k - 1] if k <= len(entries) else (0, 0, 0))
                           for k in range(1, 9)))])


def _registers(od: ObjectDictionary, table: Any) -> None:
    """§11.4.6: registers 1–254 (2012h, 2014h) and 257–510 (2018h, 201Ah)."""
    u8, u16, u32 = dt.UNSIGNED8, dt.UNSIGNED16, dt.UNSIGNED32
    _record(od, "Execute command", 0x2010, [
        _var("Number of entries", 0x2010, 0, u8, "ro", 1),
        _var("Command", 0x2010, 1, u16, "rw", 0)])
    _record(od, "Module parameters", 0x2011, [
        _var("Number of entries", 0x2011, 0, u8, "ro", 17),
        *(_var({7: "Input setup", 8: "Setup", 17: "Error acknowledge DSP301"}.get(
            k, f"Reserved {k}"), 0x2011, k, u32, "rw", 0) for k in range(1, 18))])
    titles = {0x2012: "Motor parameters 1-254 (all 32-bit)",
              0x2014: "Motor parameters 1-254 (all 16-bit)",
              0x2018: "Motor parameters 257-510 (all 32-bit)",
              0x201A: "Motor parameters 257-510 (all 16-bit)"}
    for index, (base, bits) in REGISTER_OBJECTS.items():
        subs = [_var("Number of entries", index, 0, u8, "ro", 254)]
        for k in range(1, 255):
            number = base + k
            reg = table.lookup(number) if number in table else None
            name = reg.name if reg is not None else f"Register {number}"
            # the slave refuses a write to a read-only, reserved or absent register (0601 0002h)
            access = "rw" if reg is not None and reg.access == Access.RW else "ro"
            subs.append(_var(name, index, k, u32 if bits == 32 else u16, access, 0, pdo=True))
        _record(od, titles[index], index, subs)
    _record(od, "Execute fast command", 0x2013, [
        _var("Number of entries", 0x2013, 0, u8, "ro", 2),
        _var("Command", 0x2013, 1, u8, "rw", 0),
        _var("Sub command", 0x2013, 2, u8, "rw", 0)])
    _record(od, "Reserved", 0x2015, [
        _var("Number of entries", 0x2015, 0, u8, "ro", 3),
        *(_var(f"Reserved {k}", 0x2015, k, u32, "rw", 0) for k in (1, 2, 3))])
    _add(od, "Set homing torque", 0x2100, 0, u16, "rw", 1024, lo=0, hi=2047)


def _dsp402(od: ObjectDictionary, facts: CanopenFacts) -> None:
    """§11.5.1 (types, access and PDO columns; defaults §11.5.2–11.5.11)."""
    i8, i16, i32 = dt.INTEGER8, dt.INTEGER16, dt.INTEGER32
    u8, u16, u32, s = dt.UNSIGNED8, dt.UNSIGNED16, dt.UNSIGNED32, dt.VISIBLE_STRING
    _add(od, "Abort connection option code", 0x6007, 0, i16, "rw", 0)
    _add(od, "Error code", 0x603F, 0, u16, "ro", 0, pdo=True)
    _add(od, "Controlword", 0x6040, 0, u16, "rw", 0, pdo=True)
    _add(od, "Statusword", 0x6041, 0, u16, "ro", 0, pdo=True)
    _add(od, "Quick stop option code", 0x605A, 0, i16, "rw", 2, lo=0, hi=8)
    _add(od, "Modes of operation", 0x6060, 0, i8, "rw", 0, pdo=True)
    _add(od, "Modes of operation display", 0x6061, 0, i8, "ro", 0, pdo=True)
    _add(od, "Position actual value", 0x6064, 0, i32, "ro", 0, pdo=True)
    _add(od, "Position window", 0x6067, 0, u32, "rw", 100)
    _add(od, "Velocity sensor actual value", 0x6069, 0, i32, "ro", 0, pdo=True)
    _add(od, "Velocity demand value", 0x606B, 0, i32, "ro", 0, pdo=True)
    _add(od, "Velocity actual value", 0x606C, 0, i32, "ro", 0, pdo=True)
    _add(od, "Target torque", 0x6071, 0, u16, "rw", 0, pdo=True, lo=0, hi=1000)
    _add(od, "Max torque", 0x6072, 0, u16, "rw", 1000, pdo=True, lo=0, hi=1000)
    _add(od, "Torque demand value", 0x6074, 0, u16, "ro", 0, pdo=True)
    _add(od, "Torque actual value", 0x6077, 0, u16, "ro", 0, pdo=True)
    _add(od, "Target position", 0x607A, 0, i32, "rw", 0, pdo=True)
    _add(od, "Home offset", 0x607C, 0, i32, "rw", 0, pdo=True)
    _record(od, "Software position limit", 0x607D, [
        _var("Number of entries", 0x607D, 0, u8, "ro", 2),
        _var("Min position limit", 0x607D, 1, i32, "rw", -(2**31)),
        _var("Max position limit", 0x607D, 2, i32, "rw", 2**31 - 1)])
    _add(od, "Polarity", 0x607E, 0, u8, "rw", 0, pdo=True)
    _add(od, "Max motor speed", 0x6080, 0, u32, "rw", 300000, pdo=True, lo=0, hi=300000)
    _add(od, "Profile velocity", 0x6081, 0, u32, "rw", 10000, pdo=True, lo=1, hi=300000)
    _add(od, "Profile acceleration", 0x6083, 0, u32, "rw", 1000, pdo=True, lo=1, hi=500000)
    _add(od, "Profile deceleration", 0x6084, 0, u32, "rw", 0, pdo=True, lo=0, hi=500000)
    _add(od, "Quick stop deceleration", 0x6085, 0, u32, "rw", 5000, lo=1, hi=500000)
    _add(od, "Torque slope", 0x6087, 0, u32, "rw", 1000, pdo=True)
    _add(od, "Torque profile type", 0x6088, 0, i16, "rw", 0, lo=0, hi=0)
    _record(od, "Position encoder resolution", 0x608F, [
        _var("Number of entries", 0x608F, 0, u8, "ro", 2),
        _var("Encoder increments", 0x608F, 1, u32, "ro", facts.counts_per_rev),
        _var("Motor revolutions", 0x608F, 2, u32, "ro", 1)])
    for index, name, subs in (
            (0x6091, "Gear ratio", ("Motor revolutions", "Shaft revolutions")),
            (0x6092, "Feed constant", ("Feed", "Shaft revolutions")),
            (0x6094, "Velocity encoder factor", ("Numerator", "Divisor")),
            (0x6097, "Acceleration factor", ("Numerator", "Divisor"))):
        one = facts.counts_per_rev if index == 0x6092 else 1
        _record(od, name, index, [
            _var("Number of entries", index, 0, u8, "ro", 2),
            _var(subs[0], index, 1, u32, "rw", one, lo=1),
            _var(subs[1], index, 2, u32, "rw", 1, lo=1)])
    _add(od, "Homing method", 0x6098, 0, i8, "rw", 0)
    _record(od, "Homing speeds", 0x6099, [
        _var("Number of entries", 0x6099, 0, u8, "ro", 2),
        _var("Speed during search for switch", 0x6099, 1, i32, "rw", 5000, pdo=True,
             lo=1, hi=300000),
        _var("Speed during search for zero", 0x6099, 2, i32, "rw", 0, pdo=True,
             lo=0, hi=300000)])
    _add(od, "Homing acceleration", 0x609A, 0, i32, "rw", 1000, pdo=True, lo=1, hi=500000)
    _record(od, "Interpolation data record", 0x60C1, [
        _var("Number of entries", 0x60C1, 0, u8, "ro", 2),
        _var("IP data position", 0x60C1, 1, i32, "rw", 0, pdo=True),
        _var("IP data position type", 0x60C1, 2, u8, "rw", 0, lo=0, hi=1)])
    _record(od, "Interpolation time period", 0x60C2, [
        _var("Number of entries", 0x60C2, 0, u8, "ro", 2),
        _var("IP time period", 0x60C2, 1, u8, "rw", 10, lo=1, hi=20),
        _var("IP time index", 0x60C2, 2, i8, "rw", -3, lo=-3, hi=-3)])
    _add(od, "Digital inputs", 0x60FD, 0, u32, "ro", 0, pdo=True)
    _record(od, "Digital outputs", 0x60FE, [
        _var("Number of entries", 0x60FE, 0, u8, "ro", 2),
        _var("Physical outputs", 0x60FE, 1, u32, "rw", 0, pdo=True),
        _var("Bit mask", 0x60FE, 2, u32, "rw", 0, pdo=True)])
    _add(od, "Target velocity", 0x60FF, 0, i32, "rw", 0, pdo=True, lo=-300000, hi=300000)
    for index, name in ((0x6402, "Motor type"), (0x6403, "Motor catalogue number"),
                        (0x6404, "Motor manufacturer"), (0x6405, "http motor catalog address"),
                        (0x6503, "Drive catalogue number"), (0x6504, "Drive manufacturer"),
                        (0x6505, "http drive catalog address")):
        text = (facts.device_name if "manufacturer" in name
                else facts.motor_name if index == 0x6402 else "-")
        _add(od, name, index, 0, s, "const", text)
    _add(od, "Supported drive modes", 0x6502, 0, u32, "ro", sum(SUPPORTED_MODES.values()))
    _add(od, "Device type", 0x67FF, 0, u32, "ro", facts.device_type)


def build_dictionary(table: Any, facts: CanopenFacts) -> ObjectDictionary:
    """The object dictionary of a motor with register ``table`` and CANopen ``facts``
    (module docstring; the same for every node id: COB-IDs are relative to it)."""
    od = ObjectDictionary()
    _comm(od, facts)
    _pdos(od)
    _registers(od, table)
    _dsp402(od, facts)
    info = od.device_information
    info.vendor_name, info.vendor_number = facts.device_name, facts.vendor_id
    info.product_name = facts.product_name
    info.nr_of_RXPDO, info.nr_of_TXPDO = len(RPDOS), len(TPDOS)
    info.LSS_supported = True
    info.dynamic_channels_supported = False
    info.granularity = 8
    info.simple_boot_up_slave = True
    info.simple_boot_up_master = False
    info.allowed_baudrates = {10e3, 20e3, 50e3, 100e3, 125e3, 250e3, 500e3, 800e3, 1000e3}
    return od
