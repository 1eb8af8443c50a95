"""Structured run logs: JSON lines in the run folder, a readable rendering on the console.

Each run gets its own structlog logger (no global configuration is touched, so runs and cells
in one process do not fight over it). Every event passes :class:`Redactor` first: values of
keys named like a secret, ``sk-...`` keys, ``Bearer ...`` tokens, credentials inside URLs
(``http://user:password@host``), a key pasted into a ``*_env`` field where a variable's name
belongs, and the current values of ``*_API_KEY`` (and ``*_TOKEN``/``*_SECRET``) environment
variables never reach a file or a terminal. The same redaction guards error messages stored in
result rows and the resolved ``config.yaml``.

This module formats and writes log events; it must not decide what to log.
"""

from __future__ import annotations

import contextlib
import functools
import json
import os
import re
import sys
import threading
from datetime import UTC, datetime
from pathlib import Path
from typing import Any, Callable, Mapping, TextIO, cast

import structlog
from structlog.typing import EventDict

REDACTED = "[REDACTED]"

#: Keys whose string values are secrets. Counts stay (``prompt_tokens`` is a number).
_SECRET_KEY = re.compile(r"(key|token|secret|authorization|password|passwd|cookie|credential)", re.IGNORECASE)
#: Keys that match the pattern above but never hold a secret.
_NOT_SECRET = frozenset({"row", "key_count", "cache_key", "request_hash", "config_hash"})
_SECRET_TEXT = [
    re.compile(r"sk-[A-Za-z0-9_\-]{8,}"),
    re.compile(r"(?i:bearer)\s+[A-Za-z0-9._~+/=\-]{8,}"),
    re.compile(r"AIza[0-9A-Za-z_\-]{20,}"),  # Google API keys
    # The user-info part of a URL (``scheme://user:password@host``): scheme and host stay.
    re.compile(r"(?<=://)[^\s/?#@]+(?=@)"),
]
#: What a plausible environment variable name looks like (``OPENAI_API_KEY``, ``my_key_2``).
ENV_VAR_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
#: What a ``*_env`` field wants, for messages refusing a value (which they never repeat).
ENV_NAME_WANTED = (
    "wants the name of an environment variable that holds the key (letters, digits and _, not "
    "starting with a digit, e.g. OPENAI_API_KEY), not the key itself; the value given is not such "
    "a name and is not shown (it may be a key). Export the key (export MY_KEY=...) and write "
    "api_key_env: MY_KEY"
)
#: Longer "names" are refused too: a variable name is a word, a key is a long random string.
MAX_VARIABLE_NAME = 64
_SECRET_ENV = re.compile(r".*(_API_KEY|_TOKEN|_SECRET|_ACCESS_KEY)$|^API_KEY$", re.IGNORECASE)

LEVELS = {"debug": 10, "info": 20, "warning": 30, "error": 40, "critical": 50}


class Redactor:
    """Removes secrets from strings and nested structures.

    Environment secrets are read when the redactor is made (a run makes one at start), so a
    key exported later is not known; pass ``extra_secrets`` for values from elsewhere.
    """

    def __init__(self, extra_secrets: tuple[str, ...] = ()) -> None:
        secrets = {v for k, v in os.environ.items() if _SECRET_ENV.match(k) and len(v) >= 6}
        secrets.update(s for s in extra_secrets if s and len(s) >= 6)
        patterns = list(_SECRET_TEXT)
        #: the secret values themselves (no pattern): what :meth:`known` removes from answers
        self._known: re.Pattern[str] | None = None
        if secrets:
            # Longest first so a key containing another is removed whole.
            self._known = re.compile("|".join(re.escape(s) for s in sorted(secrets, key=len, reverse=True)))
            patterns.append(self._known)
        self._patterns = patterns
        # One search decides the common case (nothing to redact); it runs on every logged string.
        self._any = re.compile("|".join(f"(?:{p.pattern})" for p in patterns))

    def text(self, value: str) -> str:
        """``value`` with every secret-looking substring replaced."""
        if not self._any.search(value):
            return value
        for p in self._patterns:
            value = p.sub(REDACTED, value)
        return value

    @property
    def knows_secrets(self) -> bool:
        """Whether any secret value is known (else :meth:`known` changes nothing)."""
        return self._known is not None

    def known(self, value: str) -> str:
        """``value`` with every secret value povagent knows replaced, and nothing else touched.

        For what a server sends back in a successful answer (a server echoing the request's
        ``Authorization`` header): an answer is kept exactly as sent, except for the keys
        povagent itself holds; the secret-looking patterns of :meth:`text` are for messages.
        """
        if self._known is None or not self._known.search(value):
            return value
        return self._known.sub(REDACTED, value)

    def value(self, value: Any, key: str | None = None) -> Any:
        """Redact a value found under ``key`` (recursing into mappings and lists)."""
        if value is None or isinstance(value, (int, float)):
            return value  # counts, sizes and flags are never secrets (``prompt_tokens`` stays)
        if key is not None and _secret_key(key):
            return REDACTED
        if key is not None and isinstance(value, str) and _names_a_variable(key) and not self.plausible_variable_name(value):
            return REDACTED  # not a variable's name: most likely the key itself, pasted
        if isinstance(value, str):
            return self.text(value)
        if isinstance(value, Mapping):
            return {k: self.value(v, str(k)) for k, v in value.items()}
        if isinstance(value, (list, tuple)):
            return [self.value(v) for v in value]
        return value

    def plausible_variable_name(self, value: str) -> bool:
        """Whether ``value`` can be the *name* of an environment variable (``OPENAI_API_KEY``)
        rather than a secret: name characters only, and nothing a secret pattern or a current
        secret's value matches (``AIza...`` keys are made of name characters too)."""
        return bool(ENV_VAR_NAME.match(value)) and len(value) <= MAX_VARIABLE_NAME and self.text(value) == value

    def __call__(self, logger: Any, method: str, event: EventDict) -> dict[str, Any]:
        """structlog processor."""
        return {k: self.value(v, k) for k, v in event.items()}


