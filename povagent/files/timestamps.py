"""The wall-clock time as rows and log events write it: ISO-8601 UTC with milliseconds.

A run writes such a time three times a key (a row's start and end, its request's log event),
and ``datetime.now(UTC).isoformat(timespec="milliseconds")`` costs about 1.5 microseconds each:
:func:`utc_now` makes the text once a millisecond and hands the same text to every call within
it. The text is the same: ``datetime.now`` floors the clock to the microsecond and the
isoformat cuts it to the millisecond, which is the clock floored to the millisecond.

Ground floor: it reads the clock and nothing else.
"""

from __future__ import annotations

import time
from datetime import UTC, datetime

#: The millisecond last made into text, and its text (one tuple, read and replaced whole: a
#: thread never pairs one millisecond with another's text).
_last: tuple[int, str] = (-1, "")


def utc_now() -> str:
    """The time now as ISO-8601 UTC with milliseconds (``2026-12-07T16:55:09.153+00:00``)."""
    global _last
    ms = time.time_ns() // 1_000_000
    last = _last
    if last[0] == ms:
        return last[1]
    text = ms_text(ms)
    _last = (ms, text)
    return text


def ms_text(ms: int) -> str:
    """Milliseconds since the epoch as :func:`utc_now` writes them."""
    seconds, millis = divmod(ms, 1000)
    return datetime.fromtimestamp(seconds, UTC).replace(microsecond=millis * 1000).isoformat(timespec="milliseconds")
