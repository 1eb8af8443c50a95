"""Test-only plugin (loaded by path through ``plugins:``): an offline backend, a strategy, a parser.

Kept independent of the built-in plugins so runner tests specify the runner alone. Used
in-process and by the kill-and-resume subprocess alike.

* backend ``test-center``: answers the image centre (frame 0 for A/B); options ``delay_s``
  (sleep per request), ``cacheable``, ``reply`` (a fixed answer), ``pad`` (that many spaces
  after it: a reply of a million characters, which a pipeline YAML holds only at seconds of
  quoting and scanning), ``encode`` (base64 every
  image shown, as a real backend does) and ``in_process`` (declares
  ``answers_in_process``; its ``delay_s`` is then spent without suspending); counts calls in ``CALLS``.
* backend ``test-flaky``: fails per a script of status codes, then answers like test-center.
* strategy ``test-point``: one user message with the instance's frames and its sentence.
* parser ``test-json``: ``{"selected_image", "x", "y"}`` or ``{"x", "y"}``; anything else is unparseable.
"""

from __future__ import annotations

import asyncio
import json
import time
from typing import Any, ClassVar

from povagent import hookimpl
from povagent.answers.spec import AnswerSpec, ParsedAnswer, ParseStatus, frame_answer_schema, point_answer_schema, unparseable
from povagent.exchange.messages import GenerationParams, ImagePart, Message, Request, Response, TextPart, Usage
from povagent.interfaces import Backend, Parser, PermanentBackendError, Strategy, TransientBackendError

CALLS = {"count": 0}


def center_reply(request: Request) -> str:
    spec = request.answer
    point = {"x": (spec.width - 1) / 2, "y": (spec.height - 1) / 2}
    return json.dumps({"selected_image": 0, **point} if spec.asks_frame else point)


class CenterBackend(Backend):
    """Answers the centre of the image (frame 0 for A/B)."""

    def __init__(
        self, delay_s: float = 0.0, cacheable: bool = True, reply: str | None = None, encode: bool = False, in_process: bool = False, pad: int = 0
    ) -> None:
        if in_process:  # else the class's: a test may declare it there
            self.answers_in_process = True  # type: ignore[misc]
        self.delay_s = delay_s
        self.cacheable = cacheable  # type: ignore[misc]
        self.reply = reply if reply is None or not pad else reply + " " * pad
        self.encode = encode

    def identity(self) -> dict[str, Any]:
        return {"backend": "test-center", "reply": self.reply}

    async def complete(self, request: Request, images: Any) -> Response:
        CALLS["count"] += 1
        if self.encode:  # as a real backend does: every image it is shown, as a data URL
            for h in request.image_hashes():
                images.data_url(h)
        if self.delay_s and self.answers_in_process:
            time.sleep(self.delay_s)  # a slow computation: the event loop waits too
        elif self.delay_s:
            await asyncio.sleep(self.delay_s)
        text = self.reply if self.reply is not None else center_reply(request)
        return Response(text=text, usage=Usage(prompt_tokens=100, completion_tokens=10, cost_usd=0.001), model="test-center")


class FlakyBackend(CenterBackend):
    """Fails with the scripted statuses in order (shared across instances), then answers.

    ``script`` items: an HTTP status (429 carries ``retry_after``), ``"timeout"`` (sleeps past
    any timeout), ``"connection"``, ``"crash"`` (a plugin bug) or ``"ok"`` (answer this one).
    """

    SCRIPT: ClassVar[list[Any]] = []  # shared across instances: the script outlives each one

    def __init__(self, script: list[Any] | None = None, retry_after: float | None = None, **kw: Any) -> None:
        super().__init__(**kw)
        if script is not None:
            FlakyBackend.SCRIPT[:] = script
        self.retry_after = retry_after

    async def complete(self, request: Request, images: Any) -> Response:
        if FlakyBackend.SCRIPT:
            CALLS["count"] += 1
            step = FlakyBackend.SCRIPT.pop(0)
            if step == "ok":
                return await super().complete(request, images)
            if step == "timeout":
                await asyncio.sleep(60)
            if step == "connection":
                raise ConnectionResetError("connection reset by peer")
            if step == "crash":
                raise RuntimeError("bug in backend")
            if isinstance(step, int) and (step == 429 or step >= 500):
                raise TransientBackendError(f"HTTP {step}", status=step, retry_after=self.retry_after if step == 429 else None)
            if isinstance(step, int):
                raise PermanentBackendError(f"HTTP {step}: Authorization: Bearer sk-live-abcdefgh12345678 rejected", status=step)
        return await super().complete(request, images)


class PointStrategy(Strategy):
    """One user message: the frames, then the sentence."""

    def __init__(self, max_tokens: int = 32) -> None:
        self.generation = GenerationParams(max_tokens=max_tokens)

    def build(self, instance: Any, images: Any) -> Request:
        parts: list[Any] = [ImagePart(images.add_file(f.file).image_hash, f"Image {f.index}") for f in instance.frames]
        parts.append(TextPart(instance.sentence))
        w, h = instance.frame_size
        asks_frame = instance.condition.uses_exploration_frames
        schema = frame_answer_schema(len(instance.frames), w, h) if asks_frame else point_answer_schema(w, h)
        spec = AnswerSpec(schema=schema, width=w, height=h, n_frames=len(instance.frames), asks_frame=asks_frame)
        return Request(messages=(Message("user", tuple(parts)),), answer=spec, generation=self.generation, instance=instance)


class JsonParser(Parser):
    """The asked JSON object, nothing else."""

    def parse(self, text: str, spec: AnswerSpec) -> ParsedAnswer:
        try:
            obj = json.loads(text)
            x, y = float(obj["x"]), float(obj["y"])
        except (ValueError, TypeError, KeyError):
            return unparseable("not the asked JSON object", text)
        sel = obj.get("selected_image")
        return ParsedAnswer(status=ParseStatus.OK, selected_image=sel if isinstance(sel, int) else None, x=x, y=y, span=text)


@hookimpl
def register_backends(register: Any) -> None:
    register("test-center", CenterBackend, description="test: answers the centre")
    register("test-flaky", FlakyBackend, description="test: scripted failures")


@hookimpl
def register_strategies(register: Any) -> None:
    register("test-point", PointStrategy, description="test: frames and sentence")


@hookimpl
def register_parsers(register: Any) -> None:
    register("test-json", JsonParser, description="test: the asked JSON")
