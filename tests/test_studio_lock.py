"""The studio's lock (jvl_gym.studio.lock, docs/studio.md "Who may open the studio"): the rules
on their own (Host, Origin, token, the cookie), then over plain HTTP against a started
``jvl-gym studio`` serving a twin: each rule refused with its status and one-line reason, the
websocket upgrade included, and the twin's registers unchanged by every refused request; the
command line's ``--host`` and ``--toolkit`` errors and the warning for a studio open to the
network. The helpers that start a studio are shared with the Chromium tests."""

from __future__ import annotations

import asyncio
import functools
import os
import re
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from jvl_gym.studio.lock import Access, StudioLock, is_loopback, split_host

ROOT = Path(__file__).resolve().parents[1]
#: the line the studio prints with its URL
URL_LINE = re.compile(r"open (http://\S+?)/\?token=(\S+)")


def _run(coroutine: Any) -> None:
    """Run ``coroutine`` to its end on an event loop of its own, in a thread of its own: the
    test's thread may already run a loop (Playwright's, when a browser test ran first in this
    worker), where ``asyncio.run`` refuses."""
    errors: list[BaseException] = []

    def target() -> None:
        try:
            asyncio.run(coroutine)
        except BaseException as exc:  # re-raised in the test's thread
            errors.append(exc)

    thread = threading.Thread(target=target)
    thread.start()
    thread.join()
    if errors:
        raise errors[0]


# ---------------------------------------------------------------------- a started studio
def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@functools.cache
def _entry_points() -> Path:
    """A folder with the distribution metadata of this tree's entry points (pyproject.toml's
    ``[project.entry-points]``), so that the studio finds the tuning toolkit the way an
    installed package announces it, also when the installed metadata is older than the tree."""
    import tempfile

    import tomllib

    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    folder = Path(tempfile.mkdtemp(prefix="jvl-entry-points-"))
    dist = folder / "jvl_gym_tree_entry_points-0.dist-info"
    dist.mkdir()
    (dist / "METADATA").write_text("Metadata-Version: 2.1\nName: jvl-gym-tree-entry-points\n"
                                   "Version: 0\n")
    (dist / "entry_points.txt").write_text("".join(
        f"[{group}]\n" + "".join(f"{k} = {v}\n" for k, v in eps.items())
        for group, eps in project.get("entry-points", {}).items()))
    return folder


def _env() -> dict[str, str]:
    env = dict(os.environ, MPLBACKEND="Agg")
    env.pop("PYTEST_CURRENT_TEST", None)  # NiceGUI would start in its own test mode
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT / "src"), str(ROOT), str(_entry_points()),
                                         env.get("PYTHONPATH", "")])
    return env


class Studio:
    """A ``jvl-gym studio --no-browser`` process on a free port.

    Attributes
    ----------
    url : str
        ``http://127.0.0.1:<port>``.
    token : str
        The token of this start, read from the URL the studio printed.
    stdout, stderr : list of str
        What the process printed so far.
    """

    def __init__(self, *args: str, seconds: float = 300.0) -> None:
        self.port = free_port()
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "jvl_gym.cli", "studio", "--no-browser", "--port",
             str(self.port), *args], env=_env(), cwd=ROOT, stdout=subprocess.PIPE,
            stderr=subprocess.PIPE, text=True)
        self.stdout: list[str] = []
        self.stderr: list[str] = []
        for stream, lines in ((self.proc.stdout, self.stdout), (self.proc.stderr, self.stderr)):
            threading.Thread(target=lambda s=stream, out=lines: out.extend(s), daemon=True
                             ).start()
        try:
            self.url, self.token = self._printed_url(seconds)
            self._wait_http(seconds)
        except Exception:
            self.stop()
            raise

    def _printed_url(self, seconds: float) -> tuple[str, str]:
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            for line in list(self.stdout):
                if m := URL_LINE.search(line):
                    return m.group(1), m.group(2)
            if self.proc.poll() is not None:
                break
            time.sleep(0.1)
        raise RuntimeError(f"the studio printed no URL: {''.join(self.stdout + self.stderr)}")

    def _wait_http(self, seconds: float) -> None:
        import httpx

        end = time.monotonic() + seconds
        while time.monotonic() < end:
            if self.proc.poll() is not None:
                raise RuntimeError(f"the studio exited: {''.join(self.stdout + self.stderr)}")
            try:
                # an empty studio's first view sends the browser on to Connections
                if httpx.get(self.url + "/", headers={"X-JVL-Token": self.token},
                             timeout=5, follow_redirects=True).status_code == 200:
                    return
            except httpx.HTTPError:
                pass
            time.sleep(0.3)
        raise TimeoutError(f"{self.url} did not answer within {seconds} s")

    def with_token(self, path: str) -> str:
        """The URL of ``path`` with the token in its query."""
        return f"{self.url}{path}{'&' if '?' in path else '?'}token={self.token}"

    def stop(self) -> None:
        stop_process(self.proc)


