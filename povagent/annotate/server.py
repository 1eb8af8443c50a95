"""The annotation page's web server: loopback only, a token on every request, nothing else served.

Built on the standard library's :class:`~http.server.ThreadingHTTPServer` (no framework). It
binds 127.0.0.1 on a free port and prints one URL carrying a random token
(:func:`secrets.token_urlsafe`). Every request must carry that token: the page's URL (its
first load sets a strict same-site cookie, which the page's images then carry) or, for the API,
the ``X-Povagent-Token`` header; a request whose ``Host`` or ``Origin`` is not this server's
own (another site, a DNS-rebound name) is refused. What it serves is a closed list: the page,
its script and style, the state of the session as JSON, and an image of the open question by
question number and image index, resolved here (no path from the client is ever joined to a
folder). A strict Content-Security-Policy allows the page's own script and style only; the page
builds its text with ``textContent`` (dataset text is never markup). Request lines are not
logged (the token is in the URL).
"""

from __future__ import annotations

import hmac
import json
import re
import secrets
import threading
from http.cookies import SimpleCookie
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from importlib import resources
from typing import Any, Protocol
from urllib.parse import parse_qs, urlsplit

from povagent.annotate.desk import AnswerRefused

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
COOKIE = "povagent_annotate"
TOKEN_HEADER = "X-Povagent-Token"
#: The page's files, by the only paths that name them.
ASSETS = {"/": ("annotate.html", "text/html; charset=utf-8"), "/annotate.js": ("annotate.js", "text/javascript; charset=utf-8"),
          "/annotate.css": ("annotate.css", "text/css; charset=utf-8")}  # fmt: skip
IMAGE_PATH = re.compile(r"/api/image/([0-9]{1,9})/([0-9]{1,4})")
#: The largest request body read (an answer or a judgement with its note).
MAX_BODY = 64 * 1024


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

    def __init__(self, app: PageApp, port: int = 0, client_timeout: float = 60.0) -> None:
        self.app = app
        #: seconds a client may take to send its request
        self.client_timeout = client_timeout
        self.token = secrets.token_urlsafe(32)
        self.httpd = ThreadingHTTPServer(("127.0.0.1", port), _handler_for(self))
        self.httpd.daemon_threads = True
        self.port = int(self.httpd.server_address[1])
        self._thread: threading.Thread | None = None

    @property
    def url(self) -> str:
        """The page's address with its token."""
        return f"http://127.0.0.1:{self.port}/?token={self.token}"

    @property
    def origins(self) -> frozenset[str]:
        """The origins (and hosts) this server answers as."""
        return frozenset({f"127.0.0.1:{self.port}", f"localhost:{self.port}"})

    def start(self) -> None:
        """Serve in a background thread."""
        self._thread = threading.Thread(target=self.httpd.serve_forever, name="povagent-annotate", daemon=True)
        self._thread.start()

    def close(self) -> None:
        """Stop serving and release the port."""
        self.httpd.shutdown()
        self.httpd.server_close()

    def token_ok(self, given: str | None) -> bool:
        """Whether ``given`` is this session's token (compared in constant time)."""
        return given is not None and hmac.compare_digest(given.encode(), self.token.encode())


def _asset(name: str) -> bytes:
    return resources.files("povagent.annotate").joinpath("assets", name).read_bytes()


def _handler_for(server: AnnotateServer) -> type[BaseHTTPRequestHandler]:
    class Handler(BaseHTTPRequestHandler):
        server_version = "povagent-annotate"
        sys_version = ""
        #: a body promised and never sent is no wait forever
        timeout = server.client_timeout

        def log_message(self, format: str, *args: Any) -> None:  # noqa: A002 - the base class's name
            """Nothing: a request line carries the token."""

        # -- the gate every request passes ---------------------------------------------------
        def _refusal(self, *, api: bool) -> tuple[int, str] | None:
            if self.headers.get("Host", "") not in server.origins:
                return 403, "wrong host"
            origin = self.headers.get("Origin")
            if origin is not None and origin.removeprefix("http://") not in server.origins:
                return 403, "wrong origin"
            if self.headers.get("Sec-Fetch-Site", "same-origin") not in ("same-origin", "none"):
                return 403, "cross-site request"
            if server.token_ok(self.headers.get(TOKEN_HEADER)):
                return None
            if api and self.command == "POST":
                return 401, "token header missing"
            cookie = SimpleCookie()
            try:
                cookie.load(self.headers.get("Cookie", ""))
            except Exception:
                pass
            if COOKIE in cookie and server.token_ok(cookie[COOKIE].value):
                return None
            query = parse_qs(urlsplit(self.path).query).get("token")
            if query and server.token_ok(query[0]):
                return None
            return 401, "token missing or wrong"

        def _send(self, status: int, body: bytes, media_type: str, extra: dict[str, str] | None = None) -> None:
            self.send_response(status)
            for k, v in {**SECURITY_HEADERS, **(extra or {})}.items():
                self.send_header(k, v)
            self.send_header("Content-Type", media_type)
            self.send_header("Content-Length", str(len(body)))
            self.end_headers()
            if self.command != "HEAD":
                self.wfile.write(body)

        def _json(self, status: int, doc: Any) -> None:
            self._send(status, json.dumps(doc).encode(), "application/json")

        # -- routes --------------------------------------------------------------------------
        def do_GET(self) -> None:
            path = urlsplit(self.path).path
            refused = self._refusal(api=path.startswith("/api/"))
            if refused is not None:
                return self._json(refused[0], {"error": refused[1]})
            if path in ASSETS:
                name, media = ASSETS[path]
                cookie = f"{COOKIE}={server.token}; Path=/; HttpOnly; SameSite=Strict"
                return self._send(200, _asset(name), media, {"Set-Cookie": cookie} if path == "/" else None)
            if path == "/api/state":
                return self._json(200, server.app.state())
            match = IMAGE_PATH.fullmatch(path)
            if match:
                found = server.app.image(int(match.group(1)), int(match.group(2)))
                if found is not None:
                    return self._send(200, found[0], found[1])
            self._json(404, {"error": "not found"})

        def do_POST(self) -> None:
            path = urlsplit(self.path).path
            refused = self._refusal(api=True)
            if refused is not None:
                return self._json(refused[0], {"error": refused[1]})
            try:
                length = int(self.headers.get("Content-Length", "0"))
            except ValueError:
                length = -1
            if not 0 <= length <= MAX_BODY:
                return self._json(413, {"error": f"a body of at most {MAX_BODY} bytes"})
            try:
                body = json.loads(self.rfile.read(length) or b"{}")
            except (ValueError, RecursionError):
                return self._json(400, {"error": "the body is not JSON"})
            if not isinstance(body, dict) or not path.startswith("/api/"):
                return self._json(404 if isinstance(body, dict) else 400, {"error": "not found" if isinstance(body, dict) else "a JSON object"})
            try:
                self._json(200, server.app.post(path.removeprefix("/api/"), body))
            except AnswerRefused as exc:
                self._json(422, {"error": str(exc)})
            except KeyError:
                self._json(404, {"error": "not found"})

    return Handler
