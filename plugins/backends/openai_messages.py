"""Our :class:`~povagent.exchange.messages.Request` as OpenAI chat messages (the form litellm takes).

Parts keep their order: a text part becomes ``{"type": "text"}``, an image part becomes
``{"type": "image_url", "image_url": {"url": <URL>}}`` with the URL from the run's image store:
a data URL (encoded once per image per run) by default, or a ``file://``/``http://`` reference
when the pipeline sends images by reference (``images: {transport: file | http}``, see
:mod:`povagent.exchange.transport`). The strategy lays out the "Image i:" labels as
text parts before each image; nothing is added or reordered here. Pure apart from reading the
image store; never calls a model.
"""

from __future__ import annotations

import json
from typing import Any

from povagent.engine.received import MAX_TOOL_CALLS, bounded_call
from povagent.exchange.images import ImageStore
from povagent.exchange.messages import ImagePart, Message, Request, TextPart, ToolCall


def openai_content(message: Message, images: ImageStore) -> str | list[dict[str, Any]]:
    """The ``content`` of one message: a plain string when it is text only and not from the user.

    System and assistant turns are sent as strings because some providers reject content
    lists there; user turns are always a list of parts (the multi-image form).
    """
    if message.role != "user" and all(isinstance(p, TextPart) for p in message.parts):
        return "".join(p.text for p in message.parts if isinstance(p, TextPart))  # all are (checked above)
    parts: list[dict[str, Any]] = []
    for part in message.parts:
        if isinstance(part, TextPart):
            parts.append({"type": "text", "text": part.text})
        elif isinstance(part, ImagePart):
            parts.append({"type": "image_url", "image_url": {"url": images.url(part.image_hash)}})
        else:  # a new part type must be taught here, not silently dropped
            raise TypeError(f"cannot send message part of type {type(part).__name__}")
    return parts


def openai_message(message: Message, images: ImageStore) -> dict[str, Any]:
    """One message in OpenAI chat form: an assistant's tool calls as ``tool_calls`` (content
    ``None`` when it said nothing), a tool result with its ``tool_call_id``."""
    out: dict[str, Any] = {"role": message.role, "content": openai_content(message, images)}
    if message.tool_calls:
        out["content"] = out["content"] or None
        out["tool_calls"] = [
            {"id": c.id, "type": "function", "function": {"name": c.name, "arguments": c.arguments}} for c in message.tool_calls
        ]
    if message.tool_call_id is not None:
        out["tool_call_id"] = message.tool_call_id
    return out


def openai_messages(request: Request, images: ImageStore) -> list[dict[str, Any]]:
    """Every message of ``request`` in OpenAI chat form, in order."""
    return [openai_message(m, images) for m in request.messages]


def tool_calls_of(response: Any) -> tuple[ToolCall, ...]:
    """The function calls of an answer, as sent (names and arguments as text, cut to the bounds
    of :mod:`povagent.engine.received` while read, so a flood of calls is never held whole); a
    call the client could not read at all is kept with an empty name, for the strategy to
    report as an invalid call."""
    try:
        raw = response.choices[0].message.tool_calls or ()
    except (AttributeError, IndexError, TypeError):
        return ()
    calls = []
    for k, call in enumerate(list(raw)[:MAX_TOOL_CALLS]):
        function = getattr(call, "function", None)
        name, arguments = getattr(function, "name", None), getattr(function, "arguments", None)
        call_id = getattr(call, "id", None)
        text = arguments if isinstance(arguments, str) else json.dumps(arguments, default=repr)
        calls.append(bounded_call(ToolCall(str(call_id) if call_id else f"call_{k}", str(name) if name is not None else "", text)))
    return tuple(calls)
