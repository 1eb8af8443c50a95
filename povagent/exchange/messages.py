"""One exchange with a model: the request a strategy builds and the response a backend returns.

Requests carry images by reference (content hash), never as bytes: the backend asks the run's
:class:`povagent.exchange.images.ImageStore` for the encoded bytes, and the cache key hashes the
references, so identical requests share one key whatever their images weigh.
"""

from __future__ import annotations

import functools
import hashlib
import json
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Callable, Generic, Literal, Mapping, Sequence, TypeVar, overload

from povagent.answers.spec import AnswerSpec

if TYPE_CHECKING:
    from povagent.dataset.instances import Instance


def _canonical(value: Any) -> str:
    """The one JSON form hashes are taken of: keys sorted, no spaces."""
    return json.dumps(value, sort_keys=True, separators=(",", ":"))


#: A string as :func:`_canonical` writes it (JSON's escapes, ASCII only: ``json.dumps``'s own).
_string = json.encoder.encode_basestring_ascii

T = TypeVar("T")


class _made_once(Generic[T]):
    """``functools.cached_property`` without its lock (Python 3.11's takes one at each first
    read, ~0.5 us: a request's message is read once): the value is computed from a frozen
    object's fields, the same whichever thread makes it, and kept in the object's ``__dict__``,
    where later reads find it first."""

    def __init__(self, make: Callable[[Any], T]) -> None:
        self.make, self.name, self.__doc__ = make, make.__name__, make.__doc__

    def __set_name__(self, owner: type, name: str) -> None:
        self.name = name

    @overload
    def __get__(self, instance: None, owner: type | None = None) -> _made_once[T]: ...
    @overload
    def __get__(self, instance: object, owner: type | None = None) -> T: ...
    def __get__(self, instance: object | None, owner: type | None = None) -> T | _made_once[T]:
        if instance is None:
            return self
        value = instance.__dict__[self.name] = self.make(instance)
        return value


@dataclass(frozen=True)
class TextPart:
    """A piece of text in a message."""

    text: str


@dataclass(frozen=True)
class ImagePart:
    """An image in a message, by content hash (see :class:`povagent.exchange.images.ImageStore`)."""

    image_hash: str
    label: str = ""


Part = TextPart | ImagePart


@dataclass(frozen=True)
class ToolCall:
    """One function call a model asked for: its id, the function's name and its arguments as
    the model sent them (JSON text, untrusted: the strategy that offered the tool checks it)."""

    id: str
    name: str
    arguments: str


@dataclass(frozen=True)
class Message:
    """A chat message: a role and an ordered list of parts.

    An assistant message may carry the ``tool_calls`` the model made; a ``tool`` message is the
    result of one call, named by ``tool_call_id`` (text only: tool results carry no images,
    so a strategy shows an image in a user message after them).
    """

    role: Literal["system", "user", "assistant", "tool"]
    parts: tuple[Part, ...]
    tool_calls: tuple[ToolCall, ...] = ()
    tool_call_id: str | None = None

    @classmethod
    def text(cls, role: Literal["system", "user", "assistant", "tool"], text: str) -> Message:
        """A message holding one text part."""
        return cls(role, (TextPart(text),))

    @_made_once
    def fingerprint_json(self) -> str:
        """:meth:`fingerprint` as canonical JSON, made once per message: a long conversation
        repeats every earlier message in each request, and hashing one must not redo them all."""
        # the same text as _canonical(self.fingerprint()), put together from each part's JSON
        # (keys in sorted order: parts, role, tool_call_id, tool_calls): a request of 30
        # frames has 61 parts, and a dict a part made this the larger half of hashing it
        parts = ",".join(('{"text":' + _string(p.text) if isinstance(p, TextPart) else '{"image":' + _string(p.image_hash)) + "}" for p in self.parts)
        out = '{"parts":[' + parts + '],"role":' + _string(self.role)
        if self.tool_call_id is not None:
            out += ',"tool_call_id":' + _string(self.tool_call_id)
        if self.tool_calls:
            out += ',"tool_calls":' + _canonical(self.fingerprint()["tool_calls"])
        return out + "}"

    def fingerprint(self) -> dict[str, Any]:
        """JSON-able form (images by hash); tool fields only when set, so a plain message's
        fingerprint is what it always was."""
        out: dict[str, Any] = {
            "role": self.role,
            "parts": [{"text": p.text} if isinstance(p, TextPart) else {"image": p.image_hash} for p in self.parts],
        }
        if self.tool_calls:
            out["tool_calls"] = [{"id": c.id, "name": c.name, "arguments": c.arguments} for c in self.tool_calls]
        if self.tool_call_id is not None:
            out["tool_call_id"] = self.tool_call_id
        return out


