"""An OpenAI-compatible chat server on 127.0.0.1 for tests, benchmarks and plugin authors.

It answers ``POST /v1/chat/completions`` with scripted replies (texts and tool calls, queued in
code or read from a turns file: :mod:`povagent.testing.scripted_turns`), records every request
body (so a test can check which images, labels, prompt text and generation parameters arrived),
and injects faults: an HTTP status (429 with ``Retry-After``, 500, 400, 401...), a delay, or a
dropped connection (the socket closed without a response).

With ``fetch_images=True`` it also does what a vLLM server does with image URLs: it decodes
``data:`` URLs, opens ``file://`` URLs (only under ``local_media_root``, like vLLM's
``--allowed-local-media-path``) and downloads ``http://`` URLs (from 127.0.0.1 only), and
records each image's SHA-256 and, unless ``keep_image_bytes=False``, its bytes
(:attr:`RecordedRequest.images`). An image it cannot fetch, or one ``image_check`` rejects,
is answered 400, as a model server would. With ``count_bodies=True`` it counts the SHA-256 of
every request body as received (:attr:`LoopbackServer.body_digests`), so a benchmark can check
that two clients sent byte-identical requests.

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
import hashlib
import json
import signal
import socket
import time
from dataclasses import dataclass, field
from http.server import BaseHTTPRequestHandler
from pathlib import Path
from typing import Any, Callable, Iterable

from povagent.testing.background_server import BackgroundServer, TrackedHTTPServer
from povagent.testing.image_urls import FetchedImage, ImageFetchError, decode_data_url, download, read_file_url
from povagent.testing.scripted_turns import Turn, read_turns

__all__ = ["Fault", "FetchedImage", "Reply", "RecordedRequest", "LoopbackServer", "read_turns"]

#: Hosts an ``http://`` image URL may name: the server never reaches beyond this machine.


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
    #: Function calls to answer with, each ``{"name": ..., "arguments": <dict or raw text>}``
    #: (raw text is sent as is, so a test can send malformed arguments), and ``"id"`` when the
    #: call's id is not to be ``call_<request>_<k>``.
    tool_calls: tuple[dict[str, Any], ...] = ()


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
    """One request the server received: path, headers (lower-case names), JSON body, time,
    and (with ``fetch_images``) every image it carried or referred to, in order."""

    path: str
    headers: dict[str, str]
    body: dict[str, Any]
    received_at: float
    images: list[FetchedImage] = field(default_factory=list)

    def image_urls(self) -> list[str]:
        """The URL of every image part of the user messages, in order."""
        urls = []
        for part in self.user_parts():
            if part.get("type") == "image_url":
                ref = part.get("image_url")
                urls.append(ref.get("url", "") if isinstance(ref, dict) else str(ref))
        return urls

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
    server: _Server

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
        if owner.count_bodies:
            digest = hashlib.sha256(raw).hexdigest()
            with owner._lock:
                owner.body_digests[digest] += 1
        recorded = RecordedRequest(self.path, {k.lower(): v for k, v in self.headers.items()}, body, time.monotonic())
        if owner.fetch_images:
            try:
                recorded.images = [owner._fetch(i, url) for i, url in enumerate(recorded.image_urls())]
            except ImageFetchError as exc:
                with owner._lock:
                    owner.image_failures += 1
                    if owner.record:
                        owner.requests.append(recorded)
                self._send_json(400, _error_body(str(exc), "invalid_request_error"))
                return
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


class _Server(TrackedHTTPServer):
    # many concurrent clients in benchmarks: the default backlog of 5 refuses connections
    request_queue_size = 256
    owner: LoopbackServer


class LoopbackServer(BackgroundServer):
    """An OpenAI-compatible ``/v1/chat/completions`` server on 127.0.0.1 in a background thread.

    ``reply`` answers every request not taken by the script: a fixed text, or a callable given
    the :class:`RecordedRequest` and returning text, a :class:`Reply` or a :class:`Fault`.
    :meth:`script` queues outcomes used first, one per request, in order. ``port=0`` picks a
    free port. The server stops itself after ``max_lifetime_s`` seconds.
    """

    server_class = _Server
    handler = _Handler
    thread_name = "loopback-server"

    def __init__(
        self,
        reply: Outcome | ReplyFn = '{"x": 0, "y": 0}',
        *,
        port: int = 0,
        model: str = "loopback",
        max_lifetime_s: float = 120.0,
        record: bool = True,
        fetch_images: bool = False,
        local_media_root: str | Path | None = None,
        keep_image_bytes: bool = True,
        image_check: Callable[[FetchedImage], str | None] | None = None,
        count_bodies: bool = False,
    ) -> None:
        super().__init__(port, max_lifetime_s)
        self.reply = reply
        self.model = model
        self.record = record
        self.fetch_images = fetch_images
        self.local_media_root = Path(local_media_root).resolve() if local_media_root is not None else None
        self.keep_image_bytes = keep_image_bytes
        self.image_check = image_check
        self.count_bodies = count_bodies
        #: with ``count_bodies``: how many requests had each body (by the SHA-256 of its bytes)
        self.body_digests: collections.Counter[str] = collections.Counter()
        self.requests: list[RecordedRequest] = []
        self.request_count = 0
        #: images fetched and accepted, and requests refused because an image was not
        self.images_fetched = 0
        self.image_failures = 0
        self._script: collections.deque[Outcome | ReplyFn] = collections.deque()

    @property
    def url(self) -> str:
        """The ``api_base`` clients use: ``http://127.0.0.1:<port>/v1``."""
        return f"http://127.0.0.1:{self.port}/v1"

    # -- scripting ----------------------------------------------------------------------------
    def script(self, *outcomes: Outcome | ReplyFn | Turn | Iterable[Outcome | ReplyFn | Turn]) -> None:
        """Queue outcomes for the next requests, in order (then ``reply`` answers again).

        An item may be a callable like ``reply`` (it answers that one request), or a
        :class:`~povagent.testing.scripted_turns.Turn` of a turns file (:func:`read_turns`).
        """
        with self._lock:
            for o in outcomes:
                if isinstance(o, (str, Reply, Fault, Turn)) or callable(o):
                    self._script.append(_outcome(o))
                else:
                    self._script.extend(_outcome(x) for x in o)

    # -- images -------------------------------------------------------------------------------
    def _fetch(self, index: int, url: str) -> FetchedImage:
        """The bytes behind one image URL, checked; an :class:`ImageFetchError` says why not."""
        scheme = url.split(":", 1)[0].lower() if ":" in url else ""
        try:
            if scheme == "data":
                data = decode_data_url(url)
            elif scheme == "file":
                data = read_file_url(url, self.local_media_root)
            elif scheme in ("http", "https"):
                data = download(url)
                scheme = "http"
            else:
                raise ImageFetchError(f"unsupported image URL scheme {scheme!r}")
        except ImageFetchError as exc:
            raise ImageFetchError(f"image {index}: {exc}") from None
        image = FetchedImage(scheme, hashlib.sha256(data).hexdigest(), len(data), data if self.keep_image_bytes else None)
        if self.image_check is not None:
            problem = self.image_check(image)
            if problem:
                raise ImageFetchError(f"image {index}: {problem}")
        with self._lock:
            self.images_fetched += 1
        return image

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
            "choices": [] if reply.no_choices else [_choice(reply, n)],
            "usage": {
                "prompt_tokens": reply.prompt_tokens,
                "completion_tokens": reply.completion_tokens,
                "total_tokens": reply.prompt_tokens + reply.completion_tokens,
            },
        }