def stop_process(proc: subprocess.Popen) -> None:
    """End ``proc``: SIGTERM, then SIGKILL if it has not ended within 10 s."""
    proc.terminate()
    try:
        proc.wait(10)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()


def start_twin(types: list[str], addresses: list[int], port: int = 0):
    """The twins of ``types`` at ``addresses`` served in-process (what ``jvl-gym serve --tcp``
    serves) on ``port`` (0: a free one); a fresh line each time, as a restarted server."""
    from jvl_gym.cli.serve import build_line
    from jvl_gym.protocol.serving.transport import TwinServer

    line, _ = build_line(types, addresses)
    return TwinServer(line, tcp=("127.0.0.1", port)).start()


def twin_registers(twin, names: tuple[str, ...] = ("MODE_REG", "V_SOLL", "A_SOLL", "P_SOLL",
                                                   "KVOUT")) -> dict[str, int]:
    """The registers ``names`` of the (first) twin on the served line."""
    t = twin.twin.twins[0] if hasattr(twin.twin, "twins") else twin.twin
    with t.lock:
        return {n: int(t.m.read_raw(n)[0]) for n in names}


# ---------------------------------------------------------------------- the rules alone
ACCESS = Access("s3cret-token", 8080, ["studio.lan"])


@pytest.mark.parametrize("host, ok", [
    ("127.0.0.1:8080", True), ("127.0.0.1", True), ("localhost:8080", True),
    ("LOCALHOST", True), ("[::1]:8080", True), ("[::1]", True), ("::1", True),
    ("studio.lan:8080", True), ("127.0.0.1:8081", False), ("evil.example", False),
    ("evil.example:8080", False), ("", False), ("127.0.0.1:80x", False),
    ("127.0.0.1.evil.example", False), ("[::1]x", False)])
def test_host_allow_list(host, ok):
    assert ACCESS.host_allowed(host) is ok


@pytest.mark.parametrize("origin, ok", [
    ("http://127.0.0.1:8080", True), ("http://localhost:8080", True),
    ("http://[::1]:8080", True), ("http://studio.lan:8080", True),
    ("http://127.0.0.1:9999", False), ("http://evil.example:8080", False),
    ("null", False), ("file://", False), ("http://127.0.0.1", False)])
def test_origin_allow_list(origin, ok):
    assert ACCESS.origin_allowed(origin) is ok


def test_host_names():
    assert split_host("[::1]:8080") == ("::1", 8080) and split_host("::1") == ("::1", None)
    assert all(is_loopback(h) for h in ("127.0.0.1", "localhost", "::1", "[::1]", "127.8.0.1"))
    assert not any(is_loopback(h) for h in ("0.0.0.0", "::", "192.168.1.5", "example.org"))
    url = Access("t", 8080).url("0.0.0.0")
    assert url == "http://127.0.0.1:8080/?token=t"
    assert Access("t", 81).url("::1") == "http://[::1]:81/?token=t"
    with pytest.raises(ValueError, match="token"):
        Access("", 8080)


def _asgi(scope_type: str, headers: dict[str, str], query: str = "", method: str = "GET"
          ) -> tuple[list[dict], list[dict]]:
    """Run ``scope`` through :class:`StudioLock` in front of an app that records what reaches
    it; return (what reached the app, what the lock sent)."""
    reached: list[dict] = []
    sent: list[dict] = []

    async def app(scope, receive, send) -> None:
        reached.append(scope)
        await send({"type": "http.response.start", "status": 200, "headers": []})

    async def receive() -> dict:
        return {"type": "websocket.connect"}

    async def send(message) -> None:
        sent.append(message)

    scope = {"type": scope_type, "path": "/", "method": method,
             "query_string": query.encode(), "extensions": {"websocket.http.response": {}},
             "headers": [(k.lower().encode(), v.encode()) for k, v in headers.items()]}
    _run(StudioLock(app, ACCESS)(scope, receive, send))
    return reached, sent


