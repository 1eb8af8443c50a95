"""Which failures are worth another attempt, what they are called, and how long to wait.

One rule for every caller (the runner, sweeps and the embedded agent): timeouts, dropped or
refused connections, 408/425/429 and 5xx are transient and retried; any other 4xx, a missing
key or an unknown model is permanent and recorded at once; an exception that is neither an API
failure nor a file-system one is a bug in a plugin and keeps its traceback. Waits follow the
server's ``Retry-After`` when it sent one (capped at :data:`MAX_RETRY_AFTER_S`), else an
exponential backoff with jitter.

The policy's numbers (attempts, waits) are configuration: :class:`~povagent.config.retry_policy.RetryPolicy`.

Pure: no clock, no sleeping, no I/O (the jitter's random source is a parameter).
"""

from __future__ import annotations

import asyncio
import math
import random
from typing import Callable

from povagent.config.retry_policy import RetryPolicy
from povagent.interfaces import PermanentBackendError, TransientBackendError

#: Longest Retry-After honoured (a server asking for an hour is treated as asking for this).
MAX_RETRY_AFTER_S = 600.0

#: File-system errors that no retry will fix.
_PERMANENT_OS_ERRORS = (FileNotFoundError, PermissionError, IsADirectoryError, NotADirectoryError)

#: HTTP statuses a later attempt may get past.
_TRANSIENT_STATUSES = frozenset({408, 425, 429})


def status_of(exc: BaseException) -> int | None:
    """The HTTP status an exception carries (``status`` or ``status_code``), if any."""
    for attr in ("status", "status_code"):
        value = getattr(exc, attr, None)
        if isinstance(value, int) and not isinstance(value, bool):
            return value
    return None


def is_transient(exc: BaseException) -> bool:
    """Whether a failure is worth retrying: timeouts, connection errors, 408/425/429 and 5xx.

    Never another 4xx such as a bad request or an authentication error. Exceptions from
    libraries that carry an HTTP ``status_code``/``status`` are classified by it.
    """
    if isinstance(exc, TransientBackendError):
        return True
    if isinstance(exc, PermanentBackendError):
        return False
    if isinstance(exc, (TimeoutError, asyncio.TimeoutError, ConnectionError)):
        return True
    if isinstance(exc, _PERMANENT_OS_ERRORS):
        return False
    if isinstance(exc, OSError):
        return True
    status = status_of(exc)
    if status is not None:
        return status in _TRANSIENT_STATUSES or status >= 500
    return False


def error_type_of(exc: BaseException) -> str:
    """A short typed name for a failure, as stored in an ``infra_error`` row's ``error_type``.

    A backend error may name its own kind (``kind="connection"``); otherwise the kind follows
    the exception's type and HTTP status.
    """
    kind = getattr(exc, "kind", None)
    if isinstance(kind, str) and kind:
        return kind
    if isinstance(exc, (TimeoutError, asyncio.TimeoutError)):
        return "timeout"
    if isinstance(exc, ConnectionError) or (isinstance(exc, OSError) and not isinstance(exc, _PERMANENT_OS_ERRORS)):
        return "connection"
    status = status_of(exc)
    if status == 429:
        return "rate_limited"
    if status == 408:
        return "timeout"
    if status is not None and status >= 500:
        return "server_error"
    if status in (401, 403):
        return "auth"
    if status == 400:
        return "bad_request"
    if status == 404:
        return "not_found"
    if isinstance(exc, TransientBackendError):
        return "transient"
    if isinstance(exc, PermanentBackendError):
        return "permanent"
    return "backend_exception"


def retry_after_of(exc: BaseException | None) -> float | None:
    """The server's Retry-After carried by ``exc`` (seconds), capped; ``None`` when absent."""
    value = getattr(exc, "retry_after", None)
    if isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value) and value >= 0:
        return min(float(value), MAX_RETRY_AFTER_S)
    return None


def wait_before_retry(
    policy: RetryPolicy, exc: BaseException | None, failed_attempts: int, uniform: Callable[[float, float], float] = random.uniform
) -> float:
    """Seconds to wait after ``failed_attempts`` failures, the last being ``exc``.

    The server's Retry-After when it sent one (capped at :data:`MAX_RETRY_AFTER_S`); otherwise
    ``initial_wait * 2**(failed_attempts - 1)`` plus a jitter of up to ``initial_wait`` (so
    clients that failed together do not retry together), capped at ``max_wait``.
    """
    retry_after = retry_after_of(exc)
    if retry_after is not None:
        return retry_after
    backoff = policy.initial_wait * 2 ** (failed_attempts - 1) + uniform(0, policy.initial_wait)
    return min(backoff, policy.max_wait)


class InfraFailure(Exception):
    """No answer for a request: the last error after retries, typed, with the attempts made."""

    def __init__(self, error_type: str, message: str, attempts: int) -> None:
        super().__init__(message)
        self.error_type = error_type
        self.message = message
        self.attempts = attempts

    @property
    def retries(self) -> int:
        """Attempts after the first."""
        return max(0, self.attempts - 1)
