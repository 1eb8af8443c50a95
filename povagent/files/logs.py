"""Structured run logs: JSON lines in the run folder, a readable rendering on the console.

Each run gets its own structlog logger (no global configuration is touched, so runs and cells
in one process do not fight over it). Every event passes a :class:`~povagent.files.redaction.Redactor`
first, so no secret reaches a file or a terminal (what counts as one is the redactor's to say).

This module formats and writes log events; it must not decide what to log.
"""
from __future__ import annotations

import contextlib
import json
import sys
import threading
from pathlib import Path
from typing import Any, Callable, TextIO, cast

import structlog
from structlog.typing import EventDict, Processor

from povagent.files.confined_write import open_inside
from povagent.files.redaction import Redactor
from povagent.files.timestamps import utc_now

LEVELS = {"debug": 10, "info": 20, "warning": 30, "error": 40, "critical": 50}


def _default(obj: Any) -> Any:
    if isinstance(obj, Path):
        return str(obj)
    if isinstance(obj, BaseException):
        return f"{type(obj).__name__}: {obj}"
    return repr(obj)


class _Sinks:
    """The final processor: JSON line to the file, rendered line to the console; drops the event."""

    def __init__(self, file: TextIO | None, console: Callable[[], TextIO] | None, console_level: int) -> None:
        self.file = file
        #: the first write to the file that failed (a full disk): no further line goes there, and
        #: :meth:`flush` raises it, so the runner writes no row whose events are not in the log
        self.error: OSError | None = None
        self.console = console
        self.console_level = console_level
        self._lock = threading.Lock()
        self._render = structlog.dev.ConsoleRenderer(colors=bool(console is not None and console().isatty()))
        self._encode = _line_encoder()

    def _line(self, event: EventDict) -> str:
        """``_LINE.encode(event)``, by an encoder made once (under the lock: one event at a time)."""
        if self._encode is None:  # no C encoder in this Python
            return _LINE.encode(event)
        try:
            return "".join(self._encode(event, 0))
        except BaseException:  # it may hold the containers it was inside: a fresh one next time
            self._encode = _line_encoder()
            raise

    def __call__(self, logger: Any, method: str, event: EventDict) -> Any:
        self.write(logger, method, event)
        raise structlog.DropEvent

    def write(self, logger: Any, method: str, event: EventDict) -> None:
        """The event's line to the file, and its rendering to the console at its level."""
        level = event.get("level", method)
        with self._lock:
            if self.file is not None and self.error is None:
                try:
                    self.file.write(self._line(event) + "\n")
                except OSError as exc:  # logging must not fail the request that logs
                    self.error = _named(exc, self.file)
            if self.console is not None and LEVELS.get(level, 20) >= self.console_level:
                stream = self.console()
                stream.write(self._render(logger, method, dict(event)) + "\n")
                stream.flush()

    def flush(self) -> None:
        """Flush the file sink; raises the first write failure (an ``OSError`` naming the file)."""
        with self._lock:
            if self.file is not None and self.error is None:
                try:
                    self.file.flush()
                except OSError as exc:
                    self.error = _named(exc, self.file)
            if self.error is not None:
                raise self.error


def _named(exc: OSError, file: TextIO) -> OSError:
    """``exc`` with the file's name (a failed ``write`` on an open file does not carry it)."""
    if exc.filename is None and exc.errno is not None:
        return OSError(exc.errno, exc.strerror, getattr(file, "name", None))
    return exc


#: A log line's encoder, made once: ``json.dumps(event, default=_default, separators=(",", ":"))``
#: makes the same one for every event.
_LINE = json.JSONEncoder(default=_default, separators=(",", ":"))


def _line_encoder() -> Any:
    """The C encoder :meth:`json.JSONEncoder.encode` makes for each call of ``_LINE`` (its own
    record of the containers it is inside, for circular references), made once a log: making it
    cost a request's event about a fifth of its encoding. ``None`` without the C module."""
    make = getattr(json.encoder, "c_make_encoder", None)
    if make is None:
        return None
    line = _LINE
    strings = json.encoder.encode_basestring_ascii  # ensure_ascii, as _LINE's
    return make({}, line.default, strings, line.indent, line.key_separator, line.item_separator, line.sort_keys, line.skipkeys, line.allow_nan)


