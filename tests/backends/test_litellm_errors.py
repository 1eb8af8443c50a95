"""litellm failures as transient or permanent (plugins/backends/litellm_errors.py)."""

from __future__ import annotations

import email.utils

import httpx
import pytest

from povagent.engine.llm_import import import_litellm
from povagent.interfaces import PermanentBackendError, TransientBackendError
from povagent_plugins.backends.litellm_errors import map_litellm_error, retry_after_seconds, scrub

litellm = import_litellm()
ARGS = {"message": "boom", "llm_provider": "openai", "model": "m"}


def test_retry_after_in_seconds():
    assert retry_after_seconds({"Retry-After": "3"}) == 3.0


def test_retry_after_in_milliseconds_wins():
    assert retry_after_seconds({"retry-after-ms": "1500", "retry-after": "9"}) == 1.5


def test_retry_after_as_an_http_date():
    date = email.utils.formatdate(1_000_010, usegmt=True)
    assert retry_after_seconds({"retry-after": date}, now=1_000_000) == pytest.approx(10)


def test_retry_after_missing_or_garbage_is_none():
    assert retry_after_seconds({}) is None
    assert retry_after_seconds({"retry-after": "soon"}) is None


def test_rate_limit_reads_retry_after_from_the_response_headers():
    response = httpx.Response(429, headers={"retry-after": "4"}, request=httpx.Request("POST", "http://x"))
    mapped = map_litellm_error(litellm, litellm.RateLimitError(response=response, **ARGS))
    assert isinstance(mapped, TransientBackendError) and mapped.retry_after == 4 and mapped.status == 429


@pytest.mark.parametrize(
    "exc",
    [
        litellm.InternalServerError(**ARGS),
        litellm.ServiceUnavailableError(**ARGS),
        litellm.APIConnectionError(**ARGS),
        litellm.Timeout(**ARGS),
    ],
    ids=lambda e: type(e).__name__,
)
def test_transient_failures(exc):
    assert isinstance(map_litellm_error(litellm, exc), TransientBackendError)


@pytest.mark.parametrize(
    "exc",
    [
        litellm.BadRequestError(**ARGS),
        litellm.AuthenticationError(**ARGS),
        litellm.NotFoundError(**ARGS),
        litellm.PermissionDeniedError(**ARGS, response=httpx.Response(403, request=httpx.Request("POST", "http://x"))),
        litellm.ContextWindowExceededError(**ARGS),
    ],
    ids=lambda e: type(e).__name__,
)
def test_permanent_failures(exc):
    assert isinstance(map_litellm_error(litellm, exc), PermanentBackendError)


def test_transient_failure_after_router_retries_is_permanent():
    mapped = map_litellm_error(litellm, litellm.InternalServerError(**ARGS), retried_inside=True)
    assert isinstance(mapped, PermanentBackendError) and mapped.status == 500


def test_foreign_exceptions_are_left_alone():
    exc = ZeroDivisionError("bug")
    assert map_litellm_error(litellm, exc) is exc


def test_scrub_masks_keys_but_not_short_placeholders():
    assert scrub("key sk-abcdef1234 rejected", ("sk-abcdef1234",)) == "key *** rejected"
    assert scrub("index x", ("x",)) == "index x"


@pytest.mark.parametrize(
    "exc",
    [
        # what litellm 1.103 raises for a call without a key: a 500, a connection error, a 401
        litellm.InternalServerError(message="OpenAIException - Missing credentials. Please pass an `api_key`", llm_provider="openai", model="m"),
        litellm.APIConnectionError(
            message="Missing Gemini API key. Set the GEMINI_API_KEY or GOOGLE_API_KEY environment variable.\nTraceback (most recent call last):\n  File x",
            llm_provider="gemini",
            model="m",
        ),
        litellm.AuthenticationError(
            message="Missing Anthropic API Key - A call is being made to anthropic but no key is set", llm_provider="anthropic", model="m"
        ),
    ],
    ids=["openai", "gemini", "anthropic"],
)
def test_a_missing_api_key_is_permanent_and_says_so(exc):
    mapped = map_litellm_error(litellm, exc)
    assert isinstance(mapped, PermanentBackendError) and mapped.status == 401
    assert str(mapped).startswith("no API key:") and "api_key_env" in str(mapped)
    assert "Traceback" not in str(mapped)


def test_litellms_pasted_traceback_is_cut_from_messages():
    exc = litellm.APIConnectionError(message="Connection reset\nTraceback (most recent call last):\n  File x", llm_provider="openai", model="m")
    mapped = map_litellm_error(litellm, exc)
    assert isinstance(mapped, TransientBackendError) and "Traceback" not in str(mapped) and "Connection reset" in str(mapped)
