"""The twin every bus serves: simulated motors with their addresses, flash files, clock and lock.

A :class:`MotorTwin` wraps a :class:`~jvl_gym.MotorArray` (or anything with the same subset of
methods, :class:`MotorBackend`) the way a line of real motors is reached: each motor at its
address (MYADDR, kept as its factory address), its flash kept in a file across restarts
(``flash_<i>.json``), the simulation advanced in whole outer samples of the motors' own rate,
and one lock held while a request is carried out or the simulation steps. Every bus's serving
side (:mod:`jvl_gym.protocol.mactalk.twin16`, :mod:`jvl_gym.protocol.modbus.twin`, the CANopen
server, the J1939 node, the DMX512 server) takes a :class:`MotorTwin` and carries out its
requests through it: :meth:`~MotorTwin.store` writes as one transaction (a refusal changes
nothing, a write that saves to flash writes the flash file), :meth:`~MotorTwin.value` reads,
:meth:`~MotorTwin.dispatch` runs a request on each addressed motor.

A flash directory has one owner: the twin holds an exclusive lock (``fcntl.flock``) on the
file :data:`LOCK_NAME` in it, which names the owner's process, from its start to :meth:`close`
(or its end); a second twin on the directory, in this process or another, is refused with
:class:`FlashDirectoryInUse` naming the holder. A flash file is written under a unique temporary
name in the same directory, flushed to disk and renamed over the old one (``os.replace``, then
the directory synced), so a reader sees the old image or the new, never a part; a save that
does not reach the file raises :class:`FlashFileError`, which every bus answers as a failure.

No I/O here but the flash files and their lock (the transport is :mod:`.transport`).
"""

from __future__ import annotations

import contextlib
import fcntl
import json
import logging
import os
import tempfile
import threading
import weakref
from collections import Counter
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from ...families.contract import Capability, TwinSpec, UnsupportedOperation
from ...registers.errors import echo

__all__ = ["MotorBackend", "TwinFamily", "MotorTwin", "RegisterNumbers", "FlashFileError",
           "FlashDirectoryInUse", "LOCK_NAME"]

log = logging.getLogger(__name__)

#: the file in a flash directory that its owner (a twin) holds locked; it names its process
LOCK_NAME = "owner.lock"


class FlashFileError(ValueError):
    """A flash file that could not be written: the save is answered to its requester as
    failed (the motor's flash keeps the image it had before the save)."""


class FlashDirectoryInUse(ValueError):
    """The flash directory is held by another twin (one line, naming its process)."""


def _process_name(pid: int) -> str:
    """``"process 1234 (python)"``: a process id with its command name where the system
    tells it (``/proc``)."""
    try:
        comm = Path(f"/proc/{pid}/comm").read_text(encoding="utf-8").strip()
    except OSError:
        return f"process {pid}"
    return f"process {pid} ({comm})"


def _lock_flash_dir(folder: Path) -> int:
    """Lock ``folder`` for this twin: the open lock file's descriptor, locked, holding this
    process's id. FlashDirectoryInUse naming the holder if another twin holds it."""
    path = folder / LOCK_NAME
    try:
        fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o644)
    except OSError as exc:
        reason = exc.strerror or exc
        raise ValueError(f"flash directory {folder}: cannot open its lock file ({reason}); "
                         "give a writable --flash-dir") from None
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        holder = os.pread(fd, 32, 0).decode("ascii", "replace").strip()
        os.close(fd)
        who = _process_name(int(holder)) if holder.isdigit() else "another process"
        here = " (this one)" if holder == str(os.getpid()) else ""
        raise FlashDirectoryInUse(f"flash directory {folder} is in use by {who}{here}: one "
                                  "twin per flash directory; stop it or give another "
                                  "--flash-dir") from None
    os.ftruncate(fd, 0)
    os.pwrite(fd, f"{os.getpid()}\n".encode("ascii"), 0)
    return fd


