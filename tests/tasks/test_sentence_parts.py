"""A generated sentence taken apart with the generator's own parts, and nothing else taken apart."""

from __future__ import annotations

import pytest

from povagent.dataset.loader import load_dataset
from povagent.tasks.sentence_parts import SentenceShapeError, sentence_parts


def test_every_generated_sentence_comes_apart_and_back_together(generated_release):
    instances = load_dataset(generated_release, check_images=False).instances()
    for inst in instances:
        parts = sentence_parts(inst.sentence, str(inst.direction))
        assert parts.with_anchor(parts.anchor) == inst.sentence
        assert parts.context.endswith((f" the {parts.target}", f"The {parts.target} was", f"The {parts.target} were"))


@pytest.mark.parametrize(
    ("sentence", "direction", "context", "anchor", "target"),
    [
        ("While replacing the bulb, I saw the book on the left side of the counter.", "left", "While replacing the bulb, I saw the book", "counter", "book"),
        (
            "I was turning on the floor lamp when I noticed the keys on the sofa.",
            "up",
            "I was turning on the floor lamp when I noticed the keys",
            "sofa",
            "keys",
        ),
        (
            "The boots were in front of the doorway between the kitchen and the bedroom.",
            "front",
            "The boots were",
            "doorway between the kitchen and the bedroom",
            "boots",
        ),
    ],
)
def test_the_relation_phrase_of_the_direction_splits_context_and_anchor(sentence, direction, context, anchor, target):
    parts = sentence_parts(sentence, direction)
    assert (parts.context, parts.anchor, parts.target) == (context, anchor, target)


@pytest.mark.parametrize(
    ("sentence", "direction"),
    [
        ("While replacing the bulb, I saw the book to the left of the bed.", "right"),  # another direction's phrase
        ("A book lies to the left of the bed.", "left"),  # no sighting, no Given subject
        ("While replacing the bulb, I saw the book to the left of the bed", "left"),  # no full stop
    ],
)
def test_a_sentence_the_generator_does_not_write_is_refused(sentence, direction):
    with pytest.raises(SentenceShapeError):
        sentence_parts(sentence, direction)
