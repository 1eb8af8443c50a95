"""The base of povagent's loopback test servers: an HTTP server on 127.0.0.1 in a daemon thread.

:class:`~povagent.testing.loopback_server.LoopbackServer` (an OpenAI-compatible endpoint) and
:class:`~povagent.testing.hub_server.HubServer` (a Hugging Face Hub) share how they start, stop
themselves after ``max_lifetime_s``, track their kept-alive connections and cut them on
:meth:`BackgroundServer.stop`, so that a stopped server looks like a network failure to every
client rather than an answer from a lingering thread. What each serves is its own handler's job.
"""

from __future__ import annotations

import socket
import threading
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from typing import Any, ClassVar, Self

from povagent.exchange.disconnects import QuietDisconnects


class TrackedHTTPServer(QuietDisconnects, ThreadingHTTPServer):
    """A threading HTTP server that tells its :class:`BackgroundServer` of every open connection."""

    daemon_threads = True
    block_on_close = False
    owner: BackgroundServer

    def process_request(self, request: Any, client_address: Any) -> None:
        """Track each open connection, so :meth:`BackgroundServer.stop` can close it."""
        with self.owner._lock:
            self.owner._connections.add(request)
        super().process_request(request, client_address)

    def shutdown_request(self, request: Any) -> None:
        """Forget a connection as it closes."""
        with self.owner._lock:
            self.owner._connections.discard(request)
        super().shutdown_request(request)


class BackgroundServer:
    """Serve ``handler`` with ``server_class`` on 127.0.0.1 in a daemon thread (``port=0``: a
    free port); the server stops itself after ``max_lifetime_s`` seconds. Use it as a context
    manager, or :meth:`start` and :meth:`stop`."""

    #: The server class (a :class:`TrackedHTTPServer`) and the request handler.
    server_class: ClassVar[type[TrackedHTTPServer]] = TrackedHTTPServer
    handler: ClassVar[type[BaseHTTPRequestHandler]]
    #: The serving thread's name, before its port.
    thread_name: ClassVar[str] = "background-server"
    #: How :meth:`stop` cuts a kept-alive connection (``SHUT_RD`` lets an answer being written
    #: still reach its client).
    cut_connections: ClassVar[int] = socket.SHUT_RD

    def __init__(self, port: int = 0, max_lifetime_s: float = 120.0) -> None:
        self.port = port
        self.max_lifetime_s = max_lifetime_s
        self._lock = threading.Lock()
        #: Set by :meth:`stop`: a handler waiting (a delayed answer, a stall) wakes on it.
        self._stopping = threading.Event()
        self._server: TrackedHTTPServer | None = None
        self._thread: threading.Thread | None = None
        self._timer: threading.Timer | None = None
        #: open client connections (kept alive between requests), closed by :meth:`stop`
        self._connections: set[socket.socket] = set()

    def start(self) -> Self:
        """Bind 127.0.0.1 and serve in a daemon thread; returns ``self``."""
        if self._server is not None:
            return self
        self._stopping.clear()
        server = self.server_class(("127.0.0.1", self.port), self.handler)
        server.owner = self
        self._server = server
        self.port = server.server_address[1]
        self._thread = threading.Thread(
            target=server.serve_forever, kwargs={"poll_interval": 0.05}, daemon=True, name=f"{self.thread_name}-{self.port}"
        )
        self._thread.start()
        self._timer = threading.Timer(self.max_lifetime_s, self.stop)
        self._timer.daemon = True
        self._timer.start()
        return self

    def stop(self) -> None:
        """Stop serving, wake every waiting handler, close the socket and every kept-alive
        connection (a later request is refused, as on a network failure). Safe to call twice."""
        self._stopping.set()
        server, self._server = self._server, None
        if self._timer is not None and self._timer is not threading.current_thread():
            self._timer.cancel()
        if server is None:
            return
        server.shutdown()
        server.server_close()
        with self._lock:
            connections, self._connections = list(self._connections), set()
        for connection in connections:
            try:
                connection.shutdown(self.cut_connections)
            except OSError:
                pass
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join(timeout=5)

    def __enter__(self) -> Self:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()