HOST = {"Host": "127.0.0.1:8080"}


@pytest.mark.parametrize("scope_type", ["http", "websocket"])
def test_the_lock_refuses_before_the_app(scope_type):
    """Each refusal answers with its status and one line and never reaches the application,
    for a page and for a websocket upgrade alike."""
    prefix = "websocket.http" if scope_type == "websocket" else "http"
    cases = [({"Host": "evil.example", "X-JVL-Token": "s3cret-token"}, "", 403, "Host"),
             ({**HOST}, "", 401, "token"),
             ({**HOST}, "token=wrong", 401, "token"),
             ({**HOST, "Cookie": "jvl_studio_8080=wrong"}, "", 401, "token"),
             ({**HOST, "Cookie": "jvl_studio_8081=s3cret-token"}, "", 401, "token"),
             ({**HOST, "Authorization": "Basic s3cret-token"}, "", 401, "token")]
    if scope_type == "websocket":
        cases.append(({**HOST, "Origin": "http://evil.example", "X-JVL-Token": "s3cret-token"},
                      "", 403, "Origin"))
    for headers, query, status, word in cases:
        reached, sent = _asgi(scope_type, headers, query)
        assert not reached, headers
        assert sent[0]["type"] == f"{prefix}.response.start" and sent[0]["status"] == status
        body = sent[1]["body"].decode()
        assert body.startswith("refused: ") and word in body and body.count("\n") == 1


def test_a_cross_site_post_is_refused_by_its_origin():
    reached, sent = _asgi("http", {**HOST, "Origin": "http://evil.example",
                                   "Cookie": "jvl_studio_8080=s3cret-token"}, method="POST")
    assert not reached and sent[0]["status"] == 403
    reached, _ = _asgi("http", {**HOST, "Origin": "http://127.0.0.1:8080",
                                "Cookie": "jvl_studio_8080=s3cret-token"}, method="POST")
    assert reached


def test_the_token_opens_and_sets_the_cookie():
    reached, sent = _asgi("http", HOST, "token=s3cret-token&m=1")
    assert reached and (b"set-cookie", b"jvl_studio_8080=s3cret-token; Path=/; HttpOnly; "
                        b"SameSite=Strict") in sent[0]["headers"]
    for headers in ({"Cookie": "a=b; jvl_studio_8080=s3cret-token"},
                    {"Authorization": "Bearer s3cret-token"}, {"X-JVL-Token": "s3cret-token"}):
        reached, sent = _asgi("http", {**HOST, **headers})
        assert reached and not any(k == b"set-cookie" for k, _ in sent[0]["headers"])
    reached, _ = _asgi("websocket", {**HOST, "Origin": "http://localhost:8080",
                                     "Cookie": "jvl_studio_8080=s3cret-token"})
    assert reached


def _upload(headers: dict[str, str], chunks: list[bytes]) -> tuple[bytes, list[dict]]:
    """POST ``chunks`` through the lock to an app that reads the whole body and answers 200;
    return (what the app read, what was sent)."""
    read = bytearray()
    sent: list[dict] = []
    pending = [{"type": "http.request", "body": c, "more_body": k < len(chunks) - 1}
               for k, c in enumerate(chunks)]

    async def app(scope, receive, send) -> None:
        while True:
            message = await receive()
            if message["type"] == "http.disconnect":
                return  # as Starlette: the client is gone, nothing is answered
            read.extend(message.get("body", b""))
            if not message.get("more_body"):
                break
        await send({"type": "http.response.start", "status": 200, "headers": []})
        await send({"type": "http.response.body", "body": b"ok"})

    async def receive() -> dict:
        return pending.pop(0) if pending else {"type": "http.disconnect"}

    async def send(message) -> None:
        sent.append(message)

    scope = {"type": "http", "path": "/upload", "method": "POST", "query_string": b"",
             "headers": [(k.lower().encode(), v.encode())
                         for k, v in {**HOST, "X-JVL-Token": "s3cret-token", **headers}.items()]}
    _run(StudioLock(app, ACCESS)(scope, receive, send))
    return bytes(read), sent


