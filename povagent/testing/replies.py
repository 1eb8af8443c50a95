"""What the loopback server answers a request with: a reply (text, tool calls) or a fault.

Its own module so that both the server (:mod:`povagent.testing.loopback_server`) and a turns
file's reader (:mod:`povagent.testing.scripted_turns`) build the same types without importing
each other. Plain values: nothing here serves, reads or sends.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

__all__ = ["Fault", "Reply"]


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
    #: (raw text is sent as is, so a test can send malformed arguments).
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
