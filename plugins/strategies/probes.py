"""The perception probes ``probe-anchor`` and ``probe-observer``: can the model find the object at all?

An addition (issue 26, docs/how-to/why-models-fail.md): they measure perception apart from reasoning, on
the same instances and in the frame the model itself chose.

* **Inferred / Stated** (three turns): turn 1 is the ``basic`` strategy's own question (the
  very request a ``basic`` run sends, so a run with the response cache answers it from the
  cache); the frame the answer selects (read leniently, with the ``json`` parser) is shown
  alone in turn 2, which asks the model to point at the named object
  (``prompts/probe_point.txt``); turn 3 is worked out, never sent (``by_strategy``): the
  answer ``{"selected_image": <turn 1's frame>, "x", "y"}`` with turn 2's point, so the row is
  scored in the frame it was asked in, then a line saying how it was made. When turn 1 selects
  no frame, turn 2 is not asked and the answer says so (a parse error, as an unanswered row).
* **Given**: ``probe-anchor`` asks the one question about the observer view (``{"x", "y"}``,
  the run's parser reads it). ``probe-observer`` has nothing to ask there (the observer view is
  taken from the observer: it is not in it) and refuses the instance: run it with
  ``instances: {conditions: [a, b]}``.

The object is named by its type in words (``SideTable`` -> ``side table``, as the ``geometric``
strategy names it); a frame showing two objects of that type may be answered with the other
one. Score with the scorer of the same name (``probe-anchor``, ``probe-observer``): the error
against the object's projected box and centre. Turn 2 carries ``Request.question``
(``{"kind": "probe", "role", "object", "frame"}``): model backends ignore it, the ``planted``
simulation answers it. This module must not score or read dataset records.
"""

from __future__ import annotations

import json
from typing import Any, ClassVar

from povagent import hookimpl
from povagent.answers.spec import AnswerSpec, point_answer_schema
from povagent.dataset.instances import Frame, Instance
from povagent.exchange.images import ImageStore
from povagent.exchange.messages import ImagePart, Message, Request, Response, TextPart
from povagent.exchange.prompts import frame_values, render
from povagent.geometry.ground_truth import anchor_keywords
from povagent.interfaces import Ask, PlannedTurn, Strategy, earlier_answer
from povagent_plugins.parsers.json_answer import JsonAnswerParser
from povagent_plugins.strategies.basic import BasicStrategy
from povagent_plugins.strategies.layout import GIVEN_LABEL, shown_images

#: ``Request.question["kind"]`` of the probe turn, and of the worked-out answer (never sent).
PROBE, PROBE_FINAL = "probe", "probe-final"
#: The template of the probe turn.
PROBE_TEMPLATE = "probe_point"
#: What the worked-out answer's second line starts with.
ACCOUNT_HEADER = "perception probe (worked out from the turns above, not asked):"


def object_words(object_type: str) -> str:
    """How the probe names a type: ``SideTable`` -> ``side table`` (the ground-truth keywords)."""
    return anchor_keywords(object_type)[0]


