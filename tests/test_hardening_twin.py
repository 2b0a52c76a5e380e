"""The digital twin: flash files named in errors, an unwritable flash directory
neither loses state nor drops the client, the banner shows the addresses the motors answer at,
closed connections are released, and garbage is skipped a run at a time."""

from __future__ import annotations

import json
import socket
import time
from pathlib import Path

import pytest

from jvl_gym import MotorArray
from jvl_gym.protocol.mactalk import codec16 as mt
from jvl_gym.protocol.mactalk.twin16 import Twin
from jvl_gym.protocol.serving.transport import TwinServer


def _twin(tmp_path: Path | None = None, addresses=(19,)) -> Twin:
    return Twin(MotorArray("MAC140", n=len(addresses), seed=0), list(addresses),
                flash_dir=tmp_path)


@pytest.mark.parametrize("text", ["{not json", "[1, 2]", '{"registers": {"13": 1.5}}',
                                  '{"registers": {"12": 5}}', '{"registers": {"x": 1}}',
                                  '{"motor": 0}', '{"registers": []}'])
def test_corrupt_flash_file_is_named(tmp_path, text):
    (tmp_path / "flash_0.json").write_text(text)
    with pytest.raises(ValueError, match="flash_0.json"):
        _twin(tmp_path)


@pytest.mark.parametrize(("text", "words"), [
    ('{"motor": 0}', 'no "registers" key'),
    ("{}", 'no "registers" key'),
    ('{"registers": [1]}', '"registers" is not a mapping'),
])
def test_flash_file_without_registers_says_so(tmp_path, text, words):
    (tmp_path / "flash_0.json").write_text(text)
    with pytest.raises(ValueError) as info:
        _twin(tmp_path)
    message = str(info.value)
    assert "flash_0.json" in message and words in message and "fix or delete it" in message
    assert len(message.splitlines()) == 1


@pytest.mark.parametrize("second", ['{"motor": 1}', '{"registers": {"13": 99999999}}',
                                    '{"registers": {"12": 5}}'])
def test_a_bad_flash_file_loads_no_motor_and_changes_no_file(tmp_path, second):
    """Motor 0's file is good, motor 1's is not: the twin is refused naming motor 1's file,
    motor 0's flash and registers are as they were, and both files are unchanged."""
    (tmp_path / "flash_0.json").write_text('{"motor": 0, "registers": {"13": 700}}')
    (tmp_path / "flash_1.json").write_text(second)
    files = {p.name: p.read_text() for p in tmp_path.glob("flash_*")}
    m = MotorArray("MAC140", n=2, seed=0)
    regs = m.regs.copy()
    with pytest.raises(ValueError, match="flash_1.json"):
        Twin(m, [19, 20], flash_dir=tmp_path)
    assert m.flash_image(0) == {} and m.flash_image(1) == {} and (m.regs == regs).all()
    assert {p.name: p.read_text() for p in tmp_path.glob("flash_*")} == files
    (tmp_path / "flash_1.json").unlink()  # the refused twin left the directory free
    Twin(MotorArray("MAC140", n=2, seed=0), [19, 20], flash_dir=tmp_path).close()


def test_serve_with_a_flash_file_without_registers_is_one_line(tmp_path, capsys):
    from jvl_gym.cli.main import app

    (tmp_path / "flash_0.json").write_text('{"motor": 0}')
    with pytest.raises(SystemExit) as info:
        app(["serve", "--tcp", "127.0.0.1:0", "--flash-dir", str(tmp_path)])
    assert info.value.code not in (0, None)
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "flash_0.json" in err[0] and '"registers"' in err[0]


def test_non_utf8_flash_file_is_named(tmp_path):
    (tmp_path / "flash_0.json").write_bytes(b"\xff\xfe{")
    with pytest.raises(ValueError, match="flash_0.json"):
        _twin(tmp_path)


def test_flash_dir_that_is_a_file_is_refused_at_start(tmp_path):
    path = tmp_path / "plain"
    path.write_text("")
    with pytest.raises(ValueError, match="plain"):
        _twin(path)


def test_serve_with_a_corrupt_flash_file_is_one_line(tmp_path, capsys):
    from jvl_gym.cli.main import app

    (tmp_path / "flash_0.json").write_text("{not json")
    with pytest.raises(SystemExit) as info:
        app(["serve", "--tcp", "127.0.0.1:0", "--flash-dir", str(tmp_path)])
    assert info.value.code == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "flash_0.json" in err[0]


