"""The CANopen slave of one motor (MIS manual §11): its object values, where each object's value
comes from, and what each received frame does.

A :class:`CanopenSlave` serves motor ``index`` of a :class:`~jvl_gym.MotorArray` with the
dictionary of :func:`~.objects.build_dictionary`, through the motor array's register API only
(``read_raw``, ``write_raw``, ``software_reset``/``reset``, ``flash_image``,
``load_flash_image``) and the facts of :mod:`.facts`. It sends frames through ``send(cob_id,
data, remote)``; the server (:mod:`.server`) feeds it the frames of the bus and its time
(:meth:`CanopenSlave.tick`, once per simulated millisecond).

Where each object's value comes from:

* 2012h/2014h/2018h/201Ah: the registers (§11.4.6). A 32-bit write is the register's 32 bits
  (signed unless the register is unsigned); a 16-bit write is "treated as signed" (§11.4.6),
  a read is the low 16 bits. A register the table does not have, or a reserved one, reads 0
  and refuses writes, as over MacTalk. The motor's refusals are aborts: read-only 0601 0002h,
  out of range 0609 0030h, refused in the motor's present mode 0800 0022h.
* 2010h sub 1 and 2013h sub 1: the command register (§8.2.20); 2100h: the zero search torque
  T_HOME (§11.5.6, 0 … 2047); 1018h sub 2–4: motor type, firmware version, serial number.
* 6040h/6041h/6060h/6061h and the actual values: the DSP-402 drive (:mod:`.dsp402`); 6064h,
  606Ch, 6069h, 606Bh: P_IST, V_IST, V_IST and V_SOLL through the factors; 60FDh: bit 0
  negative limit, 1 positive limit, 2 home switch, 16–23 the inputs IO1–8; 60FEh sub 1: bits
  16–23 the outputs (written where sub 2, the bit mask, has ones).
* everything else: the node's own values, set to the dictionary's defaults at power-on (the
  communication objects 1000h–1FFFh also at reset communication).

**Store and restore** (§11.4.4–5): 1010h sub 1 := "save" (65766173h) stores the motor's
registers in its flash with the motor's own command (save to flash, §8.2.22, which a motor in an
active mode refuses: abort 0800 0022h) and keeps the storable DSP-402 objects (6091h, 6092h,
6094h, 6097h) in the node's non-volatile memory; ``on_store`` (the twin's flash file) is then
called, and a file it cannot write aborts the save with 0800 0020h (the motor's flash keeps
its previous image). 1011h sub 1 := "load" (64616F6Ch) sets the DSP-402 objects to their
factory defaults without storing them. Any other value: abort 0800 0020h.

**Reset node** (NMT 129) resets the motor (registers from its flash, its power-on) and every
object; **reset communication** (130) the objects 1000h–1FFFh; both re-read the node id from
its register, send the boot-up message and enter pre-operational. SETUP_BITS bit 14 read then
selects Beckhoff mode (§11.4.11–14): PDOs 1–4 with the Beckhoff mappings, enabled.
"""

from __future__ import annotations

import logging
from collections import Counter
from collections.abc import Callable
from typing import Any

import numpy as np
from canopen.objectdictionary import ObjectDictionary
from canopen.objectdictionary import datatypes as dt
from canopen.sdo import SdoAbortedError

from ...registers import ReadOnlyRegisterError, RegisterError, RegisterRangeError
from ...registers.table import Access, Format
from . import emcy as em
from .dsp402 import Drive
from .facts import CanopenFacts
from .lss import LssSlave
from .nmt import BOOTUP_COB, Guarding, Heartbeat, NmtCommand, NmtState
from .objects import (
    BECKHOFF_RPDO_MAP,
    BECKHOFF_TPDO_MAP,
    LOAD,
    REGISTER_OBJECTS,
    SAVE,
    STORABLE_402,
)
from .pdo import Pdos, comm_index, map_index, pdo_of
from .sdo import ABORT, NodeSdoServer

__all__ = ["CanopenSlave", "Send"]

log = logging.getLogger(__name__)

#: sends one frame: (COB-ID, data, remote request)
Send = Callable[[int, bytes, bool], None]


def _s(value: int, bits: int) -> int:
    value &= (1 << bits) - 1
    return value - (1 << bits) if value >> (bits - 1) else value


