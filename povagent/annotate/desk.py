"""The answer desk: where the ``human`` backend's questions wait for the browser's answers.

The runner (an event loop in the main thread) puts one question at a time on the desk and
awaits its answer; the web server (its own threads) shows the question and hands the answer
back. The backend turns an answer into the very text a model would have written (the answer
format the request asks for), so the run's parser and scorers read a person's answer like a model's.

A question is shown only once every earlier answer's row is durable in ``results.jsonl``, and
the browser hears "saved" only then: a server killed at any moment loses no answer it
acknowledged, and a resumed session starts at the first instance with no row.
"""

from __future__ import annotations

import asyncio
import concurrent.futures
import contextlib
import threading
import time
from dataclasses import dataclass, field
from typing import Any, Callable, Iterator

from povagent.errors import PovagentError
from povagent.exchange.images import ImageStore
from povagent.exchange.messages import ImagePart, Request, TextPart

#: What an annotator or a judge may be called: the name is a system's (``human:NAME``) or a file's.
PERSON_NAME = r"[A-Za-z0-9][A-Za-z0-9_.-]{0,63}"


class AnswerRefused(PovagentError):
    """An answer the browser sent that does not fit the question (the page shows the reason)."""


@dataclass(frozen=True)
class HumanAnswer:
    """What a person's answer stands for (the backend's reading of it: the text a model would
    have written, or a tool call), and how long they looked before giving it."""

    value: Any
    seconds: float


@dataclass
class Question:
    """One request waiting for a person: numbered in the session so a late answer to an earlier
    question is never taken for the current one."""

    number: int
    request: Request
    images: ImageStore
    #: the backend's reading of the browser's answer (the text a model would have written, or a
    #: tool call); raises :class:`AnswerRefused` for one that does not fit
    read: Callable[[Question, Any], Any]
    future: concurrent.futures.Future[HumanAnswer] = field(default_factory=concurrent.futures.Future)
    shown_at: float | None = None

    @property
    def key(self) -> tuple[str | None, int]:
        """The key (instance id, run) the question belongs to: an episode asks several."""
        instance = self.request.instance
        return (instance.id if instance is not None else None, self.request.run)

    def image_hashes(self) -> list[str]:
        """The request's images, in the order the page numbers them."""
        return self.request.image_hashes()

    def page(self) -> dict[str, Any]:
        """What the page shows: the request's messages as text and numbered images, in order,
        and what kind of answer it takes. Instance ids are left out: they name the condition."""
        parts: list[dict[str, Any]] = []
        index = 0
        for message in self.request.messages:
            if message.role == "assistant":
                continue
            for part in message.parts:
                if isinstance(part, TextPart):
                    parts.append({"text": part.text})
                elif isinstance(part, ImagePart):
                    info = self.images.info(part.image_hash)
                    parts.append({"image": index, "label": part.label, "width": info.width, "height": info.height})
                    index += 1
        spec = self.request.answer
        return {
            "number": self.number,
            "parts": parts,
            "choices": [list(c) for c in spec.choices],
            "asks_frame": spec.asks_frame,
            "frames": spec.n_frames,
            "tools": [_tool_form(t) for t in self.request.tools],
        }


def _tool_form(schema: Any) -> dict[str, Any]:
    """What the page needs of an offered tool (an OpenAI function schema): its name, what it
    does and its parameters' names, types and descriptions."""
    function = schema.get("function", {}) if isinstance(schema, dict) else {}
    properties = function.get("parameters", {}).get("properties", {})
    return {
        "name": str(function.get("name", "")),
        "description": str(function.get("description", "")),
        "parameters": [{"name": str(k), "type": str(v.get("type", "string")), "description": str(v.get("description", ""))}
                       for k, v in properties.items() if isinstance(v, dict)],
    }


