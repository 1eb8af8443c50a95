"""The retry rule: which failures are transient, what they are called, how long to wait."""

from __future__ import annotations

import math

import pytest
from pydantic import ValidationError

from povagent.config.retry_policy import RetryPolicy
from povagent.engine.retry import (
    MAX_RETRY_AFTER_S,
    InfraFailure,
    error_type_of,
    is_transient,
    wait_before_retry,
)
from povagent.interfaces import PermanentBackendError, TransientBackendError


class Status(Exception):
    """A library exception carrying an HTTP status, as openai/httpx ones do."""

    def __init__(self, status_code: int) -> None:
        super().__init__(f"HTTP {status_code}")
        self.status_code = status_code


@pytest.mark.parametrize("status", [408, 425, 429, 500, 502, 503, 504, 529])
def test_timeouts_rate_limits_and_every_5xx_are_transient(status):
    assert is_transient(Status(status))


@pytest.mark.parametrize("status", [400, 401, 403, 404, 409, 413, 422, 499])
def test_other_4xx_are_permanent(status):
    assert not is_transient(Status(status))


@pytest.mark.parametrize(
    ("exc", "transient"),
    [
        (TimeoutError(), True),
        (ConnectionRefusedError(), True),
        (ConnectionResetError(), True),
        (OSError("network down"), True),
        (FileNotFoundError("x.png"), False),
        (PermissionError("x.png"), False),
        (IsADirectoryError("x"), False),
        (ValueError("a bug"), False),
        (TransientBackendError("x", status=400), True),  # the backend's own word wins over a status
        (PermanentBackendError("x", status=503), False),
    ],
)
def test_exception_types_are_classified(exc, transient):
    assert is_transient(exc) is transient


def test_a_boolean_status_is_not_a_status():
    exc = Exception("x")
    exc.status = True  # type: ignore[attr-defined]
    assert not is_transient(exc) and error_type_of(exc) == "backend_exception"


@pytest.mark.parametrize(
    ("exc", "kind"),
    [
        (TimeoutError(), "timeout"),
        (Status(408), "timeout"),
        (Status(429), "rate_limited"),
        (Status(500), "server_error"),
        (Status(401), "auth"),
        (Status(403), "auth"),
        (Status(400), "bad_request"),
        (Status(404), "not_found"),
        (ConnectionRefusedError(), "connection"),
        (TransientBackendError("x"), "transient"),
        (PermanentBackendError("x"), "permanent"),
        (TransientBackendError("x", status=500, kind="connection"), "connection"),
        (PermanentBackendError("x", kind="missing_key"), "missing_key"),
        (RuntimeError("bug"), "backend_exception"),
    ],
)
def test_each_failure_gets_its_kind(exc, kind):
    assert error_type_of(exc) == kind


POLICY = RetryPolicy(attempts=5, initial_wait=1.0, max_wait=60.0)


def no_jitter(low, high):
    return 0.0


def test_backoff_doubles_from_the_initial_wait():
    assert [wait_before_retry(POLICY, None, n, no_jitter) for n in (1, 2, 3, 4)] == [1.0, 2.0, 4.0, 8.0]


def test_backoff_is_capped_at_max_wait():
    assert wait_before_retry(POLICY, None, 10, no_jitter) == 60.0


def test_jitter_adds_up_to_one_initial_wait():
    seen = []

    def jitter(low, high):
        seen.append((low, high))
        return high

    assert wait_before_retry(RetryPolicy(initial_wait=0.5, max_wait=60), None, 2, jitter) == 1.5
    assert seen == [(0, 0.5)]


def test_the_servers_retry_after_wins_over_backoff():
    assert wait_before_retry(POLICY, TransientBackendError("x", retry_after=7.0), 1, no_jitter) == 7.0
    assert wait_before_retry(POLICY, TransientBackendError("x", retry_after=0.0), 3, no_jitter) == 0.0


def test_retry_after_is_capped():
    assert wait_before_retry(POLICY, TransientBackendError("x", retry_after=3600.0), 1, no_jitter) == MAX_RETRY_AFTER_S


@pytest.mark.parametrize("bad", [-1.0, math.nan, math.inf, True])
def test_a_meaningless_retry_after_falls_back_to_backoff(bad):
    assert wait_before_retry(POLICY, TransientBackendError("x", retry_after=bad), 2, no_jitter) == 2.0


@pytest.mark.parametrize(
    "fields",
    [
        {"initial_wait": math.inf},
        {"max_wait": math.inf},
        {"initial_wait": math.nan},
        {"attempts": 0},
        {"attempts": 101},
        {"max_wait": -1},
        {"max_wait": 3601},
        {"tries": 3},
    ],
)
def test_a_policy_cannot_wait_forever_or_say_nonsense(fields):
    with pytest.raises(ValidationError):
        RetryPolicy(**fields)


def test_an_infra_failure_counts_retries_after_the_first_attempt():
    assert InfraFailure("auth", "x", 1).retries == 0 and InfraFailure("server_error", "x", 4).retries == 3
