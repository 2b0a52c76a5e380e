"""Process data objects of a node (MIS manual §11.4.7–11.4.10, §11.9.3): configuration rules,
transmission types, production and consumption.

**Configuration** (communication parameter 1400h+/1800h+, mapping 1600h+/1A00h+):

* a PDO is enabled when bit 31 of its COB-ID (sub 1) is 0 and disabled when it is 1 (§11.4.7);
  the COB-ID of an enabled PDO cannot be changed, only disabled (abort 0609 0030h);
* the mapping is changed by the procedure of §11.4.8: in pre-operational, PDO disabled, number
  of entries (sub 0) := 0, the entries written, then sub 0 := their number, which checks them:
  each mapped object must exist (0602 0000h), be mappable and of the stated length
  (0604 0041h), readable for a transmit and writable for a receive PDO, and all together at
  most 64 bits (0604 0042h); an entry written while sub 0 ≠ 0, or any mapping write while the
  PDO is enabled or the node operational, is refused (0800 0022h);
* transmission types: 0 synchronous acyclic, 1–240 every n-th SYNC, 252/253 on a remote request
  only (transmit), 254/255 event driven; anything else 0609 0030h. Inhibit time (100 µs units)
  only while the PDO is disabled.

**Transmit PDOs** (operational only): types 1–240 after every n-th SYNC; type 0 at a SYNC after
the mapped data changed; types 254/255 every event-timer period (1800h sub 5, ms), or, with
the timer 0, when the mapped data change; never twice within the inhibit time; types 252/253 and
every PDO without bit 30 of its COB-ID on a remote request of its COB-ID.

**Receive PDOs** (operational only): a frame of the mapped length is written object by object,
at once for types 254/255, at the next SYNC for types 0–240; a frame of another length changes
nothing and raises EMCY 8210h (§11.4.2).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from canopen.sdo import SdoAbortedError

from .objects import RPDOS, TPDOS
from .sdo import ABORT

__all__ = ["Pdos", "comm_index", "map_index", "pdo_of", "TX_TYPES", "RX_TYPES"]

TX_TYPES = frozenset(range(0, 241)) | {252, 253, 254, 255}
RX_TYPES = frozenset(range(0, 241)) | {254, 255}
DISABLED, NO_RTR = 1 << 31, 1 << 30


def _usable(cob: int) -> bool:
    """Whether an 11-bit identifier may carry a PDO: not NMT, SYNC, SDO, NMT error control or
    LSS (DS-301 restricted identifiers; MIS manual §11.1.5: 11-bit identifiers only)."""
    return not (cob in (0, 0x80, 0x7E4, 0x7E5) or 0x580 <= cob <= 0x67F
                or 0x700 <= cob <= 0x77F)


def comm_index(n: int, receive: bool) -> int:
    """Communication parameter index of PDO ``n``."""
    return (0x1400 if receive else 0x1800) + n - 1


def map_index(n: int, receive: bool) -> int:
    """Mapping parameter index of PDO ``n``."""
    return (0x1600 if receive else 0x1A00) + n - 1


def pdo_of(index: int) -> tuple[int, bool, bool] | None:
    """(PDO number, receive, mapping) of a PDO parameter index, or None."""
    for base, receive, mapping, numbers in ((0x1400, True, False, RPDOS),
                                            (0x1600, True, True, RPDOS),
                                            (0x1800, False, False, TPDOS),
                                            (0x1A00, False, True, TPDOS)):
        n = index - base + 1
        if n in numbers:
            return n, receive, mapping
    return None


@dataclass
class _Tx:
    count: int = 0
    last_ms: int | None = None
    next_ms: int | None = None
    data: bytes | None = None
    changed: bool = False


@dataclass
class Pdos:
    """The PDO state of a node ``node`` (its values and live objects, see the module text)."""

    node: Any
    tx: dict[int, _Tx] = field(default_factory=dict)
    pending: dict[int, bytes] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.reset()

    def reset(self) -> None:
        """Communication reset: counters and timers start afresh."""
        self.tx = {n: _Tx() for n in TPDOS}
        self.pending = {}

    # ------------------------------------------------------------------ configuration
    def cob(self, n: int, receive: bool) -> int:
        return int(self.node.value(comm_index(n, receive), 1))

    def enabled(self, n: int, receive: bool) -> bool:
        return not self.cob(n, receive) & DISABLED

    def mapping(self, n: int, receive: bool) -> list[tuple[int, int, int]]:
        """The mapped (index, sub-index, bits) of PDO ``n``."""
        m = map_index(n, receive)
        return [(e >> 16, e >> 8 & 0xFF, e & 0xFF) for e in
                (int(self.node.value(m, k)) for k in range(1, int(self.node.value(m, 0)) + 1))]

    def _check_entry(self, entry: int, receive: bool) -> int:
        """Bits of mapping entry ``entry``; abort if it cannot be mapped."""
        index, sub, bits = entry >> 16, entry >> 8 & 0xFF, entry & 0xFF
        od = self.node.object_dictionary
        if index not in od:
            raise SdoAbortedError(ABORT["no_object"])
        obj = od[index]
        if not hasattr(obj, "data_type"):
            if sub not in obj.subindices:
                raise SdoAbortedError(ABORT["no_sub"])
            obj = obj[sub]
        elif sub:
            raise SdoAbortedError(ABORT["no_sub"])
        if (not obj.pdo_mappable or len(obj) != bits
                or not (obj.writable if receive else obj.readable)):
            raise SdoAbortedError(ABORT["not_mappable"])
        return bits

    def check_write(self, index: int, sub: int, value: int) -> None:
        """Abort a write of ``value`` to PDO parameter ``index``/``sub`` the rules refuse."""
        n, receive, mapping = pdo_of(index)  # type: ignore[misc]
        enabled = self.enabled(n, receive)
        if not mapping:
            if sub == 1:
                old = self.cob(n, receive)
                if not value & DISABLED:
                    cob = value & 0x7FF
                    if value & 0x3FFFF800 or not _usable(cob):
                        raise SdoAbortedError(ABORT["range"])
                    if enabled and cob != old & 0x7FF:
                        raise SdoAbortedError(ABORT["range"])
                    length = sum(b for _, _, b in self.mapping(n, receive))
                    if length > 64 or not length:
                        raise SdoAbortedError(ABORT["incompatible"])
            elif sub == 2 and value not in (RX_TYPES if receive else TX_TYPES):
                raise SdoAbortedError(ABORT["range"])
            elif sub == 3 and enabled:
                raise SdoAbortedError(ABORT["range"])
            return
        if enabled or self.node.operational:
            raise SdoAbortedError(ABORT["state"])
        m = map_index(n, receive)
        if sub == 0:
            if value > 8:
                raise SdoAbortedError(ABORT["pdo_length"])
            bits = sum(self._check_entry(int(self.node.value(m, k)), receive)
                       for k in range(1, value + 1))
            if bits > 64:
                raise SdoAbortedError(ABORT["pdo_length"])
        else:
            if int(self.node.value(m, 0)):
                raise SdoAbortedError(ABORT["state"])
            if value:
                self._check_entry(value, receive)

    def changed(self, index: int, sub: int) -> None:
        """A PDO parameter was written: restart the PDO's timers."""
        n, receive, _ = pdo_of(index)  # type: ignore[misc]
        if not receive:
            self.tx[n] = _Tx()
            period = int(self.node.value(comm_index(n, False), 5))
            if period:
                self.tx[n].next_ms = self.node.now_ms + period

    # ------------------------------------------------------------------ transmit
    def _data(self, n: int) -> bytes:
        bits = 0
        value = 0
        for index, sub, width in self.mapping(n, False):
            raw = int(self.node.pdo_read(index, sub)) & ((1 << width) - 1)
            value |= raw << bits
            bits += width
        return value.to_bytes((bits + 7) // 8, "little")

    def _send(self, n: int, data: bytes | None = None) -> None:
        t = self.tx[n]
        inhibit = int(self.node.value(comm_index(n, False), 3))  # 100 µs units
        now = self.node.now_ms
        if t.last_ms is not None and inhibit and (now - t.last_ms) * 10 < inhibit:
            t.changed = True
            return
        data = self._data(n) if data is None else data
        self.node.send(self.cob(n, False) & 0x7FF, data)
        self.node.stats["TPDO"] += 1
        t.last_ms, t.data, t.changed = now, data, False

    def on_sync(self) -> None:
        """A SYNC: synchronous transmit PDOs, then the buffered receive PDOs."""
        if not self.node.operational:
            return
        for n in TPDOS:
            if not self.enabled(n, False):
                continue
            kind = int(self.node.value(comm_index(n, False), 2))
            t = self.tx[n]
            if 1 <= kind <= 240:
                t.count += 1
                if t.count >= kind:
                    t.count = 0
                    self._send(n)
            elif kind == 0:
                data = self._data(n)
                if data != t.data:
                    self._send(n, data)
        pending, self.pending = self.pending, {}
        for n, data in pending.items():
            self._apply(n, data)

    def tick(self) -> None:
        """Event-driven transmit PDOs due at the node's time now."""
        if not self.node.operational:
            return
        now = self.node.now_ms
        for n in TPDOS:
            if not self.enabled(n, False):
                continue
            if int(self.node.value(comm_index(n, False), 2)) < 254:
                continue
            t = self.tx[n]
            period = int(self.node.value(comm_index(n, False), 5))
            if period:
                if t.next_ms is None:
                    t.next_ms = now + period
                if now >= t.next_ms:
                    t.next_ms = now + period
                    self._send(n)
            else:
                data = self._data(n)
                if data != t.data or t.changed:
                    self._send(n, data)

    def on_remote(self, cob: int) -> bool:
        """A remote request of ``cob``: the transmit PDO of that COB-ID answers; whether one
        did."""
        for n in TPDOS:
            c = self.cob(n, False)
            if not c & (DISABLED | NO_RTR) and c & 0x7FF == cob and self.node.operational:
                self._send(n)
                return True
        return False

    # ------------------------------------------------------------------ receive
    def receive_cobs(self) -> dict[int, int]:
        """COB-ID → number of every enabled receive PDO."""
        return {self.cob(n, True) & 0x7FF: n for n in RPDOS if self.enabled(n, True)}

    def on_receive(self, n: int, data: bytes) -> None:
        """Receive PDO ``n`` arrived with ``data``."""
        if not self.node.operational:
            return
        length = sum(b for _, _, b in self.mapping(n, True)) // 8
        if len(data) != length:
            self.node.emergency(0x8210)
            return
        if int(self.node.value(comm_index(n, True), 2)) <= 240:
            self.pending[n] = bytes(data)
        else:
            self._apply(n, bytes(data))

    def _apply(self, n: int, data: bytes) -> None:
        value = int.from_bytes(data, "little")
        for index, sub, bits in self.mapping(n, True):
            raw = value & ((1 << bits) - 1)
            value >>= bits
            try:
                self.node.pdo_write(index, sub, raw)
            except SdoAbortedError as exc:
                self.node.refuse(f"RPDO {n}: 0x{index:04X}:{sub} refused (0x{exc.code:08X})")
        self.node.stats["RPDO"] += 1
