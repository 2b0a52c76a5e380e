"""A flash directory has one owner, and every save reaches its file or is answered as failed.

The twin holds a lock on its flash directory (a second twin, in this process or another
``jvl-gym serve``, is refused in one line naming the holder's process); a flash file is replaced
atomically, so a reader never sees an empty or partial file, and concurrent saves lose nothing;
a save whose file cannot be written is answered to the requester as failed on every bus: the
32-bit MacTalk's WRITE FLASH with its failure response (MIS manual §18.2.7), the MIS COMMAND
save over Modbus with an exception reply (MIS manual §12), CANopen's 1010h with the SDO abort
0800 0020h (MIS manual §11.4.5).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import threading
from pathlib import Path

import canopen
import pytest

from canopen_rig import Rig
from jvl_gym import MotorArray
from jvl_gym.protocol.canopen.objects import SAVE
from jvl_gym.protocol.mactalk import codec32 as m32
from jvl_gym.protocol.mactalk.twin16 import Twin
from jvl_gym.protocol.modbus import codec as mb
from jvl_gym.protocol.modbus.twin import modbus_bus
from jvl_gym.protocol.serving.twin import LOCK_NAME, FlashDirectoryInUse

ROOT = Path(__file__).resolve().parents[1]


def _mis(folder: Path, address: int = 7) -> Twin:
    return Twin(MotorArray("MIS232", n=1, seed=0), [address], flash_dir=folder)


def test_a_second_twin_on_one_flash_dir_is_refused_naming_the_holder(tmp_path) -> None:
    first = _mis(tmp_path)
    with pytest.raises(FlashDirectoryInUse) as info:
        _mis(tmp_path)
    message = str(info.value)
    assert len(message.splitlines()) == 1
    assert str(tmp_path) in message and f"process {os.getpid()}" in message
    assert (tmp_path / LOCK_NAME).read_text().strip() == str(os.getpid())
    first.close()
    _mis(tmp_path).close()  # closed: the directory takes a new owner


def test_jvl_gym_serve_on_a_held_flash_dir_exits_with_one_line(tmp_path) -> None:
    """A second ``jvl-gym serve`` on the directory (another process) exits non-zero at once,
    naming this process, the holder."""
    holder = _mis(tmp_path)
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT / "src"), str(ROOT)])}
    run = subprocess.run([sys.executable, "-m", "jvl_gym.cli", "serve", "-m", "MIS232",
                          "-a", "7", "--tcp", "127.0.0.1:0", "--flash-dir", str(tmp_path)],
                         capture_output=True, text=True, timeout=300, env=env)
    holder.close()
    assert run.returncode not in (0, None)
    err = run.stderr.strip().splitlines()
    assert len(err) == 1, run.stderr
    assert f"process {os.getpid()}" in err[0] and "--flash-dir" in err[0]


def test_a_reader_never_sees_a_partial_flash_file_and_no_save_is_lost(tmp_path) -> None:
    """Two threads save the flash of one twin 200 times each while an observer reads the file:
    every read is a whole flash image, every save is written, the file ends as the flash."""
    twin = _mis(tmp_path)
    path = tmp_path / "flash_0.json"
    twin.save_flash_file(0)
    done = threading.Event()
    bad: list[str] = []
    reads = [0]

    def observe() -> None:
        while not done.is_set():
            try:
                text = path.read_text()
            except FileNotFoundError:
                bad.append("missing")
                continue
            reads[0] += 1
            try:
                json.loads(text)["registers"]
            except (ValueError, KeyError):
                bad.append(text[:40])

    errors: list[BaseException] = []

    def save() -> None:
        for _ in range(200):
            try:
                twin.save_flash_file(0)
            except ValueError as exc:
                errors.append(exc)

    observer = threading.Thread(target=observe)
    observer.start()
    savers = [threading.Thread(target=save) for _ in range(2)]
    for t in savers:
        t.start()
    for t in savers:
        t.join()
    done.set()
    observer.join()
    assert reads[0] > 0 and bad == [] and errors == []
    assert twin.stats["flash_file_errors"] == 0
    saved = {int(k): v for k, v in json.loads(path.read_text())["registers"].items()}
    assert saved == twin.m.flash_image(0)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["flash_0.json", LOCK_NAME]


def _block(folder: Path) -> None:
    """Make motor 0's flash file unwritable (a directory in its place)."""
    path = folder / "flash_0.json"
    if path.exists():
        path.unlink()
    path.mkdir()


def test_a_failed_write_flash_over_mactalk32_is_answered_as_failed(tmp_path) -> None:
    twin = _mis(tmp_path)
    session = twin.session()
    assert session.feed(m32.encode_write_value(7, 5, 1234)) == m32.ACCEPT  # V_SOLL
    assert session.feed(m32.encode_enter_safe_mode(7)) == m32.ACCEPT
    before = twin.m.flash_image(0)
    _block(tmp_path)
    # MIS §18.2.7: "The response will only be transmitted if the command failed"
    assert session.feed(m32.encode_write_flash(7)) == m32.ACCEPT
    assert twin.stats["flash_file_errors"] == 1 and "not written" in twin.last_refusal
    assert twin.m.flash_image(0) == before  # flash and file agree: nothing saved
    (tmp_path / "flash_0.json").rmdir()
    assert session.feed(m32.encode_enter_safe_mode(7)) == m32.ACCEPT
    assert session.feed(m32.encode_write_flash(7)) == b""  # saved: no response
    assert json.loads((tmp_path / "flash_0.json").read_text())["registers"]["5"] == 1234


def test_a_failed_save_command_over_modbus_is_an_exception_reply(tmp_path) -> None:
    twin = _mis(tmp_path)
    bus = modbus_bus(twin)

    def write(first: int, values: list[int]) -> mb.Response:
        words = [w for v in values for w in mb.words_of(v)]
        reply, _ = bus.handle(mb.encode_write_request(7, 2 * first, words), 0.0)
        return mb.decode_response(reply)

    assert not isinstance(write(5, [1234]), mb.ExceptionResponse)
    before = twin.m.flash_image(0)
    _block(tmp_path)
    reply = write(24, [268])  # COMMAND: save to flash (MIS manual §8.2.22)
    assert isinstance(reply, mb.ExceptionResponse)
    assert twin.m.flash_image(0) == before and twin.stats["flash_file_errors"] == 1


def test_a_failed_store_over_canopen_is_aborted(tmp_path) -> None:
    rig = Rig(flash_dir=tmp_path)
    try:
        node = rig.node()
        node.sdo[0x2012][6].raw = 1234
        node.sdo[0x1010][1].raw = SAVE
        node.sdo[0x2012][6].raw = 4321
        before = rig.m.flash_image(0)
        _block(tmp_path)
        with pytest.raises(canopen.SdoAbortedError) as info:
            node.sdo[0x1010][1].raw = SAVE
        assert info.value.code == 0x08000020
        assert rig.m.flash_image(0) == before
        (tmp_path / "flash_0.json").rmdir()
        node.sdo[0x1010][1].raw = SAVE  # the file can be written again: stored
        assert json.loads((tmp_path / "flash_0.json").read_text())["registers"]
    finally:
        rig.close()