class AnswerDesk:
    """One annotator's desk: one question at a time, answers back to the waiting backend."""

    def __init__(self, annotator: str, total: int = 0, done: int = 0) -> None:
        self.annotator = annotator
        self.total, self.done = total, done
        self._lock = threading.Condition()
        self._question: Question | None = None
        self._numbers = 0
        #: the key (instance, run) of the last answer until its row is durable, or until the
        #: same key asks again (a tool call: the episode goes on, no row is due yet)
        self._unsaved: tuple[str | None, int] | None = None
        self._finished = False

    # -- the runner's side (event loop) --------------------------------------------------------
    async def ask(self, request: Request, images: ImageStore, read: Callable[[Question, Any], Any]) -> HumanAnswer:
        """Show ``request`` to the person and wait for their answer, read by ``read``."""
        with self._lock:
            self._numbers += 1
            question = Question(self._numbers, request, images, read)
            if self._unsaved == question.key:
                self._unsaved = None  # the same episode goes on
            self._question = question
            self._lock.notify_all()
        try:
            return await asyncio.wrap_future(question.future)
        finally:
            with self._lock:
                if self._question is question:
                    self._question = None

    def row_saved(self) -> None:
        """A row is durable (the runner's journal said so)."""
        with self._lock:
            self.done += 1
            self._unsaved = None
            self._lock.notify_all()

    def finish(self) -> None:
        """The run ended: no question will come; one still waiting for an answer is cancelled
        (its asker stops waiting, and leaves the desk it served)."""
        with self._lock:
            self._finished = True
            if self._question is not None:
                self._question.future.cancel()
            self._lock.notify_all()

    # -- the page's side (server threads) ------------------------------------------------------
    def current(self, wait_s: float = 10.0) -> Question | None:
        """The question to show, once every earlier answer is saved (waits up to ``wait_s``);
        ``None`` when there is none yet or the session is over."""
        deadline = time.monotonic() + wait_s
        with self._lock:
            while not self._finished and (self._question is None or self._unsaved is not None):
                left = deadline - time.monotonic()
                if left <= 0:
                    return None
                self._lock.wait(left)
            question = self._question if self._unsaved is None else None
            if question is not None and question.shown_at is None:
                question.shown_at = time.monotonic()
            return question

    def question(self, number: int) -> Question | None:
        """The open question numbered ``number`` (``None``: answered, or never asked)."""
        with self._lock:
            q = self._question
            return q if q is not None and q.number == number and not q.future.done() else None

    def answer(self, number: int, answer: Any, wait_s: float = 30.0) -> bool:
        """Take the browser's answer to question ``number``; wait until its row is durable (or,
        for a step of an episode, until the episode asks again).

        Raises :class:`AnswerRefused` for an answer that does not fit; returns whether it was
        saved within ``wait_s``."""
        with self._lock:
            question = self.question(number)
            if question is None:
                raise AnswerRefused(f"question {number} is not open (answered already, or not asked yet)")
            value = question.read(question, answer)
            seconds = time.monotonic() - (question.shown_at or time.monotonic())
            self._unsaved = question.key
            question.future.set_result(HumanAnswer(value, round(seconds, 3)))
            deadline = time.monotonic() + wait_s
            while self._unsaved is not None and not self._finished:
                left = deadline - time.monotonic()
                if left <= 0:
                    return False
                self._lock.wait(left)
            return self._unsaved is None

    @property
    def finished(self) -> bool:
        """Whether the session is over."""
        with self._lock:
            return self._finished


#: The desk the ``human`` backend answers through: set by ``povagent annotate`` while it serves.
_ACTIVE: list[AnswerDesk] = []


@contextlib.contextmanager
def serving(desk: AnswerDesk) -> Iterator[AnswerDesk]:
    """Make ``desk`` the one the ``human`` backend answers through, for the ``with`` block."""
    _ACTIVE.append(desk)
    try:
        yield desk
    finally:
        _ACTIVE.remove(desk)


def active_desk() -> AnswerDesk | None:
    """The desk being served, or ``None`` outside ``povagent annotate``."""
    return _ACTIVE[-1] if _ACTIVE else None
