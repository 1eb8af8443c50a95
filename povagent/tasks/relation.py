"""Relation classification: "From where the speaker stood, where is the X relative to the Y?"

What it is for: the first of the paper's future-work tasks. Each point instance becomes a
multiple-choice question over the same frames: the condition's sentence without its relation
(A: the activity that implies the observer, B: the activity naming it, C: nothing but the
question, beside the observer's view), where the target is in a frame's pixels (the generator
renders no target: :func:`sighting`), then the question. A model answers it by taking the
speaker's place: the pixel says where the target is from the camera, the question asks where
it is from the speaker (in C the image is the speaker's view). The options are the direction
registry's members in its short words ("to the left", "on top"), shuffled per instance by a
generator seeded from the instance id, so a position bias never lines up with the gold; the
gold is the instance's direction. The question is ``profile="plain"`` and its ``category`` is
the direction, the slice accuracy is broken down by.

What it must not do: word the direction anywhere but among the options.
"""

from __future__ import annotations

import hashlib
import random
from dataclasses import replace

from povagent.answers.choice_question import ChoiceQuestion
from povagent.dataset.instances import Instance
from povagent.geometry.directions import DIRECTION_NAMES, spec_of
from povagent.tasks.scene_facts import NoTeachingFrame, gt_pixel, teaching_frame
from povagent.tasks.sentence_parts import SentenceParts, sentence_parts

#: Option labels, one per registry direction.
LABELS = "ABCDEFGH"

#: What a Given question says of its one image (the A/B sentences say where the speaker was).
GIVEN_VIEW = "The image shows the view from where the speaker stood."


def shuffled_directions(seed_text: str) -> list[str]:
    """The registry's directions in an order drawn from ``seed_text`` (an instance id): the
    same order on every run and machine."""
    digest = hashlib.sha256(seed_text.encode()).digest()
    order = list(DIRECTION_NAMES)
    random.Random(int.from_bytes(digest[:8], "big")).shuffle(order)
    return order


def direction_options(seed_text: str) -> tuple[tuple[str, str], ...]:
    """``(("A", "on top"), ("B", "to the left"), ...)``: every direction once, shuffled."""
    return tuple((LABELS[k], spec_of(d).short_words) for k, d in enumerate(shuffled_directions(seed_text)))


def label_of(options: tuple[tuple[str, str], ...], direction: str) -> str:
    """The label whose text is ``direction``'s short words."""
    words = spec_of(direction).short_words
    return next(label for label, text in options if text == words)


def sighting(instance: Instance) -> str | None:
    """Where the target is seen, in a frame's pixels: "In Image 3, the book is at pixel (231,
    340)." (Given: "In the image, ..."), or None when no frame shows its place.

    The generator renders no target, so the question says where it is in the images (the frame
    the point task teaches with: the anchor seen, the target inside); which way that is from
    the speaker is what the question asks."""
    if instance.povbench_condition.uses_exploration_frames:
        try:
            frame = teaching_frame(instance)
        except NoTeachingFrame:
            return None
        where = f"In Image {frame.index}"
    else:
        frame, where = instance.frames[0], "In the image"
    pixel = gt_pixel(frame.camera, instance.target)
    if pixel is None:
        return None
    return f"{where}, the {{target}} is at pixel ({int(pixel[0])}, {int(pixel[1])})."


def question_text(given: bool, parts: SentenceParts, seen: str, target: str, reference: str) -> str:
    """The context the condition gives (none for Given: its image is the view), where the
    target is seen, then "From where the speaker stood, where is the <target> relative to the
    <reference>?"."""
    lead = GIVEN_VIEW if given else parts.observed
    return f"{lead} {seen.format(target=target)} From where the speaker stood, where is the {target} relative to the {reference}?"


def relation_instance(instance: Instance) -> Instance | None:
    """The point instance asked as a relation question (same id, frames and ground truth), or
    None when no frame shows the target's place.

    A sentence the generator does not write is a
    :class:`~povagent.tasks.sentence_parts.SentenceShapeError`."""
    parts = sentence_parts(instance.sentence, str(instance.direction))
    seen = sighting(instance)
    if seen is None:
        return None
    options = direction_options(instance.id)
    text = question_text(not instance.povbench_condition.uses_exploration_frames, parts, seen, parts.target, parts.anchor)
    question = ChoiceQuestion(
        question=text,
        options=options,
        gold=label_of(options, str(instance.direction)),
        category=str(instance.direction),
        profile="plain",
    )
    # the sentence a point strategy would send named the direction: only the question stays
    return replace(instance, sentence=text, question=question)
