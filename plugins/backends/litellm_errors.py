"""litellm's exceptions as povagent's two kinds: worth retrying, or not.

Transient (the runner retries): 429 rate limits (with the server's ``Retry-After``), timeouts,
dropped connections, 5xx. Permanent (recorded, never retried): bad request, authentication,
permission, unknown model, context window exceeded and any other 4xx. Exceptions that are
neither litellm's nor the HTTP client's are bugs and are left alone (they keep their
traceback). Messages are scrubbed of the API key.
"""

from __future__ import annotations

import email.utils
import errno
import re
import time
from types import ModuleType
from typing import Any, Mapping

from povagent.interfaces import PermanentBackendError, TransientBackendError

#: HTTP statuses that a later attempt may get past.
TRANSIENT_STATUSES = frozenset({408, 409, 425, 429, 500, 502, 503, 504, 529})


def retry_after_seconds(headers: Mapping[str, Any] | None, now: float | None = None) -> float | None:
    """Seconds to wait from ``Retry-After`` (seconds or an HTTP date) or ``retry-after-ms``."""
    if not headers:
        return None
    lower = {str(k).lower(): v for k, v in dict(headers).items()}
    ms = lower.get("retry-after-ms")
    if ms is not None:
        try:
            return max(0.0, float(ms) / 1000.0)
        except (TypeError, ValueError):
            pass
    value = lower.get("retry-after")
    if value is None:
        return None
    try:
        return max(0.0, float(value))
    except (TypeError, ValueError):
        pass
    try:
        when = email.utils.parsedate_to_datetime(str(value))
    except (TypeError, ValueError, IndexError):
        return None
    return max(0.0, when.timestamp() - (time.time() if now is None else now))


def _response_headers(exc: BaseException) -> Mapping[str, Any] | None:
    # litellm copies the provider's headers to litellm_response_headers; the exception's own
    # `response` is often a stand-in without them
    for source in (
        getattr(exc, "litellm_response_headers", None),
        getattr(exc, "headers", None),
        getattr(getattr(exc, "response", None), "headers", None),
    ):
        if source:
            return source
    return None


def _status(exc: BaseException) -> int | None:
    status = getattr(exc, "status_code", None)
    try:
        return int(status) if status is not None else None
    except (TypeError, ValueError):
        return None


#: How providers say no key was given. litellm reports it as a 500 (OpenAI's "Missing
#: credentials") or a connection error (Gemini): retrying cannot fix it, so it is permanent.
_MISSING_KEY = re.compile(
    r"missing (?:\w+ )?(?:api[ _]?key|credentials)|api_key client option must be set|no api[ _]?key (?:provided|found|set)",
    re.IGNORECASE,
)

#: litellm pastes its own traceback into some messages; rows and logs keep the text before it.
_TRACEBACK = "Traceback (most recent call last)"

#: Shorter "secrets" are placeholders (local servers take any key); masking them would mangle text.
MIN_SECRET_LENGTH = 6


def scrub(message: str, secrets: tuple[str, ...]) -> str:
    """``message`` with every secret (of at least 6 characters) replaced by ``***``."""
    for s in secrets:
        if s and len(s) >= MIN_SECRET_LENGTH:
            message = message.replace(s, "***")
    return message


