"""What a model sent back, made fit to keep: the one door an answer passes into povagent.

A server is untrusted: it may echo the ``Authorization`` header (the key) anywhere in what it
returns, in the text, in the model name, in a tool call's id, name or arguments, and it may
send more tool calls, longer than anything a row, a log or the next request should carry. So
every answer, from any backend (litellm, a local checkpoint, a plugin's), fresh or from the
cache, goes through :func:`received` before the strategy, the row, the cache, the log or the
report sees it: every string in it, found by walking the answer's fields (a field added later
is covered without being named here), has the keys povagent knows replaced and lone
surrogates made into U+FFFD; tool calls are bounded in number and length; and the text of an
answer to a request that offered tools (a turn of an episode: a remark beside the calls, or
the final answer in JSON) is bounded too, so one episode's row stays small whatever a model
sends each turn. The text of any other answer is kept whole (a chain of thought runs long).

This module must not send requests or know runs, rows or strategies.
"""

from __future__ import annotations

import dataclasses
import re
from typing import Any, Callable

from povagent.exchange.messages import Response, ToolCall, Usage

#: Lone UTF-16 surrogates (``"\\ud800"`` in a JSON answer) are not text: UTF-8 cannot hold them.
_LONE_SURROGATE = re.compile("[\ud800-\udfff]")

#: The most tool calls kept from one answer (the rest are dropped: each kept one becomes a
#: message sent back), and the longest id, function name and arguments text of a call.
MAX_TOOL_CALLS = 128
MAX_CALL_ID_CHARS = 128
MAX_TOOL_NAME_CHARS = 64
MAX_ARGUMENTS_CHARS = 4096
#: The longest text kept from an answer to a request that offered tools.
MAX_TOOL_TURN_TEXT_CHARS = 8192


def valid_text(text: str) -> str:
    """``text`` with lone surrogates replaced by U+FFFD, so rows, logs and the cache (all
    UTF-8) can hold every answer a server sends."""
    if text.isascii():  # (told at C speed: most answers) no character of it is a surrogate
        return text
    return _LONE_SURROGATE.sub("\ufffd", text) if _LONE_SURROGATE.search(text) else text


def bounded_call(call: ToolCall) -> ToolCall:
    """``call`` with its id, name and arguments cut to their bounds."""
    return ToolCall(call.id[:MAX_CALL_ID_CHARS], call.name[:MAX_TOOL_NAME_CHARS], call.arguments[:MAX_ARGUMENTS_CHARS])


def received(response: Response, redact: Callable[[str], str], *, offered_tools: bool = False) -> Response:
    """``response`` as povagent keeps it: bounded, valid UTF-8 text, no known key in any string.

    ``redact`` removes the keys povagent knows (:meth:`povagent.files.redaction.Redactor.known`);
    ``offered_tools``: the request offered tools, so the text is bounded too.
    """
    if response.tool_calls:
        calls = tuple(bounded_call(c) for c in response.tool_calls[:MAX_TOOL_CALLS])
        response = dataclasses.replace(response, tool_calls=calls)
    if offered_tools and len(response.text) > MAX_TOOL_TURN_TEXT_CHARS:
        response = dataclasses.replace(response, text=response.text[:MAX_TOOL_TURN_TEXT_CHARS])
    if _plain(response):
        # the usual answer (texts and numbers only): what the walk below gives, without walking
        # (a copy, as the walk copies a dataclass that is not frozen)
        usage, model = response.usage, response.model
        return Response(
            text=redact(valid_text(response.text)),
            usage=Usage(usage.prompt_tokens, usage.completion_tokens, usage.cost_usd),
            latency_s=response.latency_s,
            model=None if model is None else redact(valid_text(model)),
            retries=response.retries,
            cached=response.cached,
            by_strategy=response.by_strategy,
        )
    return _strings_of(response, lambda text: redact(valid_text(text)))


def _plain(response: Response) -> bool:
    """Whether ``response`` is a plain :class:`Response` whose only strings are its text and
    model name: no tool calls, no solved point, every other field a number, a flag or None."""
    if type(response) is not Response or type(response.text) is not str or (response.model is not None and type(response.model) is not str):
        return False
    usage = response.usage
    if type(usage) is not Usage or response.tool_calls != () or type(response.tool_calls) is not tuple or response.solved_point is not None:
        return False
    return all(
        type(v) in _NO_STRINGS
        for v in (usage.prompt_tokens, usage.completion_tokens, usage.cost_usd, response.latency_s, response.retries, response.cached, response.by_strategy)
    )


def _strings_of(value: Any, clean: Callable[[str], str]) -> Any:
    """``value`` with ``clean`` applied to every string inside it (dataclass fields, tuples). A
    frozen dataclass or a tuple in which nothing changed is kept as it is (nobody can change
    it); any other dataclass is copied."""
    if isinstance(value, str):
        return clean(value)
    if isinstance(value, tuple):
        cleaned = tuple(_strings_of(v, clean) for v in value)
        return value if type(value) is tuple and all(a is b for a, b in zip(cleaned, value)) else cleaned
    kind = type(value)
    shape = _SHAPES.get(kind)
    if shape is None:
        shape = _SHAPES.setdefault(kind, _shape(kind))
    names, frozen = shape
    if not names:
        return value
    # a number, a flag or None holds no string: kept without a call (most of a response's fields)
    changed = {name: v if type(v := getattr(value, name)) in _NO_STRINGS else _strings_of(v, clean) for name in names}
    if frozen and all(v is getattr(value, name) for name, v in changed.items()):
        return value
    return dataclasses.replace(value, **changed)


#: Types whose values hold no string (what :func:`_strings_of` gives back unchanged).
_NO_STRINGS = frozenset({int, float, bool, type(None)})
#: Each type's dataclass fields set by its ``__init__`` and whether it is frozen (no fields:
#: not a dataclass instance), found once per type.
_SHAPES: dict[type, tuple[tuple[str, ...], bool]] = {}


def _shape(kind: type) -> tuple[tuple[str, ...], bool]:
    if not dataclasses.is_dataclass(kind):
        return (), False
    return tuple(f.name for f in dataclasses.fields(kind) if f.init), bool(kind.__dataclass_params__.frozen)  # type: ignore[attr-defined]