@dataclass(frozen=True)
class GenerationParams:
    """Sampling settings a strategy asks for (backends may add their own options).

    ``max_tokens`` ``None`` sends no limit (the authors' runner set none for Gemini and Gemma).
    """

    max_tokens: int | None = 256
    temperature: float | None = None
    extra: tuple[tuple[str, Any], ...] = ()

    def as_dict(self) -> dict[str, Any]:
        """Plain dict, ``None`` values dropped."""
        d: dict[str, Any] = {} if self.max_tokens is None else {"max_tokens": self.max_tokens}
        if self.temperature is not None:
            d["temperature"] = self.temperature
        d.update(dict(self.extra))
        return d

    @functools.cached_property
    def canonical_json(self) -> str:
        """:meth:`as_dict` as canonical JSON, made once: a strategy's every request shares its
        generation settings, and each request's hash holds them."""
        return _canonical(self.as_dict())


@dataclass(frozen=True)
class Request:
    """What a strategy asks a backend.

    ``instance`` is context for offline baselines (the oracle reads the GT from it) and ``run``
    the repeat index (seeded baselines and replay read it). ``question`` is a machine-readable
    description of a strategy's sub-question (``{"kind": "locate", "object": "Sofa", ...}``):
    model backends ignore it, the ``simulated`` backend answers from it. None of the three is
    sent to models nor part of :meth:`fingerprint` (the runner adds the run index to the cache
    key itself).
    """

    messages: tuple[Message, ...]
    answer: AnswerSpec
    generation: GenerationParams = field(default_factory=GenerationParams)
    instance: Instance | None = field(default=None, compare=False)
    run: int = field(default=0, compare=False)
    question: Mapping[str, Any] | None = field(default=None, compare=False)
    #: Functions the model may call (OpenAI function-calling schema, sent as litellm's
    #: ``tools=``); empty for the usual single-answer request.
    tools: tuple[Mapping[str, Any], ...] = field(default=(), compare=False)

    def fingerprint(self) -> dict[str, Any]:
        """JSON-able description of everything that determines the answer (images by hash)."""
        out: dict[str, Any] = {
            "messages": [m.fingerprint() for m in self.messages],
            "generation": self.generation.as_dict(),
        }
        if self.tools:
            out["tools"] = [dict(t) for t in self.tools]
        return out

    def content_hash(self) -> str:
        """SHA-256 of :meth:`fingerprint` as canonical JSON (stable across runs and machines),
        put together from each message's own JSON (the same bytes, each message serialized once)."""
        blob = (
            '{"generation":'
            + self.generation.canonical_json
            + ',"messages":['
            + ",".join(m.fingerprint_json for m in self.messages)
            + "]"
            + (',"tools":' + _canonical([dict(t) for t in self.tools]) if self.tools else "")
            + "}"
        )
        return hashlib.sha256(blob.encode()).hexdigest()

    def as_text(self) -> str:
        """The request as a reader sees it (:func:`messages_text` of every message). Rows keep
        it as the transcript."""
        return messages_text(self.messages)

    def image_hashes(self) -> list[str]:
        """Hashes of every image in the request, in order."""
        return messages_images(self.messages)


def messages_text(messages: Sequence[Message]) -> str:
    """Messages as a reader sees them: each message's role on a line (``--- user ---``), its
    text parts verbatim, each image as ``[image: LABEL]`` (hashes in :func:`messages_images`,
    in the same order) and each tool call as ``[tool call ID: NAME(ARGUMENTS)]``. The text of
    a list that extends another is that list's text, a newline, then the added messages'."""
    lines: list[str] = []
    for m in messages:
        lines.append(f"--- {m.role} ---" if m.tool_call_id is None else f"--- {m.role} ({m.tool_call_id}) ---")
        lines += [p.text if isinstance(p, TextPart) else f"[image: {p.label or 'unlabelled'}]" for p in m.parts]
        lines += [f"[tool call {c.id}: {c.name}({c.arguments})]" for c in m.tool_calls]
    return "\n".join(lines)


def messages_images(messages: Sequence[Message]) -> list[str]:
    """Hashes of every image in ``messages``, in order."""
    return [p.image_hash for m in messages for p in m.parts if isinstance(p, ImagePart)]


@dataclass
class Usage:
    """Token counts and cost of one model call (``None`` where the provider does not say)."""

    prompt_tokens: int | None = None
    completion_tokens: int | None = None
    cost_usd: float | None = None


@dataclass
class Response:
    """What a backend returns: the raw text and what it cost.

    ``retries`` and ``cached`` are filled in by the runner. ``by_strategy`` marks an answer a
    multi-turn strategy worked out itself from the model's earlier answers (no model call): the
    runner records it as the row's last exchange, so the row holds the answer it scored.
    ``solved_point`` is the 3D target such a strategy worked out (in the world frame of the
    frames' cameras), which the GroundingAgent returns as its goal. ``tool_calls`` are the
    function calls of a request that offered ``tools`` (never cached: the cache keeps text).
    """

    text: str
    usage: Usage = field(default_factory=Usage)
    latency_s: float = 0.0
    model: str | None = None
    retries: int = 0
    cached: bool = False
    by_strategy: bool = False
    solved_point: tuple[float, float, float] | None = None
    #: The function calls the model made instead of (or beside) a text answer.
    tool_calls: tuple[ToolCall, ...] = ()
