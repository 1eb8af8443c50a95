"""The ``choice-3dsrbench`` scorer: a choice scorer with 3DSRBench's four accuracies.

3DSRBench asks each question in copies (:mod:`povagent.dataset.choice_sets.srbench3d`): its
flipped copy (``-flip``), its circular copies with the options rotated (``-N``), and both
(``-flip-N``). Its accuracies, as lmms-eval's ``3dsrbench`` task aggregates them (@
75571cfe0fa36ca5ec2e6aa2bb268f9d38295af3, ``lmms_eval/tasks/3dsrbench/utils.py``):

- ``vanilla_accuracy``: correct / every record (every copy counts once);
- ``flip_accuracy``: a question and its flipped copy form a pair (``Q`` with ``Q-flip``,
  ``Q-2`` with ``Q-flip-2``); a pair is right when both are;
- ``circular_accuracy``: a question and its circular copies form a set, the flipped ones a set
  of their own (``Q``, ``Q-1``, ... and ``Q-flip``, ``Q-flip-1``, ...); right when all are;
- ``flip_circular_accuracy``: every copy of the question together; right when all are.

An answer naming no option is wrong, as in :mod:`povagent_plugins.scorers.choice`. Each row
records its pair, set and question (``flip_pair``, ``circular_set``, ``question_group``);
the grouped metrics read them (:class:`povagent.scoring.metrics.Metric` ``group``).
"""

from __future__ import annotations

from typing import Any

from povagent import hookimpl
from povagent.answers.spec import ParsedAnswer
from povagent.dataset.instances import Instance
from povagent.interfaces import Scorer
from povagent.scoring.metrics import Metric
from povagent_plugins.scorers.choice import ChoiceScorer


def copy_groups(group: str, variant: str) -> dict[str, str]:
    """The pair, the set and the question a copy belongs to (see the module docstring):
    ``("Q", "flip-2")`` -> ``{"flip_pair": "Q-2", "circular_set": "Q-flip", "question_group": "Q"}``."""
    flipped = variant == "flip" or variant.startswith("flip-")
    number = variant.removeprefix("flip").removeprefix("-")
    return {
        "flip_pair": f"{group}-{number}" if number else group,
        "circular_set": f"{group}-flip" if flipped else group,
        "question_group": group,
    }


class SRBench3DScorer(Scorer):
    """The choice scorer's fields, the copy's groups, and 3DSRBench's four accuracies."""

    metrics = (
        Metric("vanilla_accuracy", "higher", "rate", "correct", "Vanilla accuracy",
               "Correct / all records, every copy counted once (no option read = wrong).", over="all"),
        Metric("flip_accuracy", "higher", "rate", "correct", "Flip accuracy",
               "Pairs of a question and its flipped copy with both right / all pairs.", over="all", group="flip_pair"),
        Metric("circular_accuracy", "higher", "rate", "correct", "Circular accuracy",
               "Sets of a question's circular copies (flipped ones apart) all right / all sets.", over="all", group="circular_set"),
        Metric("flip_circular_accuracy", "higher", "rate", "correct", "Flip+Circular accuracy",
               "Questions with every copy right / all questions.", over="all", group="question_group"),
        Metric("response_rate", "higher", "rate", "answered", "Response rate",
               "Answers naming an option / all records.", over="all"),
    )  # fmt: skip

    def score(self, instance: Instance, answer: ParsedAnswer, dataset: Any = None) -> dict[str, Any]:
        """The choice scorer's fields and the copy's groups."""
        fields = ChoiceScorer().score(instance, answer, dataset)
        question = instance.question
        assert question is not None  # the choice scorer refused an instance without one
        return fields | copy_groups(question.group or instance.pair_id, question.variant)


@hookimpl
def register_scorers(register) -> None:
    """Contribute the 3DSRBench scorer."""
    register("choice-3dsrbench", SRBench3DScorer,
             description="3DSRBench: vanilla, Flip, Circular and Flip+Circular accuracy over a question's copies")  # fmt: skip
