"""The studio's door: who may reach its pages, uploads, writes and live connection.

The studio moves motors, so it is locked as a notebook server is. :class:`StudioLock` is a
pure ASGI middleware in front of the whole application, so it sees every HTTP request *and*
every websocket upgrade (NiceGUI's live connection at ``/_nicegui_ws/socket.io/``, polling and
websocket alike); an HTTP-only middleware function would never see the upgrades. Its rules, in
order:

1. **Host**: the ``Host`` header must name this studio (:meth:`Access.host_allowed`: localhost,
   127.0.0.1, ::1 and the listening host, with or without the port). A page that a foreign
   name resolves to (DNS rebinding) is refused with 403.
2. **Origin**: a websocket, and any HTTP request that is not a GET or HEAD, whose ``Origin`` is
   present must come from the studio itself (``http://<allowed host>:<port>``); else 403.
3. **Token**: a secret made at each start (:func:`new_token`) must come with the request, as
   the query parameter ``token`` (the URL the studio prints), the cookie
   :meth:`Access.cookie_name`, or the header ``Authorization: Bearer <token>`` or
   ``X-JVL-Token`` (for scripts); else 401. A request that brings the right token in its query
   gets the cookie (HttpOnly, SameSite=Strict), which carries the later requests.

4. **Size**: a request body (a setup file's upload, a form) of more than
   :data:`MAX_BODY_BYTES` is refused with 413: by its ``Content-Length`` before any of it is
   read, and a body without one (chunked) as soon as it passes the limit (the application then
   reads the end of the body and answers nothing; the lock answers 413).

A refused request gets a one-line plain-text reason and never reaches the application: it
changes nothing. Tokens are compared with :func:`hmac.compare_digest`.
"""

from __future__ import annotations

import hmac
import ipaddress
import secrets
from collections.abc import Awaitable, Callable, Iterable, MutableMapping
from http.cookies import CookieError, SimpleCookie
from typing import Any
from urllib.parse import parse_qs, urlsplit

__all__ = ["Access", "StudioLock", "new_token", "is_loopback", "LOOPBACK_NAMES", "TOKEN_PARAM",
           "TOKEN_HEADER", "MAX_BODY_BYTES"]

#: the names of this machine's loopback that every studio answers to
LOOPBACK_NAMES = ("localhost", "127.0.0.1", "::1")
TOKEN_PARAM = "token"  #: the query parameter that carries the token
TOKEN_HEADER = "x-jvl-token"  #: the header that carries the token (besides Authorization)
#: the largest request body the studio takes [bytes]: a setup file of every register of a motor
#: is a few kilobytes
MAX_BODY_BYTES = 1 << 20
#: methods that read only: no Origin check (a browser sends one on its own page's POSTs)
_SAFE_METHODS = frozenset({"GET", "HEAD"})

Scope = MutableMapping[str, Any]
Message = MutableMapping[str, Any]
Receive = Callable[[], Awaitable[Message]]
Send = Callable[[Message], Awaitable[None]]
ASGIApp = Callable[[Scope, Receive, Send], Awaitable[None]]


def new_token() -> str:
    """A fresh secret for one start of the studio (32 random bytes, URL-safe)."""
    return secrets.token_urlsafe(32)


def is_loopback(host: str) -> bool:
    """Whether ``host`` (a listening address or name) reaches this machine only."""
    host = host.strip("[]")
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def _bare(host: str) -> str:
    """``host`` without brackets, lower case (``"[::1]"`` → ``"::1"``)."""
    return host.strip().strip("[]").lower()


def split_host(value: str) -> tuple[str, int | None]:
    """A ``Host`` header (or an origin's netloc) as (name, port or None).

    ``"127.0.0.1:8080"`` → ("127.0.0.1", 8080), ``"[::1]"`` → ("::1", None), ``"::1"`` →
    ("::1", None); a malformed port gives ("", None), which no allow-list holds.
    """
    value = value.strip()
    if value.startswith("["):
        name, _, rest = value[1:].partition("]")
        port_text = rest[1:] if rest.startswith(":") else None
        if rest and port_text is None:
            return "", None
    elif value.count(":") == 1:
        name, _, port_text = value.partition(":")
    else:  # a bare name, or a bare IPv6 address without brackets
        name, port_text = value, None
    if port_text is None:
        return name.lower(), None
    if not port_text.isdigit():
        return "", None
    return name.lower(), int(port_text)