def _outcome(item: Any) -> Any:
    """A turns file's turn as the reply it stands for; anything else as it is."""
    return Reply(item.text, tool_calls=item.tool_calls) if isinstance(item, Turn) else item


def _choice(reply: Reply, n: int) -> dict[str, Any]:
    """The one choice of an answer: the text, and the scripted tool calls (ids per request)."""
    message: dict[str, Any] = {"role": "assistant", "content": reply.text}
    if not reply.tool_calls:
        return {"index": 0, "message": message, "finish_reason": "stop"}
    message["tool_calls"] = [
        {
            "id": c.get("id") or f"call_{n}_{k}",
            "type": "function",
            "function": {"name": c.get("name"), "arguments": c["arguments"] if isinstance(c.get("arguments"), str) else json.dumps(c.get("arguments", {}))},
        }
        for k, c in enumerate(reply.tool_calls)
    ]
    return {"index": 0, "message": message, "finish_reason": "tool_calls"}


#: What the command-line server answers by default: a valid answer for conditions A and B.
DEFAULT_REPLY = '{"selected_image": 0, "x": 256, "y": 256}'


def argument_parser() -> argparse.ArgumentParser:
    """The options of ``python -m povagent.testing.loopback_server``, each explained."""
    from povagent.testing.server_command import port_number

    ap = argparse.ArgumentParser(
        prog="python -m povagent.testing.loopback_server",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        description="An OpenAI-compatible chat server on 127.0.0.1 that answers every request\n"
        "with one fixed reply (after the turns of --script, if given): try a pipeline\n"
        "or a backend without a model. The first line it prints is its URL, the\n"
        "api_base to give a litellm backend; it serves until Ctrl-C or --lifetime.",
        epilog="example:\n"
        "  python -m povagent.testing.loopback_server --port 8000 \\\n"
        "      --reply '{\"x\": 1, \"y\": 2}'\n"
        "  and in the pipeline: backend: {name: litellm, options: {model: openai/any,\n"
        "    api_base: http://127.0.0.1:8000/v1, api_key_env: SOME_VAR}}  (any value)\n"
        "  python -m povagent.testing.loopback_server --script turns.yaml\n"
        "  a model that calls tools, turn by turn (see povagent.testing.scripted_turns)",
    )
    ap.add_argument("--port", type=port_number, default=0, metavar="N",
                    help="port on 127.0.0.1 to listen on (default: 0, any free port)")
    ap.add_argument("--reply", default=DEFAULT_REPLY, metavar="TEXT",
                    help="the assistant's text in every answer (default: %(default)s)")
    ap.add_argument("--script", default=None, metavar="FILE",
                    help="answer the first requests with the turns of FILE, in order, then --reply: a JSON or "
                    "YAML list, each turn a text or {tool_calls: [{name: ..., arguments: {...}}]}")
    ap.add_argument("--delay", type=float, default=0.0, metavar="SECONDS",
                    help="wait this long before each answer, as a model takes time to answer (default: 0)")
    ap.add_argument("--lifetime", type=float, default=3600.0, metavar="SECONDS",
                    help="stop after this many seconds (default: %(default).0f)")
    ap.add_argument("--fetch-images", action="store_true",
                    help="decode, open or download every image URL of a request, as a vLLM server does, "
                    "and answer 400 when one cannot be read")
    ap.add_argument("--local-media-root", default=None, metavar="FOLDER",
                    help="with --fetch-images: file:// image URLs are read only beneath this folder "
                    "(default: none is read)")
    ap.add_argument("--expect-sha256", default=None, metavar="FILE",
                    help="a file of SHA-256 digests, one a line: a request with any other image is "
                    "answered 400 (implies --fetch-images)")
    ap.add_argument("--count-bodies", action="store_true",
                    help="count the SHA-256 of every request body as received and print the counts on exit "
                    "(a benchmark's check that two clients sent the same bytes)")
    return ap


