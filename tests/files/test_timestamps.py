"""The time rows and log events write: ISO-8601 UTC with milliseconds, made once a millisecond."""

from __future__ import annotations

import time
from datetime import UTC, datetime

from povagent.files.timestamps import ms_text, utc_now


def test_a_millisecond_is_written_as_datetime_writes_the_clock_floored_to_it():
    for ns in (0, 1_765_126_509_153_999_999, 1_765_126_509_999_500_000, 1_765_126_510_000_000_000, 4_102_444_799_999_999_000):
        as_datetime = datetime.fromtimestamp(ns // 1000 / 1_000_000, UTC).replace(microsecond=(ns // 1000) % 1_000_000)
        assert ms_text(ns // 1_000_000) == as_datetime.isoformat(timespec="milliseconds")


def test_the_time_now_lies_between_the_clock_read_before_and_after():
    before = datetime.now(UTC).isoformat(timespec="milliseconds")
    now = utc_now()
    after = datetime.now(UTC).isoformat(timespec="milliseconds")
    assert before <= now <= after and now.endswith("+00:00") and len(now) == len("2026-12-07T16:55:09.153+00:00")


def test_the_text_follows_the_clock_from_one_millisecond_to_the_next(monkeypatch):
    clock = [1_765_126_509_153_100_000]
    monkeypatch.setattr(time, "time_ns", lambda: clock[0])
    first = utc_now()
    clock[0] += 800_000  # the same millisecond
    assert utc_now() is first
    clock[0] += 100_000  # the next one
    assert utc_now() == "2025-12-07T16:55:09.154+00:00" and first == "2025-12-07T16:55:09.153+00:00"