def test_a_body_larger_than_the_studio_takes_is_refused():
    from jvl_gym.studio.lock import MAX_BODY_BYTES

    read, sent = _upload({"Content-Length": str(64 * 2**20)}, [b"x" * 1024])
    assert read == b"" and sent[0]["status"] == 413  # refused by its length, unread
    body = sent[1]["body"].decode()
    assert body.startswith("refused: ") and str(MAX_BODY_BYTES) in body and body.count("\n") == 1
    chunk = b"x" * (256 * 1024)
    read, sent = _upload({}, [chunk] * 8)  # chunked, no length: cut where it passes the limit
    assert len(read) <= MAX_BODY_BYTES and [m.get("status") for m in sent[:1]] == [413]
    read, sent = _upload({}, [chunk] * 4)  # within the limit: taken whole
    assert len(read) == 4 * len(chunk) and sent[0]["status"] == 200


def test_a_websocket_without_the_denial_extension_is_closed():
    """A server without the ASGI websocket denial response gets a close (it answers 403)."""
    sent: list[dict] = []

    async def app(scope, receive, send) -> None:
        raise AssertionError("reached the app")

    async def send(message) -> None:
        sent.append(message)

    scope = {"type": "websocket", "path": "/", "query_string": b"", "headers": [
        (b"host", b"evil.example")]}
    _run(StudioLock(app, ACCESS)(scope, None, send))
    assert sent == [{"type": "websocket.close", "code": 1008, "reason": sent[0]["reason"]}]


# ---------------------------------------------------------------------- the command line
def _cli(args, capsys) -> tuple[int, str, str]:
    from jvl_gym.cli.main import app

    with pytest.raises(SystemExit) as info:
        app(["studio", *args])
    out, err = capsys.readouterr()
    lines = [ln for ln in err.strip().splitlines() if not ln.startswith("jvl_gym: compil")]
    assert info.value.code not in (0, None) and len(lines) == 1 and "Traceback" not in err, err
    return info.value.code, lines[0], out


def test_a_bad_host_is_named(capsys):
    """An address that is no address (a number above 255) or not this machine's is an error
    about --host, not advice to take another --port."""
    for host in ("256.1.1.1", "1.2.3", "192.0.2.1"):  # 192.0.2.0/24: documentation only
        code, line, _ = _cli(["--host", host, "--no-browser", "--port", str(free_port())],
                             capsys)
        assert code == 1 and "--host" in line and "--port" not in line, line


def test_a_toolkit_that_is_no_toolkit_is_named(capsys):
    code, line, _ = _cli(["--toolkit", "json:dumps", "--no-browser", "--port",
                          str(free_port())], capsys)
    assert code == 1 and "--toolkit json:dumps" in line and "tuning toolkit" in line
    assert "<function" not in line and "function" in line


# ---------------------------------------------------------------------- over HTTP
@pytest.fixture(scope="module")
def served() -> Iterator[tuple[Studio, object]]:
    """A studio on a twin of an MAC140 at address 19 (``jvl-gym serve``)."""
    twin = start_twin(["MAC140"], [19])
    studio = None
    try:
        studio = Studio("--connect", f"socket://127.0.0.1:{twin.endpoint('mactalk', 'tcp').port}",
                        "--address", "19")
        yield studio, twin
    finally:
        if studio is not None:
            studio.stop()
        twin.stop()


def _refused(response, status: int, word: str) -> None:
    text = response.text
    assert response.status_code == status, (response.status_code, text[:200])
    assert text.startswith("refused: ") and word in text and text.count("\n") == 1


