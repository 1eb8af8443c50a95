"""A small read-only HTTP server for the run's images, for a model server on another host.

With ``images: {transport: http}`` the model server fetches each frame by URL instead of
receiving it base64-encoded in the request. This server answers those fetches, and nothing
else:

* it serves only files it was told about (:meth:`StaticImageServer.publish`), each under its
  content hash (``/<sha256>.png``): a URL never names a path, so no path can be guessed;
* a published file must lie inside one of the roots it was given (the dataset, the folder of
  derived images) once symlinks are resolved, when published and again when served: a
  symlink out of the dataset, or a file swapped for one later, is refused;
* the bytes served are the bytes the URL names: a file whose content changed since it was
  published (its SHA-256 is no longer the URL's hash) is refused with 409, never served;
* it is bounded: at most ``max_connections`` requests are served at once (more are told
  503) and four times as many connections are kept open; a connection waiting for a request
  is idle, and is closed after ``idle_timeout_s`` (5 s), or at once, oldest first, when a new
  connection needs its place, so idle or slow clients can never lock a real one out (only
  when every open connection is being served is a new one closed at once); a request being
  sent times out after 30 s, and the server stops with the run (a context manager).

It binds the address the user chose (``bind``), and hands out URLs under ``public_url`` (how
the model server reaches it; by default ``http://<bind>``). It only reads files; it never
writes, lists directories, or follows a URL path to the file system.
"""

from __future__ import annotations

import contextlib
import hashlib
import re
import socket
import sys
import threading
import time
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path
from typing import Any, Sequence

from povagent.config.addresses import parse_bind
from povagent.exchange.disconnects import QuietDisconnects

__all__ = ["ImageReferenceError", "StaticImageServer"]

_HASHED_NAME = re.compile(r"^/([0-9a-f]{64})\.(png|jpeg|jpg|webp|gif)$")
_EXTENSIONS = {"image/png": "png", "image/jpeg": "jpeg", "image/webp": "webp", "image/gif": "gif"}


class ImageReferenceError(ValueError):
    """An image cannot be sent by reference (outside the served roots, not a file...)."""


def inside(path: Path, roots: Sequence[Path]) -> Path:
    """``path`` with symlinks resolved, if it is a regular file inside one of ``roots`` (resolved).

    Raises :class:`ImageReferenceError` otherwise.
    """
    try:
        real = path.resolve(strict=True)
    except (OSError, RuntimeError) as exc:  # missing, or a symlink loop
        raise ImageReferenceError(f"{path}: cannot be served: {exc}") from None
    if not any(real.is_relative_to(root) for root in roots):
        shown = ", ".join(str(r) for r in roots)
        raise ImageReferenceError(f"{path}: resolves to {real}, outside the folders served ({shown}); refused")
    if not real.is_file():
        raise ImageReferenceError(f"{path}: not a regular file; refused")
    return real


class _Handler(BaseHTTPRequestHandler):
    protocol_version = "HTTP/1.1"
    # a client that stops reading the answer does not hold a thread for ever
    timeout = 30
    server: _Server

    def handle_one_request(self) -> None:
        """Wait for the next request at most the idle timeout (the connection is idle until served)."""
        self.connection.settimeout(self.server.owner.idle_timeout_s)
        super().handle_one_request()

    def log_message(self, format: str, *args: Any) -> None:  # noqa: A002 - stdlib signature
        """Silence the stdlib's per-request stderr log."""

    def do_GET(self) -> None:  # noqa: N802 - stdlib name
        """The published file named by the URL's hash, or 404/403."""
        self._serve(body=True)

    def do_HEAD(self) -> None:  # noqa: N802 - stdlib name
        """As GET, without the body."""
        self._serve(body=False)

    def _serve(self, body: bool) -> None:
        owner = self.server.owner
        if not owner._connections.acquire(blocking=False):
            self._send_status(503, "too many connections")
            return
        owner._mark_busy(self.connection, True)
        self.connection.settimeout(self.timeout)
        try:
            match = _HASHED_NAME.match(self.path.split("?", 1)[0])
            named = match.group(1) if match else None
            entry = owner._published.get(named) if named else None
            if entry is None:
                owner.refused += 1
                self._send_status(404, "not published")
                return
            try:
                real = inside(entry[0], owner.roots)  # again: the file may have been swapped since
                data = real.read_bytes()
            except (ImageReferenceError, OSError):
                owner.refused += 1
                self._send_status(403, "refused")
                return
            if hashlib.sha256(data).hexdigest() != named:
                # changed since published (swapped inside the dataset): not the image the URL names
                owner.refused += 1
                self._send_status(409, "changed since published")
                return
            # counted before the bytes go out: a client that has read the body sees the count
            owner.served += 1
            self.send_response(200)
            self.send_header("Content-Type", entry[1])
            self.send_header("Content-Length", str(len(data)))
            self.send_header("Cache-Control", "public, max-age=86400, immutable")
            self.end_headers()
            if body:
                self.wfile.write(data)
        finally:
            owner._mark_busy(self.connection, False)
            owner._connections.release()

    def _send_status(self, status: int, text: str) -> None:
        data = text.encode()
        self.send_response(status)
        self.send_header("Content-Type", "text/plain")
        self.send_header("Content-Length", str(len(data)))
        self.end_headers()
        self.wfile.write(data)

    def do_POST(self) -> None:  # noqa: N802 - stdlib name
        """Read-only: every other method is refused."""
        self.close_connection = True
        self._send_status(405, "read-only")

    do_PUT = do_DELETE = do_PATCH = do_POST  # noqa: N815


