"""An OpenAI-compatible chat server on 127.0.0.1 for tests, benchmarks and plugin authors.

It answers ``POST /v1/chat/completions`` with scripted replies, records every request body
(so a test can check which images, labels, prompt text and generation parameters arrived), and
injects faults: an HTTP status (429 with ``Retry-After``, 500, 400, 401...), a delay, or a
dropped connection (the socket closed without a response).

It is bounded so a forgotten server can never hang a test run: it listens on loopback only,
stops by itself after ``max_lifetime_s``, and every delay is cut short when it stops. It holds
no state beyond one server: nothing here is global, and it never touches the network beyond
127.0.0.1.

Use it as a context manager::

    with LoopbackServer(reply='{"x": 1, "y": 2}') as server:
        litellm.completion(model="openai/test", api_base=server.url, api_key="x", messages=...)
        assert server.requests[0].body["max_tokens"] == 256
"""

from __future__ import annotations

import argparse
import collections
import json
import socket
import threading
import time
from dataclasses import dataclass
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from typing import Any, Callable, Iterable

__all__ = ["Fault", "Reply", "RecordedRequest", "LoopbackServer"]


@dataclass(frozen=True)
class Reply:
    """A successful answer: the assistant's text, after ``delay_s``, with token counts.

    ``text=None`` sends ``content: null``; ``no_choices=True`` sends an empty ``choices`` list
    (both seen from real servers under load, and neither is an answer).
    """

    text: str | None
    delay_s: float = 0.0
    prompt_tokens: int = 10
    completion_tokens: int = 5
    no_choices: bool = False


@dataclass(frozen=True)
class Fault:
    """A failure to inject.

    ``status`` sends that HTTP status with an OpenAI-style error body (and ``Retry-After`` when
    ``retry_after`` is set); ``drop`` closes the connection without answering; ``delay_s``
    waits first (a delay longer than the client's timeout is a timeout).
    """

    status: int | None = None
    retry_after: float | None = None
    delay_s: float = 0.0
    drop: bool = False
    message: str = "injected fault"


@dataclass
class RecordedRequest:
    """One request the server received: path, headers (lower-case names), JSON body, time."""

    path: str
    headers: dict[str, str]
    body: dict[str, Any]
    received_at: float

    def user_parts(self) -> list[dict[str, Any]]:
        """Content parts of every user message in order (a string content is one text part)."""
        parts: list[dict[str, Any]] = []
        for msg in self.body.get("messages", []):
            if msg.get("role") != "user":
                continue
            content = msg.get("content")
            if isinstance(content, str):
                parts.append({"type": "text", "text": content})
            else:
                parts.extend(content or [])
        return parts


#: What a scripted step or the reply callable may produce.
Outcome = str | Reply | Fault
ReplyFn = Callable[[RecordedRequest], Outcome]


class _Handler(BaseHTTPRequestHandler):
    # keep-alive like a real API server, so clients reuse connections as they would in production
    protocol_version = "HTTP/1.1"
    server: "_Server"

    def log_message(self, format: str, *args: Any) -> None:  # noqa: A002 - stdlib signature
        """Silence the stdlib's per-request stderr log."""

    def do_GET(self) -> None:  # noqa: N802 - stdlib name
        """``/v1/models``: the one model name, for clients that list models first."""
        if self.path.rstrip("/").endswith("/models"):
            self._send_json(200, {"object": "list", "data": [{"id": self.server.owner.model, "object": "model"}]})
        else:
            self._send_json(404, _error_body("not found", "not_found_error"))

    def do_POST(self) -> None:  # noqa: N802 - stdlib name
        """Record the request, then answer with the next scripted outcome."""
        length = int(self.headers.get("Content-Length") or 0)
        raw = self.rfile.read(length) if length else b""
        try:
            body = json.loads(raw or b"{}")
        except json.JSONDecodeError:
            self._send_json(400, _error_body("request body is not JSON", "invalid_request_error"))
            return
        if not self.path.rstrip("/").endswith("/chat/completions"):
            self._send_json(404, _error_body(f"unknown path {self.path}", "not_found_error"))
            return
        owner = self.server.owner
        recorded = RecordedRequest(self.path, {k.lower(): v for k, v in self.headers.items()}, body, time.monotonic())
        outcome = owner._record_and_choose(recorded)
        delay = outcome.delay_s if isinstance(outcome, (Reply, Fault)) else 0.0
        if delay > 0 and owner._stopping.wait(delay):
            self._drop()  # stopping: never leave a handler sleeping
            return
        if isinstance(outcome, Fault):
            self._send_fault(outcome)
        else:
            reply = outcome if isinstance(outcome, Reply) else Reply(outcome)
            self._send_json(200, owner._completion(body, reply))

    # -- sending ------------------------------------------------------------------------------
    def _send_fault(self, fault: Fault) -> None:
        if fault.drop or fault.status is None:
            self._drop()
            return
        headers = {}
        if fault.retry_after is not None:
            headers["Retry-After"] = f"{fault.retry_after:g}"
        kind = {400: "invalid_request_error", 401: "authentication_error", 429: "rate_limit_error"}.get(
            fault.status, "server_error"
        )
        self._send_json(fault.status, _error_body(fault.message, kind), headers)

    def _send_json(self, status: int, payload: dict[str, Any], headers: dict[str, str] | None = None) -> None:
        data = json.dumps(payload).encode()
        self.send_response(status)
        self.send_header("Content-Type", "application/json")
        self.send_header("Content-Length", str(len(data)))
        for k, v in (headers or {}).items():
            self.send_header(k, v)
        self.end_headers()
        self.wfile.write(data)

    def _drop(self) -> None:
        # close without a status line: the client sees a dropped connection, not an HTTP error
        self.close_connection = True
        try:
            self.connection.shutdown(socket.SHUT_RDWR)
        except OSError:
            pass