def map_litellm_error(
    litellm: ModuleType,
    exc: BaseException,
    *,
    secrets: tuple[str, ...] = (),
    retried_inside: bool = False,
    url: str | None = None,
) -> BaseException:
    """The povagent error for a litellm failure (or ``exc`` itself when it is not one).

    ``retried_inside`` says litellm's Router already spent its retries: the failure is then
    returned as permanent so no second retry loop stacks on the Router's. ``url`` names the
    endpoint in connection failures (a refused or dropped connection is ``connection``, not a
    server error, whatever status litellm gives it).
    """
    import httpx
    import openai

    msg = scrub(str(exc) or type(exc).__name__, secrets)
    msg = msg.split(_TRACEBACK, 1)[0].rstrip() or msg
    status = _status(exc)
    if _MISSING_KEY.search(msg) and isinstance(exc, (litellm.APIError, openai.APIError)):
        return PermanentBackendError(
            f"no API key: {msg} (export the provider's key variable, or name yours with api_key_env)", status=401
        )
    refused = _connection_failure(exc, openai, httpx)
    if refused is not None and not isinstance(exc, (litellm.Timeout, openai.APITimeoutError, httpx.TimeoutException)):
        # litellm reports a refused or dropped connection as a 500: it is no server's answer
        where = f"cannot reach {url}" if url else "cannot reach the server"
        cause = scrub(refused, secrets)
        cause = cause.split(_TRACEBACK, 1)[0].rstrip() or cause
        transient = TransientBackendError(f"{where}: {cause}", kind="connection")
    elif isinstance(exc, litellm.RateLimitError):
        transient = TransientBackendError(
            msg, retry_after=retry_after_seconds(_response_headers(exc)), status=429
        )
    elif isinstance(exc, (litellm.Timeout, openai.APITimeoutError, httpx.TimeoutException)):
        transient = TransientBackendError(msg, status=status or 408, kind="timeout")
    elif isinstance(exc, (litellm.InternalServerError, litellm.ServiceUnavailableError, litellm.BadGatewayError)):
        transient = TransientBackendError(msg, status=status)
    elif isinstance(exc, (litellm.APIConnectionError, openai.APIConnectionError, httpx.TransportError)):
        where = f"cannot reach {url}: " if url else ""
        transient = TransientBackendError(f"{where}{msg}", kind="connection")
    elif isinstance(
        exc,
        (
            litellm.BadRequestError,  # includes ContextWindowExceededError, ContentPolicyViolationError
            litellm.AuthenticationError,
            litellm.NotFoundError,
            litellm.PermissionDeniedError,
            litellm.UnprocessableEntityError,
        ),
    ):
        return PermanentBackendError(msg, status=status)
    elif isinstance(exc, (openai.APIError, litellm.APIError)) or _is_router_error(exc):
        if status in TRANSIENT_STATUSES or (status is None and _is_router_error(exc)):
            transient = TransientBackendError(msg, retry_after=retry_after_seconds(_response_headers(exc)), status=status)
        else:
            return PermanentBackendError(msg, status=status)
    else:
        return exc
    if retried_inside:
        return PermanentBackendError(f"{msg} (after litellm Router retries)", status=transient.status, kind=transient.kind)
    return transient


def _is_router_error(exc: BaseException) -> bool:
    # "No deployments available": every deployment is cooling down or over its rate limit
    return type(exc).__name__ in {"RouterRateLimitError", "RouterRateLimitErrorBasic"}


def _connection_failure(exc: BaseException, openai: ModuleType, httpx: ModuleType) -> str | None:
    """The deepest cause's message when ``exc`` was caused by a refused, reset or dropped
    connection (anywhere in its chain), else ``None``."""
    found: str | None = None
    seen: set[int] = set()
    link: BaseException | None = exc
    while link is not None and id(link) not in seen:
        seen.add(id(link))
        if isinstance(link, (openai.APIConnectionError, httpx.TransportError, ConnectionError)) and not isinstance(
            link, (openai.APITimeoutError, httpx.TimeoutException)
        ):
            found = str(link) or type(link).__name__
        link = link.__cause__ or link.__context__
    return found



def unreachable_for_good(exc: BaseException) -> str | None:
    """Why a connection failure cannot be a passing one, or ``None`` when it may be: a refused
    connection (``ECONNREFUSED``: nothing listens at the address), or an address the HTTP
    client will not use at all (a ``ValueError`` before any connection: e.g. credentials in
    ``api_base`` beside the key's header). A reset, a dropped connection or a timeout may pass."""
    seen: set[int] = set()
    link: BaseException | None = exc
    while link is not None and id(link) not in seen:
        seen.add(id(link))
        if isinstance(link, ConnectionRefusedError) or (isinstance(link, OSError) and link.errno == errno.ECONNREFUSED):
            return "connection refused: nothing listens at that address"
        if isinstance(link, ValueError) and not isinstance(link, UnicodeError):
            return f"the HTTP client cannot use that address ({type(link).__name__}: {str(link)[:200]})"
        link = link.__cause__ or link.__context__
    return None
