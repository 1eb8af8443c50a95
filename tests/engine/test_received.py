"""Every answer passes one door: each string in it cleaned of known keys, tool calls bounded."""

from __future__ import annotations

import pytest

from povagent.engine.received import (
    MAX_ARGUMENTS_CHARS,
    MAX_CALL_ID_CHARS,
    MAX_TOOL_CALLS,
    MAX_TOOL_NAME_CHARS,
    MAX_TOOL_TURN_TEXT_CHARS,
    received,
    valid_text,
)
from povagent.exchange.messages import Response, ToolCall, Usage
from povagent.files.redaction import Redactor

KEY = "lab-key-4f9a8c7e2b1d"


def test_every_string_of_an_answer_loses_the_known_key_tool_calls_included():
    answer = Response(text=f"ok {KEY}", model=f"m-{KEY}", tool_calls=(ToolCall(f"id-{KEY}", f"fly{KEY}", f'{{"k": "{KEY}"}}'),))
    kept = received(answer, Redactor((KEY,)).known, offered_tools=True)
    assert KEY not in repr(kept)
    assert (kept.text, kept.model) == ("ok [REDACTED]", "m-[REDACTED]")
    assert kept.tool_calls == (ToolCall("id-[REDACTED]", "fly[REDACTED]", '{"k": "[REDACTED]"}'),)


def test_a_lone_surrogate_in_a_tool_call_becomes_a_replacement_character():
    kept = received(Response("", tool_calls=(ToolCall("c", "turn", '{"degrees": "\ud800"}'),)), str)
    assert kept.tool_calls[0].arguments == '{"degrees": "\ufffd"}'


def test_tool_calls_and_the_text_beside_them_are_cut_to_their_bounds_whatever_the_backend():
    flood = tuple(ToolCall("i" * 999, "n" * 999, "a" * 9999) for _ in range(MAX_TOOL_CALLS + 10))
    kept = received(Response("t" * 99_999, tool_calls=flood), str, offered_tools=True)
    assert len(kept.tool_calls) == MAX_TOOL_CALLS and len(kept.text) == MAX_TOOL_TURN_TEXT_CHARS
    lengths = {(len(c.id), len(c.name), len(c.arguments)) for c in kept.tool_calls}
    assert lengths == {(MAX_CALL_ID_CHARS, MAX_TOOL_NAME_CHARS, MAX_ARGUMENTS_CHARS)}


def test_the_text_of_an_answer_to_a_request_without_tools_is_kept_whole():
    assert received(Response("t" * 99_999), str).text == "t" * 99_999


@pytest.mark.parametrize(
    "response",
    [
        Response(text="A", usage=Usage(0, 0, 0.0), latency_s=0.0, model="random"),
        Response(text="key sk-SECRET in the text", usage=Usage(12, None, None), latency_s=0.5, model=None, retries=2, cached=True),
        Response(text="lone \ud800 surrogate", model="model sk-SECRET \udfff", by_strategy=True),
    ],
)
def test_a_plain_answer_is_what_walking_its_fields_gives(response):
    """The usual answer takes a shorter path than the walk over its fields: the same result."""
    from povagent.engine.received import _strings_of

    redact = Redactor(("sk-SECRET",)).known
    walked = _strings_of(response, lambda text: redact(valid_text(text)))
    got = received(response, redact)
    assert got == walked and got is not response and got.usage is not response.usage
    assert "sk-SECRET" not in got.text and "\ud800" not in got.text