def _error_body(message: str, kind: str) -> dict[str, Any]:
    return {"error": {"message": message, "type": kind, "param": None, "code": None}}


class _Server(ThreadingHTTPServer):
    daemon_threads = True
    block_on_close = False
    # many concurrent clients in benchmarks: the default backlog of 5 refuses connections
    request_queue_size = 256
    owner: "LoopbackServer"


class LoopbackServer:
    """An OpenAI-compatible ``/v1/chat/completions`` server on 127.0.0.1 in a background thread.

    ``reply`` answers every request not taken by the script: a fixed text, or a callable given
    the :class:`RecordedRequest` and returning text, a :class:`Reply` or a :class:`Fault`.
    :meth:`script` queues outcomes used first, one per request, in order. ``port=0`` picks a
    free port. The server stops itself after ``max_lifetime_s`` seconds.
    """

    def __init__(
        self,
        reply: Outcome | ReplyFn = '{"x": 0, "y": 0}',
        *,
        port: int = 0,
        model: str = "loopback",
        max_lifetime_s: float = 120.0,
        record: bool = True,
    ) -> None:
        self.reply = reply
        self.port = port
        self.model = model
        self.max_lifetime_s = max_lifetime_s
        self.record = record
        self.requests: list[RecordedRequest] = []
        self.request_count = 0
        self._script: collections.deque[Outcome | ReplyFn] = collections.deque()
        self._lock = threading.Lock()
        self._stopping = threading.Event()
        self._server: _Server | None = None
        self._thread: threading.Thread | None = None
        self._timer: threading.Timer | None = None

    # -- lifecycle ----------------------------------------------------------------------------
    def start(self) -> "LoopbackServer":
        """Bind 127.0.0.1 and serve in a daemon thread; returns ``self``."""
        if self._server is not None:
            return self
        self._stopping.clear()
        server = _Server(("127.0.0.1", self.port), _Handler)
        server.owner = self
        self._server = server
        self.port = server.server_address[1]
        self._thread = threading.Thread(target=server.serve_forever, kwargs={"poll_interval": 0.05}, daemon=True,
                                        name=f"loopback-server-{self.port}")
        self._thread.start()
        self._timer = threading.Timer(self.max_lifetime_s, self.stop)
        self._timer.daemon = True
        self._timer.start()
        return self

    def stop(self) -> None:
        """Stop serving, wake every delayed handler, close the socket. Safe to call twice."""
        self._stopping.set()
        server, self._server = self._server, None
        if self._timer is not None and self._timer is not threading.current_thread():
            self._timer.cancel()
        if server is None:
            return
        server.shutdown()
        server.server_close()
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join(timeout=5)

    def __enter__(self) -> "LoopbackServer":
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    @property
    def url(self) -> str:
        """The ``api_base`` clients use: ``http://127.0.0.1:<port>/v1``."""
        return f"http://127.0.0.1:{self.port}/v1"

    # -- scripting ----------------------------------------------------------------------------
    def script(self, *outcomes: Outcome | ReplyFn | Iterable[Outcome | ReplyFn]) -> None:
        """Queue outcomes for the next requests, in order (then ``reply`` answers again).

        An item may be a callable like ``reply`` (it answers that one request).
        """
        with self._lock:
            for o in outcomes:
                if isinstance(o, (str, Reply, Fault)) or callable(o):
                    self._script.append(o)
                else:
                    self._script.extend(o)

    def _record_and_choose(self, recorded: RecordedRequest) -> Outcome:
        with self._lock:
            self.request_count += 1
            if self.record:
                self.requests.append(recorded)
            chosen = self._script.popleft() if self._script else self.reply
        return chosen(recorded) if callable(chosen) else chosen

    def _completion(self, body: dict[str, Any], reply: Reply) -> dict[str, Any]:
        with self._lock:
            n = self.request_count
        return {
            "id": f"chatcmpl-loopback-{n}",
            "object": "chat.completion",
            "created": int(time.time()),
            "model": body.get("model", self.model),
            "choices": []
            if reply.no_choices
            else [{"index": 0, "message": {"role": "assistant", "content": reply.text}, "finish_reason": "stop"}],
            "usage": {
                "prompt_tokens": reply.prompt_tokens,
                "completion_tokens": reply.completion_tokens,
                "total_tokens": reply.prompt_tokens + reply.completion_tokens,
            },
        }


def main(argv: list[str] | None = None) -> None:
    """Serve a fixed reply until interrupted (``python -m povagent.testing.loopback_server``)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--port", type=int, default=0)
    ap.add_argument("--reply", default='{"selected_image": 0, "x": 256, "y": 256}')
    ap.add_argument("--lifetime", type=float, default=3600.0, help="stop after this many seconds")
    args = ap.parse_args(argv)
    server = LoopbackServer(reply=args.reply, port=args.port, max_lifetime_s=args.lifetime, record=False).start()
    print(server.url, flush=True)
    try:
        while not server._stopping.wait(0.5):
            pass
    except KeyboardInterrupt:
        pass
    finally:
        server.stop()


if __name__ == "__main__":
    main()