class CanopenSlave:
    """The CANopen slave of motor ``index`` of ``motors``.

    Parameters
    ----------
    motors : MotorArray
        The motors (their family declares a CANopen interface, :func:`~.facts.facts_of`).
    index : int
        The motor this slave serves.
    od : canopen.ObjectDictionary
        The dictionary it serves (:func:`~.objects.build_dictionary`).
    facts : CanopenFacts
        Registers by number, bits, modes (:func:`~.facts.facts_of`).
    send : callable
        ``send(cob_id, data, remote)`` puts a frame on the bus.
    node_id : int, optional
        Node id 1 … 127 to give the motor now (written to its node-id register and flash);
        default: the register's value.
    on_store : callable, optional
        Called with the motor's flash image before the save after a successful "save" (the
        twin writes its flash file); a ValueError it raises aborts the save (0800 0020h).

    Attributes
    ----------
    node_id : int
        The node id in use (from the register at the last reset).
    nmt : NmtState
        Communication state.
    now_ms : int
        The node's simulated time [ms].
    stats : collections.Counter
        Frames received and sent by kind, refusals.
    """

    def __init__(self, motors: Any, index: int, od: ObjectDictionary, facts: CanopenFacts,
                 send: Send, node_id: int | None = None,
                 on_store: Callable[[dict[int, int]], None] | None = None) -> None:
        self.m = motors
        self.i = index
        self.object_dictionary = od
        self.facts = facts
        self._send = send
        self.on_store = on_store
        self.stats: Counter[str] = Counter()
        self.last_refusal = ""
        self.now_ms = 0
        self.values: dict[tuple[int, int], Any] = {}
        self.stored: dict[tuple[int, int], Any] = {}
        self.heartbeat = Heartbeat()
        self.guarding = Guarding()
        self.emcy = em.Emcy()
        self.pdos = Pdos(self)
        self.drive = Drive(self)
        self.lss = LssSlave(self)
        self.nmt = NmtState.INITIALISING
        self.node_id = 0
        self.sdo: NodeSdoServer | None = None
        if node_id is not None:
            self.set_node_id(node_id)
        self._defaults(lambda index: True)

    # ------------------------------------------------------------------ frames out
    def send(self, cob: int, data: bytes, remote: bool = False) -> None:
        """Put one frame on the bus."""
        self._send(cob, bytes(data), remote)

    def send_message(self, cob: int, data: bytes) -> None:
        """The SDO server's way out (the ``canopen`` network interface)."""
        self.stats["SDO"] += 1
        self.send(cob, data)

    def refuse(self, why: str) -> None:
        self.last_refusal = why
        self.stats["refused"] += 1
        log.info("node %d refused: %s", self.node_id, why)

    # ------------------------------------------------------------------ life cycle
    @property
    def operational(self) -> bool:
        return self.nmt == NmtState.OPERATIONAL

    def set_node_id(self, node_id: int) -> None:
        """Give the motor node id ``node_id``: its register and its flash (kept over resets)."""
        if not 1 <= int(node_id) <= 127:
            raise ValueError(f"a CANopen node id is 1..127 (MIS manual §11.1.5), got {node_id}")
        self.reg_write(self.facts.node_id, int(node_id), sdo=False)
        image = dict(self.m.flash_image(self.i))
        image[self.facts.node_id] = int(node_id)
        if len(image) == 1:  # no flash yet: it holds the registers as they are now
            image = self.register_image() | image
        self.m.load_flash_image(self.i, image)

    def register_image(self) -> dict[int, int]:
        """The registers flash holds, as they are now (read-write, not MODE_REG)."""
        return {r.number: self.reg_read(r.number) for r in self.m.table
                if r.access == Access.RW and r.number != self.facts.mode
                and r.format != Format.LONGINT_HIGH}

    def _defaults(self, which: Callable[[int], bool]) -> None:
        for index in self.object_dictionary:
            if not which(index):
                continue
            obj = self.object_dictionary[index]
            for var in ([obj] if hasattr(obj, "data_type") else obj.values()):
                self.values[(index, var.subindex)] = var.default
        for key, value in self.stored.items():
            if which(key[0]):
                self.values[key] = value

    def boot(self) -> None:
        """Initialisation → pre-operational: node id from its register, Beckhoff mode, the
        SDO server, the boot-up message (§11.9.2)."""
        self.nmt = NmtState.INITIALISING
        self.node_id = self.lss.pending or self.reg_read(self.facts.node_id)
        self.lss.pending = None
        nid = self.node_id
        for (index, sub), var in self._relative():
            self.values[(index, sub)] = var.default + nid
        if self.reg_read(self.facts.setup_bits) & self.facts.beckhoff_bit:
            self._beckhoff()
        self.sdo = NodeSdoServer(0x600 + nid, 0x580 + nid, self)
        self.sdo.network = self
        self.guarding.reset()
        self.pdos.reset()
        self.heartbeat.configure(0, self.now_ms)
        self.emcy.last_err = self.reg_read(self.facts.err_bits)
        self.send(BOOTUP_COB + nid, b"\x00")
        self.stats["boot-up"] += 1
        self.nmt = NmtState.PRE_OPERATIONAL
        self.heartbeat.configure(int(self.values[(0x1017, 0)]), self.now_ms)

    def _relative(self) -> list[tuple[tuple[int, int], Any]]:
        out = []
        for index in self.object_dictionary:
            obj = self.object_dictionary[index]
            for var in ([obj] if hasattr(obj, "data_type") else obj.values()):
                if var.relative:
                    out.append(((index, var.subindex), var))
        return out

    def _beckhoff(self) -> None:
        for receive, maps in ((True, BECKHOFF_RPDO_MAP), (False, BECKHOFF_TPDO_MAP)):
            for n, entries in maps.items():
                m = map_index(n, receive)
                self.values[(m, 0)] = len(entries)
                for k in range(1, 9):
                    e = entries[k - 1] if k <= len(entries) else (0, 0, 0)
                    self.values[(m, k)] = e[0] << 16 | e[1] << 8 | e[2]
                c = comm_index(n, receive)
                self.values[(c, 1)] = int(self.values[(c, 1)]) & 0x7FFFFFFF
                self.values[(c, 2)] = 255

    def reset_node(self) -> None:
        """NMT reset node: the motor restarts from its flash, every object from its default."""
        reset = getattr(self.m, "software_reset", None) or self.m.reset
        reset(self.i)
        self._defaults(lambda index: True)
        self.drive.power_on()
        self.emcy = em.Emcy()
        self.boot()

    def reset_communication(self) -> None:
        """NMT reset communication: the objects 1000h–1FFFh from their defaults."""
        self._defaults(lambda index: index < 0x2000)
        self.emcy.clear()
        self.boot()

    # ------------------------------------------------------------------ registers
    def reg_read(self, number: int) -> int:
        """Register ``number`` of the motor (0 where the table has none or it is reserved)."""
        t = self.m.table
        if number not in t or t.lookup(number).access == Access.RESERVED:
            return 0
        return int(self.m.read_raw(number)[self.i])

    def reg_write(self, number: int, value: int, sdo: bool = True) -> None:
        """Write register ``number``; the motor's refusal as an SDO abort (nothing changed). A
        write of the motor's command register that saves its flash (§8.2.22) writes the flash
        file too (``on_store``), and aborts 0800 0020h if the file cannot be written."""
        t = self.m.table
        if number not in t or t.lookup(number).access == Access.RESERVED:
            raise SdoAbortedError(ABORT["read_only"])
        before = (self.m.flash_image(self.i)
                  if self.on_store is not None and number == self.facts.command else None)
        self._write_register(number, value)
        if before is not None and self.m.flash_image(self.i) != before:
            self._save_file(before)

    def _save_file(self, before: dict[int, int]) -> None:
        """The motor's flash to its file (``on_store``); abort 0800 0020h if it fails."""
        if self.on_store is None:
            return
        try:
            self.on_store(before)
        except ValueError as exc:
            self.refuse(str(exc))
            raise SdoAbortedError(ABORT["store"]) from None

    def _write_register(self, number: int, value: int) -> None:
        """Write register ``number`` as the motor does; its refusal as an SDO abort."""
        try:
            self.m.write_raw(number, np.int64(value), index=self.i)
        except ReadOnlyRegisterError as exc:
            self.refuse(str(exc))
            raise SdoAbortedError(ABORT["read_only"]) from None
        except RegisterRangeError as exc:
            self.refuse(str(exc))
            raise SdoAbortedError(ABORT["range"]) from None
        except (RegisterError, ValueError) as exc:
            self.refuse(str(exc))
            raise SdoAbortedError(ABORT["state"]) from None

    def _register_object(self, index: int, sub: int) -> tuple[int, int] | None:
        spec = REGISTER_OBJECTS.get(index)
        if spec is None or sub == 0:
            return None
        return spec[0] + sub, spec[1]

    # ------------------------------------------------------------------ object values
    def value(self, index: int, sub: int = 0) -> Any:
        """The node's own value of an object (not the live ones)."""
        return self.values[(index, sub)]

    def _find(self, index: int, sub: int) -> Any:
        od = self.object_dictionary
        if index not in od:
            raise SdoAbortedError(ABORT["no_object"])
        obj = od[index]
        if hasattr(obj, "data_type"):
            if sub:
                raise SdoAbortedError(ABORT["no_sub"])
            return obj
        if sub not in obj.subindices:  # (an ODArray makes up any other sub-index)
            raise SdoAbortedError(ABORT["no_sub"])
        return obj[sub]

    def read_value(self, index: int, sub: int) -> Any:
        """The value of object ``index``/``sub`` now."""
        f = self.facts
        reg = self._register_object(index, sub)
        if reg is not None:
            return self.reg_read(reg[0]) & ((1 << reg[1]) - 1)
        if index == 0x1001:
            return self.emcy.register(self.reg_read(f.err_bits), f.err_follow, f.err_low_bus,
                                      f.err_position)
        if index == 0x1003:
            h = self.emcy.history
            return len(h) if sub == 0 else (h[sub - 1] if sub <= len(h) else 0)
        if index == 0x1018 and sub >= 2:
            return self.reg_read((0, 0, f.motor_type, f.version, f.serial)[sub]) & 0xFFFFFFFF
        if index in (0x2010, 0x2013) and sub == 1:
            return self.reg_read(f.command) & (0xFFFF if index == 0x2010 else 0xFF)
        if index == 0x2100:
            return self.reg_read(f.t_home)
        d = self.drive
        live = {0x6040: lambda: d.controlword, 0x6041: d.statusword, 0x6061: lambda: d.mode,
                0x6064: lambda: d.user_position(self.reg_read(f.p_ist)),
                0x606C: lambda: d.user_velocity(self.reg_read(f.v_ist)),
                0x6069: lambda: d.user_velocity(self.reg_read(f.v_ist)),
                0x606B: lambda: d.user_velocity(self.reg_read(f.v_soll)),
                0x6074: d.torque_demand, 0x6077: d.torque_demand, 0x60FD: self._inputs}
        if index in live:
            return live[index]()
        if index == 0x60FE and sub == 1:
            return (self.reg_read(f.outputs) & 0xFF) << 16
        return self.values[(index, sub)]

    def _inputs(self) -> int:
        f = self.facts
        ins = self.reg_read(f.inputs)
        bits = [bool(ins & self.reg_read(f.nl_mask)), bool(ins & self.reg_read(f.pl_mask)),
                bool(ins & self.reg_read(f.home_mask))]
        return sum(b << k for k, b in enumerate(bits)) | (ins & 0xFF) << 16

    def write_value(self, index: int, sub: int, value: Any) -> None:
        """Write ``value`` (decoded, in range) to object ``index``/``sub``; abort if refused."""
        f = self.facts
        key = (index, sub)
        reg = self._register_object(index, sub)
        if reg is not None:
            number, bits = reg
            if bits == 16:
                raw = _s(value, 16)
            else:
                r = self.m.table.lookup(number) if number in self.m.table else None
                raw = value if r is not None and r.format == Format.WORD32 else _s(value, 32)
            self.reg_write(number, raw)
            return
        pdo = pdo_of(index)
        if pdo is not None:
            self.pdos.check_write(index, sub, value)
            self.values[key] = value
            self.pdos.changed(index, sub)
            return
        if index == 0x1003:
            if value:
                raise SdoAbortedError(ABORT["range"])
            self.emcy.clear()
            self.reg_write(f.command, f.cmd_clear_errors)
        elif index == 0x1005:
            if value & 0x7FFFF800:
                raise SdoAbortedError(ABORT["range"])  # no SYNC producer, 11-bit only
            self.values[key] = value
        elif index == 0x1014:
            if value & 0x3FFFF800 or not value & 0x7FF:
                raise SdoAbortedError(ABORT["range"])
            self.values[key] = value
        elif index == 0x1010:
            if value != SAVE:
                raise SdoAbortedError(ABORT["store"])
            self.store()
        elif index == 0x1011:
            if value != LOAD:
                raise SdoAbortedError(ABORT["store"])
            self._defaults(lambda i: 0x6000 <= i < 0xA000 and i not in (0x6040, 0x6060))
            for k in [k for k in self.values if k[0] in STORABLE_402]:
                self.values[k] = self._find(*k).default
        elif index == 0x1017:
            self.values[key] = value
            self.heartbeat.configure(value, self.now_ms)
        elif index in (0x2010, 0x2013) and sub == 1:
            if index == 0x2013 and value > 127:
                raise SdoAbortedError(ABORT["range"])
            self.reg_write(f.command, value)
        elif index == 0x2011 and sub == 17:
            if value:
                self.reg_write(f.command, f.cmd_clear_errors)
            self.values[key] = value
        elif index == 0x2100:
            self.reg_write(f.t_home, value)
        elif index == 0x6040:
            self.drive.write_controlword(value)
        elif index == 0x6060:
            self.drive.write_mode(value)
        elif index == 0x6098:
            self.drive.write_homing_method(value)
            self.values[key] = value
        elif index == 0x60FE and sub == 1:
            mask = (int(self.values[(0x60FE, 2)]) >> 16) & 0xFF
            old = self.reg_read(f.outputs)
            self.reg_write(f.outputs, (old & ~mask) | ((value >> 16) & mask))
        else:
            self.values[key] = value
            if index == 0x607A:
                self.drive.write_target_position(_s(value, 32))
            elif index == 0x60FF:
                self.drive.write_target_velocity(value)

    def store(self) -> None:
        """1010h "save": the motor's registers to its flash, the storable DSP-402 objects kept
        (§11.4.5); abort 0800 0022h if the motor refuses (not passive), 0800 0020h if its flash
        file cannot be written (``on_store``; the motor's flash then keeps its previous
        image)."""
        before = self.m.flash_image(self.i)
        self.reg_write(self.facts.command, self.facts.cmd_save)  # a changed flash: its file
        if self.m.flash_image(self.i) == before:
            self._save_file(before)  # unchanged: the file is written all the same
        self.stored = {k: v for k, v in self.values.items() if k[0] in STORABLE_402}

    # ------------------------------------------------------------------ the canopen node
    def get_data(self, index: int, subindex: int, check_readable: bool = False) -> bytes:
        """Encoded value of an object (the SDO server's upload)."""
        obj = self._find(index, subindex)
        if check_readable and not obj.readable:
            raise SdoAbortedError(ABORT["write_only"])
        value = self.read_value(index, subindex)
        if obj.data_type in dt.SIGNED_TYPES:
            value = _s(int(value), len(obj))
        return obj.encode_raw(value)

    def check_download(self, index: int, subindex: int) -> None:
        """Abort a download to an object that does not exist or cannot be written."""
        if not self._find(index, subindex).writable:
            raise SdoAbortedError(ABORT["read_only"])

    def set_data(self, index: int, subindex: int, data: bytes,
                 check_writable: bool = False) -> None:
        """Decode, check and write ``data`` to an object (the SDO server's download)."""
        obj = self._find(index, subindex)
        if check_writable and not obj.writable:
            raise SdoAbortedError(ABORT["read_only"])
        if obj.data_type in dt.NUMBER_TYPES:
            if 8 * len(data) > len(obj):
                raise SdoAbortedError(ABORT["too_long"])
            if 8 * len(data) < len(obj):
                raise SdoAbortedError(ABORT["too_short"])
        elif obj.data_type == dt.VISIBLE_STRING:
            raise SdoAbortedError(ABORT["read_only"])
        self._checked_write(obj, obj.decode_raw(bytes(data)))

    def _checked_write(self, obj: Any, value: Any) -> None:
        if obj.min is not None and value < obj.min:
            raise SdoAbortedError(ABORT["too_low"])
        if obj.max is not None and value > obj.max:
            raise SdoAbortedError(ABORT["too_high"])
        self.write_value(obj.index, obj.subindex, value)
        self.stats["writes"] += 1

    def pdo_read(self, index: int, sub: int) -> int:
        """Raw value of a mapped object for a transmit PDO."""
        return int(self.read_value(index, sub))

    def pdo_write(self, index: int, sub: int, raw: int) -> None:
        """A mapped object's ``raw`` bits from a receive PDO, checked like an SDO write."""
        obj = self._find(index, sub)
        value = _s(raw, len(obj)) if obj.data_type in dt.SIGNED_TYPES else raw
        self._checked_write(obj, value)

    # ------------------------------------------------------------------ frames in
    def emergency(self, code: int) -> None:
        """A communication or profile error event: EMCY ``code``."""
        self.emcy.event(code)
        self._emcy(code)

    def _emcy(self, code: int) -> None:
        cob = int(self.values[(0x1014, 0)])
        if cob & (1 << 31) or self.nmt not in (NmtState.PRE_OPERATIONAL,
                                               NmtState.OPERATIONAL):
            return
        err = self.reg_read(self.facts.err_bits)
        self.send(cob & 0x7FF, self.emcy.frame(code, int(self.read_value(0x1001, 0)), err))
        self.stats["EMCY"] += 1

    def on_nmt(self, data: bytes) -> None:
        """An NMT command (§11.9.6); other lengths and other nodes' commands are ignored."""
        if len(data) != 2 or data[1] not in (0, self.node_id):
            return
        self.stats["NMT"] += 1
        cs = data[0]
        if cs == NmtCommand.START:
            self.nmt = NmtState.OPERATIONAL
        elif cs == NmtCommand.STOP:
            self.nmt = NmtState.STOPPED
        elif cs == NmtCommand.PRE_OPERATIONAL:
            self.nmt = NmtState.PRE_OPERATIONAL
        elif cs == NmtCommand.RESET_NODE:
            self.reset_node()
        elif cs == NmtCommand.RESET_COMMUNICATION:
            self.reset_communication()

    def on_frame(self, cob: int, data: bytes, remote: bool = False) -> None:
        """One frame of the bus addressed to anyone (§11.9.6's table: what each state takes)."""
        nid = self.node_id
        if cob == 0:
            self.on_nmt(data)
            return
        if cob == 0x7E5:
            self.lss.on_request(data)
            return
        if self.nmt == NmtState.INITIALISING:
            return
        if cob == BOOTUP_COB + nid and remote:
            self.send(BOOTUP_COB + nid, self.guarding.answer(self.nmt, self.now_ms))
            self.stats["guarding"] += 1
            return
        if self.nmt == NmtState.STOPPED:
            return
        if cob == int(self.values[(0x1005, 0)]) & 0x7FF and not remote:
            self.stats["SYNC"] += 1
            self.pdos.on_sync()
            self.drive.on_sync()
            return
        if cob == 0x600 + nid and not remote and self.sdo is not None:
            self.sdo.on_request(cob, data, 0.0)
            return
        if remote:
            self.pdos.on_remote(cob)
            return
        n = self.pdos.receive_cobs().get(cob)
        if n is not None:
            self.pdos.on_receive(n, data)

    # ------------------------------------------------------------------ time
    def tick(self) -> None:
        """One simulated millisecond has passed: heartbeat, life guarding, EMCY of the motor's
        error bits, event-driven PDOs, the drive."""
        self.now_ms += 1
        if self.nmt == NmtState.INITIALISING:
            return
        if self.heartbeat.due(self.now_ms):
            self.send(BOOTUP_COB + self.node_id, bytes((int(self.nmt),)))
            self.stats["heartbeat"] += 1
        if self.guarding.lost(int(self.values[(0x100C, 0)]), int(self.values[(0x100D, 0)]),
                              self.now_ms):
            self.emergency(em.NODE_GUARD)
        f = self.facts
        err = self.reg_read(f.err_bits)
        new = err & ~self.emcy.last_err
        if new:
            self._emcy(self.emcy.code_of(new, f.err_follow, f.err_low_bus, f.err_position))
        elif not err and self.emcy.last_err:
            self._emcy(0)
        self.emcy.last_err = err
        self.drive.tick(1)
        self.pdos.tick()