class Access:
    """Who may reach one studio.

    Parameters
    ----------
    token : str
        The secret of this start.
    port : int
        The port the studio listens on.
    hosts : iterable of str
        Names and addresses the studio answers to beyond :data:`LOOPBACK_NAMES` (the
        ``--host`` it listens on, and for a wildcard host this machine's names).

    Raises
    ------
    ValueError
        An empty token.
    """

    def __init__(self, token: str, port: int, hosts: Iterable[str] = ()) -> None:
        if not token:
            raise ValueError("the studio's token must not be empty")
        self.token = token
        self.port = int(port)
        #: the names the studio answers to, lower case, without brackets
        self.hosts = frozenset(_bare(h) for h in (*LOOPBACK_NAMES, *hosts) if _bare(h))

    def cookie_name(self) -> str:
        """The cookie that carries the token (per port: cookies do not tell ports apart)."""
        return f"jvl_studio_{self.port}"

    def host_allowed(self, value: str) -> bool:
        """Whether a ``Host`` header names this studio: an allowed name, with no port or
        with the studio's port."""
        name, port = split_host(value)
        return name in self.hosts and port in (None, self.port)

    def origin_allowed(self, origin: str) -> bool:
        """Whether ``origin`` is the studio's own (``http://<allowed host>:<port>``)."""
        parts = urlsplit(origin)
        if parts.scheme not in ("http", "https"):
            return False
        name, port = split_host(parts.netloc)
        if port is None:
            port = 443 if parts.scheme == "https" else 80
        return name in self.hosts and port == self.port

    def token_matches(self, given: str | None) -> bool:
        """Whether ``given`` is this start's token (compared in constant time)."""
        if not given:
            return False
        return hmac.compare_digest(given.encode("utf-8", "replace"),
                                   self.token.encode("utf-8"))

    def path(self, path: str = "/") -> str:
        """``path`` with the token as its query (``/?token=…``)."""
        return f"{path}?{TOKEN_PARAM}={self.token}"

    def url(self, host: str, path: str = "/") -> str:
        """The URL that opens ``path`` with the token (``http://127.0.0.1:8080/?token=…``);
        a wildcard ``host`` (0.0.0.0, ::) is shown as 127.0.0.1."""
        shown = _bare(host)
        if shown in ("0.0.0.0", "::", ""):
            shown = "127.0.0.1"
        if ":" in shown:
            shown = f"[{shown}]"
        return f"http://{shown}:{self.port}{self.path(path)}"


def _headers(scope: Scope) -> dict[str, str]:
    """The request's headers, lower-case name → value (the first of repeated ones)."""
    out: dict[str, str] = {}
    for key, value in scope.get("headers", ()):
        out.setdefault(key.decode("latin-1").lower(), value.decode("latin-1"))
    return out


class Refusal(Exception):
    """A request the lock refuses: the HTTP status and a one-line reason."""

    def __init__(self, status: int, reason: str) -> None:
        super().__init__(reason)
        self.status = status
        self.reason = reason


