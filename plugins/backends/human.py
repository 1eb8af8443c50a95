"""The ``human`` backend: a person answers in the browser, through ``povagent annotate``.

Registered like any backend, so a person's answers are rows of an ordinary run folder, named
``human:NAME`` (the ``annotator`` option), which ``report``, ``rescore`` and ``compare`` treat
like any system's. Each request waits on the answer desk (:mod:`povagent.annotate.desk`) until
the person answers; the answer is written as the text a model would have written (the answer
format the request asks for: a bare label for a choice, else the JSON of a frame and a pixel),
so the run's own parser and scorers read it. The seconds the person looked are the answer's
latency. Outside ``povagent annotate`` there is no desk, and the first request says so.
"""

from __future__ import annotations

import json
import math
import re
from typing import Any, ClassVar, Mapping

from povagent import hookimpl
from povagent.annotate.desk import PERSON_NAME, AnswerDesk, AnswerRefused, Question, active_desk
from povagent.errors import ConfigError
from povagent.exchange.images import ImageStore
from povagent.exchange.messages import ImagePart, Request, Response, ToolCall, Usage
from povagent.interfaces import Backend, PermanentBackendError
from povagent_plugins.backends.baselines import answer_text

#: What an annotator's name may be: it names the system in every report.
ANNOTATOR_NAME = re.compile(PERSON_NAME)


def read_answer(question: Question, answer: Any) -> str | ToolCall:
    """What the browser's ``answer`` stands for: a call of an offered tool (``tool``,
    ``arguments``; a click on an image fills a tool's ``image`` argument with the image's name,
    ``frame k`` or ``view n``); else the text a model would have written: a bare label for a
    choice, or the requested JSON of a frame and a pixel, scaled from the clicked image's own
    pixels to the answer's (the request's width and height), whatever size the page showed it."""
    if not isinstance(answer, dict):
        raise AnswerRefused("an answer is a JSON object")
    if "tool" in answer:
        return _tool_call(question, answer)
    spec = question.request.answer
    if spec.choices:
        label = answer.get("choice")
        if not isinstance(label, str) or label not in {c[0] for c in spec.choices}:
            raise AnswerRefused(f"choice must be one of {', '.join(c[0] for c in spec.choices)}")
        return str(label)
    image, x, y = answer.get("image"), answer.get("x"), answer.get("y")
    hashes = question.image_hashes()
    if not isinstance(image, int) or isinstance(image, bool) or not 0 <= image < len(hashes):
        raise AnswerRefused(f"image must be an index below {len(hashes)}")
    if not all(isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v) for v in (x, y)):
        raise AnswerRefused("x and y must be finite numbers")
    assert isinstance(x, int | float) and isinstance(y, int | float)  # checked just above
    info = question.images.info(hashes[image])
    if not (0 <= x <= info.width and 0 <= y <= info.height):
        raise AnswerRefused(f"the point must lie in the image ({info.width}x{info.height})")
    if spec.asks_frame and image >= spec.n_frames:
        raise AnswerRefused(f"the answer must be in one of the first {spec.n_frames} images")
    px = min(x * spec.width / info.width, spec.width - 1)
    py = min(y * spec.height / info.height, spec.height - 1)
    return answer_text(question.request, image if spec.asks_frame else None, px, py)


def _tool_call(question: Question, answer: dict[str, Any]) -> ToolCall:
    """A call of one of the request's tools, with the arguments the page sent (the tool reads
    and checks them, as it does a model's)."""
    offered = {t.get("function", {}).get("name") for t in question.request.tools if isinstance(t, dict)}
    name, arguments = answer.get("tool"), answer.get("arguments", {})
    if not isinstance(name, str) or name not in offered:
        raise AnswerRefused(f"tool must be one of {', '.join(sorted(str(n) for n in offered)) or 'none (no tool is offered)'}")
    if not isinstance(arguments, dict):
        raise AnswerRefused("arguments must be a JSON object")
    image = answer.get("image")
    if image is not None:
        arguments = {**arguments, "image": _image_name(question, image)}
    return ToolCall(id=f"human-{question.number}", name=str(name), arguments=json.dumps(arguments))


def _image_name(question: Question, index: Any) -> str:
    """``view n`` for a rendered view (labelled ``View n``), else ``frame k``: its place among the frames shown."""
    parts = [p for m in question.request.messages for p in m.parts if isinstance(p, ImagePart)]
    if not isinstance(index, int) or isinstance(index, bool) or not 0 <= index < len(parts):
        raise AnswerRefused(f"image must be an index below {len(parts)}")
    label = parts[index].label
    if label.lower().startswith("view "):
        return label.lower()
    return f"frame {sum(1 for p in parts[:index] if not p.label.lower().startswith('view '))}"


class HumanBackend(Backend):
    """A person at the browser: never cached (a person's second answer is a new answer)."""

    cacheable: ClassVar[bool] = False

    def __init__(self, annotator: str) -> None:
        if not isinstance(annotator, str) or not ANNOTATOR_NAME.fullmatch(annotator):
            raise ConfigError(
                f"backend 'human': option 'annotator': {annotator!r} is not a name (letters, digits, '_', '.', '-'; at most 64)"
            )
        self.annotator = annotator
        self._desk: AnswerDesk | None = None

    def identity(self) -> Mapping[str, Any]:
        """The annotator: reports name the system ``human:NAME``."""
        return {"backend": "human", "model": f"human:{self.annotator}"}

    async def start(self) -> None:
        """Find the desk ``povagent annotate`` serves; without one nobody can answer."""
        self._desk = active_desk()
        if self._desk is None:
            raise PermanentBackendError(
                "backend 'human' answers in the browser: start it with `povagent annotate CONFIG.yaml`", kind="load_failed"
            )

    async def complete(self, request: Request, images: ImageStore) -> Response:
        """Wait for the person's answer to ``request``."""
        if self._desk is None:
            await self.start()
        assert self._desk is not None
        answer = await self._desk.ask(request, images, read_answer)
        usage = Usage(prompt_tokens=0, completion_tokens=0, cost_usd=0.0)
        if isinstance(answer.value, ToolCall):
            return Response(text="", usage=usage, latency_s=answer.seconds, model=f"human:{self.annotator}", tool_calls=(answer.value,))
        return Response(text=answer.value, usage=usage, latency_s=answer.seconds, model=f"human:{self.annotator}")


@hookimpl
def register_backends(register) -> None:
    """Contribute the ``human`` backend."""
    register("human", HumanBackend, description="A person answering in the browser (povagent annotate); rows named human:NAME")