def test_unwritable_flash_dir_keeps_state_and_session(tmp_path):
    twin = _twin(tmp_path)
    twin.m.write("KVOUT", 2.5)
    session = twin.session()
    assert session.feed(mt.encode_go_safe_mode(19)) == mt.ACCEPT
    twin.m.step(300)
    blocked = tmp_path / "blocked"
    blocked.write_text("")
    saved = twin.m.flash_image(0)
    twin.flash_dir = blocked  # the file cannot be written
    assert session.feed(mt.encode_write_flash(19)) == b""  # 56h has no answer (manual 5.1)
    assert twin.stats["flash_file_errors"] == 1
    assert "blocked" in twin.last_refusal and "the save failed" in twin.last_refusal
    # the save failed where the requester sees it: the motor stays in SAFE_MODE, its flash
    # as the file has it; the registers keep KVOUT 2.5 (nothing is lost)
    assert twin.mode(0) == 15 and twin.m.flash_image(0) == saved
    reply = mt.decode(session.feed(mt.encode_read(19, 13)))  # the session still answers
    assert mt.bytes_to_words(reply.data)[0] == 640


def test_banner_shows_the_flashed_address(tmp_path):
    from jvl_gym.cli.serve import banner

    (tmp_path / "flash_0.json").write_text(json.dumps({"motor": 0, "registers": {"156": 33}}))
    twin = _twin(tmp_path)
    lines = banner(["MAC140"], twin)
    assert lines == ["motor 0: MAC140 at address 33 (flash; --address said 19)"] or \
        lines[0].startswith("motor 0: MAC140 at address 33")


def test_server_releases_closed_connections():
    twin = _twin()
    with TwinServer(twin, tcp=("127.0.0.1", 0), run_clock=False) as server:
        port = server.endpoint("mactalk", "tcp").port
        for _ in range(20):
            with socket.create_connection(("127.0.0.1", port), timeout=2) as s:
                s.sendall(mt.encode_read(19, 13))
                s.recv(64)
        deadline = time.monotonic() + 5
        while time.monotonic() < deadline and (len(server._socks) > 1
                                               or len(server._threads) > 1):
            time.sleep(0.05)
        assert len(server._socks) == 1  # the listener
        assert len(server._threads) == 1  # the accept loop


def test_a_run_of_sync_bytes_is_one_error_and_the_next_frame_decodes():
    d = mt.MacTalkDecoder()
    garbage = b"\x50" * 300_000
    items = []
    for k in range(0, len(garbage), 4096):
        items += d.feed(garbage[k:k + 4096])
    items += d.feed(mt.encode_read(19, 7))
    errors = [x for x in items if isinstance(x, mt.FrameError)]
    frames = [x for x in items if not isinstance(x, mt.FrameError)]
    assert sum(len(e.data) for e in errors) == len(garbage)
    assert len(errors) <= 2 * (len(garbage) // 4096 + 1)
    assert frames == [mt.Request(mt.Command.READ, 19, 7)]


def test_random_garbage_is_skipped_to_the_next_sync():
    import numpy as np

    rng = np.random.default_rng(0)
    junk = bytes(rng.integers(0, 256, 50_000, dtype=np.uint8))
    junk = junk.replace(b"\x11", b"\x12")
    items = mt.MacTalkDecoder().feed(junk + mt.encode_read(19, 7))
    errors = [x for x in items if isinstance(x, mt.FrameError)]
    assert sum(len(e.data) for e in errors) == len(junk)
    assert items[-1] == mt.Request(mt.Command.READ, 19, 7)


@pytest.mark.parametrize("speed", [float("inf"), float("nan"), 0.0, -1.0])
def test_server_speed_must_be_finite_and_positive(speed):
    with pytest.raises(ValueError, match="speed"):
        TwinServer(_twin(), speed=speed, run_clock=False)


def test_a_port_in_use_is_named():
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen(1)
        port = taken.getsockname()[1]
        server = TwinServer(_twin(), tcp=("127.0.0.1", port), run_clock=False)
        with pytest.raises(OSError, match=f"127.0.0.1:{port}.*choose another port"):
            server.start()
        server.stop()


def test_serve_on_a_port_in_use_is_one_line(capsys):
    from jvl_gym.cli.main import app

    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen(1)
        port = taken.getsockname()[1]
        with pytest.raises(SystemExit) as info:
            app(["serve", "--motor", "MAC140", "--tcp", f"127.0.0.1:{port}"])
    err = capsys.readouterr().err.strip().splitlines()
    assert info.value.code not in (0, None)
    assert f"127.0.0.1:{port}" in err[-1] and "Traceback" not in "".join(err)