def main(argv: list[str] | None = None) -> None:
    """Serve a fixed reply until interrupted (``python -m povagent.testing.loopback_server``).

    Bad options and a port that cannot be bound end with a one-line message and exit code 2,
    never a traceback. SIGINT (Ctrl-C) and SIGTERM both stop it, and it then prints its counts
    (with ``--fetch-images`` or ``--count-bodies``): a benchmark started in the background
    inherits SIGINT ignored, which Python would otherwise keep ignoring.
    """
    from povagent.testing.server_command import bind_failure

    ap = argument_parser()
    args = ap.parse_args(argv)
    check = None
    if args.expect_sha256:
        try:
            expected = set(Path(args.expect_sha256).read_text().split())
        except (OSError, UnicodeDecodeError) as exc:
            ap.error(f"--expect-sha256 {args.expect_sha256}: cannot read it ({exc})")

        def check(image: FetchedImage) -> str | None:
            return None if image.sha256 in expected else f"unexpected image (sha256 {image.sha256[:16]}...)"

    if args.local_media_root is not None and not Path(args.local_media_root).is_dir():
        ap.error(f"--local-media-root {args.local_media_root}: not a folder")
    turns: list[Turn] = []
    if args.script is not None:
        from povagent.errors import ConfigError

        try:
            turns = read_turns(args.script)
        except ConfigError as exc:
            ap.error(f"--script {exc}")
    server = LoopbackServer(
        reply=Reply(args.reply, delay_s=args.delay) if args.delay > 0 else args.reply,
        port=args.port,
        max_lifetime_s=args.lifetime,
        record=False,
        fetch_images=args.fetch_images or check is not None,
        local_media_root=args.local_media_root,
        keep_image_bytes=False,
        image_check=check,
        count_bodies=args.count_bodies,
    )
    server.script(turns)
    try:
        server.start()
    except OSError as exc:
        ap.exit(2, f"{ap.prog}: error: {bind_failure(args.port, exc)}\n")

    def stop_serving(signum: int, frame: Any) -> None:
        server._stopping.set()

    for signum in (signal.SIGINT, signal.SIGTERM):  # before the URL: a client may signal at once
        signal.signal(signum, stop_serving)
    print(server.url, flush=True)
    try:
        while not server._stopping.wait(0.5):
            pass
    finally:
        server.stop()
        if server.fetch_images or server.count_bodies:
            counts: dict[str, Any] = {"requests": server.request_count}
            if server.fetch_images:
                counts |= {"images_fetched": server.images_fetched, "image_failures": server.image_failures}
            if server.count_bodies:
                counts["body_sha256"] = dict(server.body_digests)
            print(json.dumps(counts), flush=True)


if __name__ == "__main__":
    main()