class StudioLock:
    """ASGI middleware that lets through only what :class:`Access` allows (module docstring).

    Parameters
    ----------
    app : ASGI application
        The studio (NiceGUI's FastAPI application).
    access : Access
        Who may reach it.
    """

    def __init__(self, app: ASGIApp, access: Access) -> None:
        self.app = app
        self.access = access

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] not in ("http", "websocket"):  # lifespan
            await self.app(scope, receive, send)
            return
        try:
            from_query = self.check(scope)
        except Refusal as refusal:
            await self._refuse(scope, send, refusal)
            return
        if from_query and scope["type"] == "http":
            send = self._with_cookie(send)
        if scope["type"] == "http":
            await self._bounded(scope, receive, send)
            return
        await self.app(scope, receive, send)

    async def _bounded(self, scope: Scope, receive: Receive, send: Send) -> None:
        """Pass an HTTP request on whose body stays within :data:`MAX_BODY_BYTES`; answer 413
        for one that passes it (the application gets a disconnect in place of the rest)."""
        too_big = Refusal(413, f"refused: the request's body is larger than the studio takes "
                          f"({MAX_BODY_BYTES} bytes)")
        size = _headers(scope).get("content-length", "")
        if size.isdigit() and int(size) > MAX_BODY_BYTES:
            await self._refuse(scope, send, too_big)
            return
        state = {"read": 0, "over": False, "started": False}

        async def bounded_receive() -> Message:
            if state["over"]:
                return {"type": "http.disconnect"}
            message = await receive()
            if message["type"] == "http.request":
                state["read"] += len(message.get("body", b""))
                if state["read"] > MAX_BODY_BYTES:
                    state["over"] = True
                    return {"type": "http.disconnect"}
            return message

        async def watched_send(message: Message) -> None:
            if state["over"] and not state["started"]:
                return  # the lock answers
            state["started"] = True
            await send(message)

        try:
            await self.app(scope, bounded_receive, watched_send)
        except Exception:
            if not state["over"]:
                raise
        if state["over"] and not state["started"]:
            await self._refuse(scope, send, too_big)

    def check(self, scope: Scope) -> bool:
        """Apply the rules to a request; return whether the token came in its query.

        Raises
        ------
        Refusal
            The rule the request breaks, with its status and reason.
        """
        headers = _headers(scope)
        host = headers.get("host", "")
        if not self.access.host_allowed(host):
            raise Refusal(403, f"refused: Host {host[:80]!r} is not this studio's address "
                          "(open the URL the studio printed)")
        origin = headers.get("origin")
        checks_origin = (scope["type"] == "websocket"
                         or scope.get("method", "GET") not in _SAFE_METHODS)
        if origin is not None and checks_origin and not self.access.origin_allowed(origin):
            raise Refusal(403, f"refused: Origin {origin[:80]!r} is not this studio's page")
        query = parse_qs(scope.get("query_string", b"").decode("latin-1"))
        if any(self.access.token_matches(t) for t in query.get(TOKEN_PARAM, ())):
            return True
        if self.access.token_matches(self._cookie(headers)):
            return False
        auth = headers.get("authorization", "")
        scheme, _, credential = auth.partition(" ")
        if scheme.lower() == "bearer" and self.access.token_matches(credential.strip()):
            return False
        if self.access.token_matches(headers.get(TOKEN_HEADER)):
            return False
        raise Refusal(401, "refused: the studio's token is missing or wrong (open the URL with "
                      "?token=... that the studio printed)")

    def _cookie(self, headers: dict[str, str]) -> str | None:
        jar: SimpleCookie = SimpleCookie()
        try:
            jar.load(headers.get("cookie", ""))
        except CookieError:
            return None
        morsel = jar.get(self.access.cookie_name())
        return morsel.value if morsel is not None else None

    def _with_cookie(self, send: Send) -> Send:
        """``send`` that adds the token's cookie to the response's headers."""
        cookie = (f"{self.access.cookie_name()}={self.access.token}; Path=/; HttpOnly; "
                  "SameSite=Strict").encode("latin-1")

        async def send_with_cookie(message: Message) -> None:
            if message["type"] == "http.response.start":
                message = dict(message)
                message["headers"] = [*message.get("headers", ()), (b"set-cookie", cookie)]
            await send(message)
        return send_with_cookie

    @staticmethod
    async def _refuse(scope: Scope, send: Send, refusal: Refusal) -> None:
        """Answer ``refusal``: a plain-text response, or for a websocket the same as its
        upgrade's response where the server offers it (else a close, which the server sends
        as 403)."""
        body = (refusal.reason + "\n").encode("utf-8")
        headers = [(b"content-type", b"text/plain; charset=utf-8"),
                   (b"content-length", str(len(body)).encode())]
        if scope["type"] == "http":
            await send({"type": "http.response.start", "status": refusal.status,
                        "headers": headers})
            await send({"type": "http.response.body", "body": body})
            return
        if "websocket.http.response" in scope.get("extensions", {}):
            await send({"type": "websocket.http.response.start", "status": refusal.status,
                        "headers": headers})
            await send({"type": "websocket.http.response.body", "body": body})
        else:
            await send({"type": "websocket.close", "code": 1008, "reason": refusal.reason})
