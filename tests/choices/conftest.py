"""A multiple-choice instance: a hand-made POVBench instance asking where its target is."""

from __future__ import annotations

import dataclasses

import pytest

from povagent.answers.choice_question import ChoiceQuestion


@pytest.fixture
def choice_instance(mini_dataset):
    """The first Given instance of the hand-made set, asking a four-option question (gold ``C``)."""
    base = next(i for i in mini_dataset.instances() if not i.condition.uses_exploration_frames)
    question = ChoiceQuestion(
        question="From where the speaker stood, where is the target relative to the anchor?",
        options=(("A", "left"), ("B", "right"), ("C", "front"), ("D", "behind")),
        gold="C",
        category="relation",
    )
    return dataclasses.replace(base, question=question)
