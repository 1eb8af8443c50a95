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

from typing import Any

from povagent.exchange.images import ImageStore
from povagent.exchange.messages import ImagePart, Message, Request, TextPart


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


def openai_messages(request: Request, images: ImageStore) -> list[dict[str, Any]]:
    """Every message of ``request`` in OpenAI chat form, in order."""
    return [{"role": m.role, "content": openai_content(m, images)} for m in request.messages]
