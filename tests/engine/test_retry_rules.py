"""The retry rule's bounds and names, pinned at their edges (what the mutation check asked for).

Facts: a server's Retry-After is honoured up to ten minutes; a policy is finite (at most 100
attempts, waits of at most one hour, no NaN or infinity) and immutable once built; the defaults
are 5 attempts, 1 s initial wait doubling up to 60 s; every 5xx is a server error.
"""

from __future__ import annotations

import math

import pytest
from pydantic import ValidationError

from povagent.config.retry_policy import MAX_ATTEMPTS, MAX_POLICY_WAIT_S, RetryPolicy
from povagent.engine.retry import (
    MAX_RETRY_AFTER_S,
    InfraFailure,
    error_type_of,
    retry_after_of,
    wait_before_retry,
)


class Status(Exception):
    def __init__(self, status_code: int) -> None:
        super().__init__(f"HTTP {status_code}")
        self.status_code = status_code


class RetryAfter(Exception):
    def __init__(self, seconds: object) -> None:
        super().__init__("slow down")
        self.retry_after = seconds


def test_retry_after_is_capped_at_ten_minutes():
    assert MAX_RETRY_AFTER_S == 600.0
    assert retry_after_of(RetryAfter(600.0)) == 600.0
    assert retry_after_of(RetryAfter(601.0)) == 600.0
    assert retry_after_of(RetryAfter(599.0)) == 599.0


def test_the_longest_configurable_wait_is_one_hour():
    assert MAX_POLICY_WAIT_S == 3600.0
    assert RetryPolicy(initial_wait=3600.0, max_wait=3600.0).max_wait == 3600.0
    with pytest.raises(ValidationError):
        RetryPolicy(max_wait=3600.5)
    with pytest.raises(ValidationError):
        RetryPolicy(initial_wait=3600.5)


def test_the_most_attempts_a_policy_may_ask_for_is_100():
    assert MAX_ATTEMPTS == 100
    assert RetryPolicy(attempts=100).attempts == 100
    with pytest.raises(ValidationError):
        RetryPolicy(attempts=101)


def test_default_policy_is_5_attempts_from_1_s_up_to_60_s():
    policy = RetryPolicy()
    assert (policy.attempts, policy.initial_wait, policy.max_wait) == (5, 1.0, 60.0)


def test_a_policy_needs_at_least_one_attempt_and_no_negative_wait():
    assert RetryPolicy(attempts=1, initial_wait=0.0, max_wait=0.0).attempts == 1
    for bad in ({"attempts": 0}, {"initial_wait": -0.5}, {"max_wait": -0.5}):
        with pytest.raises(ValidationError):
            RetryPolicy(**bad)


@pytest.mark.parametrize("value", [math.inf, math.nan])
def test_a_policy_refuses_infinite_or_nan_waits(value):
    with pytest.raises(ValidationError):
        RetryPolicy(max_wait=value)


def test_a_policy_is_immutable():
    policy = RetryPolicy()
    with pytest.raises(ValidationError):
        policy.attempts = 3  # type: ignore[misc]


def test_a_backend_error_may_name_its_own_kind_but_not_an_empty_one():
    exc = Status(500)
    exc.kind = "connection"  # type: ignore[attr-defined]
    assert error_type_of(exc) == "connection"
    exc.kind = ""  # type: ignore[attr-defined]
    assert error_type_of(exc) == "server_error"
    exc.kind = 7  # type: ignore[attr-defined]
    assert error_type_of(exc) == "server_error"


def test_a_missing_file_is_not_called_a_connection_failure():
    assert error_type_of(FileNotFoundError("results.jsonl")) == "backend_exception"
    assert error_type_of(OSError("network unreachable")) == "connection"
    assert error_type_of(ConnectionResetError()) == "connection"


@pytest.mark.parametrize("status", [500, 501, 503, 529])
def test_every_5xx_is_a_server_error(status):
    assert error_type_of(Status(status)) == "server_error"


def test_499_is_not_a_server_error():
    assert error_type_of(Status(499)) == "backend_exception"


def test_retries_count_the_attempts_after_the_first_and_never_go_negative():
    assert InfraFailure("timeout", "t", attempts=3).retries == 2
    assert InfraFailure("timeout", "t", attempts=1).retries == 0
    assert InfraFailure("timeout", "t", attempts=0).retries == 0


def test_backoff_doubles_from_the_initial_wait_with_jitter_below_it():
    policy = RetryPolicy(initial_wait=2.0, max_wait=1000.0)
    calls = []

    def uniform(a: float, b: float) -> float:
        calls.append((a, b))
        return 0.5

    waits = [wait_before_retry(policy, None, n, uniform) for n in (1, 2, 3, 4)]
    assert waits == [2.5, 4.5, 8.5, 16.5]
    assert set(calls) == {(0, 2.0)}
    assert wait_before_retry(policy, None, 20, uniform) == 1000.0