def test_http_rules(served):
    """Over HTTP: a foreign Host is refused (403) even with the token, no token or a wrong one
    is refused (401) for a page, NiceGUI's assets and an upload POST; the token in the query
    serves the page and sets the cookie, which then suffices, as do the script headers.
    The twin's registers are unchanged by all the refusals."""
    import httpx

    studio, twin = served
    before = twin_registers(twin)
    url = studio.url
    _refused(httpx.get(studio.with_token("/"), headers={"Host": "evil.example"}), 403, "Host")
    _refused(httpx.get(url + "/", headers={"Host": f"evil.example:{studio.port}"}), 403, "Host")
    _refused(httpx.get(url + "/"), 401, "token")
    _refused(httpx.get(url + "/registers?m=0&token=wrong"), 401, "token")
    _refused(httpx.get(url + "/_nicegui_ws/socket.io/?EIO=4&transport=polling"), 401, "token")
    _refused(httpx.post(url + "/_nicegui/client/x/upload/1",
                        files={"file": ("setup.yaml", b"registers: {A_SOLL: 5}\n")}),
             401, "token")
    _refused(httpx.post(url + "/_nicegui/client/x/upload/1", headers={
        "Origin": "http://evil.example", "X-JVL-Token": studio.token},
        files={"file": ("setup.yaml", b"registers: {A_SOLL: 5}\n")}), 403, "Origin")
    assert twin_registers(twin) == before
    with httpx.Client() as client:
        page = client.get(studio.with_token("/registers"))
        assert page.status_code == 200 and "jvl-gym studio" in page.text
        cookie = page.headers["set-cookie"]
        assert "HttpOnly" in cookie and "SameSite=Strict" in cookie
        assert client.get(url + "/scope").status_code == 200  # the cookie alone
    for headers in ({"Authorization": f"Bearer {studio.token}"}, {"X-JVL-Token": studio.token}):
        assert httpx.get(url + "/", headers=headers).status_code == 200
    assert httpx.get(f"http://localhost:{studio.port}/", headers={
        "X-JVL-Token": studio.token}).status_code == 200


def _upgrade(studio: Studio, headers: dict[str, str], query: str = "") -> tuple[int, str]:
    """A raw websocket upgrade of NiceGUI's live connection: the status line and the body."""
    request = (f"GET /_nicegui_ws/socket.io/?EIO=4&transport=websocket{query} HTTP/1.1\r\n"
               "Connection: Upgrade\r\nUpgrade: websocket\r\nSec-WebSocket-Version: 13\r\n"
               "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n"
               + "".join(f"{k}: {v}\r\n" for k, v in headers.items()) + "\r\n")
    with socket.create_connection(("127.0.0.1", studio.port), timeout=30) as sock:
        sock.sendall(request.encode())
        data = b""
        while b"\r\n\r\n" not in data:
            chunk = sock.recv(4096)
            if not chunk:
                break
            data += chunk
        head, _, body = data.partition(b"\r\n\r\n")
        status = int(head.split()[1])
        length = re.search(rb"(?i)content-length: (\d+)", head)
        while length and len(body) < int(length.group(1)):
            chunk = sock.recv(4096)
            if not chunk:
                break
            body += chunk
    return status, body.decode("utf-8", "replace")  # after a 101: websocket frames


def test_websocket_rules(served):
    """The websocket upgrade of the live connection: a foreign Origin (403), a foreign Host
    (403) and no token (401) are refused with their reason; the studio's own origin with the
    token (or its cookie) is switched (101)."""
    studio, twin = served
    before = twin_registers(twin)
    host = f"127.0.0.1:{studio.port}"
    own = f"http://{host}"
    cookie = f"jvl_studio_{studio.port}={studio.token}"
    status, body = _upgrade(studio, {"Host": host, "Origin": "http://evil.example",
                                     "Cookie": cookie})
    assert status == 403 and body.startswith("refused: Origin")
    status, body = _upgrade(studio, {"Host": "evil.example", "Origin": "http://evil.example"},
                            f"&token={studio.token}")
    assert status == 403 and body.startswith("refused: Host")
    status, body = _upgrade(studio, {"Host": host, "Origin": own})
    assert status == 401 and body.startswith("refused: ") and "token" in body
    assert _upgrade(studio, {"Host": host, "Origin": own, "Cookie": cookie})[0] == 101
    assert _upgrade(studio, {"Host": host, "Origin": own}, f"&token={studio.token}")[0] == 101
    assert twin_registers(twin) == before


def test_a_studio_open_to_the_network_warns_and_needs_the_token():
    """``--host 0.0.0.0``: a warning on stderr, and still the token."""
    import httpx

    studio = Studio("--host", "0.0.0.0")
    try:
        warning = "".join(studio.stderr)
        assert "warning: --host 0.0.0.0" in warning and "token" in warning
        assert studio.url.startswith("http://127.0.0.1:")
        _refused(httpx.get(studio.url + "/"), 401, "token")
        _refused(httpx.get(studio.url + "/", headers={"Host": "evil.example"}), 403, "Host")
        assert httpx.get(studio.with_token("/"), follow_redirects=True).status_code == 200
    finally:
        studio.stop()