class PerceptionProbe(Strategy):
    """Turn 1 the basic question, turn 2 "point at the <object>" in the frame it chose (see the
    module docstring). Options are the ``basic`` strategy's (``prompts``, ``max_tokens``,
    ``temperature``, ``max_frames``), for turn 1; turn 2 has the same budget."""

    #: ``anchor`` or ``observer``: the object pointed at.
    role: ClassVar[str] = "anchor"

    def __init__(self, **options: Any) -> None:
        self.task = BasicStrategy(**options)
        self.generation = self.task.generation

    def probed(self, instance: Instance) -> Any:
        """The object this probe asks about."""
        return instance.anchor_object if self.role == "anchor" else instance.observer_object

    def answer_spec(self, instance: Instance) -> AnswerSpec:
        """The row's answer: the basic strategy's (``{selected_image, x, y}`` over the frames
        shown in turn 1, ``{x, y}`` on Given)."""
        return self.task.answer_spec(instance)

    def _refuse_given(self, instance: Instance) -> None:
        if self.role == "observer" and not instance.povbench_condition.uses_exploration_frames:
            raise ValueError(
                f"strategy probe-observer: {instance.id} is a Given (c) instance, whose observer view is taken from the "
                "observer, so the observer is not in it; run probe-observer with instances: {conditions: [a, b]}"
            )

    def probe_request(self, instance: Instance, images: ImageStore, frame: Frame, index: int | None, words: str | None = None) -> Request:
        """The probe turn: ``frame`` alone (turn 1's choice, or the observer view), and the
        question to point at the object (``words`` replace its name: a planned turn's)."""
        width, height = instance.frame_size
        obj = self.probed(instance)
        name = object_words(obj.object_type) if words is None else words
        text = render(PROBE_TEMPLATE, object=name, **frame_values(width, height))
        image = shown_images(instance, images, (frame,))
        label = "observer view" if index is None else f"Image {index}"
        message = Message("user", (TextPart(GIVEN_LABEL), ImagePart(image[0], label=label), TextPart(text)))
        spec = AnswerSpec(schema=point_answer_schema(width, height), width=width, height=height, n_frames=1, asks_frame=False)
        question = {"kind": PROBE, "role": self.role, "object": obj.object_type, "frame": index}
        return Request((message,), spec, self.generation, instance=instance, question=question)

    def final_request(self, instance: Instance) -> Request:
        """The worked-out answer's request: it stands for the answer and is never sent."""
        note = f"(the {self.role} probe's answer in the frame chosen in turn 1; worked out, not sent to a model)"
        return Request((Message.text("user", note),), self.answer_spec(instance), self.generation, instance=instance, question={"kind": PROBE_FINAL})

    def build(self, instance: Instance, images: ImageStore) -> Request:
        """The first request: the basic question (A/B), or the probe itself (Given)."""
        self._refuse_given(instance)
        if instance.povbench_condition.uses_exploration_frames:
            return self.task.build(instance, images)
        return self.probe_request(instance, images, instance.frames[0], None)

    def plan_turns(self, instance: Instance, images: ImageStore) -> list[PlannedTurn]:
        """A/B: the basic question, the probe (shown here in frame 0; asked in the frame turn 1
        selects), the worked-out answer. Given: the probe alone."""
        first = self.build(instance, images)
        if not instance.povbench_condition.uses_exploration_frames:
            return [PlannedTurn(first)]
        probe = self.probe_request(instance, images, instance.frames[0], 0)
        return [
            PlannedTurn(first),
            PlannedTurn(probe, note=f"asked in the frame turn 1 selects ({earlier_answer(1, 'selected_image')}; frame 0 shown here), when it selects one"),
            PlannedTurn(self.final_request(instance), sent=False, note="turn 1's frame with turn 2's point"),
        ]

    async def solve(self, instance: Instance, ask: Ask, images: ImageStore) -> list[tuple[Request, Response]]:
        """Ask the basic question, then the probe in the frame it selected (see the module docstring)."""
        first = self.build(instance, images)
        if not instance.povbench_condition.uses_exploration_frames:
            return [(first, await ask(first))]
        answer = await ask(first)
        turns = [(first, answer)]
        choice = JsonAnswerParser().parse(answer.text, first.answer).selected_image
        frame = instance.selected_frame(choice) if choice is not None and choice < first.answer.n_frames else None
        if frame is None:
            return turns + [self._final(instance, None, f"turn 1 selected no frame shown ({choice!r}): the probe was not asked")]
        probe = self.probe_request(instance, images, frame, frame.index)
        pointed = await ask(probe)
        turns.append((probe, pointed))
        point = JsonAnswerParser().parse(pointed.text, probe.answer)
        if not point.answered:
            return turns + [self._final(instance, None, f"no point read from turn 2 ({point.reason}): no answer")]
        assert point.x is not None and point.y is not None  # answered
        doc = {"selected_image": frame.index, "x": point.x, "y": point.y}
        return turns + [self._final(instance, doc, f"the {self.role} pointed at in frame {frame.index}, the frame turn 1 selected")]

    def _final(self, instance: Instance, doc: dict[str, Any] | None, account: str) -> tuple[Request, Response]:
        text = (json.dumps(doc) + "\n" if doc is not None else "") + f"{ACCOUNT_HEADER} {account}"
        return self.final_request(instance), Response(text=text, model="perception probe", by_strategy=True)


class AnchorProbe(PerceptionProbe):
    """Point at the anchor in the chosen frame (A/B) or the observer view (C)."""

    role = "anchor"


class ObserverProbe(PerceptionProbe):
    """Point at the observer's object in the chosen frame (A/B only)."""

    role = "observer"


@hookimpl
def register_strategies(register) -> None:
    """Contribute the two perception probes."""
    register("probe-anchor", AnchorProbe, description="Addition: the basic question, then 'point at the <anchor>' in the frame it chose (C: the observer view)")
    register(
        "probe-observer", ObserverProbe, description="Addition: the basic question, then 'point at the <observer's object>' in the frame it chose (A/B only)"
    )