def _add_level(logger: Any, method: str, event: EventDict) -> EventDict:
    event["level"] = _LEVEL_NAME.get(method, method)
    return event


#: The level a method writes, where it is not the method's own name.
_LEVEL_NAME = {"warn": "warning"}
#: Event names (with their level) whose redacted text a log keeps at most.
_NAMED_KEPT = 256


def _timestamp(logger: Any, method: str, event: EventDict) -> EventDict:
    event["ts"] = utc_now()
    return event


class RunLog:
    """A run's logger: ``log = RunLog(path); log.info("request", latency_s=...)``; ``close()`` at end."""

    def __init__(
        self,
        path: str | Path | None,
        *,
        console: bool | Callable[[], TextIO] = False,
        console_level: str = "warning",
        redactor: Redactor | None = None,
        **context: Any,
    ) -> None:
        self.path = Path(path) if path is not None else None
        self._file: TextIO | None = None
        if self.path is not None:
            # line-buffered is too slow for one event per request; flushed on close and by the
            # runner before each batch of rows; no fsync (results.jsonl is the record). Never
            # through a link planted where the log goes (a resumed run's folder is untrusted).
            self._file = cast(TextIO, open_inside(self.path.parent, self.path.name, "a"))
        self.redactor = redactor or Redactor()
        stream = (_stderr if console is True else console) or None
        self._sinks = _Sinks(self._file, stream, LEVELS.get(console_level, 30))
        processors: list[Processor] = [_add_level, _timestamp, self.redactor, self._sinks]
        self.logger = structlog.wrap_logger(None, processors=processors, context_class=dict, cache_logger_on_first_use=True).bind(**context)
        self._redacted_context = self.redactor.fields(context)
        self._named: dict[tuple[str, str], tuple[str, str]] = {}
        self._ts = ("", "")

    def bind(self, **context: Any) -> Any:
        """A bound logger carrying ``context`` on every event."""
        return self.logger.bind(**context)

    def _emit(self, method: str, event: str, kw: dict[str, Any]) -> None:
        # What the bound logger does with a call (its context, the call's fields, the event,
        # its level and time, each field redacted, then the sink), without the wrapper's layers
        # of calls around it: a run logs an event for every request, and those layers cost more
        # than the line. The same fields in the same order, so the same line; the redactor
        # redacts each field by its own key and value, so the context (the same at every
        # event) is redacted once, when the log is made, and the event's name, level and time
        # (texts under keys naming no secret: the redactor's ``text`` of each) once an event
        # name, and once a millisecond.
        named = self._named.get((event, method))
        if named is None:
            text = self.redactor.text
            named = (text(event), text(_LEVEL_NAME.get(method, method)))
            if len(self._named) < _NAMED_KEPT:
                self._named[event, method] = named
        ts = utc_now()
        if ts is not self._ts[0]:
            self._ts = (ts, self.redactor.text(ts))
        event_dict = {**self._redacted_context, **self.redactor.fields(kw), "event": named[0], "level": named[1], "ts": self._ts[1]}
        self._sinks.write(None, method, event_dict)

    def debug(self, event: str, **kw: Any) -> None:
        """Log at debug level."""
        self._emit("debug", event, kw)

    def info(self, event: str, **kw: Any) -> None:
        """Log at info level."""
        self._emit("info", event, kw)

    def warning(self, event: str, **kw: Any) -> None:
        """Log at warning level."""
        self._emit("warning", event, kw)

    def error(self, event: str, **kw: Any) -> None:
        """Log at error level."""
        self._emit("error", event, kw)

    def flush(self) -> None:
        """Push buffered lines to the file."""
        self._sinks.flush()

    def close(self) -> None:
        """Flush and close the file. A write that failed (a full disk) does not raise here: the
        runner has already stopped on it (see :meth:`flush`), and closing must still happen."""
        with contextlib.suppress(OSError):
            self._sinks.flush()
        if self._file is not None:
            with contextlib.suppress(OSError):  # the buffer's lines could not be written
                self._file.close()
            self._file = None
            self._sinks.file = None


def _stderr() -> TextIO:
    # Looked up at each write: a live progress display swaps sys.stderr to keep lines above it.
    return sys.stderr