def _write_atomically(path: Path, text: str) -> None:
    """Replace ``path`` by a file holding ``text``: written under a unique temporary name in
    the same directory, flushed to disk, renamed over ``path``, the directory synced. OSError
    if any step fails (``path`` is then as it was, the temporary file removed)."""
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
    dfd = os.open(path.parent, os.O_RDONLY | os.O_DIRECTORY)
    try:
        os.fsync(dfd)
    finally:
        os.close(dfd)


class RegisterNumbers:
    """Numbers of the registers the twin uses, looked up by name in the motors' register
    table (manual 3.2 for the MACs); −1 where the table has no such register.

    Attributes
    ----------
    MODE_REG, P_SOLL, V_SOLL, T_SOLL, P_FNC, P_IST, FLWERR, ERR_STAT, CNTRL_BITS, HOME_MODE,
    P_REG_P, V_REG_P, A_REG_P, T_REG_P, L_REG_P, Z_REG_P, P1, P7, P8, SAMPLE1, REC_CNT, MYADDR,
    GROUP_ID, GROUP_SEQ
        Register numbers.
    """

    NAMES = ("MODE_REG", "P_SOLL", "V_SOLL", "T_SOLL", "P_FNC", "P_IST", "FLWERR", "ERR_STAT",
             "CNTRL_BITS", "HOME_MODE", "P_REG_P", "V_REG_P", "A_REG_P", "T_REG_P", "L_REG_P",
             "Z_REG_P", "P1", "P7", "P8", "SAMPLE1", "REC_CNT", "MYADDR", "GROUP_ID",
             "GROUP_SEQ")
    #: other names of a register in other families' tables (MIS §8.2.88, MAC800: MY_ADDR)
    ALIASES = {"MYADDR": ("MY_ADDR",)}

    def __init__(self, table: Any) -> None:
        from ...registers import RegisterError

        for name in self.NAMES:
            number = -1
            for spelling in (name, *self.ALIASES.get(name, ())):
                try:
                    number = table.lookup(spelling).number
                    break
                except RegisterError:
                    continue
            setattr(self, name, number)
        #: register-set pointer of each FastMAC group letter (manual 5.2.1)
        self.pointer = {"P": self.P_REG_P, "V": self.V_REG_P, "A": self.A_REG_P,
                        "T": self.T_REG_P, "L": self.L_REG_P, "Z": self.Z_REG_P}


class TwinFamily(Protocol):
    """What the twin asks of the motors' family (:class:`jvl_gym.families.Family` has it)."""

    title: str
    twin: TwinSpec

    def supports(self, capability: Capability) -> bool: ...


class MotorBackend(Protocol):
    """The subset of :class:`jvl_gym.MotorArray` the twin uses."""

    n: int
    table: Any
    OUTER_HZ: float

    @property
    def family(self) -> TwinFamily: ...

    def read_raw(self, key: str | int) -> np.ndarray: ...
    def write_raw(self, key: str | int, raw: Any, index: Any = None) -> None: ...
    def write_raw_many(self, values: Mapping[int, int], index: Any = None) -> None: ...
    def step(self, n_outer: int = 1) -> None: ...
    def enter_safe_mode(self, index: Any = None) -> None: ...
    def go_init_mode(self, index: Any = None) -> None: ...
    def exit_safe_mode(self, index: Any = None) -> None: ...
    def write_flash(self, index: Any = None) -> None: ...
    def software_reset(self, index: Any = None) -> None: ...
    def reset(self, index: Any = None) -> None: ...
    def flash_image(self, index: int) -> dict[int, int]: ...
    def load_flash_image(self, index: int, image: dict[int, int]) -> None: ...
    def check_flash_image(self, index: int, image: dict[int, int]) -> None: ...
    def sample_buffer_raw(self, index: int) -> np.ndarray: ...

    @property
    def interface_bits(self) -> np.ndarray: ...