class _Server(QuietDisconnects, ThreadingHTTPServer):
    daemon_threads = True
    block_on_close = False
    request_queue_size = 128
    owner: StaticImageServer

    def process_request(self, request: Any, client_address: Any) -> None:
        """One thread per connection, up to the bound; at the bound the oldest idle connection
        makes room, and only when none is idle is the new connection closed at once."""
        owner = self.owner
        with owner._lock:
            full = len(owner._idle_since) >= owner.max_open_connections and not owner._close_oldest_idle()
            if not full:
                owner._idle_since[request] = time.monotonic()
        if full:
            self.shutdown_request(request)
            return
        super().process_request(request, client_address)

    def process_request_thread(self, request: Any, client_address: Any) -> None:
        """Serve one connection; count it closed afterwards."""
        try:
            super().process_request_thread(request, client_address)
        finally:
            with self.owner._lock:
                self.owner._idle_since.pop(request, None)

    def handle_error(self, request: Any, client_address: Any) -> None:
        """A client gone mid-answer (or a connection closed to make room) is not a server error;
        anything else is a bug and keeps its traceback."""
        if not isinstance(sys.exc_info()[1], OSError):
            super().handle_error(request, client_address)


class _Server6(_Server):
    """The same server on an IPv6 address."""

    address_family = socket.AF_INET6


class StaticImageServer:
    """Published image files, read-only over HTTP at ``bind``; see the module docstring.

    ``roots``: the folders files may lie in. ``bind``: ``host:port`` to listen on (port 0
    picks a free one). ``public_url``: the base of the URLs handed out (default
    ``http://<host>:<port>`` of the bound socket).
    """

    def __init__(
        self,
        roots: Sequence[str | Path],
        *,
        bind: str = "127.0.0.1:0",
        public_url: str | None = None,
        max_connections: int = 64,
        idle_timeout_s: float = 5.0,
    ) -> None:
        if not roots:
            raise ValueError("a static image server needs at least one root folder")
        self.roots = tuple(Path(r).resolve() for r in roots)
        self.host, self.port = parse_bind(bind)
        self._public_url = public_url.rstrip("/") if public_url else None
        self._connections = threading.BoundedSemaphore(max_connections)
        #: open (kept-alive) connections allowed, each holding a thread for at most its timeout
        self.max_open_connections = 4 * max_connections
        #: how long a connection may wait for its next request before it is closed
        self.idle_timeout_s = idle_timeout_s
        #: open connections: since when each is idle (waiting for a request), ``None`` while served
        self._idle_since: dict[Any, float | None] = {}
        #: idle connections closed to make room for a new one
        self.closed_idle = 0
        self._published: dict[str, tuple[Path, str]] = {}
        self._lock = threading.Lock()
        self._server: _Server | None = None
        self._thread: threading.Thread | None = None
        self.served = 0
        self.refused = 0

    # -- lifecycle ----------------------------------------------------------------------------
    def start(self) -> StaticImageServer:
        """Bind and serve in a daemon thread; returns ``self``. A taken port is an OSError."""
        if self._server is not None:
            return self
        server_class = _Server6 if ":" in self.host else _Server  # ":": an IPv6 address
        server = server_class((self.host, self.port), _Handler)
        server.owner = self
        self._server = server
        self.port = server.server_address[1]
        self._thread = threading.Thread(target=server.serve_forever, kwargs={"poll_interval": 0.1}, daemon=True,
                                        name=f"image-server-{self.port}")
        self._thread.start()
        return self

    def stop(self) -> None:
        """Stop serving and close the socket (safe to call twice)."""
        server, self._server = self._server, None
        if server is None:
            return
        server.shutdown()
        server.server_close()
        if self._thread is not None:
            self._thread.join(timeout=5)

    def __enter__(self) -> StaticImageServer:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    @property
    def base_url(self) -> str:
        """The URL prefix handed out (``public_url``, or the bound address)."""
        if self._public_url:
            return self._public_url
        host = f"[{self.host}]" if ":" in self.host else self.host
        return f"http://{host}:{self.port}"

    @property
    def _open_connections(self) -> int:
        """Connections open now (idle or being served)."""
        return len(self._idle_since)

    def _mark_busy(self, connection: Any, busy: bool) -> None:
        with self._lock:
            if connection in self._idle_since:  # not if closed to make room meanwhile
                self._idle_since[connection] = None if busy else time.monotonic()

    def _close_oldest_idle(self) -> bool:
        """Close the connection idle longest (under ``_lock``); ``False`` when none is idle."""
        idle = [(since, id(c), c) for c, since in self._idle_since.items() if since is not None]
        if not idle:
            return False
        _, _, oldest = min(idle, key=lambda t: (t[0], t[1]))
        del self._idle_since[oldest]
        with contextlib.suppress(OSError):  # its thread, blocked reading, sees the end and exits
            oldest.shutdown(socket.SHUT_RDWR)
        self.closed_idle += 1
        return True

    # -- publishing ---------------------------------------------------------------------------
    def publish(self, path: str | Path, image_hash: str, media_type: str = "image/png") -> str:
        """Serve the file ``path`` (whose content hash is ``image_hash``); return its URL.

        Raises :class:`ImageReferenceError` when the file is outside the roots (symlinks
        resolved) or not a regular file.
        """
        if not re.fullmatch(r"[0-9a-f]{64}", image_hash):
            raise ImageReferenceError(f"{image_hash!r} is not a SHA-256 hex digest")
        ext = _EXTENSIONS.get(media_type)
        if ext is None:
            raise ImageReferenceError(f"{path}: media type {media_type!r} is not served")
        inside(Path(path), self.roots)
        with self._lock:
            self._published.setdefault(image_hash, (Path(path), media_type))
        return f"{self.base_url}/{image_hash}.{ext}"

    @property
    def published(self) -> int:
        """How many files are served."""
        return len(self._published)
