"""The ``choice-or-number`` strategy: images, then a question in its set's wording, asking for an
option label or a number, as the question asks.

For a set mixing multiple-choice and numerical questions (VSI-Bench): an instance carrying a
multiple-choice question (``Instance.question``) is asked exactly as the ``choice`` strategy asks
it; one carrying a numerical question (``Instance.numeric``) is asked for ``{"number"}``
(:func:`povagent.answers.numeric_question.number_answer_schema`). The wording is the question's prompt
profile (a registered dataset format's), which words both kinds. Options as the ``choice``
strategy's (``max_tokens``, ``temperature``, ``profile``).
"""

from __future__ import annotations

from typing import Any

from povagent import hookimpl
from povagent.answers.numeric_question import number_answer_schema
from povagent.answers.spec import AnswerSpec
from povagent.dataset.instances import Instance
from povagent_plugins.strategies.choice import ChoiceProfile, ChoiceStrategy, choice_answer_spec


class ChoiceOrNumberStrategy(ChoiceStrategy):
    """The ``choice`` strategy, asking a numerical question for a number (module docstring)."""

    answer_type = "choice-or-number"
    default_parser = None  # type: ignore[assignment]  # a set's own rule reads both kinds: its format names it

    def profile_of(self, instance: Instance) -> tuple[ChoiceProfile, Any]:
        """The profile the instance is asked in and its question, multiple-choice or numerical."""
        if instance.question is not None:
            return super().profile_of(instance)
        question = instance.numeric
        if question is None:
            raise ValueError(f"instance {instance.id} asks neither a multiple-choice nor a numerical question: use a point strategy")
        return self.named_profile(instance, question.profile), question

    def answer_spec(self, instance: Instance) -> AnswerSpec:
        """One of the question's labels, or a number."""
        if instance.question is not None:
            return choice_answer_spec(instance)
        width, height = instance.frame_size
        return AnswerSpec(schema=number_answer_schema(), width=width, height=height, n_frames=len(instance.frames), asks_frame=False)


@hookimpl
def register_strategies(register) -> None:
    """Contribute the choice-or-number strategy."""
    register(
        "choice-or-number",
        ChoiceOrNumberStrategy,
        description="An option label or a number, as each question asks: the images, then the question in its set's wording",
    )