_LITELLM_ENV_REF = "os.environ/"


def secrets_named_by(config: Any) -> tuple[str, ...]:
    """The values of the environment variables a resolved config names in its ``*_env`` fields
    (a backend's ``api_key_env``, each router deployment's) or by litellm's ``os.environ/NAME``
    reference: keys povagent sends, whatever the variable is called (``MY_LAB_KEY`` matches no
    secret-looking name). Unset ones are skipped."""
    found: list[str] = []

    def walk(node: Any) -> None:
        if isinstance(node, Mapping):
            for k, v in node.items():
                # ``api_key_env: NAME``, and litellm's own reference ``api_key: os.environ/NAME``
                name = v if isinstance(v, str) and _names_a_variable(str(k)) else None
                if isinstance(v, str) and v.startswith(_LITELLM_ENV_REF):
                    name = v[len(_LITELLM_ENV_REF):]
                if name is not None and ENV_VAR_NAME.match(name):
                    value = os.environ.get(name)
                    if value:
                        found.append(value)
                else:
                    walk(v)
        elif isinstance(node, (list, tuple)):
            for v in node:
                walk(v)

    walk(config)
    return tuple(found)


@functools.lru_cache(maxsize=1024)
def _secret_key(key: str) -> bool:
    # ``api_key_env: OPENAI_API_KEY`` names a variable; its value is not the secret.
    return key not in _NOT_SECRET and not key.lower().endswith("_env") and bool(_SECRET_KEY.search(key))


def _names_a_variable(key: str) -> bool:
    # ``api_key_env``, ``token_env``: fields whose value is the name of an environment variable
    return key.lower().endswith("_env")


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

    def __call__(self, logger: Any, method: str, event: EventDict) -> Any:
        level = event.get("level", method)
        with self._lock:
            if self.file is not None and self.error is None:
                try:
                    self.file.write(_LINE.encode(event) + "\n")
                except OSError as exc:  # logging must not fail the request that logs
                    self.error = _named(exc, self.file)
            if self.console is not None and LEVELS.get(level, 20) >= self.console_level:
                stream = self.console()
                stream.write(self._render(logger, method, dict(event)) + "\n")
                stream.flush()
        raise structlog.DropEvent

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


def _add_level(logger: Any, method: str, event: EventDict) -> EventDict:
    event["level"] = "warning" if method == "warn" else method
    return event


def _timestamp(logger: Any, method: str, event: EventDict) -> EventDict:
    event["ts"] = datetime.now(UTC).isoformat(timespec="milliseconds")
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
            from povagent.run.confined_write import open_inside

            # line-buffered is too slow for one event per request; flushed on close and by the
            # runner before each batch of rows; no fsync (results.jsonl is the record). Never
            # through a link planted where the log goes (a resumed run's folder is untrusted).
            self._file = cast(TextIO, open_inside(self.path.parent, self.path.name, "a"))
        self.redactor = redactor or Redactor()
        stream = (_stderr if console is True else console) or None
        self._sinks = _Sinks(self._file, stream, LEVELS.get(console_level, 30))
        self.logger = structlog.wrap_logger(
            None,
            processors=[_add_level, _timestamp, self.redactor, self._sinks],
            context_class=dict,
            cache_logger_on_first_use=True,
        ).bind(**context)

    def bind(self, **context: Any) -> Any:
        """A bound logger carrying ``context`` on every event."""
        return self.logger.bind(**context)

    def debug(self, event: str, **kw: Any) -> None:
        """Log at debug level."""
        self.logger.debug(event, **kw)

    def info(self, event: str, **kw: Any) -> None:
        """Log at info level."""
        self.logger.info(event, **kw)

    def warning(self, event: str, **kw: Any) -> None:
        """Log at warning level."""
        self.logger.warning(event, **kw)

    def error(self, event: str, **kw: Any) -> None:
        """Log at error level."""
        self.logger.error(event, **kw)

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

