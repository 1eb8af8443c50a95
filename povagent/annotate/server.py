"""The annotation page's web server: loopback only, a token on every request, nothing else served.

Built on the standard library's :class:`~http.server.ThreadingHTTPServer` (no framework). It
binds 127.0.0.1 on a free port (or the one asked; a busy port is one line, never a traceback) and
prints one URL whose path carries a random token (:func:`secrets.token_urlsafe`):
``http://127.0.0.1:PORT/TOKEN/``. Everything the page loads lives below that path (its script,
style, state and images, by relative URLs), so every request carries the token, and nothing
carries it anywhere else: no cookie (a browser sends a cookie to every port of a host, so another
local server would receive it), no ``Referer`` (``no-referrer``); two sessions in one browser never
share anything. An answer also carries it in the ``X-Povagent-Token`` header. A request whose
``Host`` or ``Origin`` is not this server's own (another site, another port, a DNS-rebound name)
is refused. What it serves is a closed list: the page, its script and style, the state of the
session as JSON, and an image of the open question by question number and image index, resolved
here (no path from the client is ever joined to a folder). A strict Content-Security-Policy
allows the page's own script and style only; the page builds its text with ``textContent``
(dataset text is never markup).

A client has :attr:`AnnotateServer.client_timeout` seconds to send its whole request (one
deadline from the connection's opening, however it trickles its bytes: the connection is then
shut), and at most :data:`MAX_CONNECTIONS` connections are served at once (one more is closed
unread). Every refusal is a 4xx with its reason in JSON and one line on the log (never a request
line or a path: they carry the token); a body that is not JSON, or holds a string that is not
text (a lone surrogate), is a 400.
"""

from __future__ import annotations

import errno
import hmac
import json
import re
import secrets
import socket
import sys
import threading
import time
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from importlib import resources
from typing import Any, Callable, Protocol
from urllib.parse import urlsplit

from povagent.annotate.desk import AnswerRefused
from povagent.dataset.problems import not_text_problems
from povagent.errors import ConfigError

#: The headers every answer carries.
SECURITY_HEADERS = {
    "Content-Security-Policy": (
        "default-src 'none'; script-src 'self'; style-src 'self'; img-src 'self'; connect-src 'self'; "
        "base-uri 'none'; form-action 'none'; frame-ancestors 'none'"
    ),
    "X-Content-Type-Options": "nosniff",
    "Referrer-Policy": "no-referrer",
    "Cache-Control": "no-store",
    "X-Frame-Options": "DENY",
    "Cross-Origin-Resource-Policy": "same-origin",
}
TOKEN_HEADER = "X-Povagent-Token"
#: The page's files, by the only paths that name them (below the token).
ASSETS = {
    "": ("annotate.html", "text/html; charset=utf-8"),
    "annotate.js": ("annotate.js", "text/javascript; charset=utf-8"),
    "annotate.css": ("annotate.css", "text/css; charset=utf-8"),
}
IMAGE_PATH = re.compile(r"api/image/([0-9]{1,9})/([0-9]{1,4})")
#: The largest request body read (an answer or a judgement with its note).
MAX_BODY = 64 * 1024
#: The most connections served at once: a page loads its images a few at a time (a browser opens
#: six connections a server), so more is someone holding them.
MAX_CONNECTIONS = 32
#: How often the deadline of each connection is looked at.
_DEADLINE_TICK_S = 0.1
#: One line on the log (standard error by default).
Log = Callable[[str], None]


def _stderr_line(line: str) -> None:
    print(line, file=sys.stderr, flush=True)


class PageApp(Protocol):
    """What a mode of the page offers the server (answer mode, judge mode)."""

    def state(self) -> dict[str, Any]:
        """The session's state for the page as JSON (may wait briefly for a question)."""
        ...

    def image(self, number: int, index: int) -> tuple[bytes, str] | None:
        """The encoded bytes and media type of image ``index`` of item ``number``, or ``None``."""
        ...

    def post(self, action: str, body: dict[str, Any]) -> dict[str, Any]:
        """Take an action of the page (``answer``, ``judge``); raise :class:`AnswerRefused`
        for one that does not fit, ``KeyError`` for an unknown action."""
        ...


