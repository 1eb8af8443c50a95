"""The ``choice`` scorer: whether a multiple-choice answer chose the gold option.

Accuracy counts every row: an answer from which no option can be read is wrong, as every
multiple-choice benchmark counts it (none of them leaves a non-response out of the mean).
Scores: ``answered`` (an option was read), ``correct``, ``chosen``, ``gold`` and ``category``
(the set's question type, the slice its report breaks accuracy down by).
"""

from __future__ import annotations

from typing import Any, ClassVar

from povagent import hookimpl
from povagent.answers.spec import ParsedAnswer
from povagent.dataset.instances import Instance
from povagent.interfaces import Scorer
from povagent.scoring.metrics import Metric


class ChoiceScorer(Scorer):
    """Hit when the chosen label is the gold label (no options)."""

    metrics: ClassVar[tuple[Metric, ...]] = (
        Metric("accuracy", "higher", "rate", "correct", "Accuracy", "Correct / all questions; an answer naming no option counts as wrong.", over="all"),
        Metric("response_rate", "higher", "rate", "answered", "Response rate", "Answers naming an option / all questions.", over="all"),
    )

    def score(self, instance: Instance, answer: ParsedAnswer, dataset: Any = None) -> dict[str, Any]:
        """``correct`` and what was compared (see the module docstring)."""
        question = instance.question
        if question is None:
            raise ValueError(f"instance {instance.id} asks no multiple-choice question: score it with a point scorer")
        chosen = answer.choice if answer.status.answered else None
        return {
            "answered": chosen is not None,
            "correct": chosen is not None and chosen == question.gold,
            "chosen": chosen,
            "gold": question.gold,
            "category": question.category,
        }



class QuestionCopiesScorer(Scorer):
    """The choice scorer for a set that asks each question in copies (3DSRBench's flips and
    circular orders, MMSI-Bench's rotations): its fields, with the question a row is a copy of
    (``question_group``) and which copy (``variant``), which the sets' grouped metrics read.
    Subclasses declare those metrics."""

    def score(self, instance: Instance, answer: ParsedAnswer, dataset: Any = None) -> dict[str, Any]:
        """The choice scorer's fields, the question this is a copy of and which copy."""
        fields = ChoiceScorer().score(instance, answer, dataset)
        question = instance.question
        assert question is not None  # the choice scorer refused an instance without one
        return fields | {"question_group": question.group, "variant": question.variant}

@hookimpl
def register_scorers(register) -> None:
    """Contribute the choice scorer."""
    register("choice", ChoiceScorer, description="Multiple choice: the chosen label is the gold one (no option read = wrong)")