class MotorTwin:
    """Simulated motors as a line of real ones is reached: addresses, flash files, clock, lock.

    Parameters
    ----------
    motors : MotorBackend
        Usually ``MotorArray(type, n=len(addresses))``.
    addresses : list of int, optional
        MYADDR (1..254) of each motor, kept as the motor's factory address: written now and
        stored in flash unless a flash file provides the registers.
    flash_dir : path, optional
        Directory of the flash files ``flash_<i>.json`` (loaded at start, written when a motor
        saves to flash); created if missing, and held by this twin until :meth:`close`. A
        directory that cannot be created or written, or a flash file that cannot be read as a
        flash image, raises ValueError naming it; a directory another twin holds raises
        :class:`FlashDirectoryInUse` naming the holder's process.

    Attributes
    ----------
    m : MotorBackend
        The motors.
    family : TwinFamily
        The motors' family: its twin facts (``family.twin``, also ``spec``) and capabilities.
    reg : RegisterNumbers
        Numbers of the registers the twin uses, from the motors' register table.
    outer_dt : float
        Seconds per outer sample of the motors (``1 / OUTER_HZ``).
    lock : threading.RLock
        Held while a request is carried out or the simulation steps.
    stats : collections.Counter
        ``frames``, ``errors``, ``refused``, ``replies``, ``ignored`` …
    alone : bool
        Whether the twin's motors are the only units on their line (a broadcast is then
        answered when there is one motor); a line of several twins clears it.
    """

    def __init__(self, motors: MotorBackend, addresses: list[int] | None = None,
                 flash_dir: str | os.PathLike[str] | None = None) -> None:
        self.m = motors
        self.family = motors.family
        self.spec = motors.family.twin
        self.outer_dt = 1.0 / float(motors.OUTER_HZ)
        self._sim_time = 0.0
        self._stepped = 0
        self._warm = False
        self.reg = RegisterNumbers(motors.table)
        self.lock = threading.RLock()
        self.stats: Counter[str] = Counter()
        self.flash_dir = Path(flash_dir) if flash_dir is not None else None
        self.last_refusal: str = ""
        self.alone = True
        if addresses is not None:
            if len(addresses) != motors.n:
                raise ValueError(f"{len(addresses)} addresses for {motors.n} motors")
            for a in addresses:
                if not 1 <= a <= 254:
                    raise ValueError(f"a unit address is 1..254 (manual 3.2.156), got {a}")
        self._check_flash_dir()
        self._release: Callable[[], None] | None = None
        if self.flash_dir is not None:
            fd = _lock_flash_dir(self.flash_dir)
            self._release = weakref.finalize(self, os.close, fd)
        try:
            # every flash file is read and checked (MotorArray.check_flash_image) before any
            # is loaded: a bad one changes nothing
            images = [self._read_flash_file(i) for i in range(motors.n)]
            for i, image in enumerate(images):
                if image is not None:
                    self._flash_file_call(i, motors.check_flash_image, image)
        except BaseException:
            self.close()
            raise
        for i, image in enumerate(images):
            if image is not None:
                self._flash_file_call(i, motors.load_flash_image, image)
                self.power_on(i)
            elif addresses is not None:
                motors.load_flash_image(i, {self.reg.MYADDR: addresses[i]})
                motors.write_raw(self.reg.MYADDR, addresses[i], index=i)

    def close(self) -> None:
        """Give up the flash directory (its lock; idempotent). The twin serves on, but another
        twin may now take the directory: close a twin when it stops."""
        release, self._release = self._release, None
        if release is not None:
            release()

    def __enter__(self) -> MotorTwin:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def supports(self, capability: Capability) -> bool:
        """Whether the motors' family declares ``capability``."""
        return self.family.supports(capability)

    def require(self, capability: Capability) -> None:
        """:class:`~jvl_gym.families.UnsupportedOperation` unless the family declares
        ``capability`` (the request is then refused)."""
        if not self.family.supports(capability):
            raise UnsupportedOperation(self.family.title, capability)

    def in_safe_mode(self, i: int) -> bool:
        """Whether motor ``i`` is in the family's safe mode (never, for a family without)."""
        return self.spec.safe_mode is not None and self.mode(i) == self.spec.safe_mode

    def power_on(self, i: int) -> None:
        """Motor ``i`` restarts from its flash: the family's ``software_reset`` where it has
        one (:attr:`~jvl_gym.families.Capability.SOFTWARE_RESET`), else the power-on
        ``reset`` of every motor array."""
        if self.supports(Capability.SOFTWARE_RESET):
            self.m.software_reset(i)
        else:
            self.m.reset(i)

    def _flash_path(self, i: int) -> Path | None:
        return None if self.flash_dir is None else self.flash_dir / f"flash_{i}.json"

    def _check_flash_dir(self) -> None:
        """Create the flash directory if needed; ValueError if it cannot hold flash files."""
        if self.flash_dir is None:
            return
        try:
            self.flash_dir.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise ValueError(f"flash directory {self.flash_dir} cannot be created: "
                             f"{exc.strerror or exc}; give a writable --flash-dir") from exc
        if not os.access(self.flash_dir, os.W_OK | os.X_OK):
            raise ValueError(f"flash directory {self.flash_dir} is not writable; give a "
                             "writable --flash-dir")

    def _read_flash_file(self, i: int) -> dict[int, int] | None:
        """The flash image in motor ``i``'s flash file (register number → raw), None if there
        is no file; the motor is not touched. ValueError naming the file if it is not a flash
        image: not JSON, or no ``"registers"`` mapping of register numbers to integers."""
        path = self._flash_path(i)
        if path is None or not path.exists():
            return None
        try:
            data = json.loads(path.read_text(encoding="utf-8"))
            if not isinstance(data, dict) or "registers" not in data:
                raise ValueError('it has no "registers" key: expected {"registers": '
                                 '{"<number>": <raw>, ...}}')
            regs = data["registers"]
            if not isinstance(regs, dict):
                raise ValueError('"registers" is not a mapping: expected {"registers": '
                                 '{"<number>": <raw>, ...}}')
            image = {}
            for k, v in regs.items():
                if not k.isdigit() or type(v) is not int:
                    raise ValueError(f"entry {echo(k)}: {echo(v)} is not register number: integer")
                image[int(k)] = v
        except (OSError, UnicodeDecodeError, ValueError) as exc:
            raise self._flash_file_error(i, exc) from exc
        return image

    def _flash_file_call(self, i: int, method: Any, image: dict[int, int]) -> None:
        """``method(i, image)``: check or load the image of motor ``i``'s flash file (the motor
        checks every register); ValueError naming the file if the motor refuses it (its flash
        is then unchanged)."""
        try:
            method(i, image)
        except (ValueError, KeyError) as exc:
            raise self._flash_file_error(i, exc) from exc

    def _flash_file_error(self, i: int, exc: BaseException) -> ValueError:
        """The error of a flash file the twin cannot take: what, which file, what to do."""
        reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        return ValueError(f"flash file {self._flash_path(i)} is not a flash image of motor {i}: "
                          f"{reason}; fix or delete it (the twin writes it when the motor saves "
                          "to flash)")

    def save_flash_file(self, i: int, before: dict[int, int] | None = None) -> None:
        """Write motor ``i``'s flash to its file, atomically (:func:`_write_atomically`).

        Parameters
        ----------
        i : int
            The motor.
        before : dict, optional
            The motor's flash image before the save (:meth:`MotorBackend.flash_image`): if the
            file cannot be written, the motor's flash is given this image back, so that flash
            and file agree.

        Raises
        ------
        FlashFileError
            The file could not be written (counted in ``stats["flash_file_errors"]``, logged,
            :attr:`last_refusal`): the requester is answered that the save failed.
        """
        path = self._flash_path(i)
        if path is None:
            return
        with self.lock:
            image = self.m.flash_image(i)
            text = json.dumps({"motor": i, "registers": {str(k): v for k, v in
                                                         sorted(image.items())}}, indent=1)
            try:
                _write_atomically(path, text)
            except OSError as exc:
                if before is not None:
                    self.m.load_flash_image(i, before)
                self.stats["flash_file_errors"] += 1
                kept = ("keeps its previous image" if before is not None
                        else "holds the new image until the twin stops")
                self.last_refusal = (f"flash file {path} not written ({exc.strerror or exc}): "
                                     f"the save failed; the motor's flash {kept}")
                log.error("%s", self.last_refusal)
                raise FlashFileError(self.last_refusal) from None

    def store(self, i: int, values: Mapping[int, int]) -> None:
        """Write stored integers (register number → raw, in this order) to motor ``i`` as one
        transaction: every register is checked before the first is stored, and a refusal
        leaves the motor, its flash and its flash file as they were. A write that saves to flash
        (a user command such as the MIS's COMMAND 268/269, MIS manual §8.2.22, or MODE_REG 258
        in SAFE_MODE, MAC050–141 manual 4.4.16) writes the motor's flash file.

        Raises
        ------
        RegisterError
            The motor refuses (unknown, read-only or reserved register, range, mode).
        FlashFileError
            The write saved to flash but the flash file could not be written: the registers
            are written, the motor's flash keeps its previous image, and the request is
            answered as failed.
        """
        with self.lock:
            before = self.m.flash_image(i) if self.flash_dir is not None else None
            self.m.write_raw_many(values, index=i)
            if before is not None and self.m.flash_image(i) != before:
                self.save_flash_file(i, before)

    def addresses(self) -> list[int]:
        """MYADDR of every motor now."""
        return [int(a) for a in self.m.read_raw(self.reg.MYADDR)]

    def mode(self, i: int) -> int:
        """MODE_REG of motor ``i`` now."""
        return int(self.m.read_raw(self.reg.MODE_REG)[i])

    def value(self, i: int, reg: int) -> int:
        """The stored integer of register ``reg`` of motor ``i`` (0 where the table has no such
        register or it is reserved)."""
        if reg not in self.m.table or self.m.table.lookup(reg).access.value == "reserved":
            return 0
        return int(self.m.read_raw(reg)[i])

    def refuse(self, why: str) -> None:
        """Count and log a refused request (``stats["refused"]``, :attr:`last_refusal`)."""
        self.last_refusal = why
        self.stats["refused"] += 1
        log.info("refused: %s", why)

    def step(self, n_outer: int) -> None:
        """Advance the simulation by ``n_outer`` outer samples (under the lock)."""
        if n_outer > 0:
            with self.lock:
                self.m.step(n_outer)

    def warm_up(self) -> None:
        """Make the motors ready to answer at once: step them one outer sample (one sample of
        simulated time, as :meth:`advance`), so that their step is compiled, or loaded from
        the compile cache, before a request waits on the lock for it (a first compile takes
        minutes, a load from the cache seconds on a busy machine). A server calls it before it
        listens; later calls do nothing."""
        if not self._warm:
            self._warm = True
            self.advance(self.outer_dt)

    @property
    def answers_broadcast(self) -> bool:
        """A broadcast is answered only on a point-to-point link: one motor alone on its line
        (several answering units would collide on a bus)."""
        return self.alone and self.m.n == 1

    def advance(self, seconds: float) -> None:
        """Advance the simulation by ``seconds`` of simulated time, in whole outer samples of
        the motors' own rate (the part of a sample left over is carried to the next call)."""
        self._sim_time += seconds
        due = int(self._sim_time / self.outer_dt) - self._stepped
        if due > 0:
            self.step(due)
            self._stepped += due

    def targets(self, address: int, broadcast: int | None = None) -> list[int]:
        """Motors addressed by ``address``: each whose address (MYADDR) it is, every motor when
        it is the bus's ``broadcast`` address."""
        if broadcast is not None and address == broadcast:
            return list(range(self.m.n))
        return [i for i, a in enumerate(self.addresses()) if a == address]

    def dispatch(self, address: int, broadcast: int, one: Callable[[int], bytes]) -> bytes:
        """Carry out a request to ``address`` on each motor it names (``one(i)`` under the
        lock, the motor's reply bytes); the reply of the first, none to a ``broadcast``
        unless the twin answers broadcasts."""
        with self.lock:
            targets = self.targets(address, broadcast)
            if not targets:
                self.stats["ignored"] += 1
                return b""
            replies = [one(i) for i in targets]
        if address == broadcast and not self.answers_broadcast:
            return b""
        if replies[0]:
            self.stats["replies"] += 1
        return replies[0]