class AnnotateServer:
    """The server of one session: :attr:`url` is what the person opens."""

    def __init__(
        self, app: PageApp, port: int = 0, client_timeout: float = 30.0, *, max_connections: int = MAX_CONNECTIONS, log: Log = _stderr_line
    ) -> None:
        self.app = app
        #: seconds a client may take to send its whole request, from the connection's opening
        self.client_timeout = client_timeout
        self.token = secrets.token_urlsafe(32)
        self.log = log
        try:
            self.httpd = _BoundedServer(("127.0.0.1", port), _handler_for(self), max_connections, client_timeout, log)
        except OSError as exc:
            busy = " (another program is serving on it: pick another port, or 0 for a free one)" if exc.errno == errno.EADDRINUSE else ""
            raise ConfigError(f"--port {port}: cannot serve on 127.0.0.1:{port}: {exc.strerror or exc}{busy}") from None
        self.port = int(self.httpd.server_address[1])
        self._thread: threading.Thread | None = None

    @property
    def url(self) -> str:
        """The page's address with its token."""
        return f"http://127.0.0.1:{self.port}/{self.token}/"

    @property
    def origins(self) -> frozenset[str]:
        """The origins (and hosts) this server answers as."""
        return frozenset({f"127.0.0.1:{self.port}", f"localhost:{self.port}"})

    def start(self) -> None:
        """Serve in a background thread."""
        self._thread = threading.Thread(target=self.httpd.serve_forever, name="povagent-annotate", daemon=True)
        self._thread.start()
        self.httpd.deadlines.start()

    def close(self, grace_s: float = 3.0, told: threading.Event | None = None) -> None:
        """Stop serving and release the port.

        With ``told`` (set once a reply has told the page the session is over), serving goes on
        until it is set, ``grace_s`` at most: a page polls every fraction of a second, and its
        poll after the last answer would otherwise find the port closed. Then no new connection
        is taken, and the requests in flight get up to ``grace_s`` to be answered before their
        connections are closed."""
        if told is not None:
            told.wait(grace_s)
        self.httpd.shutdown()
        self.httpd.drain(grace_s)
        self.httpd.server_close()
        self.httpd.deadlines.stop()

    def token_ok(self, given: str | None) -> bool:
        """Whether ``given`` is this session's token (compared in constant time)."""
        return given is not None and hmac.compare_digest(given.encode(), self.token.encode())


class _Deadlines:
    """The connections still sending their request, each shut once its deadline passes (a
    per-read timeout lets a client trickling a byte at a time hold its thread for ever)."""

    def __init__(self, seconds: float) -> None:
        self.seconds = seconds
        self._open: dict[socket.socket, float] = {}
        self._lock = threading.Lock()
        self._stopped = threading.Event()
        self._thread = threading.Thread(target=self._watch, name="povagent-annotate-deadlines", daemon=True)

    def start(self) -> None:
        self._thread.start()

    def stop(self) -> None:
        self._stopped.set()

    def add(self, connection: socket.socket) -> None:
        with self._lock:
            self._open[connection] = time.monotonic() + self.seconds

    def done(self, connection: socket.socket) -> None:
        """The request is read whole (or the connection is over): no deadline any more."""
        with self._lock:
            self._open.pop(connection, None)

    def _watch(self) -> None:
        while not self._stopped.wait(_DEADLINE_TICK_S):
            now = time.monotonic()
            with self._lock:
                late = [c for c, at in self._open.items() if at <= now]
                for c in late:
                    del self._open[c]
            for c in late:
                try:  # the handler's read returns at once; its thread ends
                    c.shutdown(socket.SHUT_RDWR)
                except OSError:
                    pass


class _BoundedServer(ThreadingHTTPServer):
    """A threading server with a cap on connections and a deadline on each request."""

    daemon_threads = True

    def __init__(self, address: tuple[str, int], handler: type[BaseHTTPRequestHandler], max_connections: int, deadline_s: float, log: Log) -> None:
        self.slots = threading.BoundedSemaphore(max_connections)
        self.deadlines = _Deadlines(deadline_s)
        self.log = log
        self.in_flight = 0
        self.settled = threading.Condition()
        super().__init__(address, handler)

    def drain(self, grace_s: float) -> None:
        """Wait until no request is in flight, ``grace_s`` at most."""
        with self.settled:
            self.settled.wait_for(lambda: self.in_flight == 0, timeout=grace_s)

    def process_request(self, request: Any, client_address: Any) -> None:
        if not self.slots.acquire(blocking=False):
            self.log("povagent annotate: refused a connection: already serving the most connections at once")
            self.shutdown_request(request)  # closed unread: a flood holds no thread
            return
        self.deadlines.add(request)
        with self.settled:
            self.in_flight += 1
        try:
            super().process_request(request, client_address)
        except BaseException:
            self._ended(request)
            raise

    def process_request_thread(self, request: Any, client_address: Any) -> None:
        try:
            super().process_request_thread(request, client_address)
        finally:
            self._ended(request)

    def _ended(self, request: Any) -> None:
        self.deadlines.done(request)
        self.slots.release()
        with self.settled:
            self.in_flight -= 1
            self.settled.notify_all()

    def handle_error(self, request: Any, client_address: Any) -> None:
        exc = sys.exc_info()[1]
        if isinstance(exc, OSError):  # the client went away or its deadline passed: one line
            self.log(f"povagent annotate: a connection ended early ({type(exc).__name__})")
            return
        super().handle_error(request, client_address)  # a bug: its traceback


def _shown(reason: str) -> str:
    """A reason as one printable log line."""
    return reason.encode("ascii", "backslashreplace").decode("ascii").replace("\n", " ")[:200]


def _asset(name: str) -> bytes:
    return resources.files("povagent.annotate").joinpath("assets", name).read_bytes()


def _handler_for(server: AnnotateServer) -> type[BaseHTTPRequestHandler]:
    class Handler(BaseHTTPRequestHandler):
        server_version = "povagent-annotate"
        sys_version = ""
        #: no single read waits longer than the whole request may take
        timeout = server.client_timeout

        def log_message(self, format: str, *args: Any) -> None:  # noqa: A002 - the base class's name
            """Nothing: a request line carries the token (refusals log their own line)."""

        def send_error(self, code: int, message: str | None = None, explain: str | None = None) -> None:
            """The base class's errors (a malformed request line or header) as ours: JSON and one line."""
            self.close_connection = True
            self.request_version = "HTTP/1.0"  # a status line even for a request line that named none
            self.command = self.command or "malformed"
            self._refuse(code, message or "malformed request")

        # -- the gate every request passes ---------------------------------------------------
        def _route(self) -> tuple[str | None, tuple[int, str] | None]:
            """The path below the token, or why the request is refused."""
            if self.headers.get("Host", "") not in server.origins:
                return None, (403, "wrong host")
            origin = self.headers.get("Origin")
            if origin is not None and origin.removeprefix("http://") not in server.origins:
                return None, (403, "wrong origin")
            if self.headers.get("Sec-Fetch-Site", "same-origin") not in ("same-origin", "none"):
                return None, (403, "cross-site request")
            _, _, below = urlsplit(self.path).path.partition("/")
            token, slash, rest = below.partition("/")
            if not slash or not server.token_ok(token):
                return None, (401, "token missing or wrong")
            if self.command == "POST" and not server.token_ok(self.headers.get(TOKEN_HEADER)):
                return None, (401, "token header missing")
            return rest, None

        def _send(self, status: int, body: bytes, media_type: str) -> None:
            self.send_response(status)
            for k, v in SECURITY_HEADERS.items():
                self.send_header(k, v)
            self.send_header("Content-Type", media_type)
            self.send_header("Content-Length", str(len(body)))
            self.end_headers()
            if self.command != "HEAD":
                self.wfile.write(body)

        def _json(self, status: int, doc: Any) -> None:
            self._send(status, json.dumps(doc).encode(), "application/json")

        def _refuse(self, status: int, reason: str) -> None:
            """A 4xx (or 5xx) with its reason, and one line on the log."""
            server.log(f"povagent annotate: refused a {_shown(str(self.command))} request: {status} {_shown(reason)}")
            self._json(status, {"error": reason})

        # -- routes --------------------------------------------------------------------------
        def do_GET(self) -> None:
            server.httpd.deadlines.done(self.connection)  # no body: read whole with its headers
            rest, refused = self._route()
            if refused is not None or rest is None:
                return self._refuse(*(refused or (404, "not found")))
            if rest in ASSETS:
                name, media = ASSETS[rest]
                return self._send(200, _asset(name), media)
            if rest == "api/state":
                return self._json(200, server.app.state())
            match = IMAGE_PATH.fullmatch(rest)
            if match:
                found = server.app.image(int(match.group(1)), int(match.group(2)))
                if found is not None:
                    return self._send(200, found[0], found[1])
            self._refuse(404, "not found")

        def do_POST(self) -> None:
            rest, refused = self._route()
            if refused is not None or rest is None:
                server.httpd.deadlines.done(self.connection)
                return self._refuse(*(refused or (404, "not found")))
            try:
                length = int(self.headers.get("Content-Length", "0"))
            except ValueError:
                length = -1
            if not 0 <= length <= MAX_BODY:
                server.httpd.deadlines.done(self.connection)
                return self._refuse(413, f"a body of at most {MAX_BODY} bytes")
            raw = self.rfile.read(length)
            server.httpd.deadlines.done(self.connection)  # read whole: the answer may take its time
            if len(raw) < length:
                self.close_connection = True
                return self._refuse(400, "the body ended before its Content-Length")
            try:
                body = json.loads(raw or b"{}")
            except (ValueError, RecursionError):
                return self._refuse(400, "the body is not JSON")
            if not isinstance(body, dict):
                return self._refuse(400, "a JSON object")
            if not_text_problems("body", body):  # "\ud800": no results or judgements file can hold it
                return self._refuse(400, "the body holds a string that is not text (a lone surrogate)")
            if not rest.startswith("api/"):
                return self._refuse(404, "not found")
            try:
                self._json(200, server.app.post(rest.removeprefix("api/"), body))
            except AnswerRefused as exc:
                self._refuse(422, str(exc))
            except KeyError:
                self._refuse(404, "not found")

    return Handler
